"""Solve on the reduced problem and map the answer back (camplace.problem.model.reduce_problem).

``reduce_streaming`` gives the same Reduction as ``reduce_problem`` (same rows, columns,
weights and maps, bit for bit) without its copies of V: it reads V's rows once per pass
in compiled code (V may be memory-mapped, camplace.visibility.cache) and holds only the
reduced V and O(N_g + N_p) arrays (the reduced V's data is one broadcast byte, ``pattern_csr``,
and it is built in row chunks with V's mapped pages released after each, ``check_and_build``:
a memory-mapped V never sits in memory beside it; issue 37). Identical columns are found by two 64-bit hashes of
each column's row list, then checked exactly (every entry's row also holds the group's
first column, and the counts are equal); a failed check falls back to reduce_problem.
"""

from __future__ import annotations

import time
from dataclasses import replace
from itertools import pairwise
from typing import Callable

import numba
import numpy as np
import scipy.sparse as sp

from camplace.problem.model import PlacementProblem, Reduction, reduce_problem
from camplace.solvers.base import Placement
from camplace.core.executors import on_threads
from camplace.core.memory import release_pages

_M1 = np.uint64(0x9E3779B97F4A7C15)
_M2 = np.uint64(0xC2B2AE3D27D4EB4F)


@numba.njit(cache=True)
def _live_counts(indptr, indices, live):
    """(N_g,) int64 entries of each row in live columns."""
    n = len(indptr) - 1
    out = np.zeros(n, np.int64)
    for i in range(n):
        c = 0
        for q in range(indptr[i], indptr[i + 1]):
            if live[indices[q]]:
                c += 1
        out[i] = c
    return out


@numba.njit(cache=True)
def _is_subset(indptr, indices, live, a, stamp, token):
    """Every live column of row a carries ``token`` in stamp."""
    for q in range(indptr[a], indptr[a + 1]):
        j = indices[q]
        if live[j] and stamp[j] != token:
            return False
    return True


@numba.njit(cache=True, nogil=True)
def _dominated(indptr, indices, live, n_cols, rows, gptr, n, costs, types, use_types, g0, g1, out):
    """out[a] = True when row rows[a] is dominated inside its location group (rows[gptr[g]:
    gptr[g+1]], ascending ids) by the rule of camplace.problem.model.dominated_candidates,
    for the groups g0 <= g < g1 (serial, without the GIL: groups are split over threads)."""
    stamp = np.full(n_cols, -1, np.int64)
    for g in range(g0, g1):
        s, e = gptr[g], gptr[g + 1]
        if e - s < 2:
            continue
        for pb in range(s, e):
            b = rows[pb]
            marked = False
            for pa in range(s, e):
                if pa == pb or out[pa]:
                    continue
                a = rows[pa]
                if costs[pb] > costs[pa]:
                    continue
                if not (n[pb] > n[pa] or (n[pb] == n[pa] and (costs[pb] < costs[pa] or
                                                              (costs[pb] == costs[pa] and b < a)))):
                    continue
                if use_types and not (types[pb] == types[pa] or types[pb] < 0):
                    continue
                if not marked:
                    for q in range(indptr[b], indptr[b + 1]):
                        stamp[indices[q]] = pb
                    marked = True
                if _is_subset(indptr, indices, live, a, stamp, pb):
                    out[pa] = True


@numba.njit(cache=True)
def _column_hashes(indptr, indices, live, rows, n_cols):
    """Per column: (entries in the kept rows, two 64-bit hashes of its row list (positions in rows))."""
    cnt = np.zeros(n_cols, np.int64)
    h1 = np.zeros(n_cols, np.uint64)
    h2 = np.zeros(n_cols, np.uint64)
    for r in range(len(rows)):
        i = rows[r]
        x = np.uint64(r + 1)
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            if live[j]:
                cnt[j] += 1
                h1[j] = h1[j] * _M1 + x
                h2[j] = (h2[j] ^ x) * _M2 + np.uint64(cnt[j])
    return cnt, h1, h2


@numba.njit(cache=True)
def _has(indices, a, b, j):
    """Column j in the sorted row slice indices[a:b]."""
    lo, hi = a, b
    while lo < hi:
        m = (lo + hi) // 2
        if indices[m] < j:
            lo = m + 1
        else:
            hi = m
    return lo < b and indices[lo] == j


@numba.njit(cache=True)
def _check_count(indptr, indices, live, rows, rep, r0, r1, out_ptr):
    """Exact check of the column groups for the kept rows r0 <= r < r1 (every row holding a
    live column also holds its group's first column ``rep[j]``) and their entry counts in
    the reduced CSR: out_ptr[r + 1] = out_ptr[r] + (first columns in row r). False on a
    failed check."""
    for r in range(r0, r1):
        i = rows[r]
        c = 0
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            if live[j]:
                if rep[j] == j:
                    c += 1
                elif not _has(indices, indptr[i], indptr[i + 1], rep[j]):
                    return False
        out_ptr[r + 1] = out_ptr[r] + c
    return True


