"""Tiles of the zone solver (camplace.solvers.zones): tiling, colouring, one tile's solve,
and the runner that solves the tiles of one colour in parallel.

A tile is a square of the xy plane; a location belongs to the tile of its lowest-id
candidate's position, so all poses of a location are in one tile. A tile's targets are
the columns its rows see in V (exactly the targets whose coverage the tile can change).
Two tiles conflict when they share a target; a greedy colouring of the conflict graph in
tile order (a checkerboard when tiles are larger than twice the camera range) gives
colours whose tiles are independent: solving them from the same state and merging the
results in tile order is the same as solving them one after another.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from camplace.core.executors import DaskExecutor, check_workers, run_task, sigint_ignored
from camplace.problem.model import PlacementProblem
from camplace.solvers.base import Placement
from camplace.solvers.highs_util import convex_model_nnz


@dataclass(frozen=True)
class Tiling:
    """tile_of: (N_g,) int64 tile of each candidate; rows / cols: per tile the sorted
    candidate ids and the sorted target ids they see; colour: (T,) int64 colour of each
    tile (same colour: no shared target); neighbours: per tile the other tiles it shares a
    target with (sorted); size_m / shift_m: tile side and origin shift (m)."""

    tile_of: np.ndarray
    rows: list[np.ndarray]
    cols: list[np.ndarray]
    colour: np.ndarray
    neighbours: list[np.ndarray]
    size_m: float
    shift_m: float

    @property
    def n_tiles(self) -> int:
        return len(self.rows)

    def in_tile(self, selected: np.ndarray, tile: int) -> np.ndarray:
        """The selected candidate ids (sorted) that lie in ``tile``."""
        sel = np.asarray(selected, np.int64)
        return sel[self.tile_of[sel] == tile]


def location_xy(problem: PlacementProblem) -> np.ndarray:
    """(N_g, 2) float64: xy (m) of the lowest-id candidate at each candidate's location."""
    pos = np.asarray(problem.candidate_positions, np.float64)[:, :2]
    _, first, inv = np.unique(np.asarray(problem.location_ids), return_index=True, return_inverse=True)
    return pos[first[np.asarray(inv).ravel()]]


def estimate_range(problem: PlacementProblem, sample: int = 2000) -> float:
    """Largest xy distance (m) from a candidate to a target it sees, over ``sample`` evenly
    spaced rows of V (deterministic); 0 when they see nothing."""
    V = problem.V
    n_g = V.shape[0]
    if n_g == 0 or V.nnz == 0:
        return 0.0
    rows = np.unique(np.linspace(0, n_g - 1, min(n_g, sample)).astype(np.int64))
    cp = np.asarray(problem.candidate_positions, np.float64)[:, :2]
    tp = np.asarray(problem.target_positions, np.float64)[:, :2]
    sub = V[rows]
    owner = np.repeat(rows, np.diff(sub.indptr))
    if len(owner) == 0:
        return 0.0
    return float(np.max(np.linalg.norm(tp[sub.indices] - cp[owner], axis=1)))


def make_tiling(problem: PlacementProblem, size_m: float, shift_m: float = 0.0,
                xy: np.ndarray | None = None) -> Tiling:
    """Square tiles of side ``size_m`` (m) with the origin at the candidates' lower-left
    corner minus ``shift_m`` in x and y; ``xy``: location_xy(problem) when already known."""
    xy = location_xy(problem) if xy is None else xy
    V = problem.V
    n_g = V.shape[0]
    if n_g == 0:
        return Tiling(np.zeros(0, np.int64), [], [], np.zeros(0, np.int64), [], float(size_m), float(shift_m))
    origin = xy.min(axis=0) - float(shift_m)
    key = np.floor((xy - origin) / float(size_m)).astype(np.int64)
    _, tile_of = np.unique(key, axis=0, return_inverse=True)  # lexicographic (ix, iy): deterministic ids
    tile_of = np.asarray(tile_of, np.int64).ravel()
    order = np.argsort(tile_of, kind="stable")
    cuts = np.flatnonzero(np.diff(tile_of[order])) + 1
    rows = [np.sort(g) for g in np.split(order, cuts)]
    cols = [np.unique(V[r].indices) for r in rows]
    n_t = len(rows)
    lens = np.array([len(c) for c in cols], np.int64)
    M = sp.csr_matrix((np.ones(int(lens.sum()), np.int32), np.concatenate(cols).astype(np.int64) if n_t else [],
                       np.r_[0, np.cumsum(lens)]), shape=(n_t, V.shape[1]))
    C = (M @ M.T).tocsr()
    neighbours = [np.setdiff1d(C.indices[C.indptr[t]:C.indptr[t + 1]], [t]) for t in range(n_t)]
    colour = np.full(n_t, -1, np.int64)
    for t in range(n_t):  # greedy colouring in tile order
        used = set(colour[neighbours[t]].tolist())
        c = 0
        while c in used:
            c += 1
        colour[t] = c
    return Tiling(tile_of, rows, [c.astype(np.int64) for c in cols], colour, neighbours, float(size_m),
                  float(shift_m))


