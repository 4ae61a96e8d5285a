"""``greedy-fast``: the paper's greedy with exact incremental gains, compiled (numba).

Same rule as ``greedy`` (add the candidate of largest cost drop, ties to the lowest id,
one camera per location, within the budget, money budget and per-type limits, stop when nothing lowers
the cost), but instead of a lazy heap it keeps every candidate's gain exact: when a
camera is added, each target j it sees loses one unit of deficit, and the gain of every
candidate seeing j drops by w_j·2 (deficit was > 1) or w_j (deficit was 1), walked
through the columns of V. The columns are kept as gaps between consecutive row ids in
LEB128 varints (``csc_varint``: 7 bits a byte, ~1.03 bytes a non-zero at site scale
instead of 4 for int32 row ids, issue 37). Work per step = Σ over the new camera's
targets of their column length, + the argmax over blocks of 1,024 candidates (each
block's best kept, rescanned only when one of its gains or flags changed: ``_argmax``,
issue 37); memory = V + its varint
columns + O(N_g + N_p). Selections equal ``greedy``'s whenever
gains are exact in float64 (integer weights, as in every built-in scene); with
fractional weights, rounding can break an exact tie differently.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numba
import numpy as np

from camplace.problem.model import PlacementProblem, type_arrays
from camplace.solvers.base import OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, stopped
from camplace.solvers.contract import make_solver

STEPS_PER_CALL = 32  # steps between should_stop / time-limit polls


@numba.njit(cache=True)
def csc_indices(indptr: np.ndarray, indices: np.ndarray, n_cols: int) -> tuple[np.ndarray, np.ndarray]:
    """Column structure of a CSR pattern: (col_ptr (n_cols + 1,) int64, row ids (nnz,) int32),
    rows ascending inside each column."""
    n_rows = len(indptr) - 1
    col_ptr = np.zeros(n_cols + 1, np.int64)
    for q in range(len(indices)):
        col_ptr[indices[q] + 1] += 1
    for j in range(n_cols):
        col_ptr[j + 1] += col_ptr[j]
    fill = col_ptr[:-1].copy()
    rows = np.empty(len(indices), np.int32)
    for i in range(n_rows):
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            rows[fill[j]] = i
            fill[j] += 1
    return col_ptr, rows


@numba.njit(cache=True)
def _varint_len(x):
    """Bytes of x ≥ 0 as a LEB128 varint (7 bits a byte)."""
    n = 1
    while x >= 128:
        x >>= 7
        n += 1
    return n


@numba.njit(cache=True)
def csc_varint(indptr: np.ndarray, indices: np.ndarray, n_cols: int) -> tuple[np.ndarray, np.ndarray]:
    """Column structure of a CSR pattern as varint gaps: (col_ptr (n_cols + 1,) int64 byte
    offsets, stream (bytes,) uint8). Column j's rows, ascending, are the running sums of the
    LEB128 varints in stream[col_ptr[j]:col_ptr[j + 1]], starting from −1 (so every gap ≥ 1);
    ``csc_rows`` decodes one column. Same information as csc_indices, ~1.2 bytes a
    non-zero instead of 4 when a column's rows lie close together."""
    n_rows = len(indptr) - 1
    col_ptr = np.zeros(n_cols + 1, np.int64)
    last = np.full(n_cols, -1, np.int64)
    for i in range(n_rows):
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            col_ptr[j + 1] += _varint_len(i - last[j])
            last[j] = i
    for j in range(n_cols):
        col_ptr[j + 1] += col_ptr[j]
    fill = col_ptr[:-1].copy()
    last[:] = -1
    stream = np.empty(col_ptr[-1], np.uint8)
    for i in range(n_rows):
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            x = i - last[j]
            last[j] = i
            p = fill[j]
            while x >= 128:
                stream[p] = np.uint8((x & 127) | 128)
                x >>= 7
                p += 1
            stream[p] = np.uint8(x)
            fill[j] = p + 1
    return col_ptr, stream