@numba.njit(cache=True)
def _build(indptr, indices, live, rows, rep, new_id, r0, r1, out_ptr, out):
    """The reduced CSR's rows r0 <= r < r1: each kept row's first columns renumbered by
    ``new_id`` (ascending, as the groups are numbered in first-column order)."""
    for r in range(r0, r1):
        i = rows[r]
        p = out_ptr[r]
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            if live[j] and rep[j] == j:
                out[p] = new_id[j]
                p += 1


BUILD_CHUNK_NNZ = 1 << 25  # entries of V read between two release_pages (128 MiB of int32 ids)


def row_chunks(indptr: np.ndarray, rows: np.ndarray, chunk_nnz: int) -> np.ndarray:
    """Bounds (k + 1,) int64 of consecutive slices of ``rows`` holding about ``chunk_nnz``
    entries of V each (a slice holds at least one row)."""
    cum = np.cumsum(indptr[rows + 1] - indptr[rows])
    cuts = np.searchsorted(cum, np.arange(chunk_nnz, cum[-1] if len(cum) else 0, chunk_nnz), side="right")
    return np.unique(np.r_[0, cuts, len(rows)]).astype(np.int64)


def check_and_build(V: sp.csr_matrix, indptr: np.ndarray, live: np.ndarray, rows: np.ndarray, rep: np.ndarray,
                    new_id: np.ndarray) -> tuple[bool, np.ndarray, np.ndarray]:
    """The exact check of the column groups and the reduced CSR (ok, indptr (k + 1,) int64,
    indices (nnz,) int32) of the kept ``rows``, in row chunks: a memory-mapped V's pages are
    released after each chunk (camplace.core.memory.release_pages), so at most one chunk of V
    is resident beside the reduced V (issue 37)."""
    indices = V.indices
    bounds = row_chunks(indptr, rows, BUILD_CHUNK_NNZ)
    out_ptr = np.zeros(len(rows) + 1, np.int64)
    for r0, r1 in pairwise(bounds):
        ok = _check_count(indptr, indices, live, rows, rep, r0, r1, out_ptr)
        release_pages(indices)
        if not ok:
            return False, out_ptr, np.zeros(0, np.int32)
    out = np.empty(out_ptr[-1], np.int32)
    for r0, r1 in pairwise(bounds):
        _build(indptr, indices, live, rows, rep, new_id, r0, r1, out_ptr, out)
        release_pages(indices)
    return True, out_ptr, out


def pattern_csr(indptr: np.ndarray, indices: np.ndarray, shape: tuple[int, int]) -> sp.csr_matrix:
    """A 0/1 CSR whose data is one read-only byte broadcast over every entry (no array of
    ones: V's entries are all 1, so only the pattern takes memory; issue 37)."""
    data = np.broadcast_to(np.ones(1, np.uint8), (len(indices),))
    return sp.csr_matrix((data, indices, indptr), shape=shape, copy=False)