@dataclass(frozen=True)
class TileTask:
    """One tile's subproblem (camplace.problem.offset.offset_subproblem) and its current
    selection (local row ids), the method ('mip' or 'tabu'), time limit (s) and seed."""

    tile: int
    sub: PlacementProblem
    current: np.ndarray
    method: str
    time_limit_s: float
    seed: int


def tile_method(sub: PlacementProblem, max_tile_nnz: int) -> str:
    """'mip' when the tile's tight model has at most ``max_tile_nnz`` non-zeros, else 'tabu'."""
    return "mip" if convex_model_nnz(sub) <= max_tile_nnz else "tabu"


def solve_tile(shared: object, task: TileTask, should_stop=None) -> tuple[int, np.ndarray, float, str]:
    """(tile, local selection, its cost on the subproblem, status): the tight MIP
    (camplace.solvers.mip on the reduced tile) or tabu from the current selection; the
    current selection when neither is strictly cheaper. ``shared`` is unused (executor API)."""
    from camplace.solvers.mip import solve_mip
    from camplace.solvers.reduction import solve_reduced
    from camplace.solvers.tabu import solve_tabu

    sub, cur = task.sub, np.sort(np.asarray(task.current, np.int64))
    cur_cost = sub.cost(cur)
    if sub.budget == 0 or sub.n_candidates == 0 or cur_cost <= 0:
        return task.tile, cur, cur_cost, "unchanged"
    if task.method == "mip":
        p: Placement = solve_reduced(sub, lambda q: solve_mip(q, time_limit_s=task.time_limit_s, threads=1,
                                                              seed=task.seed, should_stop=should_stop))
    else:
        p = solve_tabu(sub, time_limit_s=task.time_limit_s, seed=task.seed, should_stop=should_stop,
                       initial=cur if len(cur) else None, max_stall_restarts=20)
    sel = np.sort(np.asarray(p.selected, np.int64))
    try:
        sub.check_feasible(sel)
    except ValueError:
        return task.tile, cur, cur_cost, "rejected"
    cost = sub.cost(sel)
    if cost < cur_cost - 1e-9 * max(1.0, cur_cost):
        return task.tile, sel, cost, p.status
    return task.tile, cur, cur_cost, p.status


def _pool_solve(task: TileTask):
    return run_task(solve_tile, None, task, 1)


class TileRunner:
    """Solves a list of TileTasks, results in task order: in-process (workers = 1), on a
    persistent local process pool (workers > 1, spawned once per solve), or on a Dask
    cluster (scheduler address, camplace.core.executors.DaskExecutor). A context manager."""

    def __init__(self, workers: int = 1, scheduler: str | None = None) -> None:
        check_workers(int(workers))
        self.workers = int(workers)
        self._dask = DaskExecutor(scheduler) if scheduler else None
        self._pool = None
        self.name = "dask" if self._dask else ("process-pool" if self.workers > 1 else "in-process")

    def map(self, tasks: list[TileTask], should_stop=None,
            end: float = float("inf")) -> list[tuple[int, np.ndarray, float, str]]:
        """(tile, local selection, cost, status) of each task, in task order; in-process,
        each task's limit is cut to the time left before ``end`` (perf_counter()) and a
        task started after it keeps its tile unchanged."""
        if not tasks:
            return []
        if self._dask is not None:
            out: dict[int, tuple] = dict(self._dask.map_unordered(solve_tile, None, tasks))
            return [out[k] for k in range(len(tasks))]
        if self.workers <= 1 or len(tasks) == 1:
            res = []
            for t in tasks:
                left = end - time.perf_counter()
                if left <= 0.05:
                    res.append((t.tile, np.sort(np.asarray(t.current, np.int64)), t.sub.cost(t.current), "skipped"))
                else:
                    res.append(solve_tile(None, replace(t, time_limit_s=min(t.time_limit_s, left)), should_stop))
            return res
        if self._pool is None:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(self.workers, mp_context=mp.get_context("spawn"))
        with sigint_ignored():  # workers spawned on the first submit keep SIGINT blocked (the parent stops them)
            results = self._pool.map(_pool_solve, tasks)
        return list(results)

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None
        if self._dask is not None:
            self._dask.close()
            self._dask = None

    def __enter__(self) -> "TileRunner":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


__all__ = ["TileRunner", "TileTask", "Tiling", "estimate_range", "location_xy", "make_tiling", "solve_tile",
           "tile_method"]
