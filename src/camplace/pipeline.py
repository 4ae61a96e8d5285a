"""The whole pipeline as one call; the CLI and the Python API both use it.

scene -> targets -> candidates -> visibility -> problem -> solve -> metrics.
Progress goes through a callback ``progress(stage, done, total)``; nothing prints.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from camplace.builtin import resolve_scene
from camplace.cameras import CameraModel, camera_from_spec
from camplace.candidates import build_candidates
from camplace.config import SceneSpec
from camplace.metrics import Metrics, compute_metrics
from camplace.problem import PlacementProblem
from camplace.scene import Scene, build_scene
from camplace.solvers import Placement, solve
from camplace.targets import build_targets
from camplace.visibility import Visibility, compute_visibility, drop_blind_candidates

Progress = Callable[[str, int, int], None]


@dataclass
class RunResult:
    scene: Scene
    visibility: Visibility
    problem: PlacementProblem
    placement: Placement
    metrics: Metrics
    timings_s: dict[str, float] = field(default_factory=dict)
    log: list[str] = field(default_factory=list)


def _stage(progress: Progress | None, name: str) -> None:
    if progress:
        progress(name, 0, 1)


def prepare(scene: str | Path | SceneSpec, progress: Progress | None = None,
            timings: dict | None = None, log: list | None = None) -> tuple[Scene, Visibility]:
    """Scene, targets, candidates and visibility (blind candidates dropped)."""
    timings = {} if timings is None else timings
    log = [] if log is None else log
    spec, base_dir, source = resolve_scene(scene)
    t = time.perf_counter()
    _stage(progress, "scene")
    sc = build_scene(spec, base_dir, source)
    timings["scene"] = time.perf_counter() - t
    t = time.perf_counter()
    _stage(progress, "targets")
    targets = build_targets(sc)
    timings["targets"] = time.perf_counter() - t
    t = time.perf_counter()
    _stage(progress, "candidates")
    cameras: dict[str, CameraModel] = {c.name: camera_from_spec(c) for c in spec.cameras}
    cands = build_candidates(sc, cameras)
    timings["candidates"] = time.perf_counter() - t
    t = time.perf_counter()
    vis = compute_visibility(sc.occupancy, targets, cands, progress=progress)
    vis = drop_blind_candidates(vis)
    timings["visibility"] = time.perf_counter() - t
    log.append(f"candidates: {cands.info['generated']} generated, {cands.info['dropped_inside_obstacle']} inside "
               f"obstacles, {vis.info['dropped_blind']} seeing no target, {len(vis.candidates)} kept")
    log.append(f"targets: {len(targets)} ({', '.join(f'{n}: {int((targets.region_ids == r).sum())}' for r, n in enumerate(targets.region_names))})")
    log.append(f"visibility: V {vis.V.shape[0]} x {vis.V.shape[1]}, nnz {vis.V.nnz}")
    if vis.V.shape[0] == 0:
        from camplace.errors import InputError

        raise InputError(f"scene '{spec.name}': no candidate pose sees any target")
    return sc, vis


def problem_from_visibility(vis: Visibility, budget: int) -> PlacementProblem:
    t = vis.targets
    return PlacementProblem(vis.V, t.gamma, t.weights, int(budget), vis.candidates.location_ids,
                            np.array([vis.candidates.cameras[c].cost for c in vis.candidates.camera_ids]))


def run(scene: str | Path | SceneSpec, budget: int | None = None, solver: str | None = None,
        progress: Progress | None = None, **solver_options) -> RunResult:
    """Run every stage on a scene (built-in name, YAML path or spec)."""
    timings: dict[str, float] = {}
    log: list[str] = []
    sc, vis = prepare(scene, progress, timings, log)
    budget = sc.spec.placement.budget if budget is None else budget
    solver = sc.spec.placement.solver if solver is None else solver
    problem = problem_from_visibility(vis, budget)
    t = time.perf_counter()
    _stage(progress, "solve")
    placement = solve(problem, solver, **solver_options)
    timings["solve"] = time.perf_counter() - t
    t = time.perf_counter()
    metrics = compute_metrics(problem, placement.selected, vis.targets.region_ids, vis.targets.region_names)
    timings["metrics"] = time.perf_counter() - t
    return RunResult(sc, vis, problem, placement, metrics, timings, log)