def reduce_streaming(problem: PlacementProblem, dominance: bool = True) -> Reduction:
    """reduce_problem(problem, dominance) (the same Reduction, bit for bit) in passes over
    V's rows: no copy of V, working set = the reduced V + O(N_g + N_p)."""
    t0 = time.perf_counter()
    V = problem.V
    if not sp.isspmatrix_csr(V) or not V.has_canonical_format:
        return reduce_problem(problem, dominance)
    n_g, n_p = V.shape
    indptr, indices = np.asarray(V.indptr, np.int64), V.indices
    info: dict = {"candidates_before": n_g, "targets_before": n_p, "nonzeros_before": int(V.nnz)}
    live = (problem.gamma > 0) & (problem.weights > 0)
    live_t = np.nonzero(live)[0]
    info["dropped_zero_targets"] = int(n_p - len(live_t))
    row_nnz = _live_counts(indptr, indices, live)
    keep_c = row_nnz > 0
    info["dropped_blind_candidates"] = int((~keep_c).sum())
    costs = problem.costs
    if dominance:
        cand = np.nonzero(keep_c)[0]
        loc = np.asarray(problem.location_ids)[cand]
        order = np.argsort(loc, kind="stable")
        rows = cand[order]
        gptr = np.r_[0, np.flatnonzero(np.diff(loc[order])) + 1, len(rows)].astype(np.int64)
        use_types = problem.has_type_limits
        types = (problem.limited_types()[rows] if use_types else np.zeros(len(rows), np.int64)).astype(np.int64)
        dom = np.zeros(len(rows), np.bool_)
        args = (indptr, indices, live, n_p, rows, gptr, row_nnz[rows], np.asarray(costs[rows], np.float64), types,
                use_types)
        on_threads(len(gptr) - 1, lambda g0, g1: _dominated(*args, g0, g1, dom), min_rows=8)
        keep_c[rows[dom]] = False
        info["dropped_dominated_candidates"] = int(dom.sum())
    cand = np.nonzero(keep_c)[0]
    cnt, h1, h2 = _column_hashes(indptr, indices, live, cand, n_p)
    gamma_live = problem.gamma[live_t]
    keys = (h2[live_t], h1[live_t], cnt[live_t], gamma_live)
    srt = np.lexsort(keys)  # equal keys adjacent, ascending j inside (lexsort is stable)
    ks = [k[srt] for k in keys]
    start = np.ones(len(srt), bool)
    if len(srt):
        start[1:] = np.any([k[1:] != k[:-1] for k in ks], axis=0)
    run = np.cumsum(start) - 1  # hash group of each sorted position
    first_of_run = srt[start]  # lowest live index of each hash group
    rep_live = first_of_run[run]  # for each sorted position: its group's first live index
    group_first = np.empty(len(live_t), np.int64)
    group_first[srt] = rep_live
    reps = np.unique(group_first)  # first live indices, ascending = group numbering order
    group_of = np.searchsorted(reps, group_first)
    n_new = len(reps)
    rep = np.full(n_p, -1, np.int64)
    rep[live_t] = live_t[group_first]
    new_id = np.full(n_p, -1, np.int64)
    new_id[live_t[reps]] = np.arange(n_new)
    release_pages(V.indices, V.data)  # a memory-mapped V (the cache): its pages leave this process's RSS
    ok, r_ptr, r_idx = check_and_build(V, indptr, live, cand, rep, new_id)
    if not ok:  # a hash collision merged two different columns: the exact (in-memory) path
        return reduce_problem(problem, dominance)
    first = reps
    weights = np.bincount(group_of, weights=problem.weights[live_t], minlength=n_new)
    Vr = pattern_csr(r_ptr, r_idx, (len(cand), n_new))
    target_map = np.full(n_p, -1, np.int64)
    target_map[live_t] = group_of
    info["merged_targets"] = int(len(live_t) - n_new)
    pick = lambda a: None if a is None else np.asarray(a)[cand]  # noqa: E731
    reduced = replace(problem, V=Vr, gamma=gamma_live[first].astype(np.int64), weights=weights.astype(np.float64),
                      location_ids=np.asarray(problem.location_ids)[cand],
                      camera_costs=None if problem.camera_costs is None else costs[cand],
                      type_ids=pick(problem.type_ids), candidate_positions=None, target_positions=None)
    info.update(candidates_after=int(len(cand)), targets_after=int(n_new), nonzeros_after=int(Vr.nnz),
                seconds=time.perf_counter() - t0)
    return Reduction(reduced, cand.astype(np.int64), target_map, info)


def reduce_with_positions(problem: PlacementProblem) -> Reduction:
    """reduce_streaming(problem) that keeps the geometry: each kept candidate its position,
    each reduced target the position of its first original target (targets merge only when
    exactly the same candidates see them, so they lie close together). For solvers that
    need positions only to place candidates and estimate ranges (zones), not for
    per-target geometry (greedy-triangulated)."""
    red = reduce_streaming(problem)
    if problem.candidate_positions is None or problem.target_positions is None:
        return red
    n_new = red.problem.n_targets
    first = np.full(n_new, len(red.target_map), np.int64)
    kept = np.flatnonzero(red.target_map >= 0)
    np.minimum.at(first, red.target_map[kept], kept)
    reduced = replace(red.problem, candidate_positions=np.asarray(problem.candidate_positions)[red.candidates],
                      target_positions=np.asarray(problem.target_positions)[first])
    return replace(red, problem=reduced)


def solve_reduced(problem: PlacementProblem, run: Callable[[PlacementProblem], Placement],
                  reduce: Callable[[PlacementProblem], Reduction] = reduce_streaming) -> Placement:
    """``run`` on reduce(problem) (default reduce_streaming: the same as reduce_problem,
    same optimum, fewer rows/columns): the selection is lifted to original candidate ids,
    the objective recomputed on ``problem``, the sizes before/after are in info['reduction']
    and info['order'] (if any) is mapped back."""
    red = reduce(problem)
    p = run(red.problem)
    sel = red.lift(p.selected)
    info = dict(p.info)
    info["reduction"] = red.info
    if isinstance(info.get("order"), list):
        info["order"] = [int(red.candidates[i]) for i in info["order"]]
    del red  # the reduced V goes before problem.cost reads V's rows (a mapped V's read-ahead: issue 37)
    return replace(p, selected=sel, objective=problem.cost(sel), info=info)


__all__ = ["reduce_streaming", "reduce_with_positions", "solve_reduced"]