@numba.njit(cache=True, inline="always")
def _varint_at(stream, r):
    """(value, next offset) of the LEB128 varint at stream[r]."""
    x, shift = np.int64(0), 0
    while stream[r] >= 128:
        x |= (np.int64(stream[r]) & 127) << shift
        shift += 7
        r += 1
    return x | (np.int64(stream[r]) << shift), r + 1


@numba.njit(cache=True)
def csc_rows(col_ptr: np.ndarray, stream: np.ndarray, j: int) -> np.ndarray:
    """(k,) int64 row ids of column j of a csc_varint structure, ascending."""
    out = np.empty(col_ptr[j + 1] - col_ptr[j], np.int64)
    n, row, r, e = 0, -1, col_ptr[j], col_ptr[j + 1]
    while r < e:
        x, r = _varint_at(stream, r)
        row += x
        out[n] = row
        n += 1
    return out[:n]


@numba.njit(cache=True)
def initial_gains(indptr, indices, deficit, weights):
    """(N_g,) float64 gain of each candidate at the given deficits (row sums in id order)."""
    n = len(indptr) - 1
    g = np.zeros(n)
    for i in range(n):
        s = 0.0
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            if deficit[j] > 0:
                s += weights[j] * (2 * deficit[j] - 1)
        g[i] = s
    return g


BLOCK_SHIFT = 10  # candidates per block of the argmax (1,024): issue 37


@numba.njit(cache=True)
def _block_best(gain, alive, b, bmax, barg):
    """bmax[b], barg[b]: the largest positive gain of an alive candidate in block b and its
    lowest id (0.0 and −1 when none)."""
    lo = b << BLOCK_SHIFT
    hi = min(len(gain), lo + (1 << BLOCK_SHIFT))
    best, bg = -1, 0.0
    for i in range(lo, hi):
        if alive[i] and gain[i] > bg:  # strict: ties keep the lowest id; gain must be > 0
            best = i
            bg = gain[i]
    bmax[b] = bg
    barg[b] = best


@numba.njit(cache=True)
def _argmax(gain, alive, bmax, barg, dirty):
    """The alive candidate of largest positive gain, lowest id on ties (−1 when none), from the
    blocks' maxima; blocks marked dirty (a gain or alive flag changed) are rescanned first.
    Same answer as one scan over every candidate, in O(blocks + dirty blocks · block size)."""
    best, bg = -1, 0.0
    for b in range(len(bmax)):
        if dirty[b]:
            _block_best(gain, alive, b, bmax, barg)
            dirty[b] = False
        if bmax[b] > bg:  # strict: an earlier block (lower ids) keeps a tie
            best = barg[b]
            bg = bmax[b]
    return best


@numba.njit(cache=True)
def _steps(indptr, indices, col_ptr, col_bytes, weights, deficit, gain, alive, loc, loc_ptr, loc_rows,
           costs, money, order, n_sel, budget, max_steps, ctype, tleft, bmax, barg, dirty):
    """Up to max_steps greedy steps, in place (ctype: limited type index or −1, tleft:
    cameras left per limited type; bmax, barg, dirty: the argmax's blocks, _argmax).
    Returns (n_sel, money, finished)."""
    for _ in range(max_steps):
        if n_sel >= budget:
            return n_sel, money, True
        best = _argmax(gain, alive, bmax, barg, dirty)
        if best < 0:
            return n_sel, money, True
        order[n_sel] = best
        n_sel += 1
        money -= costs[best]
        L = loc[best]
        for q in range(loc_ptr[L], loc_ptr[L + 1]):  # one camera per location
            alive[loc_rows[q]] = False
            dirty[loc_rows[q] >> BLOCK_SHIFT] = True
        t = ctype[best]
        if t >= 0:
            tleft[t] -= 1
            if tleft[t] <= 0:  # the type is full
                for i in range(len(gain)):
                    if ctype[i] == t:
                        alive[i] = False
                        dirty[i >> BLOCK_SHIFT] = True
        if money < np.inf:
            for i in range(len(gain)):
                if alive[i] and costs[i] > money + 1e-12:
                    alive[i] = False
                    dirty[i >> BLOCK_SHIFT] = True
        for q in range(indptr[best], indptr[best + 1]):
            j = indices[q]
            d = deficit[j]
            if d <= 0:
                continue
            delta = weights[j] * 2.0 if d > 1 else weights[j]
            row, r, e = -1, col_ptr[j], col_ptr[j + 1]
            while r < e:  # the column's rows: running sums of varint gaps (csc_varint)
                x, r = _varint_at(col_bytes, r)
                row += x
                gain[row] -= delta
                dirty[row >> BLOCK_SHIFT] = True
            deficit[j] = d - 1
    return n_sel, money, False


