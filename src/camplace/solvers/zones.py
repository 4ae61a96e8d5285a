"""``zones``: block-coordinate descent over tiles of the floor (docs/scale.md § decomposition,
option 2), for problems whose monolithic MIP is too large.

1. Start from ``greedy-fast`` (or ``initial``, or a checkpoint of this problem).
2. The full problem's Lagrangian bound (camplace.solvers.bounds.lagrangian_bound, at most
   ``bound_time_s``) is computed once on the start: Placement.bound, gap in Placement.gap.
3. Sweeps: the floor is cut into square tiles of ``tile_m`` metres (default 3 × the
   camera range estimated from V and the positions); each tile's subproblem is its
   candidates and the targets they see, with the coverage of the cameras outside the tile
   as an offset (camplace.problem.offset), and as budget the cameras it has now plus the
   unused ones (money and per-type limits: the tile's own plus the global slack). It is
   solved by the tight MIP (``mip``, ``tile_time_s`` per tile) when its model has at most
   ``max_tile_nnz`` non-zeros, else by tabu from its current selection; a strictly
   cheaper tile solution replaces the tile's cameras. Tiles of one colour
   (camplace.solvers.zones_tiles: no shared target) run in parallel on ``workers``
   processes or a Dask ``scheduler`` and are merged in tile order, each merge checked
   against the global budget, money budget and type limits, so the result equals the
   serial one. Odd sweeps shift the tile origin by half a tile.
4. Budget moves after each sweep: for each tile (cheapest removal first) remove its
   camera whose removal costs least and add the best candidate of a neighbouring tile
   (exact gain after the removal, keeping locations, types and money); accepted when the
   full cost drops.
5. Stop when two sweeps in a row (both origins) bring nothing, at ``max_sweeps``, the time
   limit, or should_stop (status 'interrupted', best so far). Each completed sweep's
   selection is saved atomically to ``checkpoint`` (a folder) under a hash of the
   problem; a later solve of the same problem resumes from it.

Every accepted change lowers the full cost, so the result is never worse than the start.
Deterministic for a seed when no per-tile time limit is hit. Status 'optimal' when the
bound meets the cost, else 'heuristic' / 'time_limit' / 'interrupted'.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from camplace.core.errors import InputError
from camplace.core.files import atomic_write_json
from camplace.problem.gains import removal_losses, target_gains
from camplace.problem.model import PlacementProblem
from camplace.problem.offset import offset_subproblem
from camplace.solvers.base import (OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, stopped, time_left,
                                   trivial_placement)
from camplace.solvers.contract import Tags, make_solver
from camplace.solvers.greedy_triangulated import positions_of
from camplace.solvers.zones_tiles import TileRunner, TileTask, Tiling, estimate_range, location_xy, make_tiling, \
    tile_method

TOL = 1e-9


def problem_key(problem: PlacementProblem) -> str:
    """Hex hash of what defines the problem: V, Γ, weights, budget, locations, prices, types."""
    h = hashlib.blake2b(digest_size=12)
    for a in (problem.V.indptr, problem.V.indices, problem.gamma, problem.weights, problem.location_ids,
              problem.costs, np.zeros(0) if problem.type_ids is None else problem.type_ids):
        a = np.asarray(a).ravel()
        kind = np.int64 if a.dtype.kind in "iub" else np.float64  # the same key whatever the stored dtype
        for i in range(0, len(a), 1 << 22):  # in pieces: a memory-mapped V is never copied whole
            h.update(memoryview(np.ascontiguousarray(a[i:i + (1 << 22)], dtype=kind)))
        h.update(b"|")
    h.update(repr((int(problem.budget), problem.money_budget, sorted((problem.type_limits or {}).items()),
                   problem.V.shape)).encode())
    return h.hexdigest()


def checkpoint_path(folder: str | Path, key: str) -> Path:
    """The checkpoint file of the problem with hash ``key`` in ``folder``."""
    return Path(folder) / f"zones-{key}.json"


def load_checkpoint(problem: PlacementProblem, folder: str | Path | None,
                    key: str) -> tuple[np.ndarray, int, int] | None:
    """(selection, sweeps done, colour batches done in the next sweep) saved for this
    problem, None when absent, unreadable or infeasible."""
    if folder is None:
        return None
    path = checkpoint_path(folder, key)
    try:
        data = json.loads(path.read_text())
        sel = np.sort(np.asarray(data["selected"], np.int64))
        if data.get("key") != key:
            return None
        problem.check_feasible(sel)
        return sel, int(data.get("sweeps", 0)), int(data.get("batches", 0))
    except (OSError, ValueError, KeyError, TypeError):
        return None


def save_checkpoint(folder: str | Path, key: str, selected: np.ndarray, cost: float, sweeps: int,
                    batches: int = 0) -> None:
    """Write the selection after ``sweeps`` complete sweeps and ``batches`` colour batches
    of the next one atomically (camplace.core.files)."""
    Path(folder).mkdir(parents=True, exist_ok=True)
    atomic_write_json(checkpoint_path(folder, key), {"key": key, "sweeps": int(sweeps), "batches": int(batches),
                                                     "cost": float(cost), "selected": [int(i) for i in selected]})


class _Globals:
    """Global limits of a selection: free camera slots, money left, per-type cameras left."""

    def __init__(self, problem: PlacementProblem) -> None:
        self.p = problem
        self.lt = problem.limited_types()
        self.costs = problem.costs

    def ok(self, sel: np.ndarray) -> bool:
        p = self.p
        if len(sel) > p.budget:
            return False
        if p.money_budget is not None and float(self.costs[sel].sum()) > p.money_budget + 1e-9 * max(1.0, p.money_budget):
            return False
        return not p.has_type_limits or p.type_ok(sel)

    def tile_limits(self, sel: np.ndarray, inside: np.ndarray) -> tuple[int, float | None, dict | None]:
        """(budget, money budget, type limits) of a tile holding ``inside`` of ``sel``."""
        p = self.p
        budget = len(inside) + max(0, p.budget - len(sel))
        money = None
        if p.money_budget is not None:
            money = max(0.0, float(p.money_budget) - float(self.costs[sel].sum()) + float(self.costs[inside].sum()))
        types = None
        if p.has_type_limits:
            out_counts = p.type_counts(np.setdiff1d(sel, inside))
            types = {k: int(v) - out_counts.get(int(k), 0) for k, v in p.type_limits.items()}
        return budget, money, types


def _tile_task(problem: PlacementProblem, g: _Globals, tiling: Tiling, t: int, sel: np.ndarray, cov: np.ndarray,
               max_tile_nnz: int, tile_time_s: float, seed: int) -> TileTask | None:
    rows, cols = tiling.rows[t], tiling.cols[t]
    if len(cols) == 0:
        return None
    inside = tiling.in_tile(sel, t)
    cov_out = cov - problem.coverage(inside)
    budget, money, types = g.tile_limits(sel, inside)
    sub = offset_subproblem(problem, rows, cols, cov_out, budget=budget, money_budget=money, type_limits=types)
    if sub.normalizer <= 0:
        return None
    return TileTask(t, sub, np.searchsorted(rows, inside), tile_method(sub, max_tile_nnz), tile_time_s,
                    seed + 7919 * t)


def budget_moves(problem: PlacementProblem, selected: np.ndarray, tiling: Tiling, g: _Globals,
                 should_stop: ShouldStop | None = None, end: float = float("inf")) -> tuple[np.ndarray, int]:
    """(selection, moves made): for each tile (cheapest removal first), its camera whose
    removal costs least moves to the best candidate of another tile, when that lowers the
    full cost (module doc, step 4). Gains in the neighbouring tiles (shared targets) are
    recomputed after the removal; elsewhere the removal changes no gain (O(nnz) per move made)."""
    sel = np.sort(np.asarray(selected, np.int64))
    if len(sel) == 0 or tiling.n_tiles < 2:
        return sel, 0
    loc = np.asarray(problem.location_ids)
    moved, done = 0, set()
    while True:
        cov = problem.coverage(sel)
        cost = problem.cost(sel)
        gain0 = np.asarray(problem.V @ target_gains(problem.gamma, problem.weights, cov)).ravel()
        losses = removal_losses(problem, sel, cov)
        order = np.lexsort((sel, losses))  # cheapest removal first (ties: lowest id)
        found = None
        for k in order:
            a = int(tiling.tile_of[sel[k]])
            if a in done:
                continue
            if stopped(should_stop) or time.perf_counter() >= end:
                return sel, moved
            done.add(a)
            r = int(sel[k])
            rest = sel[sel != r]
            ok = ~np.isin(loc, loc[rest]) & (tiling.tile_of != a)
            if problem.money_budget is not None:
                ok &= problem.costs + float(problem.costs[rest].sum()) <= problem.money_budget + 1e-9
            if problem.has_type_limits:
                ok &= ~problem.type_full(rest)
            near = np.concatenate([tiling.rows[b] for b in tiling.neighbours[a]] or [np.zeros(0, np.int64)])
            gains = np.where(ok, gain0, -np.inf)
            if len(near):
                cov_r = cov - problem.coverage(np.array([r]))
                g_near = np.asarray(problem.V[near] @ target_gains(problem.gamma, problem.weights, cov_r)).ravel()
                gains[near] = np.where(ok[near], g_near, -np.inf)
            best = int(np.argmax(gains))  # ties: lowest id
            if gains[best] > losses[k] + TOL * max(1.0, float(losses[k])):
                new = np.sort(np.append(rest, best))
                if g.ok(new) and problem.cost(new) < cost - TOL * max(1.0, cost):
                    found = new
                    break
        if found is None:
            return sel, moved
        sel, moved = found, moved + 1


def solve_zones(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                on_incumbent: OnIncumbent | None = None, tile_m: float | None = None, max_tile_nnz: int = 1_500_000,
                tile_time_s: float = 20.0, bound_time_s: float = 10.0, max_sweeps: int | None = None,
                moves: bool = True, workers: int = 1, scheduler: str | None = None,
                checkpoint: str | None = None, initial: tuple | None = None) -> Placement:
    """Zone sweeps with boundary coupling (tight MIP or tabu per tile), budget moves
    between neighbouring tiles and the full-problem Lagrangian bound (module doc), on the
    reduced problem (camplace.solvers.reduction.reduce_with_positions: the same optimum,
    V's mapped pages released, a fraction of the memory at site scale; the unreduced one
    when ``initial`` holds a candidate the reduction drops).
    tile_m: tile side (m, default 3 × the camera range); max_tile_nnz: largest tile model
    solved by the MIP; tile_time_s: per-tile limit (s); workers / scheduler: where the tiles
    of one colour run; checkpoint: folder for the per-batch selection (resume); initial:
    start selection (candidate ids; default greedy-fast)."""
    from camplace.solvers.reduction import reduce_with_positions

    opts = dict(threads=threads, seed=seed, should_stop=should_stop, progress=progress, on_incumbent=on_incumbent,
                tile_m=tile_m, max_tile_nnz=max_tile_nnz, tile_time_s=tile_time_s, bound_time_s=bound_time_s,
                max_sweeps=max_sweeps, moves=moves, workers=workers, scheduler=scheduler, checkpoint=checkpoint)
    t0 = time.perf_counter()
    if problem.candidate_positions is None or problem.target_positions is None or problem.n_candidates == 0:
        return _zones_on(problem, time_limit_s=time_limit_s, initial=initial, **opts)
    red = reduce_with_positions(problem)
    start = None
    if initial is not None:
        where = np.full(problem.n_candidates, -1, np.int64)
        where[red.candidates] = np.arange(len(red.candidates))
        start = where[np.asarray(initial, np.int64)]
        if np.any(start < 0):  # a start camera the reduction dropped: solve the problem as given
            return _zones_on(problem, time_limit_s=time_limit_s, initial=initial, **opts)
    left = None if time_limit_s is None else max(0.01, time_limit_s - (time.perf_counter() - t0))
    p = _zones_on(red.problem, time_limit_s=left, initial=None if start is None else tuple(start.tolist()), **opts)
    sel = red.lift(p.selected)
    return replace(p, selected=sel, objective=problem.cost(sel), seconds=time.perf_counter() - t0,
                   info=dict(p.info, reduction=red.info))


def _zones_on(problem: PlacementProblem, *, time_limit_s: float | None, threads: int | None, seed: int,
              should_stop: ShouldStop | None, progress: ProgressFn | None, on_incumbent: OnIncumbent | None,
              tile_m: float | None, max_tile_nnz: int, tile_time_s: float, bound_time_s: float,
              max_sweeps: int | None, moves: bool, workers: int, scheduler: str | None, checkpoint: str | None,
              initial: tuple | None) -> Placement:
    """solve_zones on ``problem`` as given (see solve_zones)."""
    from camplace.solvers.bounds import lagrangian_bound
    from camplace.solvers.greedy_fast import solve_greedy_fast

    t0 = time.perf_counter()
    if (easy := trivial_placement(problem, "zones", t0)) is not None:
        return easy
    positions_of(problem)  # InputError when the positions are missing
    if tile_m is not None and not tile_m > 0:
        raise InputError(f"tile_m: expected a positive tile size in metres, got {tile_m!r}", option="tile_m")
    if tile_time_s <= 0:
        raise InputError(f"tile_time_s: expected a positive number of seconds, got {tile_time_s!r}",
                         option="tile_time_s")
    end = deadline(time_limit_s)
    info: dict = {}
    key = problem_key(problem) if checkpoint is not None else ""
    resumed = load_checkpoint(problem, checkpoint, key)
    sweeps_done, skip = 0, 0
    if resumed is not None:
        sel, sweeps_done, skip = resumed
        info.update(resumed_from_sweep=sweeps_done, resumed_batches=skip)
    elif initial is not None:
        sel = np.sort(np.asarray(initial, np.int64))
        try:
            problem.check_feasible(sel)
        except ValueError as err:
            raise InputError(f"initial: not a feasible selection ({err})", option="initial") from None
    else:
        left = time_left(end)
        gf = solve_greedy_fast(problem, time_limit_s=None if left is None else 0.5 * left, should_stop=should_stop)
        sel = np.sort(np.asarray(gf.selected, np.int64))
        if gf.status == "interrupted":
            return Placement(sel, problem.cost(sel), None, "interrupted", "zones", time.perf_counter() - t0,
                             {"start_objective": gf.objective})
    cost = problem.cost(sel)
    info["start_objective"] = cost
    if on_incumbent:
        on_incumbent(cost, None)
    if stopped(should_stop):
        return Placement(sel, cost, None, "interrupted", "zones", time.perf_counter() - t0, info)
    left = time_left(end)
    lb = lagrangian_bound(problem, time_limit_s=bound_time_s if left is None else min(bound_time_s, 0.2 * left),
                          incumbent_cost=cost, coverage=problem.coverage(sel), should_stop=should_stop)
    bound = min(float(lb.bound), cost)
    info["lagrangian_bound"] = float(lb.bound)
    if on_incumbent:
        on_incumbent(cost, bound)
    rng_m = estimate_range(problem)
    size = float(tile_m) if tile_m is not None else max(3.0 * rng_m, 1.0)
    info.update(tile_m=size, range_m=rng_m)
    xy = location_xy(problem)
    g = _Globals(problem)
    status, idle, sweep_log = "heuristic", 0, []
    with TileRunner(workers, scheduler) as runner:
        info["executor"] = runner.name
        while idle < 2 and (max_sweeps is None or len(sweep_log) < max_sweeps):
            if stopped(should_stop) or time.perf_counter() >= end:
                status = "interrupted" if stopped(should_stop) else "time_limit"
                break
            sweep = sweeps_done + len(sweep_log)
            tiling = make_tiling(problem, size, 0.5 * size * (sweep % 2), xy)
            before, n_better, n_mip = cost, 0, 0
            n_colours = int(tiling.colour.max()) + 1 if tiling.n_tiles else 0
            saved = (sweep, skip)
            for c in range(n_colours):
                if c < skip:  # done before the restart (checkpoint)
                    continue
                left = time_left(end)
                if stopped(should_stop) or (left is not None and left <= 0.05):
                    break
                cov = problem.coverage(sel)
                tasks = [t for t in (_tile_task(problem, g, tiling, int(k), sel, cov, max_tile_nnz, tile_time_s, seed)
                                     for k in np.flatnonzero(tiling.colour == c)) if t is not None]
                if left is not None and tasks:  # the batch's tiles share the time left (rounds of `workers`)
                    rounds = -(-len(tasks) // max(1, runner.workers))
                    tasks = [replace(t, time_limit_s=max(0.05, min(tile_time_s, left / rounds))) for t in tasks]
                n_mip += sum(t.method == "mip" for t in tasks)
                results = runner.map(tasks, should_stop, end)
                cut = any(r[3] in ("interrupted", "skipped") for r in results)
                for task, (tile, local, _, _) in zip(tasks, results):
                    rows = tiling.rows[tile]
                    new = np.sort(np.concatenate([sel[tiling.tile_of[sel] != tile], rows[local]]))
                    if not g.ok(new):
                        continue
                    new_cost = problem.cost(new)
                    if new_cost < cost - TOL * max(1.0, cost):
                        sel, cost, n_better = new, new_cost, n_better + 1
                        if on_incumbent:
                            on_incumbent(cost, bound)
                if progress:
                    progress("zones", c + 1, int(tiling.colour.max()) + 1)
                if checkpoint is not None:  # a batch with a tile cut by the stop or skipped counts as not done
                    save_checkpoint(checkpoint, key, sel, cost, sweep, c if cut else c + 1)
                    saved = (sweep, c if cut else c + 1)
            n_moves = 0
            if moves and not stopped(should_stop) and time.perf_counter() < end:
                sel, n_moves = budget_moves(problem, sel, tiling, g, should_stop, end)
                if n_moves:
                    cost = problem.cost(sel)
                    if on_incumbent:
                        on_incumbent(cost, bound)
            sweep_log.append({"sweep": sweep, "tiles": tiling.n_tiles, "colours": int(tiling.colour.max()) + 1
                              if tiling.n_tiles else 0, "mip_tiles": n_mip, "improved_tiles": n_better,
                              "moves": n_moves, "cost": cost, "seconds": time.perf_counter() - t0})
            if checkpoint is not None and saved == (sweep, n_colours):  # the whole sweep done
                save_checkpoint(checkpoint, key, sel, cost, sweep + 1)
            skip = 0
            idle = idle + 1 if cost >= before - TOL * max(1.0, before) else 0
    if stopped(should_stop):  # also when the stop came in the last sweep
        status = "interrupted"
    elif status == "heuristic" and bound >= cost - 1e-9 * max(1.0, cost):
        status = "optimal"
    info.update(sweeps=sweep_log, key=key or None)
    return Placement(sel, cost, min(bound, cost), status, "zones", time.perf_counter() - t0, info)


ZONES = make_solver("zones", solve_zones, Tags(gives_bound=True, needs_positions=True),
                    summary="Zone sweeps: tight MIP / tabu per floor tile, budget moves, Lagrangian bound (needs positions)")


__all__ = ["ZONES", "budget_moves", "checkpoint_path", "load_checkpoint", "problem_key", "save_checkpoint", "solve_zones"]
