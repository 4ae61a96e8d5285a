"""Tabu search over swap moves with incremental coverage and gain updates (numba).

State: a selection S (|S| ≤ N, one camera per location), the coverage c_j of every
target and the add-gain of every candidate g_i = Σ_{j∈V_i, c_j<Γ_j} w_j (2(Γ_j−c_j)−1)
(the cost drop of adding i). A move swaps r ∈ S for a ∉ S (a's location free or
r's own: a pose change) or adds a while |S| < N; no move puts more cameras of a
type than its limit (problem.type_limits: tleft counts what is left). The exact cost change of a swap is
    Δ(r, a) = loss(r) − g_a − corr_r(a),
loss(r) = Σ_{j∈V_r, c_j≤Γ_j} w_j (2(Γ_j−c_j)+1), corr_r(a) = Σ_{j∈V_r∩V_a} (gain of j
after removing r − before), computed per r through the columns of V. Every
iteration takes the best non-tabu move (aspiration: tabu moves that beat the best
are allowed); after a stall the search restarts from a perturbed best or a
randomized greedy. Everything random comes from one xorshift state seeded by
`seed`, so a run with a fixed iteration budget is reproducible.
"""

from __future__ import annotations

import time

import numba
import numpy as np
import scipy.sparse as sp

from camplace.problem.gains import row_loss_nb as _loss, target_gain_nb as _unit_gain, target_gains
from camplace.problem.model import PlacementProblem, type_arrays
from camplace.solvers.base import Placement
from camplace.solvers.contract import make_solver

# state vector slots (int64)
_IT, _BEST_IT, _RESTARTS, _RNG, _NSEL, _MOVES = 0, 1, 2, 3, 4, 5


@numba.njit(cache=True, inline="always")
def _rand(st):
    """xorshift64*; returns a non-negative int63."""
    x = st[_RNG]
    x ^= (x >> 12) & 0x000FFFFFFFFFFFFF
    x ^= x << 25
    x ^= (x >> 27) & 0x0000001FFFFFFFFF
    st[_RNG] = x
    return (x * 2685821657736338717) & 0x7FFFFFFFFFFFFFFF


@numba.njit(cache=True)
def _apply(i, sign, indptr, indices, cptr, cidx, gamma, weights, cov, gain):
    """Add (sign=+1) or remove (sign=−1) candidate i: update coverage and every
    candidate's add-gain; returns the cost change."""
    delta = 0.0
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        g = gamma[j]
        c = cov[j]
        w = weights[j]
        before = _unit_gain(w, g, c)
        if sign > 0:
            delta -= before
            cov[j] = c + 1
        else:
            cov[j] = c - 1
            delta += _unit_gain(w, g, c - 1)
        after = _unit_gain(w, g, cov[j])
        dg = after - before
        if dg != 0.0:
            for q in range(cptr[j], cptr[j + 1]):
                gain[cidx[q]] += dg
    return delta


@numba.njit(cache=True)
def _reset(indptr, indices, cptr, cidx, gamma, weights, sel, loc, loc_used, cov, gain, base_gain, ctype, tlim, tleft):
    """Recompute coverage, gains, location use and cameras left per type from the selection
    mask; returns the cost."""
    tleft[:] = tlim
    cov[:] = 0
    gain[:] = base_gain
    loc_used[:] = -1
    cost = 0.0
    for j in range(gamma.shape[0]):
        cost += weights[j] * gamma[j] * gamma[j]
    for i in range(sel.shape[0]):
        if sel[i]:
            cost += _apply(i, 1, indptr, indices, cptr, cidx, gamma, weights, cov, gain)
            loc_used[loc[i]] = i
            if ctype[i] >= 0:
                tleft[ctype[i]] -= 1
    return cost