def solve_greedy_fast(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                      seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                      on_incumbent: OnIncumbent | None = None, local_search: bool = False,
                      cost_scaled: bool = True) -> Placement:
    """The ``greedy`` selection with exact incremental gains in compiled code (see the
    module doc). local_search=True then runs greedy's 1-swap descent. Status
    'heuristic', or 'interrupted' / 'time_limit'. With a money budget and
    cost_scaled=True this is ``greedy``'s catalogue variant (delegated to it)."""
    if cost_scaled and problem.money_budget is not None:
        from camplace.solvers.greedy import solve_greedy

        p = solve_greedy(problem, time_limit_s=time_limit_s, should_stop=should_stop, progress=progress,
                         on_incumbent=on_incumbent, local_search=local_search, cost_scaled=True)
        return replace(p, solver="greedy-fast")
    t0 = time.perf_counter()
    end = deadline(time_limit_s)
    V = problem.V
    n_g, n_p = V.shape
    indptr = np.asarray(V.indptr, np.int64)
    indices = np.asarray(V.indices, np.int32)
    col_ptr, col_bytes = csc_varint(indptr, indices, n_p)
    weights = np.asarray(problem.weights, np.float64)
    deficit = np.asarray(problem.gamma, np.int64).copy()
    gain = initial_gains(indptr, indices, deficit, weights)
    _, loc = np.unique(np.asarray(problem.location_ids), return_inverse=True)
    loc = loc.astype(np.int64).ravel()
    loc_rows = np.argsort(loc, kind="stable").astype(np.int64)
    loc_ptr = np.zeros(int(loc.max()) + 2 if n_g else 1, np.int64)
    if n_g:
        np.cumsum(np.bincount(loc), out=loc_ptr[1:])
    costs = np.asarray(problem.costs, np.float64)
    money = np.inf if problem.money_budget is None else float(problem.money_budget)
    alive = costs <= money + 1e-12
    ctype, tleft = type_arrays(problem)
    alive &= (ctype < 0) | (tleft[np.maximum(ctype, 0)] > 0)
    order = np.empty(max(0, min(problem.budget, n_g)), np.int64)
    n_blocks = (n_g >> BLOCK_SHIFT) + 1
    bmax, barg, dirty = np.zeros(n_blocks), np.full(n_blocks, -1, np.int64), np.ones(n_blocks, np.bool_)
    n_sel, cut, finished = 0, False, n_g == 0
    while not finished:
        n_sel, money, finished = _steps(indptr, indices, col_ptr, col_bytes, weights, deficit, gain, alive, loc,
                                        loc_ptr, loc_rows, costs, money, order, n_sel, len(order), STEPS_PER_CALL,
                                        ctype, tleft, bmax, barg, dirty)
        if progress:
            progress("greedy", n_sel, problem.budget)
        if not finished and (stopped(should_stop) or time.perf_counter() > end):
            cut = True
            break
    selected = [int(i) for i in order[:n_sel]]
    del col_ptr, col_bytes
    from camplace.solvers.greedy import finish_greedy

    info: dict = {"order": list(selected), "incremental": True}
    return finish_greedy(problem, selected, info, cut, "greedy-fast", t0, local_search=local_search, end=end,
                         should_stop=should_stop, on_incumbent=on_incumbent)


GREEDY_FAST = make_solver("greedy-fast", solve_greedy_fast, summary="Greedy with numba gains (same selection as greedy)")
