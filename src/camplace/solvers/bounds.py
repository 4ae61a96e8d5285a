"""Lower bounds on the optimal placement cost: Lagrangian, LP, and a location
branch-and-bound on top of the Lagrangian (proofs in docs/certify.md).

Notation: V (N_g × N_p) 0/1, Γ_j, w_j, budget N, location groups L(i).
The convex model: min Σ_j w_j Σ_{k=1..Γ_j} (2k−1) u_jk  s.t.  Σ_i V_ij x_i + Σ_k u_jk ≥ Γ_j,
Σ_i x_i ≤ N, Σ_{i∈loc} x_i ≤ 1, x ∈ {0,1}, u ∈ [0,1].
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numba
import numpy as np
import scipy.sparse as sp

from camplace.problem.gains import target_gains
from camplace.problem.model import PlacementProblem

StopFn = Callable[[], bool]


@dataclass
class BoundResult:
    """bound: proven lower bound on the optimal cost; method: how it was proven;
    multipliers: (N_p,) the Lagrange multipliers λ behind it (None for the LP);
    seconds: wall time; info: method details."""

    bound: float
    method: str
    seconds: float
    multipliers: np.ndarray | None = None
    info: dict = field(default_factory=dict)


# ---------------------------------------------------------------- Lagrangian --

@numba.njit(cache=True, nogil=True)
def _u_part(lam, gamma, weights):
    """Σ_j min over u_j ∈ [0, Γ_j] of (w_j·f_j(u_j) − λ_j u_j) + λ_j Γ_j, f_j(u) = u² on
    integers and piecewise linear between (the convex model's u-cost).

    With slope (2k−1)w_j of the k-th unit, the minimum takes every unit whose slope is
    below λ_j: k* = clip(ceil((λ_j/w_j + 1)/2) − 1, 0, Γ_j) units."""
    total = 0.0
    grad_u = np.zeros(gamma.shape[0])
    for j in range(gamma.shape[0]):
        g = gamma[j]
        lj = lam[j]
        w = weights[j]
        if g == 0:
            continue
        if w <= 0.0:
            k = g
        else:
            # units with (2k-1) w < lam  <=> k < (lam/w + 1)/2
            k = int(np.ceil((lj / w + 1.0) / 2.0)) - 1
            if k < 0:
                k = 0
            if k > g:
                k = g
        total += w * k * k - lj * k + lj * g
        grad_u[j] = g - k
    return total, grad_u


@numba.njit(cache=True, nogil=True)
def _x_part(indptr, indices, lam, loc_first, loc_members, budget, fixed_in, fixed_out, n_fixed_in):
    """max Σ_i r_i x_i, r_i = Σ_j V_ij λ_j, over at most `budget` candidates, at most one
    per location, candidates with fixed_out excluded and fixed_in forced in (their
    locations then hold nothing else). Returns (value, chosen mask, reduced gains r)."""
    n_g = indptr.shape[0] - 1
    r = np.zeros(n_g)
    for i in range(n_g):
        s = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            s += lam[indices[p]]
        r[i] = s
    n_loc = loc_first.shape[0] - 1
    best_val = np.zeros(n_loc)
    best_id = -np.ones(n_loc, np.int64)
    forced = np.zeros(n_loc, np.bool_)
    for L in range(n_loc):
        for q in range(loc_first[L], loc_first[L + 1]):
            i = loc_members[q]
            if fixed_in[i]:
                forced[L] = True
                best_val[L] = r[i]
                best_id[L] = i
                break
            if fixed_out[i]:
                continue
            if r[i] > best_val[L] or best_id[L] < 0 and r[i] > 0:
                if r[i] > 0:
                    best_val[L] = r[i]
                    best_id[L] = i
    chosen = np.zeros(n_g, np.bool_)
    value = 0.0
    for L in range(n_loc):
        if forced[L]:
            value += best_val[L]
            chosen[best_id[L]] = True
    free = budget - n_fixed_in
    cand = np.empty(n_loc)
    m = 0
    for L in range(n_loc):
        if not forced[L] and best_id[L] >= 0:
            cand[m] = best_val[L]
            m += 1
    order = np.argsort(-cand[:m])
    # map back: rebuild the list of (value, loc) in the same order
    locs = np.empty(m, np.int64)
    m2 = 0
    for L in range(n_loc):
        if not forced[L] and best_id[L] >= 0:
            locs[m2] = L
            m2 += 1
    for t in range(min(free, m)):
        L = locs[order[t]]
        value += best_val[L]
        chosen[best_id[L]] = True
    return value, chosen, r


def location_groups(location_ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(loc_first (L+1,), loc_members (N_g,)): members of dense location L are
    loc_members[loc_first[L]:loc_first[L+1]]."""
    _, dense = np.unique(location_ids, return_inverse=True)
    order = np.argsort(dense, kind="stable").astype(np.int64)
    counts = np.bincount(dense)
    first = np.zeros(len(counts) + 1, np.int64)
    np.cumsum(counts, out=first[1:])
    return first, order


class Lagrangian:
    """The Lagrangian dual of the convex model with the coverage rows dualized:
    L(λ) = Σ_j [min_u (w_j f_j(u) − λ_j u) + λ_j Γ_j] − max_x Σ_i (V λ)_i x_i, λ ≥ 0.
    Every L(λ) is a lower bound on the optimal cost (weak duality); `fixed_in` /
    `fixed_out` restrict x for branch-and-bound."""

    def __init__(self, problem: PlacementProblem) -> None:
        self.problem = problem
        V = problem.V
        self.indptr = V.indptr.astype(np.int64)
        # as stored (int32 for any V under 2^31 pairs): an int64 copy would double V's memory at site scale
        self.indices = V.indices if V.indices.dtype in (np.int32, np.int64) else V.indices.astype(np.int64)
        self.gamma = problem.gamma.astype(np.int64)
        self.weights = problem.weights.astype(np.float64)
        self.loc_first, self.loc_members = location_groups(problem.location_ids)
        n_g = V.shape[0]
        self._none_in = np.zeros(n_g, np.bool_)
        self._none_out = np.zeros(n_g, np.bool_)

    def evaluate(self, lam: np.ndarray, fixed_in: np.ndarray | None = None, fixed_out: np.ndarray | None = None,
                 budget: int | None = None) -> tuple[float, np.ndarray, np.ndarray]:
        """(L(λ), subgradient g (N_p,), chosen x mask (N_g,)) at λ ≥ 0."""
        fi = self._none_in if fixed_in is None else fixed_in
        fo = self._none_out if fixed_out is None else fixed_out
        b = self.problem.budget if budget is None else budget
        u_val, grad_u = _u_part(lam, self.gamma, self.weights)
        x_val, chosen, _ = _x_part(self.indptr, self.indices, lam, self.loc_first, self.loc_members, b,
                                   fi, fo, int(fi.sum()))
        cov = self.problem.coverage(np.flatnonzero(chosen))
        # d/dλ_j: Γ_j − u_j − (V^T x)_j
        g = grad_u - cov
        return float(u_val - x_val), g, chosen

    def initial_multipliers(self, coverage: np.ndarray | None = None) -> np.ndarray:
        """λ from an incumbent's coverage: the slope of the last missing unit,
        λ_j = w_j(2 d_j − 1) where the deficit d_j > 0, else 0 (a target the incumbent
        covers needs no price). Without an incumbent d = Γ."""
        return target_gains(self.gamma, self.weights, np.zeros_like(self.gamma) if coverage is None else coverage)


def fixing_bounds(lagr: Lagrangian, lam: np.ndarray, budget: int | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """Lagrangian bounds with one decision forced, at multipliers λ (all valid lower
    bounds on the cost of any selection obeying the forcing; docs/certify.md §2):
    (bound_in (N_g,): some selection containing candidate i, bound_out (L,): the
    dense location L left empty, L(λ) itself)."""
    N = lagr.problem.budget if budget is None else budget
    u_val, _ = _u_part(lam, lagr.gamma, lagr.weights)
    n_g = lagr.indptr.shape[0] - 1
    none = np.zeros(n_g, np.bool_)
    x_val, _, r = _x_part(lagr.indptr, lagr.indices, lam, lagr.loc_first, lagr.loc_members, N, none, none, 0)
    first, members = lagr.loc_first, lagr.loc_members
    n_loc = len(first) - 1
    loc_of = np.empty(n_g, np.int64)
    loc_of[members] = np.repeat(np.arange(n_loc), np.diff(first))
    v = np.zeros(n_loc)
    np.maximum.at(v, loc_of, r)
    order = np.argsort(-v, kind="stable")
    pos = order[v[order] > 0]
    m = len(pos)
    K = min(N, m)
    prefix = np.concatenate([[0.0], np.cumsum(v[pos])])
    T_K = prefix[K]
    rank = np.full(n_loc, n_loc + 1, np.int64)
    rank[pos] = np.arange(m)
    in_top = rank < K
    if N == 0:
        bound_in = np.full(n_g, np.inf)
    else:
        alt = T_K + r if K < N else prefix[N - 1] + r
        max_in = np.where(in_top[loc_of], T_K - v[loc_of] + r, alt)
        bound_in = u_val - max_in
    nxt = v[pos[K]] if (K == N and m > K) else 0.0
    max_out = np.where(in_top, T_K - v + nxt, T_K)
    bound_out = u_val - max_out
    return bound_in, bound_out, float(u_val - x_val)


def lagrangian_bound(problem: PlacementProblem, *, time_limit_s: float = 10.0, incumbent_cost: float | None = None,
                     coverage: np.ndarray | None = None, lam0: np.ndarray | None = None, max_iter: int = 100000,
                     should_stop: StopFn | None = None, on_bound: Callable[[float], None] | None = None,
                     fixed_in: np.ndarray | None = None, fixed_out: np.ndarray | None = None,
                     budget: int | None = None, lagr: Lagrangian | None = None) -> BoundResult:
    """Subgradient ascent on the Lagrangian dual (Polyak steps toward the incumbent
    cost, step halved after stalls), warm-started from the incumbent's coverage.
    Deterministic. Returns the best L(λ) seen (a valid lower bound)."""
    t0 = time.perf_counter()
    lg = Lagrangian(problem) if lagr is None else lagr
    lam = lg.initial_multipliers(coverage) if lam0 is None else np.array(lam0, np.float64)
    best, g, chosen = lg.evaluate(lam, fixed_in, fixed_out, budget)
    best_lam = lam.copy()
    # Polyak target: the incumbent's cost, else the cheapest x-subproblem solution seen
    # (each is a feasible selection, so an upper bound on the optimum)
    own_target = incumbent_cost is None
    target = problem.cost(np.flatnonzero(chosen)) if own_target else incumbent_cost
    alpha = 1.0
    stall = 0
    it = 0
    val = best
    while it < max_iter and time.perf_counter() - t0 < time_limit_s:
        if should_stop is not None and should_stop():
            break
        it += 1
        gn = float(np.dot(g, g))
        if gn <= 1e-12:
            break  # λ is optimal for the dual
        if best >= target - 1e-9:
            break
        step = alpha * (target - val) / gn
        lam = np.maximum(lam + step * g, 0.0)
        val, g, chosen = lg.evaluate(lam, fixed_in, fixed_out, budget)
        if own_target and it % 10 == 0:
            target = min(target, problem.cost(np.flatnonzero(chosen)))
        if val > best + 1e-9 * max(1.0, abs(best)):
            best = val
            best_lam = lam.copy()
            stall = 0
            if on_bound is not None:
                on_bound(best)
        else:
            stall += 1
            if stall >= 20:
                alpha *= 0.5
                stall = 0
                lam = best_lam.copy()
                val, g, _ = lg.evaluate(lam, fixed_in, fixed_out, budget)
                if alpha < 1e-4:
                    break
    return BoundResult(max(best, 0.0), "lagrangian", time.perf_counter() - t0, best_lam,
                       {"iterations": it, "raw": best})


# -------------------------------------------------------------- tight model --

def tight_model_arrays(problem: PlacementProblem, forced_locations: np.ndarray | None = None):
    """Column-major arrays of the convex model: returns (A csc, cost, col_lo, col_hi,
    row_lo, row_hi, n_x). Columns: x (N_g), then u_jk for each target j and k=1..Γ_j.
    Rows: coverage (N_p, ≥ Γ_j), budget (≤ N), one per location (≤ 1; = 1 for the
    location ids in `forced_locations`), one per limited camera type (≤ its limit)."""
    V = problem.V
    n_g, n_p = V.shape
    gamma = problem.gamma.astype(np.int64)
    n_u = int(gamma.sum())
    u_target = np.repeat(np.arange(n_p), gamma)
    starts = np.zeros(n_p, np.int64)
    np.cumsum(gamma[:-1], out=starts[1:]) if n_p > 1 else None
    u_k = np.arange(n_u) - np.repeat(starts, gamma) + 1
    _, dense_loc = np.unique(problem.location_ids, return_inverse=True)
    n_loc = int(dense_loc.max()) + 1 if n_g else 0
    VT = sp.csc_matrix(V.T.astype(np.float64))  # (n_p, n_g)
    budget_row = sp.csr_matrix(np.ones((1, n_g)))
    loc_rows = sp.csr_matrix((np.ones(n_g), (dense_loc, np.arange(n_g))), shape=(n_loc, n_g))
    U = sp.csr_matrix((np.ones(n_u), (u_target, np.arange(n_u))), shape=(n_p, n_u))
    T, t_hi = problem.type_rows()
    A = sp.bmat([[VT, U], [budget_row, None], [loc_rows, None]] + ([[T, None]] if len(t_hi) else []), format="csc")
    cost = np.concatenate([np.zeros(n_g), problem.weights[u_target] * (2 * u_k - 1)])
    col_lo = np.zeros(n_g + n_u)
    col_hi = np.ones(n_g + n_u)
    inf = np.inf
    loc_lo = np.full(n_loc, -inf)
    if forced_locations is not None and len(forced_locations):
        uniq = np.unique(problem.location_ids)
        loc_lo[np.searchsorted(uniq, np.asarray(forced_locations))] = 1.0
    row_lo = np.concatenate([gamma.astype(np.float64), [-inf], loc_lo, np.full(len(t_hi), -inf)])
    row_hi = np.concatenate([np.full(n_p, inf), [float(problem.budget)], np.ones(n_loc), t_hi])
    return A, cost, col_lo, col_hi, row_lo, row_hi, n_g


def convex_start(problem: PlacementProblem, x: np.ndarray) -> np.ndarray:
    """Column vector (x, u) of the convex model (tight_model_arrays' layout) for a 0/1
    selection x (N_g,): u_jk = 1 for the k <= deficit of target j."""
    x = np.asarray(x, np.float64)
    cov = np.rint(np.asarray(problem.V.T @ x).ravel())
    d = np.maximum(problem.gamma - cov, 0)
    g = problem.gamma.astype(np.int64)
    starts = np.cumsum(g) - g
    ks = np.arange(int(g.sum())) - np.repeat(starts, g) + 1
    return np.concatenate([x, (ks <= np.repeat(d, g)).astype(np.float64)])


def build_highs(problem: PlacementProblem, *, integer: bool, threads: int | None = 1, time_limit_s: float | None = None,
                log_file: str | None = None, solver: str | None = None, seed: int = 0,
                forced_locations: np.ndarray | None = None, x_cost: np.ndarray | None = None):
    """A highspy.Highs holding the convex model (x integer if `integer`; ``x_cost``: (N_g,)
    costs of the x columns instead of 0)."""
    import highspy

    from camplace.solvers.highs_util import MilpArrays, highs_from_arrays

    A, cost, clo, chi, rlo, rhi, n_x = tight_model_arrays(problem, forced_locations)
    if x_cost is not None:
        cost = np.array(cost, np.float64)
        cost[:n_x] = x_cost
    inf = highspy.kHighsInf
    integrality = np.zeros(A.shape[1], np.int32)
    integrality[:n_x] = 1 if integer else 0
    h = highs_from_arrays(MilpArrays(cost, A, np.where(np.isinf(rlo), -inf, rlo), np.where(np.isinf(rhi), inf, rhi),
                                     clo, chi, integrality, n_x), integer=integer)
    h.setOptionValue("output_flag", bool(log_file))
    if log_file:
        h.setOptionValue("log_file", str(log_file))
        h.setOptionValue("log_to_console", False)
    if threads:
        h.setOptionValue("threads", int(threads))
    h.setOptionValue("random_seed", int(seed))
    if time_limit_s is not None:
        h.setOptionValue("time_limit", float(time_limit_s))
    if solver:
        h.setOptionValue("solver", solver)
    return h, n_x


def lp_bound(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = 1,
             method: str = "ipm", end: float = float("inf"), should_stop: StopFn | None = None) -> BoundResult:
    """The LP relaxation of the convex model by HiGHS (interior point + crossover by
    default). The bound is the dual objective when HiGHS reports optimality, so it is
    valid; on a time limit or a stop, or no time to start before the deadline ``end``, the bound is 0."""
    import highspy

    from camplace.solvers.highs_util import convex_model_nnz, limit_to_deadline, model_fits, run_model

    t0 = time.perf_counter()
    end = min(end, t0 + time_limit_s) if time_limit_s is not None else end
    h = None
    if model_fits(end, convex_model_nnz(problem)):
        h, n_x = build_highs(problem, integer=False, threads=threads, time_limit_s=None, solver=method)
    if h is None or not limit_to_deadline(h, end):
        return BoundResult(0.0, "lp", time.perf_counter() - t0, None, {"status": "skipped: no time left"})
    run = run_model(h, should_stop=should_stop, end=end, duals=True)
    if run.model_status == highspy.HighsModelStatus.kOptimal:
        # the dual objective equals this up to HiGHS's tolerances; shave 1e-7 relative
        val = float(run.info.objective_function_value)
        val -= 1e-7 * max(1.0, abs(val))
        return BoundResult(max(val, 0.0), "lp", time.perf_counter() - t0, None,
                           {"status": "optimal", "x": np.array(run.col_value[:n_x]), "row_dual": run.row_dual})
    return BoundResult(0.0, "lp", time.perf_counter() - t0, None, {"status": run.status_text})


# ------------------------------------------------- fixing + exact reduced MIP --

@dataclass
class Reduction:
    """What Lagrangian fixing proved about every selection cheaper than `ub`:
    keep (N_g,) bool: candidates it may contain; forced (k,): location ids it must use."""

    keep: np.ndarray
    forced: np.ndarray
    ub: float
    lagrangian: float


def reduce_by_fixing(problem: PlacementProblem, lam: np.ndarray, ub: float, lagr: Lagrangian | None = None,
                     tol: float = 1e-6) -> Reduction:
    """Drop candidate i when the Lagrangian bound with x_i = 1 exceeds ub, and force a
    location to hold a camera when the bound with it empty exceeds ub (docs/certify.md
    §2): every selection with cost < ub survives the reduction."""
    lg = Lagrangian(problem) if lagr is None else lagr
    b_in, b_out, L = fixing_bounds(lg, lam)
    eps = tol * max(1.0, abs(ub))
    keep = ~(b_in > ub + eps)
    uniq = np.unique(problem.location_ids)
    dense_forced = np.flatnonzero(b_out > ub + eps)
    return Reduction(keep, uniq[dense_forced], float(ub), float(L))


def solve_reduced_mip(problem: PlacementProblem, red: Reduction, incumbent: np.ndarray | None, *,
                      time_limit_s: float, threads: int | None = 1, seed: int = 0,
                      should_stop: StopFn | None = None, mip_rel_gap: float = 0.0,
                      end: float = float("inf")) -> tuple[float, np.ndarray | None, dict]:
    """HiGHS branch-and-cut on the convex model restricted to the reduction.
    Returns (bound, better selection or None, info); HiGHS stops at `mip_rel_gap`
    (0: proven optimal). The bound min(ub, reduced MIP dual bound) is valid for the whole
    problem because every selection cheaper than ub lies in the reduced problem
    (docs/certify.md §3). The restricted model is shrunk once more by
    camplace.problem.model.reduce_problem (same optimum), and HiGHS prunes with ub as cutoff.
    ``end``: perf_counter() deadline of the whole solve (with t0 + time_limit_s, whichever is
    first); the model is not built, or HiGHS not started, when it cannot end before it."""
    import highspy

    from camplace.problem.model import reduce_problem
    from camplace.solvers.highs_util import convex_model_nnz, limit_to_deadline, model_fits, run_model, set_start

    t0 = time.perf_counter()
    end = min(end, t0 + time_limit_s)
    keep_ids = np.flatnonzero(red.keep)
    info: dict = {"candidates_kept": int(len(keep_ids)), "locations_forced": int(len(red.forced))}
    if len(red.forced) > problem.budget:
        # no selection can satisfy the forcing: nothing is cheaper than ub
        info["status"] = "infeasible-forcing"
        return red.ub, None, info
    V = problem.V[keep_ids]
    seen = np.zeros(problem.n_targets, np.bool_)
    seen[V.indices] = True
    cols = np.flatnonzero(seen)
    unseen = ~seen
    const = float(np.dot(problem.weights[unseen], problem.gamma[unseen].astype(np.float64) ** 2))
    sub = PlacementProblem(sp.csr_matrix(V[:, cols]), problem.gamma[cols], problem.weights[cols], problem.budget,
                           problem.location_ids[keep_ids], **problem.type_fields(keep_ids))
    if not np.all(np.isin(red.forced, sub.location_ids)):
        info["status"] = "infeasible-forcing"  # a forced location has no candidate left
        return red.ub, None, info
    rsub = reduce_problem(sub)
    small = rsub.problem
    # a forced location whose kept candidates all see nothing vanishes from `small`: any of
    # them costs the same, so it just holds one camera of the budget (type limits kept: a relaxation)
    blind = np.setdiff1d(red.forced, small.location_ids)
    forced = red.forced[np.isin(red.forced, small.location_ids)]
    small = replace(small, budget=problem.budget - len(blind))
    info.update(targets_kept=int(small.n_targets), candidates_after_reduction=int(small.n_candidates))
    if not model_fits(end, convex_model_nnz(small)):
        info["status"] = "skipped: no time left to build the reduced model"
        return red.lagrangian, None, info
    h, n_x = build_highs(small, integer=True, threads=threads, time_limit_s=None, seed=seed, forced_locations=forced)
    # building counts against the limit
    if end - time.perf_counter() <= 0.05 or not limit_to_deadline(h, end):
        info["status"] = "no time left after building"
        return red.lagrangian, None, info
    h.setOptionValue("mip_rel_gap", float(mip_rel_gap))
    h.setOptionValue("mip_abs_gap", 0.5 * float(np.min(problem.weights[problem.weights > 0], initial=1.0)) * 1e-3)
    # prune everything not cheaper than ub (a tiny slack keeps an incumbent of cost ub)
    h.setOptionValue("objective_bound", float(red.ub - const + 1e-6 * max(1.0, abs(red.ub))))
    if incumbent is not None and np.all(red.keep[incumbent]):
        where = np.full(problem.n_candidates, -1, np.int64)
        where[keep_ids[rsub.candidates]] = np.arange(small.n_candidates)
        pos = where[np.asarray(incumbent, np.int64)]
        if np.all(pos >= 0):  # no incumbent camera was dropped as blind or dominated
            x = np.zeros(n_x)
            x[pos] = 1.0
            set_start(h, convex_start(small, x))
            # with a near-optimal start the proof is the work: spend nothing on heuristics
            h.setOptionValue("mip_heuristic_effort", 0.0)
    run = run_model(h, should_stop=should_stop, end=end)
    hinfo = run.info
    info.update({"status": run.status_text, "nodes": int(hinfo.mip_node_count),
                 "seconds": round(time.perf_counter() - t0, 2)})
    if run.model_status == highspy.HighsModelStatus.kInfeasible:
        return red.ub, None, info  # nothing at or below the cutoff: ub is optimal
    dual = float(hinfo.mip_dual_bound)
    if not np.isfinite(dual):
        return red.lagrangian, None, info
    # HiGHS stops at mip_abs_gap; its dual bound is the proven one
    bound = min(red.ub, const + dual)
    sel = None
    if hinfo.primal_solution_status == 2 and run.col_value is not None:  # feasible solution available
        col = np.asarray(run.col_value[:n_x])
        sel = np.sort(keep_ids[rsub.lift(np.flatnonzero(col > 0.5))])
    return bound, sel, info
