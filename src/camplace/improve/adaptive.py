"""Adaptive candidates: refine the grid where the solution is, then solve again.

Round r (r = 1, 2, ...) generates, around every selected pose, the poses at offsets of
spacing / 2^r in x and y (a 3 x 3 patch on the mount surface) and of step / 2^r in yaw,
pitch and roll (3 values each where the mount has more than one), drops those already in
V, outside the mount surface or inside an obstacle, raycasts the rest and appends them
to V as rows (a new position is a new location; a position already in V reuses its
location id). The enlarged problem is solved again warm-started from the previous
selection (its rows keep their ids), by best-improvement swap descent
(:func:`swap_descent`) and, when given, a registered solver that accepts ``initial=``
(e.g. ``tabu``). Rounds repeat while the cost drops.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from camplace.problem.model import PlacementProblem
from camplace.improve.refine import PoseGuard, RowMap, append_candidates, extend_problem, pose_box, _valid_positions
from camplace.scene.build import Scene
from camplace.solvers.base import Placement, deadline
from camplace.solvers.local_search import NominalObjective, swap_search
from camplace.visibility.voxel import Visibility

Progress = Callable[[str, int, int], None]


def swap_descent(problem: PlacementProblem, selected: np.ndarray, time_limit_s: float | None = 30.0,
                 max_passes: int = 1000, should_stop: Callable[[], bool] | None = None) -> tuple[np.ndarray, dict]:
    """Best-improvement local search from ``selected`` (camplace.solvers.local_search): each
    pass tries, for every selected camera i, removing it and adding the best candidate j
    (any location not used by the others, money budget kept), plus plain additions while
    below the budget; applies the single best move if it lowers the cost. One pass = k
    sparse mat-vecs. Returns the sorted selection and info (moves, passes, seconds)."""
    sel, info = swap_search(problem, np.asarray(selected, np.int64), NominalObjective(problem),
                            end=deadline(time_limit_s), max_passes=max_passes, should_stop=should_stop)
    return np.array(sorted(sel), np.int64), {k: info[k] for k in ("moves", "passes", "seconds")}


def finer_poses(scene: Scene, vis: Visibility, selected: np.ndarray, level: int,
                guard: PoseGuard | None = None) -> tuple[np.ndarray, np.ndarray]:
    """New poses (K, 6) and camera ids (K,) around the selected rows at offsets of
    spacing / 2^level and angle step / 2^level (duplicates of V rows, invalid positions
    and, with ``guard``, the poses it rejects - e.g. those seeing a privacy zone - removed)."""
    cands = vis.candidates
    out, cids = [], []
    for i in np.asarray(selected, np.int64):
        box = pose_box(scene, cands, int(i), fraction=0.5 ** level)
        centre = np.r_[cands.positions[i], cands.angles_deg[i]]
        axes = [np.array([-h, 0.0, h]) if h > 0 else np.zeros(1) for h in box.half]
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 6) + centre
        grid = grid[_valid_positions(box, scene.occupancy, grid)]
        out.append(grid)
        cids.append(np.full(len(grid), cands.camera_ids[i], np.int32))
    if not out:
        return np.zeros((0, 6)), np.zeros(0, np.int32)
    poses = np.concatenate(out)
    poses[:, 3] %= 360.0
    camera_ids = np.concatenate(cids)
    if guard is not None and len(poses):
        ok = guard(poses, camera_ids)
        poses, camera_ids = poses[ok], camera_ids[ok]
    ang = cands.angles_deg.copy()
    ang[:, 0] %= 360.0
    have = np.c_[cands.positions, ang, cands.camera_ids]
    key = lambda a: [tuple(r) for r in np.round(a * 1000).astype(np.int64).tolist()]  # noqa: E731
    seen = set(key(have))
    keep = []
    for n, k in enumerate(key(np.c_[poses, camera_ids])):
        if k not in seen:
            seen.add(k)
            keep.append(n)
    return poses[keep], camera_ids[keep]


@dataclass(frozen=True)
class AdaptiveResult:
    """visibility / problem: the enlarged V and problem; placement: best selection on it;
    rounds: per round dict(round, candidates, new_candidates, nnz, cost, seconds)."""

    visibility: Visibility
    problem: PlacementProblem
    placement: Placement
    grid_cost: float
    rounds: list[dict] = field(default_factory=list)


def adaptive_rounds(scene: Scene, vis: Visibility, problem: PlacementProblem, placement: Placement,
                    rounds: int = 3, time_limit_s: float | None = 120.0, solver: str | None = None,
                    solver_time_s: float = 10.0, progress: Progress | None = None,
                    guard: PoseGuard | None = None, row_map: RowMap | None = None,
                    should_stop: Callable[[], bool] | None = None) -> AdaptiveResult:
    """Up to ``rounds`` rounds of finer candidates around the current selection, each
    solved again warm-started; stops early when a round does not lower the cost, and
    when ``should_stop()`` turns true (between the steps of a round; the best selection
    so far is kept). ``guard``: see camplace.improve.refine.refine_poses."""
    t0 = time.perf_counter()
    sel = np.asarray(placement.selected, np.int64)
    grid_cost = problem.cost(sel)
    best_cost = grid_cost
    hist = [{"round": 0, "candidates": int(problem.n_candidates), "new_candidates": 0, "nnz": int(problem.V.nnz),
             "cost": grid_cost, "seconds": round(placement.seconds, 3)}]
    cur_vis, cur_prob, cur_sel = vis, problem, sel
    stop = (lambda: False) if should_stop is None else should_stop
    for r in range(1, rounds + 1):
        if (time_limit_s is not None and time.perf_counter() - t0 > time_limit_s) or stop():
            break
        tr = time.perf_counter()
        poses, cids = finer_poses(scene, cur_vis, cur_sel, r, guard)
        if len(poses) == 0:
            break
        new_vis, _ = append_candidates(cur_vis, scene.occupancy, poses, cids)
        if stop():
            break
        new_prob = extend_problem(cur_prob, new_vis, row_map)
        left = None if time_limit_s is None else max(1.0, time_limit_s - (time.perf_counter() - t0))
        new_sel, info = swap_descent(new_prob, cur_sel, time_limit_s=left, should_stop=should_stop)
        if solver and not stop():
            from camplace.solvers import SOLVERS

            p = SOLVERS[solver](new_prob, time_limit_s=min(solver_time_s, left or solver_time_s), initial=new_sel)
            if p.objective < new_prob.cost(new_sel) - 1e-9:
                new_sel = np.asarray(p.selected, np.int64)
        cost = new_prob.cost(new_sel)
        hist.append({"round": r, "candidates": int(new_prob.n_candidates), "new_candidates": int(len(poses)),
                     "nnz": int(new_prob.V.nnz), "cost": cost, "swap_moves": info["moves"],
                     "seconds": round(time.perf_counter() - tr, 3)})
        if progress:
            progress("adaptive", r, rounds)
        if cost < best_cost - 1e-9:
            best_cost = cost
            cur_vis, cur_prob, cur_sel = new_vis, new_prob, new_sel
        else:
            break
    cur_prob.check_feasible(cur_sel)
    out = Placement(cur_sel, cur_prob.cost(cur_sel), None, "heuristic", f"{placement.solver}+adaptive",
                    placement.seconds + time.perf_counter() - t0,
                    dict(placement.info, adaptive={"rounds": hist, "grid_cost": grid_cost}))
    return AdaptiveResult(cur_vis, cur_prob, out, grid_cost, hist)


__all__ = ["AdaptiveResult", "adaptive_rounds", "finer_poses", "swap_descent"]
