"""The swap / tabu heuristic for the robust placement: camplace.solvers.local_search driven
by the worst single-failure cost (lexicographic on the TOP_M worst failure costs, then the
nominal cost), scored exactly and incrementally by :class:`_SwapScorer`."""

from __future__ import annotations

import time

import numpy as np

from camplace.problem.gains import marginal_gains, removal_losses, row, shortfall_cost, target_costs, target_losses
from camplace.problem.model import PlacementProblem
from camplace.solvers.local_search import SwapState, swap_search
from camplace.solvers.robust.failures import _better

TOP_M = 3  # moves compare the TOP_M worst failure costs, then the nominal cost (lexicographic)


class _SwapScorer:
    """Exact (worst-case, nominal) cost of every swap from the current selection, each in
    O(|row a| + |row b| + entries of the selected rows on them) via a CSC of the rows."""

    def __init__(self, problem: PlacementProblem, sel: list[int], cov: np.ndarray) -> None:
        self.p, self.sel, self.cov = problem, sel, cov
        V = problem.V
        self.base = shortfall_cost(problem.gamma, problem.weights, cov)
        self.h = target_losses(problem.gamma, problem.weights, cov)
        self.Sc = (V[np.array(sel, np.int64)] if sel else V[:0]).tocsc()
        self.L = removal_losses(problem, np.array(sel, np.int64), cov)
        self.pos = {i: k for k, i in enumerate(sel)}

    def score(self, a: int | None, b: int) -> tuple[float, float, tuple]:
        """(worst case, nominal cost, key: the TOP_M worst failure costs then the nominal
        cost) after swapping a (None: no removal) for b."""
        p, cov = self.p, self.cov
        ra = row(p.V, a) if a is not None else np.zeros(0, np.int32)
        rb = row(p.V, b)
        T, inv = np.unique(np.r_[ra, rb], return_inverse=True)
        dc = np.bincount(inv, weights=np.r_[-np.ones(len(ra)), np.ones(len(rb))], minlength=len(T))
        g, w = p.gamma[T], p.weights[T]
        c_old = cov[T]
        c_new = c_old + dc.astype(np.int64)
        base = self.base + float(np.sum(target_costs(g, w, c_new) - target_costs(g, w, c_old)))
        h_new = target_losses(g, w, c_new)
        dh = h_new - self.h[T]
        nz = np.flatnonzero(dh != 0)
        L = self.L
        if len(nz) and len(L):
            cols = T[nz]
            st, en = self.Sc.indptr[cols], self.Sc.indptr[cols + 1]
            cnt = en - st
            idx = np.repeat(st - np.cumsum(np.r_[0, cnt[:-1]]), cnt) + np.arange(int(cnt.sum()))
            L = L + np.bincount(self.Sc.indices[idx], weights=np.repeat(dh[nz], cnt), minlength=len(L))
        else:
            L = L.copy()
        if a is not None:
            L[self.pos[a]] = -np.inf
        Lb = float(h_new[inv[len(ra):]].sum())
        allL = np.r_[L[np.isfinite(L)], Lb]
        top = np.sort(allL)[::-1][:TOP_M]
        return base + float(top[0]), base, tuple(base + top) + (base,)


class WorstCaseObjective:
    """swap_search objective: the key of a selection is _SwapScorer's (worst case, nominal,
    lexicographic tuple); each pass scores the moves onto a shortlist of at most 3 × pool
    candidates: the best adds at the coverage without the worst camera, the best adds at
    the current coverage, and the worst camera's other poses (turns at its location)."""

    adds_first = False

    def __init__(self, problem: PlacementProblem, pool: int = 24) -> None:
        self.p, self.pool = problem, pool
        self.sc: _SwapScorer | None = None
        self.ranked: list[int] = []

    def start(self, state: SwapState) -> tuple:
        self.sc = _SwapScorer(self.p, state.sel, state.cov)
        sc = self.sc
        top0 = np.sort(sc.L)[::-1][:TOP_M] if len(sc.L) else np.zeros(1)
        return sc.base + float(top0[0]), sc.base, tuple(sc.base + top0) + (sc.base,)

    def begin_pass(self, state: SwapState) -> None:
        p, sel, cov, pool = self.p, state.sel, state.cov, self.pool
        locs = p.location_ids
        worst = sel[int(np.argmax(self.sc.L))] if sel else None
        c_w = cov.copy()
        if worst is not None:
            c_w[row(p.V, worst)] -= 1
        g_w, g_n = marginal_gains(p, c_w), marginal_gains(p, cov)
        free = ~state.loc_used[state.loc]
        ranked: list[int] = []
        for g in (g_w, g_n):
            cand = np.flatnonzero(free & (g > 0))
            ranked.extend(cand[np.argsort(-g[cand], kind="stable")[:pool]].tolist())
        if worst is not None:  # same-location alternatives (a turned camera) of the worst camera
            same = np.flatnonzero(locs == locs[worst])
            same = same[same != worst]
            ranked.extend(same[np.argsort(-g_w[same], kind="stable")[:pool]].tolist())
        self.ranked = list(dict.fromkeys(ranked))

    def moves(self, state: SwapState, a: int | None, allowed: np.ndarray):
        for b in self.ranked:
            if allowed[b]:
                yield b, self.sc.score(a, b)

    def better(self, k1: tuple, k2: tuple) -> bool:
        return _better(k1[2], k2[2])

    def moved(self, state: SwapState, a: int | None, b: int, key: tuple) -> tuple:
        self.sc = _SwapScorer(self.p, state.sel, state.cov)
        return key

    def done(self) -> bool:
        return False


def robust_search(problem: PlacementProblem, initial: np.ndarray, *, time_limit_s: float | None = 60.0,
                  pool: int = 24, should_stop=None, max_stall: int = 0, tenure: int = 5) -> tuple[np.ndarray, dict]:
    """Swap local search on (worst single-failure cost, 2nd and 3rd worst, nominal cost) in
    lexicographic order, from ``initial``: moves that keep the worst case but lower the next
    ones cross the plateaus of the max. With max_stall > 0 it goes on as a tabu search:
    when no move improves, it takes the least bad move (the camera removed may not come
    back for ``tenure`` passes), until max_stall passes in a row have not improved the best
    selection, and returns the best selection seen.
    Returns the selection and info (moves, passes, seconds, stopped)."""
    end = float("inf") if time_limit_s is None else time.perf_counter() + time_limit_s
    sel, info = swap_search(problem, np.asarray(initial, np.int64), WorstCaseObjective(problem, pool), end=end,
                            should_stop=should_stop, max_stall=max_stall, tenure=tenure)
    return np.array(sorted(sel), np.int64), {k: info[k] for k in ("moves", "passes", "stopped", "seconds")}


__all__ = ["WorstCaseObjective", "robust_search"]