@numba.njit(cache=True)
def _greedy_fill(st, k_rcl, budget, indptr, indices, cptr, cidx, gamma, weights, sel, loc, loc_used, cov, gain,
                 cost, ctype, tleft):
    """Add cameras while |S| < N and some candidate lowers the cost: each step picks
    one of the k_rcl best feasible candidates at random (k_rcl = 1: plain greedy,
    ties to the lowest id)."""
    n_g = sel.shape[0]
    top_i = np.empty(k_rcl, np.int64)
    top_v = np.empty(k_rcl)
    while st[_NSEL] < budget:
        m = 0
        for i in range(n_g):
            if sel[i] or loc_used[loc[i]] >= 0 or gain[i] <= 1e-12 or (ctype[i] >= 0 and tleft[ctype[i]] <= 0):
                continue
            v = gain[i]
            if m < k_rcl:
                pos = m
                m += 1
            elif v > top_v[m - 1]:
                pos = m - 1
            else:
                continue
            while pos > 0 and top_v[pos - 1] < v:
                top_v[pos] = top_v[pos - 1]
                top_i[pos] = top_i[pos - 1]
                pos -= 1
            top_v[pos] = v
            top_i[pos] = i
        if m == 0:
            break
        pick = top_i[0] if m == 1 else top_i[_rand(st) % m]
        cost += _apply(pick, 1, indptr, indices, cptr, cidx, gamma, weights, cov, gain)
        sel[pick] = True
        loc_used[loc[pick]] = pick
        if ctype[pick] >= 0:
            tleft[ctype[pick]] -= 1
        st[_NSEL] += 1
    return cost


