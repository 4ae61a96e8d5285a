"""The any-part rule (probe 1, the paper's) vs the centre rule (probe 0) in both visibility
modes on a built-in scene (default standard-store): V entries and time of voxel probe 0/1
(every candidate) and pixel probe 0/1 at stride 1 (every ``--every``-th candidate, time
extrapolated to all), voxel-vs-pixel agreement on those rows under each rule, and the
coverage gap / cost of one placement (greedy at the scene's budget on voxel probe-0 V,
the default run's) scored under both rules. Writes one JSON object to stdout.

    python benchmarks/probe_rule.py [standard-store] [--every 20] [--stride 1]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from camplace.cameras.candidates import build_candidates
from camplace.metrics.coverage import compute_metrics
from camplace.solvers import solve
from camplace.visibility.engine import compute_visibility
from camplace.visibility.pixel import PixelEngine
from camplace.visibility.voxel import VoxelEngine
from camplace.workflows.compare import entry_agreement
from camplace.workflows.run import problem_from_visibility, scene_inputs


def timed(engine, sc, targets, cands):
    """(Visibility, wall seconds, CPU seconds of this process's threads)."""
    compute_visibility(engine, sc.occupancy, targets, cands.subset(np.arange(min(2, len(cands)))))  # compile
    w, c = time.perf_counter(), time.process_time()
    vis = compute_visibility(engine, sc.occupancy, targets, cands)
    return vis, time.perf_counter() - w, time.process_time() - c


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scene", nargs="?", default="standard-store")
    ap.add_argument("--every", type=int, default=20, help="pixel mode on every N-th candidate")
    ap.add_argument("--stride", type=int, default=1)
    a = ap.parse_args()
    sc, targets, cameras, _ = scene_inputs(a.scene)
    cands = build_candidates(sc, cameras)
    rows = np.arange(0, len(cands), a.every)
    v = float(sc.spec.voxel_size)
    out: dict = {"scene": a.scene, "candidates": len(cands), "targets": len(targets), "pixel_rows": len(rows),
                 "stride": a.stride, "modes": {}, "agreement": {}}
    vox = {}
    for probe in (0.0, 1.0):
        vis, wall, cpu = timed(VoxelEngine(probe, v), sc, targets, cands)
        vox[probe] = vis
        out["modes"][f"voxel probe {probe:g}"] = {"nnz": int(vis.V.nnz), "wall_s": wall, "cpu_s": cpu}
    for probe in (0.0, 1.0):
        vis, wall, cpu = timed(PixelEngine(v, stride=a.stride, probe=probe), sc, targets, cands.subset(rows))
        scale = len(cands) / len(rows)
        out["modes"][f"pixel probe {probe:g}"] = {"nnz_rows": int(vis.V.nnz), "wall_s_rows": wall, "cpu_s_rows": cpu,
                                                   "wall_s_all_extrapolated": wall * scale,
                                                   "cpu_s_all_extrapolated": cpu * scale}
        e = entry_agreement(vox[probe].V[rows], vis.V)
        out["agreement"][f"probe {probe:g}"] = {k: e[k] for k in ("nnz_a", "nnz_b", "shared", "jaccard", "a_in_b",
                                                                  "b_in_a")}
    budget = sc.spec.placement.budget
    probs = {p: problem_from_visibility(vis, budget) for p, vis in vox.items()}
    sel = solve(probs[0.0], "greedy").selected
    out["placement"] = {"solver": "greedy", "budget": budget, "solved_on": "voxel probe 0"}
    for p, prob in probs.items():
        m = compute_metrics(prob, sel, targets.region_ids, targets.region_names)
        out["placement"][f"scored probe {p:g}"] = {"coverage_gap": float(m.coverage_gap), "cost": float(m.cost)}
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
