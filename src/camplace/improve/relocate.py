"""Refinement-aware relocation (issue 37): move one camera to the best of a few other
candidates, each judged by the pose a refinement would make of it.

A swap search judges an incoming candidate by its grid row, while the camera it replaces
sits at a refined pose; so after a refinement almost no swap pays (the kicks and the
tabu after refinement of camplace.improve.quality found nothing). Here, for each selected
camera k (least useful first), with the coverage c_o of the others fixed and
g_j = w_j (max(Γ_j − c_oj, 0)² − max(Γ_j − c_oj − 1, 0)²) the gain of one more view:

1. every row of V is scored at once, s = V g (one sparse mat-vec);
2. the ``top`` best rows at a location no other camera uses (same limit group with type
   limits, no dearer camera with a money budget) are each refined alone by the compass
   search of camplace.improve.refine (``compass``: its box around that candidate, ``levels``
   halvings), against the same g;
3. the best refined pose replaces camera k when its score beats k's own, Σ_{j∈row k} g_j.

Sweeps repeat while one camera moved. Poses off V are appended as rows at the end (the
location rule of ``append_candidates``), so the result is a selection of V rows and its
cost, recomputed from V, is lower than the start's or equal to it.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Callable

import numpy as np

from camplace.improve.refine import (PoseGuard, RefineResult, RowMap, _free_of_others, _guarded, _PolledRows,
                                     _trial_rows, _valid_positions, append_candidates, compass, extend_problem,
                                     focal_box, pose_box, target_gains)
from camplace.problem.model import PlacementProblem
from camplace.scene.build import Scene
from camplace.solvers.base import Placement
from camplace.visibility.engine import Visibility
from camplace.visibility.registry import engine_of


def _allowed_rows(problem: PlacementProblem, rows_idx: np.ndarray, k: int, locs: np.ndarray) -> np.ndarray:
    """(N_g,) bool: rows a camera in slot k may move to: no other slot's location (``locs``,
    -1 for a pose off V), the same limit group under type limits, no dearer camera under a
    money budget (so the limits and the budget hold after the move)."""
    ok = ~np.isin(problem.location_ids, np.delete(locs, k)[np.delete(locs, k) >= 0])
    if rows_idx[k] >= 0:
        i = rows_idx[k]
        if problem.has_type_limits and problem.type_ids is not None:
            ok &= problem.type_ids == problem.type_ids[i]
        if problem.money_budget is not None:
            costs = problem.costs
            ok &= costs <= costs[i] + 1e-9
    elif problem.has_type_limits or problem.money_budget is not None:
        ok[:] = False  # a slot already off V keeps its type and price only by staying put
    return ok


def relocate_placement(scene: Scene, vis: Visibility, problem: PlacementProblem, placement: Placement,
                       time_limit_s: float | None = 10.0, *, top: int = 6, levels: int = 3,
                       max_sweeps: int = 20,
                       guard: PoseGuard | None = None, row_map: RowMap | None = None,
                       should_stop: Callable[[], bool] | None = None) -> RefineResult:
    """Relocation sweeps (see module doc) from ``placement`` for at most ``time_limit_s`` s;
    returns the extended V / problem and the placement on it (solver '<solver>+relocate',
    info['relocate']: moves, refined candidates, raycast, sweeps, stopped, seconds)."""
    t0 = time.perf_counter()
    deadline = None if time_limit_s is None else t0 + float(time_limit_s)
    halt = lambda: (deadline is not None and time.perf_counter() > deadline) or (  # noqa: E731
        should_stop is not None and should_stop())
    sel = np.asarray(placement.selected, np.int64)
    start_cost = problem.cost(sel)
    cands, V = vis.candidates, problem.V
    engine = engine_of(vis)
    fb = [focal_box(cands.cameras[int(cands.camera_ids[i])]) for i in sel]
    poses = np.array([np.r_[cands.positions[i], cands.angles_deg[i], f[0]] for i, f in zip(sel, fb)]).reshape(-1, 7)
    cids = cands.camera_ids[sel].astype(np.int32)
    rows = [V[int(i)] for i in sel]
    idx = sel.copy()  # the V row of each slot; -1: a pose off V (appended at the end)
    locs = problem.location_ids[sel].copy()
    cov = problem.coverage(sel)
    polled = _PolledRows(V.shape[1])
    moves = tried = raycast = sweeps = 0
    stopped = "converged"
    while sweeps < max_sweeps and stopped == "converged":
        sweeps += 1
        moved_any = False
        gain_of = [target_gains(problem, cov - _dense(r, len(cov)))[r.indices].sum() for r in rows]
        for k in np.argsort(gain_of, kind="stable"):
            if halt():
                stopped = "interrupted" if should_stop is not None and should_stop() else "time_limit"
                break
            cov_o = cov.copy()
            cov_o[rows[k].indices] -= 1
            g = target_gains(problem, cov_o)
            cur = float(g[rows[k].indices].sum())
            s = np.asarray(V @ g).ravel()
            s[~_allowed_rows(problem, idx, int(k), locs)] = -np.inf
            if idx[k] >= 0:
                s[idx[k]] = -np.inf
            best = (cur, None)
            for j in _best_per_location(s, problem.location_ids, top):
                if not np.isfinite(s[j]) or halt():
                    break
                if not _free_of_others(poses, int(k), cands.positions[j][None, :]).all():
                    continue
                box = pose_box(scene, cands, int(j))
                cid = int(cands.camera_ids[j])
                f = focal_box(cands.cameras[cid])
                start = np.r_[box.centre, f[0]]

                def admit(trial: np.ndarray, box=box, k=int(k), cid=cid) -> np.ndarray:
                    ok = _valid_positions(box, scene.occupancy, trial) & _free_of_others(poses, k, trial)
                    if guard is not None and ok.any():
                        ok[ok] = _guarded(guard, cands, cid, trial[ok])
                    return ok

                pose, row, score, c = compass(
                    start, V[int(j)], float(s[j]), np.r_[box.half, f[1]], np.r_[box.centre - box.half, f[2]],
                    np.r_[box.centre + box.half, f[3]], g, levels, admit,
                    lambda t, cid=cid: polled.get(cid, t, lambda u: _trial_rows(engine, scene, vis, cid, u, row_map)),
                    halt)  # a pose's row depends on the pose and camera type only: polled by type
                tried += 1
                raycast += c["raycast"]
                if score > best[0] + 1e-9 * max(1.0, abs(best[0])):
                    best = (score, (int(j), cid, pose, row, c["accepted"] > 0))
            if best[1] is None:
                continue
            j, cid, pose, row, off = best[1]
            poses[k], cids[k], rows[k] = pose, cid, row
            idx[k], locs[k] = (-1, -1) if off else (j, problem.location_ids[j])
            cov = cov_o
            cov[row.indices] += 1
            moves += 1
            moved_any = True
        if not moved_any and stopped == "converged":
            break
    off = idx < 0
    vis2, new_ids = append_candidates(vis, scene.occupancy, poses[off], cids[off])
    prob2 = extend_problem(problem, vis2, row_map)
    final = idx.copy()
    final[off] = new_ids
    final = np.sort(final)
    prob2.check_feasible(final)
    cost = prob2.cost(final)
    info = {"moves": moves, "refined_candidates": tried, "raycast": raycast, "sweeps": sweeps, "stopped": stopped,
            "seconds": time.perf_counter() - t0, "start_cost": start_cost, "cost": cost}
    p2 = replace(placement, selected=final, objective=cost, status="heuristic", solver=f"{placement.solver}+relocate",
                 seconds=placement.seconds + time.perf_counter() - t0, info=dict(placement.info, relocate=info))
    return RefineResult(vis2, prob2, p2, start_cost, cost, info)


def shake_relocate(scene: Scene, vis: Visibility, problem: PlacementProblem, placement: Placement,
                   time_limit_s: float, *, seed: int = 0, moves: int = 3, places: int = 30,
                   max_fails: int | None = None, guard: PoseGuard | None = None, row_map: RowMap | None = None,
                   should_stop: Callable[[], bool] | None = None) -> tuple[Visibility, PlacementProblem, Placement]:
    """Iterated local search for ``time_limit_s`` seconds: ``moves`` cameras drawn at random, each
    moved to a row drawn among the best of ``places`` places for it (given the others, as in a
    relocation: any limit and money budget kept), then refinement, relocation and refinement
    again within the time left; the result is kept when its cost is lower. ``max_fails``: also
    end after that many tries in a row found nothing better (None: never). The rows raycast stay
    in V either way. Returns (V, problem, the best placement)."""
    from camplace.improve.refine import refine_placement

    end = time.perf_counter() + float(time_limit_s)
    rng = np.random.default_rng(seed)
    stop = (lambda: False) if should_stop is None else should_stop
    best, best_cost, fails = placement, problem.cost(placement.selected), 0
    while time.perf_counter() < end - 0.3 and not stop() and (max_fails is None or fails < max_fails):
        sel = np.asarray(best.selected, np.int64).copy()
        for k in rng.choice(len(sel), min(moves, len(sel)), replace=False):
            g = target_gains(problem, problem.coverage(np.delete(sel, k)))
            s = np.asarray(problem.V @ g).ravel()
            s[~_allowed_rows(problem, sel, int(k), problem.location_ids[sel])] = -np.inf
            s[sel[k]] = -np.inf
            pool = _best_per_location(s, problem.location_ids, places)
            if len(pool):
                sel[k] = int(rng.choice(pool))
        trial = replace(best, selected=np.sort(sel), objective=problem.cost(sel))
        for step in (refine_placement, relocate_placement, refine_placement):
            if end - time.perf_counter() < 0.2 or stop():
                break
            r = step(scene, vis, problem, trial, end - time.perf_counter(), guard=guard, row_map=row_map,
                     should_stop=should_stop)
            vis, problem, trial = r.visibility, r.problem, r.placement
        cost = problem.cost(trial.selected)
        if cost < best_cost - 1e-9:
            best, best_cost, fails = trial, cost, 0
        else:  # the same selection on the extended problem (its rows keep their ids)
            best, fails = replace(best, objective=problem.cost(best.selected)), fails + 1
    return vis, problem, best


def _best_per_location(s: np.ndarray, location_ids: np.ndarray, top: int) -> np.ndarray:
    """Rows of the ``top`` highest finite scores ``s`` (N_g,), one per location (its best pose),
    best first, among the 64·top best rows: the candidates worth refining, spread over places."""
    order = np.argsort(-s, kind="stable")
    order = order[np.isfinite(s[order])][: 64 * top]
    _, first = np.unique(location_ids[order], return_index=True)
    return order[np.sort(first)[:top]]


def _dense(row, n: int) -> np.ndarray:
    out = np.zeros(n, np.int64)
    out[row.indices] = 1
    return out


__all__ = ["relocate_placement", "shake_relocate"]