@numba.njit(cache=True, nogil=True)
def _tabu_iterations(n_iter, st, fst, budget, indptr, indices, cptr, cidx, gamma, weights, loc, base_gain,
                     sel, loc_used, cov, gain, corr, tabu_add, tabu_rem, best_sel,
                     tenure_add, tenure_rem, stall_limit, perturb, k_rcl, ctype, tlim, tleft):
    """Run n_iter tabu iterations in place. fst = [current cost, best cost]."""
    n_g = sel.shape[0]
    sel_list = np.empty(budget, np.int64)
    touched = np.empty(n_g, np.int64)
    is_touched = np.zeros(n_g, np.bool_)
    for _ in range(n_iter):
        it = st[_IT]
        st[_IT] = it + 1
        cur = fst[0]
        best = fst[1]
        # 1) fill free slots (pure additions never raise the cost)
        if st[_NSEL] < budget:
            bi = -1
            bv = 1e-12
            for i in range(n_g):
                if not sel[i] and loc_used[loc[i]] < 0 and gain[i] > bv and (ctype[i] < 0 or tleft[ctype[i]] > 0):
                    bv = gain[i]
                    bi = i
            if bi >= 0:
                cur += _apply(bi, 1, indptr, indices, cptr, cidx, gamma, weights, cov, gain)
                sel[bi] = True
                loc_used[loc[bi]] = bi
                if ctype[bi] >= 0:
                    tleft[ctype[bi]] -= 1
                st[_NSEL] += 1
                fst[0] = cur
                if cur < best - 1e-9:
                    fst[1] = cur
                    best_sel[:] = sel
                    st[_BEST_IT] = it
                continue
        # 2) best swap
        m = 0
        for i in range(n_g):
            if sel[i]:
                sel_list[m] = i
                m += 1
        best_delta = np.inf
        best_r = -1
        best_a = -1
        ties = 0
        for t in range(m):
            r = sel_list[t]
            loss = _loss(r, indptr, indices, gamma, weights, cov)
            nt = 0
            for p in range(indptr[r], indptr[r + 1]):
                j = indices[p]
                c = cov[j]
                g = gamma[j]
                if c > g:
                    continue
                dg = _unit_gain(weights[j], g, c - 1) - _unit_gain(weights[j], g, c)
                if dg == 0.0:
                    continue
                for q in range(cptr[j], cptr[j + 1]):
                    a = cidx[q]
                    if not is_touched[a]:
                        is_touched[a] = True
                        touched[nt] = a
                        nt += 1
                    corr[a] += dg
            r_tabu = tabu_rem[r] > it
            lr = loc[r]
            for a in range(n_g):
                if sel[a]:
                    continue
                la = loc[a]
                if la != lr and loc_used[la] >= 0:
                    continue
                ta = ctype[a]
                if ta >= 0 and ta != ctype[r] and tleft[ta] <= 0:
                    continue
                d = loss - gain[a] - corr[a]
                if d < best_delta + 1e-9:
                    if (r_tabu or tabu_add[a] > it) and not (cur + d < best - 1e-9):
                        continue
                    if d < best_delta - 1e-9:
                        best_delta = d
                        best_r = r
                        best_a = a
                        ties = 1
                    else:
                        # reservoir sampling among ties
                        ties += 1
                        if _rand(st) % ties == 0:
                            best_r = r
                            best_a = a
            for k in range(nt):
                a = touched[k]
                corr[a] = 0.0
                is_touched[a] = False
        if best_r >= 0:
            cur += _apply(best_r, -1, indptr, indices, cptr, cidx, gamma, weights, cov, gain)
            sel[best_r] = False
            loc_used[loc[best_r]] = -1
            cur += _apply(best_a, 1, indptr, indices, cptr, cidx, gamma, weights, cov, gain)
            sel[best_a] = True
            loc_used[loc[best_a]] = best_a
            if ctype[best_r] >= 0:
                tleft[ctype[best_r]] += 1
            if ctype[best_a] >= 0:
                tleft[ctype[best_a]] -= 1
            tabu_add[best_r] = it + tenure_add + _rand(st) % (tenure_add + 1)
            tabu_rem[best_a] = it + tenure_rem + _rand(st) % (tenure_rem + 1)
            st[_MOVES] += 1
            fst[0] = cur
            if cur < best - 1e-9:
                fst[1] = cur
                best_sel[:] = sel
                st[_BEST_IT] = it
        # 3) restart after a stall
        if it - st[_BEST_IT] >= stall_limit:
            st[_RESTARTS] += 1
            st[_BEST_IT] = it
            tabu_add[:] = 0
            tabu_rem[:] = 0
            if st[_RESTARTS] % 4 == 0:
                sel[:] = False
                st[_NSEL] = 0
                cur = _reset(indptr, indices, cptr, cidx, gamma, weights, sel, loc, loc_used, cov, gain, base_gain, ctype,
                             tlim, tleft)
                cur = _greedy_fill(st, k_rcl, budget, indptr, indices, cptr, cidx, gamma, weights, sel, loc,
                                   loc_used, cov, gain, cur, ctype, tleft)
            else:
                sel[:] = best_sel
                cur = _reset(indptr, indices, cptr, cidx, gamma, weights, sel, loc, loc_used, cov, gain, base_gain, ctype,
                             tlim, tleft)
                nsel = 0
                for i in range(n_g):
                    if sel[i]:
                        sel_list[nsel] = i
                        nsel += 1
                st[_NSEL] = nsel
                # drop `perturb` random cameras, then refill by randomized greedy
                k = min(perturb, nsel)
                for t in range(k):
                    u = t + _rand(st) % (nsel - t)
                    tmp = sel_list[t]
                    sel_list[t] = sel_list[u]
                    sel_list[u] = tmp
                    r = sel_list[t]
                    cur += _apply(r, -1, indptr, indices, cptr, cidx, gamma, weights, cov, gain)
                    sel[r] = False
                    loc_used[loc[r]] = -1
                    if ctype[r] >= 0:
                        tleft[ctype[r]] += 1
                    tabu_add[r] = it + tenure_add
                    st[_NSEL] -= 1
                cur = _greedy_fill(st, k_rcl, budget, indptr, indices, cptr, cidx, gamma, weights, sel, loc,
                                   loc_used, cov, gain, cur, ctype, tleft)
            fst[0] = cur
            if cur < fst[1] - 1e-9:
                fst[1] = cur
                best_sel[:] = sel


