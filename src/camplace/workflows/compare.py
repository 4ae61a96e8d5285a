"""Agreement of the two visibility modes (``voxel`` vs ``pixel``) on one scene.

``compare_visibility`` builds V both ways on the same candidates (no blind-candidate
drop, so rows align), counts shared entries (Jaccard and each side's share, overall
and per region) and measures the effect on the final result: it solves the placement
on each V with the same solver and scores each placement on the other V.
Where and why the modes differ: docs/lenses.md.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import scipy.sparse as sp

from camplace.cameras.candidates import build_candidates
from camplace.spec.schema import SceneSpec
from camplace.metrics.coverage import compute_metrics
from camplace.workflows.run import problem_from_visibility, scene_inputs
from camplace.solvers import solve
from camplace.visibility.engine import Visibility, compute_visibility
from camplace.visibility.registry import get_engine

Progress = Callable[[str, int, int], None]
CENTRE_PROBE = 0.0


@dataclass
class Agreement:
    """Entry counts of V_voxel and V_pixel and the coverage gaps of placements solved on
    one and scored on the other (``gap[solved_on][scored_on]``, paper eq. 8)."""

    scene: str
    stride: int
    probe: float
    candidates: int
    targets: int
    nnz_voxel: int
    nnz_pixel: int
    shared: int
    jaccard: float
    voxel_in_pixel: float  # share of voxel-mode entries that pixel mode also has
    pixel_in_voxel: float  # share of pixel-mode entries that voxel mode also has
    regions: dict = field(default_factory=dict)
    budget: int = 0
    solver: str = "greedy"
    gap: dict = field(default_factory=dict)
    seconds: dict = field(default_factory=dict)
    rays: int = 0
    rays_per_s: float = 0.0

    def to_dict(self) -> dict:
        return asdict(self)


def entry_agreement(A: sp.csr_matrix, B: sp.csr_matrix) -> dict:
    """Shared non-zeros of two same-shape sparse 0/1 matrices: counts, Jaccard, shares."""
    A = (A != 0).astype(np.uint8).tocsr()
    B = (B != 0).astype(np.uint8).tocsr()
    shared = int(A.multiply(B).nnz)
    union = A.nnz + B.nnz - shared
    return {"nnz_a": int(A.nnz), "nnz_b": int(B.nnz), "shared": shared,
            "jaccard": shared / union if union else 1.0,
            "a_in_b": shared / A.nnz if A.nnz else 1.0, "b_in_a": shared / B.nnz if B.nnz else 1.0}


def compare_visibility(scene: str | Path | SceneSpec, stride: int | None = None, probe: float = CENTRE_PROBE,
                       budget: int | None = None, solver: str = "greedy",
                       progress: Progress | None = None) -> Agreement:
    """Build V in voxel and pixel mode on the same candidates and compare them.

    probe: the rule both modes use (0 = the target's centre; 1 = any part of its voxel,
    the paper's rule; fractions between); budget: N_s for the gap comparison (default
    the scene's)."""
    sc, targets, cameras, _ = scene_inputs(scene, progress)
    cands = build_candidates(sc, cameras)
    engines = {"voxel": get_engine("voxel", probe=probe),
               "pixel": get_engine("pixel", stride=stride, probe=probe)}
    vis, secs = {}, {}
    for mode, engine in engines.items():
        t = time.perf_counter()
        vis[mode] = compute_visibility(engine, sc.occupancy, targets, cands, progress=progress)
        secs[mode] = time.perf_counter() - t
    vv, vp, t_pix = vis["voxel"], vis["pixel"], secs["pixel"]
    e = entry_agreement(vv.V, vp.V)
    regions = {}
    for r, name in enumerate(targets.region_names):
        cols = np.nonzero(targets.region_ids == r)[0]
        er = entry_agreement(vv.V[:, cols], vp.V[:, cols])
        regions[name] = {"nnz_voxel": er["nnz_a"], "nnz_pixel": er["nnz_b"], "shared": er["shared"],
                         "jaccard": er["jaccard"], "voxel_in_pixel": er["a_in_b"], "pixel_in_voxel": er["b_in_a"]}
    budget = sc.spec.placement.budget if budget is None else int(budget)
    gaps = gap_effect(vis, budget, solver)
    return Agreement(sc.name, int(vp.info["stride"]), float(probe), len(cands), len(targets),
                     e["nnz_a"], e["nnz_b"], e["shared"], e["jaccard"], e["a_in_b"], e["b_in_a"], regions,
                     budget, solver, gaps, secs, int(vp.info["rays"]),
                     float(vp.info["rays"]) / t_pix if t_pix > 0 else 0.0)


def gap_effect(vis: dict[str, Visibility], budget: int, solver: str = "greedy") -> dict:
    """Solve on each V, score on every V: {solved_on: {scored_on: coverage gap}}."""
    problems = {k: problem_from_visibility(v, budget) for k, v in vis.items()}
    out: dict[str, dict[str, float]] = {}
    for k, prob in problems.items():
        sel = solve(prob, solver).selected
        out[k] = {k2: float(compute_metrics(p2, sel, vis[k2].targets.region_ids,
                                            vis[k2].targets.region_names).coverage_gap)
                  for k2, p2 in problems.items()}
    return out