class TabuSearch:
    """Holds the compiled search state; `run(n)` advances it by n iterations."""

    def __init__(self, problem: PlacementProblem, seed: int = 0, tenure_add: int | None = None,
                 tenure_rem: int | None = None, stall_limit: int | None = None, perturb: int | None = None,
                 k_rcl: int = 3, initial: np.ndarray | None = None) -> None:
        self.problem = problem
        V = problem.V
        n_g, n_p = V.shape
        self.budget = int(problem.budget)
        self.indptr = V.indptr.astype(np.int64)
        self.indices = V.indices.astype(np.int64)
        VT = sp.csr_matrix(V.T)
        self.cptr = VT.indptr.astype(np.int64)
        self.cidx = VT.indices.astype(np.int64)
        self.gamma = problem.gamma.astype(np.int64)
        self.weights = problem.weights.astype(np.float64)
        _, self.loc = np.unique(problem.location_ids, return_inverse=True)
        self.loc = self.loc.astype(np.int64)
        n_loc = int(self.loc.max()) + 1 if n_g else 0
        unit0 = target_gains(self.gamma, self.weights, np.zeros(n_p, np.int64))
        self.base_gain = np.asarray(V @ unit0, np.float64).ravel() if n_g else np.zeros(0)
        N = max(self.budget, 1)
        self.tenure_add = int(tenure_add if tenure_add is not None else 7)
        self.tenure_rem = int(tenure_rem if tenure_rem is not None else max(2, N // 4))
        self.stall_limit = int(stall_limit if stall_limit is not None else 50 + 2 * N)
        self.perturb = int(perturb if perturb is not None else max(2, N // 8))
        self.k_rcl = int(k_rcl)
        self.st = np.zeros(8, np.int64)
        self.st[_RNG] = (int(seed) * 0x9E3779B97F4A7C15 + 0x2545F4914F6CDD1D) & 0x7FFFFFFFFFFFFFFF or 1
        self.sel = np.zeros(n_g, np.bool_)
        self.loc_used = -np.ones(n_loc, np.int64)
        self.cov = np.zeros(n_p, np.int64)
        self.gain = np.zeros(n_g)
        self.corr = np.zeros(n_g)
        self.tabu_add = np.zeros(n_g, np.int64)
        self.tabu_rem = np.zeros(n_g, np.int64)
        self.fst = np.zeros(2)
        self.ctype, self.tlim = type_arrays(problem)
        self.tleft = self.tlim.copy()
        cost = _reset(self.indptr, self.indices, self.cptr, self.cidx, self.gamma, self.weights, self.sel, self.loc,
                      self.loc_used, self.cov, self.gain, self.base_gain, self.ctype, self.tlim, self.tleft)
        if initial is not None and len(initial):
            self.sel[np.asarray(initial, np.int64)] = True
            cost = _reset(self.indptr, self.indices, self.cptr, self.cidx, self.gamma, self.weights, self.sel,
                          self.loc, self.loc_used, self.cov, self.gain, self.base_gain, self.ctype, self.tlim,
                          self.tleft)
            self.st[_NSEL] = int(self.sel.sum())
        # plain greedy fill (k_rcl = 1) completes the start
        cost = _greedy_fill(self.st, 1, self.budget, self.indptr, self.indices, self.cptr, self.cidx, self.gamma,
                            self.weights, self.sel, self.loc, self.loc_used, self.cov, self.gain, cost, self.ctype,
                            self.tleft)
        self.fst[:] = cost
        self.best_sel = self.sel.copy()

    @property
    def best_cost(self) -> float:
        return float(self.fst[1])

    @property
    def best_selected(self) -> np.ndarray:
        return np.flatnonzero(self.best_sel).astype(np.int64)

    @property
    def iterations(self) -> int:
        return int(self.st[_IT])

    @property
    def restarts(self) -> int:
        return int(self.st[_RESTARTS])

    def run(self, n_iter: int) -> None:
        if self.budget == 0 or self.problem.n_candidates == 0:
            return
        _tabu_iterations(int(n_iter), self.st, self.fst, self.budget, self.indptr, self.indices, self.cptr,
                         self.cidx, self.gamma, self.weights, self.loc, self.base_gain, self.sel, self.loc_used,
                         self.cov, self.gain, self.corr, self.tabu_add, self.tabu_rem, self.best_sel,
                         self.tenure_add, self.tenure_rem, self.stall_limit, self.perturb, self.k_rcl, self.ctype,
                         self.tlim, self.tleft)


def solve_tabu(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
               seed: int = 0, should_stop=None, progress=None, on_incumbent=None, max_iterations: int | None = None,
               initial: np.ndarray | None = None, chunk: int = 20, max_stall_restarts: int | None = 200,
               tenure_add: int | None = None, tenure_rem: int | None = None, stall_limit: int | None = None,
               perturb: int | None = None, k_rcl: int = 3) -> Placement:
    """Tabu search from greedy. Stops at `time_limit_s` (default 10 s when no
    `max_iterations` is given), after `max_iterations`, or when should_stop() is true.
    With `max_iterations` and no time limit the result depends only on the seed. It also
    stops after `max_stall_restarts` restarts in a row without a better placement (the
    search has converged; None: never).
    Options: tenure_add, tenure_rem, stall_limit, perturb, k_rcl (see TabuSearch)."""
    t0 = time.perf_counter()
    if time_limit_s is None and max_iterations is None:
        time_limit_s = 10.0
    end = t0 + time_limit_s if time_limit_s is not None else float("inf")
    ts = TabuSearch(problem, seed=seed, initial=initial, tenure_add=tenure_add, tenure_rem=tenure_rem,
                    stall_limit=stall_limit, perturb=perturb, k_rcl=k_rcl)
    best = ts.best_cost
    if on_incumbent is not None:
        on_incumbent(float(problem.cost(ts.best_selected)), None)
    status = "heuristic"
    total = max_iterations if max_iterations is not None else 0
    since = ts.restarts
    while problem.budget > 0 and problem.n_candidates > 0:
        if max_stall_restarts is not None and ts.restarts - since >= max_stall_restarts:
            break
        if max_iterations is not None and ts.iterations >= max_iterations:
            break
        if time.perf_counter() >= end:
            status = "time_limit"
            break
        if should_stop is not None and should_stop():
            status = "interrupted"
            break
        n = chunk if max_iterations is None else min(chunk, max_iterations - ts.iterations)
        ts.run(n)
        if ts.best_cost < best - 1e-9:
            best = ts.best_cost
            since = ts.restarts
            if on_incumbent is not None:
                on_incumbent(float(problem.cost(ts.best_selected)), None)
        if progress is not None:
            if max_iterations is not None:
                progress("tabu", ts.iterations, total)
            else:
                progress("tabu", int(min(time.perf_counter() - t0, time_limit_s)), int(time_limit_s))
    sel = ts.best_selected
    if problem.has_type_limits and not problem.type_ok(sel):  # only an `initial` over the limits can do this
        from camplace.solvers.catalogue import repair_to_type_limits

        sel = repair_to_type_limits(problem, sel)
    if problem.money_budget is not None:  # tabu moves ignore prices (issue 10): repair to the money budget
        from camplace.solvers.catalogue import repair_to_money_budget

        sel = repair_to_money_budget(problem, sel)
    cost = problem.cost(sel)
    return Placement(sel, cost, None, status, "tabu", time.perf_counter() - t0,
                     {"iterations": ts.iterations, "restarts": ts.restarts, "seed": int(seed),
                      "incumbent_method": "tabu"})


TABU = make_solver("tabu", solve_tabu, summary="Tabu search from greedy")
