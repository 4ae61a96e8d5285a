"""Robustness to camera failure: which cameras are essential, and placements that stay
good when any one camera fails.

Failure cost of camera i in a selection S: cost(S minus i) (one matrix-vector product
over the selected rows gives all of them: removing i raises the cost by
Σ_{j in row i} w_j (max(Γ_j − c_j + 1, 0)² − max(Γ_j − c_j, 0)²)).
Worst case: W(S) = max_i cost(S minus i).

``robust_placement`` (``--robust 1``) minimises W:

- ``robust_search``: best-improvement swap local search from the nominal placement on
  (W, second and third worst failure costs, nominal cost) in lexicographic order, continued
  as a short tabu search; it returns the best selection seen, so W never rises.
- ``scenario_mip``: the exact scenario MIP (one coverage scenario per failure, no big-M),
  solved by lazy scenario generation on HiGHS; a model with a subset of the scenarios is a
  relaxation, so its dual bound is a lower bound on the optimal W*. Whole problem when V
  is small; on store-sized V, ``robust_lns`` solves it on neighbourhoods of the costliest
  failures (most cameras fixed).
- Lower bounds on W*: ``robust_bound`` (Lagrangian bound with one camera fewer: W(S) >=
  OPT(N_s − 1)) and ``mean_failure_bound`` (W(S) >= cost(S) + mean loss, a convex placement
  problem, by LP). Proofs in docs/beyond-the-grid.md.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

import scipy.sparse as sp

from camplace.problem.model import PlacementProblem, shortfall_cost
from camplace.solvers.base import Placement, stopped
from camplace.solvers.highs_util import INF, MilpArrays, highs_from_arrays, location_rows, run_highs


def removal_losses(problem: PlacementProblem, selected: np.ndarray, cov: np.ndarray | None = None) -> np.ndarray:
    """(k,) cost added when each selected camera (in the given order) fails alone."""
    sel = np.asarray(selected, np.int64)
    if len(sel) == 0:
        return np.zeros(0)
    c = problem.coverage(sel) if cov is None else cov
    h = _h(problem.gamma, problem.weights, c)
    return np.asarray(problem.V[sel].astype(np.float64) @ h).ravel()


def worst_case(problem: PlacementProblem, selected: np.ndarray) -> tuple[float, int | None]:
    """(max over single failures of the cost, candidate id of the worst failure or None)."""
    sel = np.asarray(selected, np.int64)
    cost = problem.cost(sel)
    if len(sel) == 0:
        return cost, None
    loss = removal_losses(problem, sel)
    k = int(np.argmax(loss))
    return cost + float(loss[k]), int(sel[k])


def essential_cameras(problem: PlacementProblem, selected: np.ndarray) -> list[dict]:
    """Selected cameras ranked by the cost added if each one fails (largest first):
    dicts with candidate_id, added_cost, cost_if_fails, coverage_gap_if_fails."""
    sel = np.asarray(selected, np.int64)
    cost = problem.cost(sel)
    loss = removal_losses(problem, sel)
    norm = problem.normalizer
    order = np.lexsort((sel, -loss))
    return [{"rank": r + 1, "candidate_id": int(sel[k]), "added_cost": float(loss[k]),
             "cost_if_fails": cost + float(loss[k]),
             "coverage_gap_if_fails": (cost + float(loss[k])) / norm if norm > 0 else 0.0}
            for r, k in enumerate(order)]


@dataclass(frozen=True)
class RobustResult:
    """placement: the robust selection (objective = its nominal cost); figures for both
    placements: nominal cost / worst-case cost and their coverage gaps; bound: lower
    bound on the optimal worst case (None if not computed)."""

    placement: Placement
    nominal: dict
    robust: dict
    bound: float | None
    info: dict = field(default_factory=dict)


def _figures(problem: PlacementProblem, sel: np.ndarray) -> dict:
    cost = problem.cost(sel)
    w, who = worst_case(problem, sel)
    n = problem.normalizer or 1.0
    return {"cost": cost, "coverage_gap": cost / n, "worst_case_cost": w, "worst_case_gap": w / n,
            "worst_failure_candidate": who, "cameras": int(len(sel))}


def _h(gamma: np.ndarray, w: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Per-target cost of losing one view: w (max(Γ − c + 1, 0)² − max(Γ − c, 0)²)."""
    d0 = np.maximum(gamma - c, 0).astype(np.float64)
    d1 = np.maximum(gamma - c + 1, 0).astype(np.float64)
    return w * (d1 * d1 - d0 * d0)


def _sq(gamma: np.ndarray, w: np.ndarray, c: np.ndarray) -> np.ndarray:
    d = np.maximum(gamma - c, 0).astype(np.float64)
    return w * d * d


TOP_M = 3  # moves compare the TOP_M worst failure costs, then the nominal cost (lexicographic)


def _better(k1: tuple, k2: tuple, tol: float = 1e-9) -> bool:
    """Lexicographic k1 < k2 with a tolerance (shorter keys: fewer cameras, compare what exists)."""
    for x, y in zip(k1, k2):
        if x < y - tol:
            return True
        if x > y + tol:
            return False
    return False


class _SwapScorer:
    """Exact (worst-case, nominal) cost of every swap from the current selection, each in
    O(|row a| + |row b| + entries of the selected rows on them) via a CSC of the rows."""

    def __init__(self, problem: PlacementProblem, sel: list[int], cov: np.ndarray) -> None:
        self.p, self.sel, self.cov = problem, sel, cov
        V = problem.V
        self.base = shortfall_cost(problem.gamma, problem.weights, cov)
        self.h = _h(problem.gamma, problem.weights, cov)
        S = V[np.array(sel, np.int64)] if sel else V[:0]
        self.Sc = S.tocsc()
        self.L = np.asarray(S.astype(np.float64) @ self.h).ravel() if sel else np.zeros(0)
        self.pos = {i: k for k, i in enumerate(sel)}

    def row(self, i: int) -> np.ndarray:
        V = self.p.V
        return V.indices[V.indptr[i]:V.indptr[i + 1]]

    def score(self, a: int | None, b: int) -> tuple[float, float]:
        p, cov = self.p, self.cov
        ra = self.row(a) if a is not None else np.zeros(0, np.int32)
        rb = self.row(b)
        T, inv = np.unique(np.r_[ra, rb], return_inverse=True)
        dc = np.bincount(inv, weights=np.r_[-np.ones(len(ra)), np.ones(len(rb))], minlength=len(T))
        g, w = p.gamma[T], p.weights[T]
        c_old = cov[T]
        c_new = c_old + dc.astype(np.int64)
        base = self.base + float(np.sum(_sq(g, w, c_new) - _sq(g, w, c_old)))
        h_new = _h(g, w, c_new)
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


def robust_search(problem: PlacementProblem, initial: np.ndarray, *, time_limit_s: float | None = 60.0,
                  pool: int = 24, should_stop=None, max_stall: int = 0, tenure: int = 5) -> tuple[np.ndarray, dict]:
    """Swap local search on (worst single-failure cost, 2nd and 3rd worst, nominal cost) in
    lexicographic order, from ``initial``: moves that keep the worst case but lower the next
    ones cross the plateaus of the max. With max_stall > 0 it goes on as a tabu search:
    when no move improves, it takes the least bad move (the camera removed may not come
    back for ``tenure`` passes), until max_stall passes in a row have not improved the best
    selection, and returns the best selection seen.
    Returns the selection and info (moves, passes, seconds, stopped)."""
    t0 = time.perf_counter()
    V = problem.V
    Vf = V.astype(np.float64)
    gamma, w = problem.gamma, problem.weights
    costs = problem.costs
    locs = problem.location_ids
    n_loc = int(locs.max()) + 1 if len(locs) else 0
    sel = [int(i) for i in np.asarray(initial, np.int64)]
    cov = problem.coverage(np.array(sel, np.int64))

    def gains(c: np.ndarray) -> np.ndarray:
        d0 = np.maximum(gamma - c, 0).astype(np.float64)
        d1 = np.maximum(d0 - 1, 0)
        return np.asarray(Vf @ (w * (d0 * d0 - d1 * d1))).ravel()

    sc = _SwapScorer(problem, sel, cov)
    top0 = np.sort(sc.L)[::-1][:TOP_M] if len(sc.L) else np.zeros(1)
    cur = (sc.base + float(top0[0]), sc.base, tuple(sc.base + top0) + (sc.base,))
    moves = passes = stall = 0
    stopped = "converged"
    tabu: dict[int, int] = {}
    best_key, best_sel = cur[2], sorted(sel)
    while True:
        if time_limit_s is not None and time.perf_counter() - t0 > time_limit_s:
            stopped = "time_limit"
            break
        if should_stop is not None and should_stop():
            stopped = "interrupted"
            break
        passes += 1
        used = np.zeros(n_loc, bool)
        used[locs[sel]] = True
        spent = float(costs[sel].sum()) if sel else 0.0
        worst = sel[int(np.argmax(sc.L))] if sel else None
        c_w = cov.copy()
        if worst is not None:
            c_w[sc.row(worst)] -= 1
        g_w, g_n = gains(c_w), gains(cov)
        free = ~used[locs]
        ranked: list[int] = []
        for g in (g_w, g_n):
            cand = np.flatnonzero(free & (g > 0))
            ranked.extend(cand[np.argsort(-g[cand], kind="stable")[:pool]].tolist())
        if worst is not None:  # same-location alternatives (a turned camera) of the worst camera
            same = np.flatnonzero(locs == locs[worst])
            same = same[same != worst]
            ranked.extend(same[np.argsort(-g_w[same], kind="stable")[:pool]].tolist())
        ranked = list(dict.fromkeys(ranked))
        best = (cur, None, None)
        fallback = None  # best non-improving, non-tabu move (tabu phase)
        outs: list[int | None] = list(sel) + ([None] if len(sel) < problem.budget else [])
        for a in outs:
            for b in ranked:
                if a is not None and b == a:
                    continue
                if b in tabu and tabu[b] > passes:
                    continue
                if used[locs[b]] and (a is None or locs[a] != locs[b]):
                    continue
                if problem.money_budget is not None and \
                        spent - (costs[a] if a is not None else 0.0) + costs[b] > problem.money_budget + 1e-9:
                    continue
                s2 = sc.score(a, b)
                if _better(s2[2], best[0][2]):
                    best = (s2, a, b)
                elif fallback is None or _better(s2[2], fallback[0][2]):
                    fallback = (s2, a, b)
            if time_limit_s is not None and time.perf_counter() - t0 > time_limit_s:
                break
        if best[2] is None:
            if fallback is None or stall >= max_stall:
                break
            best = fallback  # tabu step: the least bad move; the moved cameras may not return for `tenure` passes
        cur, a, b = best
        if a is not None:
            tabu[a] = passes + tenure
            sel.remove(a)
            cov[sc.row(a)] -= 1
        sel.append(b)
        cov[sc.row(b)] += 1
        sc = _SwapScorer(problem, sel, cov)
        moves += 1
        if _better(cur[2], best_key):
            best_key, best_sel = cur[2], sorted(sel)
            stall = 0
        else:
            stall += 1  # passes since the best selection last improved
    return np.array(sorted(best_sel), np.int64), {"moves": moves, "passes": passes, "stopped": stopped,
                                                  "seconds": time.perf_counter() - t0}


def robust_bound(problem: PlacementProblem, coverage_hint: np.ndarray | None = None,
                 time_limit_s: float = 10.0, incumbent_cost: float | None = None) -> float | None:
    """Lower bound on min_S max_i cost(S minus i): a Lagrangian lower bound of the nominal
    problem with one camera fewer (None when the bounds module is unavailable)."""
    if problem.budget < 1:
        return None
    try:
        from camplace.solvers.bounds import lagrangian_bound
    except ImportError:  # pragma: no cover - bounds land with issue 11
        return None
    fewer = replace(problem, budget=problem.budget - 1)
    res = lagrangian_bound(fewer, time_limit_s=time_limit_s, coverage=coverage_hint, incumbent_cost=incumbent_cost)
    return max(0.0, float(res.bound))


def mean_failure_bound(problem: PlacementProblem, *, time_limit_s: float | None = 60.0,
                       threads: int | None = None) -> float | None:
    """Lower bound on min_S W(S) from the mean failure: for 1 <= |S| <= N_s,
    W(S) >= mean_s cost(S minus s) >= cost(S) + (1/N_s) Σ_s loss_s(S) = Σ_j w_j g_j(c_j) with
    g(c) = (Γ − c)+² + (c / N_s) ((Γ − c + 1)+² − (Γ − c)+²), a convex function of the coverage
    c (for N_s >= 2; proof in docs/beyond-the-grid.md), so min Σ_j w_j g_j(c_j) is a placement
    problem of the tight convex form with Γ_j + 1 units per target; its LP relaxation
    (HiGHS interior point + crossover) is the bound. None if the LP does not finish in
    time or N_s < 2."""
    from dataclasses import replace as _replace

    from camplace.solvers.mip import tight_model_arrays

    n = problem.budget
    if n < 2:
        return None
    g = np.asarray(problem.gamma, np.int64)
    arrays, lay = tight_model_arrays(_replace(problem, gamma=np.where(g > 0, g + 1, 0)))
    G = g[lay.u_target].astype(np.float64)
    k = lay.u_k
    c = G + 1 - k  # unit k is the step from coverage c + 1 down to c
    d = G - c
    slope = np.where(k == 1, G / n, (2 * d - 1) + (2 * c - 2 * d + 1) / n)
    arrays.c[lay.n_x:] = problem.weights[lay.u_target] * slope
    h = highs_from_arrays(arrays, integer=False)
    out = run_highs(h, time_limit_s=time_limit_s, threads=threads, options={"solver": "ipm"})
    if out.status != "optimal" or out.objective is None:
        return None
    val = float(out.objective)
    val -= 1e-7 * max(1.0, abs(val))  # the dual objective equals it up to HiGHS's tolerances
    return _round_up(problem, max(val, 0.0))


def _round_up(problem: PlacementProblem, bound: float) -> float:
    """Integer weights make every cost an integer: a bound may then be rounded up."""
    w = np.asarray(problem.weights)
    if np.all(w == np.round(w)):
        return float(np.ceil(bound - 1e-6))
    return bound


def robust_placement(problem: PlacementProblem, nominal: Placement, *, time_limit_s: float | None = 60.0,
                     bound_time_s: float = 10.0, pool: int = 24, max_stall: int = 20, method: str = "auto",
                     exact_max_nnz: int = 200_000, bound_mip_s: float = 0.0, mean_bound_s: float = 60.0,
                     seed: int = 0,
                     should_stop=None) -> RobustResult:
    """``--robust 1`` from the nominal placement, with figures for both placements and a
    lower bound on the optimal worst case. method 'auto': the swap/tabu heuristic
    (``robust_search``, 30 % of the time), then the exact scenario MIP on the whole problem
    when V has at most ``exact_max_nnz`` nonzeros (half of the time left; optimal when it
    finishes), then, unless that proved optimality, the scenario-MIP large-neighbourhood
    search (``robust_lns``) with the rest of the time. info['method'] says which ran.
    'heuristic': the swap/tabu search alone. The bound is the best of the Lagrangian bound
    of the problem with one camera fewer (``bound_time_s``), the mean-failure LP bound
    (``mean_failure_bound``, ``mean_bound_s``) and the scenario-MIP dual bound (from the
    exact solve, or from ``bound_mip_s`` seconds of it on the whole problem). The bounds come
    first, each with its own time limit; ``time_limit_s`` is for the search."""
    if method not in ("auto", "heuristic"):
        raise ValueError(f"robust_placement: method must be 'auto' or 'heuristic', got {method!r}")
    t0 = time.perf_counter()
    bounds: dict[str, float] = {}
    lag = None
    if bound_time_s > 0:  # hint: the nominal placement minus its worst camera is a feasible (N_s − 1) selection
        start = np.asarray(nominal.selected, np.int64)
        w_now, who = worst_case(problem, start)
        lag = robust_bound(problem, problem.coverage(start[start != who]), bound_time_s, w_now)
        if lag is not None:
            bounds["lagrangian_fewer_camera"] = _round_up(problem, lag)
    if mean_bound_s > 0 and not stopped(should_stop):
        mb = mean_failure_bound(problem, time_limit_s=mean_bound_s)
        if mb is not None:
            bounds["mean_failure_lp"] = mb
    lag = max(bounds.values()) if bounds else None  # t >= lag in every scenario MIP below
    t_search = time.perf_counter()  # the time limit is for the search; the bounds have their own
    end = None if time_limit_s is None else t_search + time_limit_s
    left = lambda: None if end is None else max(0.0, end - time.perf_counter())  # noqa: E731
    share = None if time_limit_s is None else (time_limit_s if method == "heuristic" else 0.3 * time_limit_s)
    sel, info = robust_search(problem, nominal.selected, time_limit_s=share, pool=pool,
                              should_stop=should_stop, max_stall=max_stall)
    problem.check_feasible(sel)
    info = {"heuristic": dict(info, cost=problem.cost(sel), worst_case_cost=worst_case(problem, sel)[0])}
    used = "heuristic"
    exact_done = False
    if method == "auto" and len(sel) and not stopped(should_stop):
        if problem.V.nnz <= exact_max_nnz:  # exact first, with half of the time left
            half = None if end is None else 0.5 * left()
            res = scenario_mip(problem, sel, time_limit_s=half, t_lower=lag or 0.0, init_scenarios=None,
                               mip_rel_gap=0.0, seed=seed, should_stop=should_stop)
            info["scenario_mip"] = dict(res.info, status=res.status)
            if res.bound is not None and res.bound > (lag or 0.0):
                bounds["scenario_mip"] = res.bound
            if _better((res.worst_case, res.cost), _key(problem, sel)):
                sel = res.selected
            exact_done = res.status == "optimal"
            used = "scenario-mip (optimal)" if exact_done else "heuristic+scenario-mip"
        if not exact_done and not stopped(should_stop) and (left() is None or left() > 1.0):
            sel, lns = robust_lns(problem, sel, time_limit_s=left(), t_lower=lag or 0.0, seed=seed,
                                  should_stop=should_stop)
            info["lns"] = lns
            used += "+lns" if used != "heuristic" else "+scenario-mip-lns"
    if method == "auto" and bound_mip_s > 0 and not exact_done and not stopped(should_stop):
        res = scenario_mip(problem, sel, time_limit_s=bound_mip_s, t_lower=lag or 0.0, seed=seed,
                           should_stop=should_stop)
        info["bound_mip"] = dict(res.info, status=res.status, bound=res.bound)
        if res.bound is not None and res.bound > (lag or 0.0):  # above t >= lag: proven by the MIP itself
            bounds["scenario_mip"] = max(res.bound, bounds.get("scenario_mip", 0.0))
        if _better((res.worst_case, res.cost), _key(problem, sel)):
            sel = res.selected
    problem.check_feasible(sel)
    nom, rob = _figures(problem, np.asarray(nominal.selected, np.int64)), _figures(problem, sel)
    bound = max(bounds.values()) if bounds else None
    if exact_done:
        bound = rob["worst_case_cost"]
    if bound is not None:
        bound = min(bound, rob["worst_case_cost"])
    info.update(method=used, moves=info["heuristic"]["moves"], nominal=nom, robust=rob, worst_case_bound=bound,
                bounds=bounds, bound_method=("scenario_mip (optimal)" if exact_done else
                                             max(bounds, key=bounds.get) if bounds else None),
                worst_case_gap_to_bound=(rob["worst_case_cost"] - bound) / rob["worst_case_cost"]
                if bound is not None and rob["worst_case_cost"] > 0 else None,
                nominal_cost_given_up=rob["cost"] - nom["cost"],
                worst_case_gained=nom["worst_case_cost"] - rob["worst_case_cost"],
                bound_seconds=t_search - t0, seconds=time.perf_counter() - t0)
    # status stays 'heuristic': objective is the nominal cost, which this placement does not minimise
    p = Placement(sel, rob["cost"], None, "heuristic", f"{nominal.solver}+robust1",
                  nominal.seconds + time.perf_counter() - t0, dict(nominal.info, robust=info))
    return RobustResult(p, nom, rob, bound, info)

# ------------------------------------------------------------- scenario MIP --
#
# Exact model of min_S W(S) (docs/beyond-the-grid.md has the proof): for a set Σ of
# scenario cameras,  min t  s.t.  t >= z  and for each s in Σ
#   t >= z + D_s + Σ_{j in row s} Σ_k c_jk (u^s_jk − u_jk),     z = C0 + Σ_jk c_jk u_jk,
# nominal rows  Σ_i V_ij x_i + Σ_k u_jk >= Γ_j,  scenario rows  Σ_{i≠s} V_ij x_i + Σ_k u^s_jk >= Γ_j
# (j in row s), c_jk = w_j (2k − 1), u in [0, 1]. The same builder solves a subproblem:
# cameras `fixed` always selected (base coverage b; their scenarios always in Σ, with
# Γ − b + 1 on their rows and the targets no pool candidate sees folded into the
# constants C0, D_s), the rest chosen among `pool`.


@dataclass
class ScenarioResult:
    """selected: (k,) candidate ids (fixed + chosen, sorted); worst_case / cost: W and the
    nominal cost recomputed from V; bound: proven lower bound on the optimum of the
    (sub)problem solved (None if none); status: 'optimal' (every selected camera's
    scenario was in the model and HiGHS proved optimality), 'time_limit', 'interrupted',
    'feasible'; info: rounds, scenarios, sizes, seconds."""

    selected: np.ndarray
    worst_case: float
    cost: float
    bound: float | None
    status: str
    info: dict = field(default_factory=dict)


def _u_cols(gam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(row of each u column, its k (1-based)) for rows with Γ' = gam."""
    gam = np.asarray(gam, np.int64)
    rows = np.repeat(np.arange(len(gam)), gam)
    starts = np.cumsum(gam) - gam
    k = np.arange(int(gam.sum())) - np.repeat(starts, gam) + 1
    return rows, k


class _ScenarioModel:
    """Arrays of the scenario model over `pool` with `fixed` cameras selected."""

    def __init__(self, problem: PlacementProblem, pool: np.ndarray, fixed: np.ndarray) -> None:
        self.p = problem
        self.pool = np.asarray(pool, np.int64)
        self.fixed = np.asarray(fixed, np.int64)
        self.pos = {int(c): k for k, c in enumerate(self.pool)}
        V = problem.V
        gamma = np.asarray(problem.gamma, np.int64)
        w = np.asarray(problem.weights, np.float64)
        b = problem.coverage(self.fixed)
        VP = V[self.pool]
        T = np.unique(VP.indices)  # targets some pool candidate sees and that can still cost:
        graw = gamma[T] - b[T]
        T = T[(graw >= 1) | ((graw == 0) & (b[T] > 0))]  # (the others cost 0 in every scenario)
        outside = np.ones(problem.n_targets, bool)
        outside[T] = False
        self.C0 = float(np.sum(_sq(gamma[outside], w[outside], b[outside])))
        self.h_out = np.where(outside, _h(gamma, w, b), 0.0)  # cost of losing a view, outside T
        # merge targets alike in every scenario: same pool column, same Γ − b, same fixed cameras
        VPc = sp.csc_matrix(VP[:, T])
        VPc.sort_indices()
        VF = sp.csc_matrix(V[self.fixed][:, T]) if len(self.fixed) else sp.csc_matrix((0, len(T)))
        VF.sort_indices()
        graw = gamma[T] - b[T]
        key_to: dict[tuple, int] = {}
        group = np.empty(len(T), np.int64)
        for j in range(len(T)):
            key = (int(graw[j]), VPc.indices[VPc.indptr[j]:VPc.indptr[j + 1]].tobytes(),
                   VF.indices[VF.indptr[j]:VF.indptr[j + 1]].tobytes())
            group[j] = key_to.setdefault(key, len(key_to))
        n_grp = len(key_to)
        rep = np.full(n_grp, -1, np.int64)
        rep[group[::-1]] = np.arange(len(T))[::-1]
        self.T = T[rep]  # one target per merged group
        self.tpos = np.full(problem.n_targets, -1, np.int64)
        self.tpos[T] = group
        self.graw = graw[rep]
        self.g = np.maximum(self.graw, 0)  # Γ' of each group
        self.w = np.bincount(group, weights=w[T], minlength=n_grp)
        self.VPT = sp.csc_matrix(VPc[:, rep], dtype=np.float64)

    def row_T(self, cand: int) -> np.ndarray:
        V = self.p.V
        r = self.tpos[V.indices[V.indptr[cand]:V.indptr[cand + 1]]]
        return np.unique(r[r >= 0])

    def build(self, scen: list[int], eps: float, t_lower: float) -> tuple[MilpArrays, dict]:
        """MILP arrays with the failure scenarios of the candidates ``scen`` (ids, each
        fixed or in the pool). Columns: x (pool), t, z, nominal u, scenario u blocks."""
        prob = self.p
        n_x = len(self.pool)
        nom_t = np.flatnonzero(self.g > 0)
        nu_rows, nu_k = _u_cols(self.g[nom_t])
        n_nu = len(nu_rows)
        nu_start = np.full(len(self.T), -1, np.int64)
        nu_start[nom_t] = np.cumsum(self.g[nom_t]) - self.g[nom_t]
        c_nu = self.w[nom_t][nu_rows] * (2 * nu_k - 1)
        col_t, col_z, col_u = n_x, n_x + 1, n_x + 2
        R, C, D = [], [], []  # COO triplets
        rlo, rhi = [], []
        cost_u = [c_nu]
        nrow = 0

        def cover(targets_local: np.ndarray, gam: np.ndarray, excl: int | None, u0: int) -> int:
            """Coverage rows Σ_{i≠excl} V_ij x_i + Σ_k u_jk >= gam for the listed targets."""
            nonlocal nrow
            keep = gam > 0
            tl, gm = targets_local[keep], gam[keep]
            sub = self.VPT[:, tl].tocoo()
            m = np.ones(sub.nnz, bool) if excl is None else sub.row != excl
            R.append(nrow + sub.col[m]); C.append(sub.row[m]); D.append(np.ones(int(m.sum())))
            ur, _ = _u_cols(gm)
            R.append(nrow + ur); C.append(u0 + np.arange(len(ur))); D.append(np.ones(len(ur)))
            rlo.append(gm.astype(np.float64)); rhi.append(np.full(len(gm), INF))
            nrow += len(gm)
            return len(ur)

        cover(nom_t, self.g[nom_t], None, col_u)
        # z = C0 + Σ c u
        R.append(np.array([nrow])); C.append(np.array([col_z])); D.append(np.array([1.0]))
        R.append(np.full(n_nu, nrow)); C.append(col_u + np.arange(n_nu)); D.append(-c_nu)
        rlo.append([self.C0]); rhi.append([self.C0]); nrow += 1
        # t >= z
        R.append(np.array([nrow, nrow])); C.append(np.array([col_t, col_z])); D.append(np.array([1.0, -1.0]))
        rlo.append([0.0]); rhi.append([INF]); nrow += 1
        ucol = col_u + n_nu
        fixed_set = set(self.fixed.tolist())
        for cand in scen:
            pos = None if cand in fixed_set else self.pos[cand]
            tl = self.row_T(cand)
            if pos is None:  # fixed camera: one view fewer on its row, constant outside T
                gam = np.maximum(self.graw[tl] + 1, 0)
                Dk = float(self.h_out[self.p.V.indices[self.p.V.indptr[cand]:self.p.V.indptr[cand + 1]]].sum())
            else:
                gam = self.g[tl]
                Dk = 0.0
            u0 = ucol
            n_us = cover(tl, gam, pos, u0)
            keep = gam > 0
            tk, gk = tl[keep], gam[keep]
            ur, uk = _u_cols(gk)
            cs = self.w[tk][ur] * (2 * uk - 1)
            cost_u.append(np.zeros(n_us))
            # t − z − Σ c u^s + Σ c u_nominal(row s) >= D_s
            nt = tl[self.g[tl] > 0]
            nr, nk = _u_cols(self.g[nt])
            ncols = col_u + nu_start[nt][nr] + nk - 1
            ncost = self.w[nt][nr] * (2 * nk - 1)
            R.append(np.full(2 + n_us + len(ncols), nrow))
            C.append(np.r_[col_t, col_z, u0 + np.arange(n_us), ncols])
            D.append(np.r_[1.0, -1.0, -cs, ncost])
            rlo.append([Dk]); rhi.append([INF]); nrow += 1
            ucol += n_us
        n_col = ucol
        # budget, money, locations (pool only)
        R.append(np.full(n_x, nrow)); C.append(np.arange(n_x)); D.append(np.ones(n_x))
        rlo.append([-INF]); rhi.append([float(prob.budget - len(self.fixed))]); nrow += 1
        if prob.money_budget is not None:
            R.append(np.full(n_x, nrow)); C.append(np.arange(n_x)); D.append(prob.costs[self.pool])
            rlo.append([-INF]); rhi.append([float(prob.money_budget - prob.costs[self.fixed].sum())]); nrow += 1
        L = location_rows(prob.location_ids[self.pool]).tocoo()
        if L.nnz:
            R.append(nrow + L.row); C.append(L.col); D.append(L.data)
            rlo.append(np.full(L.shape[0], -INF)); rhi.append(np.ones(L.shape[0])); nrow += L.shape[0]
        A = sp.csc_matrix((np.concatenate(D), (np.concatenate(R), np.concatenate(C))), shape=(nrow, n_col))
        c = np.zeros(n_col)
        c[col_t] = 1.0
        c[col_z] = eps
        col_lo = np.zeros(n_col)
        col_hi = np.ones(n_col)
        col_lo[col_t], col_hi[col_t] = t_lower, INF
        col_lo[col_z], col_hi[col_z] = -INF, INF
        integ = np.zeros(n_col, np.int32)
        integ[:n_x] = 1
        arrays = MilpArrays(c, A, np.concatenate([np.asarray(x, np.float64) for x in rlo]),
                            np.concatenate([np.asarray(x, np.float64) for x in rhi]), col_lo, col_hi, integ, n_x)
        return arrays, {"n_x": n_x, "col_t": col_t, "col_z": col_z, "rows": nrow, "cols": n_col, "nnz": int(A.nnz),
                        "scenarios": len(scen)}

    def start_values(self, arrays: MilpArrays, meta: dict, chosen: np.ndarray) -> np.ndarray:
        """Column values of a selection (pool positions): x, the smallest u, z, t."""
        x = np.zeros(meta["n_x"])
        x[np.asarray(chosen, np.int64)] = 1.0
        A = sp.csr_matrix(arrays.A)
        A.sort_indices()
        vals = np.zeros(arrays.shape[1])
        vals[:meta["n_x"]] = x
        # coverage rows: u columns of a row filled in order up to the deficit
        Ax = A[:, :meta["n_x"]] @ x
        ucols = np.arange(meta["n_x"] + 2, arrays.shape[1])
        Au = A[:, ucols].tocsc()
        Au.sort_indices()
        row_of_u = Au.indices[Au.indptr[:-1]]  # first nonzero = its coverage row (rows come before cost rows)
        deficit = np.maximum(arrays.row_lower - Ax, 0)
        order = np.argsort(row_of_u, kind="stable")
        r = row_of_u[order]
        first = np.searchsorted(r, r)
        rank = np.arange(len(r)) - first + 1
        vals[ucols[order]] = (rank <= np.round(deficit[r])).astype(np.float64)
        rows_z = A[:, meta["col_z"]].tocoo().row
        zrow = rows_z[0]
        rest = A[zrow].toarray().ravel()
        rest[meta["col_z"]] = 0
        vals[meta["col_z"]] = arrays.row_lower[zrow] - rest @ vals
        trows = A[:, meta["col_t"]].tocoo().row
        At = A[trows]
        other = At @ vals  # without t (t is still 0)
        vals[meta["col_t"]] = max(arrays.col_lower[meta["col_t"]], float(np.max(arrays.row_lower[trows] - other)))
        return vals


def _key(problem: PlacementProblem, sel: np.ndarray) -> tuple[float, float]:
    return worst_case(problem, sel)[0], problem.cost(sel)


def scenario_mip(problem: PlacementProblem, start: np.ndarray, *, pool: np.ndarray | None = None,
                 fixed: np.ndarray | None = None, time_limit_s: float | None = 60.0, threads: int | None = None,
                 seed: int = 0, eps: float = 0.0, t_lower: float = 0.0, mip_rel_gap: float | None = 1e-6,
                 init_scenarios: int | None = 5, highs_options: dict | None = None, should_stop=None,
                 max_rounds: int = 200) -> ScenarioResult:
    """min_S max_{s in S} cost(S minus s) by scenario generation on the exact scenario MIP:
    solve with the scenarios of the cameras in Σ (first: those of ``start``), add the
    scenarios of the selected cameras missing from Σ, repeat until none is missing. A model
    with a subset of the scenarios is a relaxation, so every round's HiGHS dual bound is a
    lower bound on the optimum; the round where none is missing, solved to optimality,
    proves its selection optimal. ``fixed`` cameras are kept (a subproblem: the optimum and
    bound are then those of the selections containing them), the others are chosen in
    ``pool`` (default: every candidate at a location no fixed camera uses). ``start`` (a
    feasible selection containing ``fixed``, its other cameras in the pool) warm-starts
    every round. eps > 0 adds eps·nominal cost to the objective (ties in W broken toward a
    lower nominal cost; the bound is divided by 1 + eps). t_lower: a known lower bound on
    the optimum (added as t >= t_lower). Deterministic with threads=1 unless a time limit
    cuts a round."""
    t0 = time.perf_counter()
    fixed = np.zeros(0, np.int64) if fixed is None else np.unique(np.asarray(fixed, np.int64))
    if pool is None:
        used = np.isin(problem.location_ids, problem.location_ids[fixed])
        pool = np.flatnonzero(~used)
    pool = np.unique(np.asarray(pool, np.int64))
    start = np.unique(np.asarray(start, np.int64))
    if not np.all(np.isin(fixed, start)) or not np.all(np.isin(start[~np.isin(start, fixed)], pool)):
        raise ValueError("scenario_mip: start must contain the fixed cameras and choose the others in the pool")
    problem.check_feasible(start)
    model = _ScenarioModel(problem, pool, fixed)
    best_sel = start
    best = _key(problem, start)
    chosen = np.array([model.pos[int(c)] for c in start if c not in set(fixed.tolist())], np.int64)
    if len(start):  # first scenarios: the start's most costly failures
        loss = removal_losses(problem, start)
        order = np.lexsort((start, -loss))
        n0 = len(start) if init_scenarios is None else min(init_scenarios, len(start))
        sigma = set(int(c) for c in start[order[:n0]])
    else:
        sigma = set()
    bound: float | None = None
    status = "time_limit"
    info: dict = {"rounds": 0, "pool": int(len(pool)), "fixed": int(len(fixed)), "targets": int(len(model.T)),
                  "nodes": 0}
    for _ in range(max_rounds):
        left = None if time_limit_s is None else time_limit_s - (time.perf_counter() - t0)
        if left is not None and left <= 0.05:
            break
        if stopped(should_stop):
            status = "interrupted"
            break
        arrays, meta = model.build(sorted(sigma), eps, t_lower)
        h = highs_from_arrays(arrays)
        sv = model.start_values(arrays, meta, chosen)
        left = None if time_limit_s is None else max(0.05, time_limit_s - (time.perf_counter() - t0))
        out = run_highs(h, time_limit_s=left, threads=threads, seed=seed, should_stop=should_stop, start=sv,
                        mip_rel_gap=mip_rel_gap, options=highs_options)
        info["rounds"] += 1
        info.update(scenarios=meta["scenarios"], rows=meta["rows"], columns=meta["cols"], nonzeros=meta["nnz"],
                    nodes=info["nodes"] + out.nodes)
        if out.bound is not None:
            b = max(out.bound / (1.0 + eps), t_lower)
            bound = b if bound is None else max(bound, b)
        if out.values is None:
            status = out.status if out.status in ("time_limit", "interrupted") else "feasible"
            break
        ch = np.flatnonzero(out.values[:meta["n_x"]] > 0.5)
        sel = np.sort(np.r_[fixed, model.pool[ch]])
        try:
            problem.check_feasible(sel)
        except ValueError:
            status = "feasible"
            break
        key = _key(problem, sel)
        if _better(key, best):
            best, best_sel, chosen = key, sel, ch
        # scenarios the model left out that this selection violates (failure cost above t)
        t_model = float(out.values[meta["col_t"]])
        fail = key[1] + removal_losses(problem, sel)
        tol = 1e-7 * max(1.0, abs(t_model))
        missing = {int(c) for c, f in zip(sel, fail) if f > t_model + tol and int(c) not in sigma}
        if not missing:
            status = out.status if out.status in ("optimal", "time_limit", "interrupted") else "feasible"
            break
        sigma |= missing
        if out.status != "optimal":
            status = out.status if out.status in ("time_limit", "interrupted") else "feasible"
            break
    else:
        status = "feasible"
    if bound is not None:
        bound = min(bound, best[0])
    info["seconds"] = time.perf_counter() - t0
    return ScenarioResult(best_sel, best[0], best[1], bound, status, info)


# Small sub-MIPs (tens of binaries): HiGHS presolve and its sub-MIP heuristics (RINS, RENS)
# cost 3-4 times the search itself (measured on standard-store neighbourhoods).
FAST_SUB_MIP = {"presolve": "off", "mip_heuristic_effort": 0.0, "mip_heuristic_run_rins": False,
                "mip_heuristic_run_rens": False}


def robust_lns(problem: PlacementProblem, start: np.ndarray, *, time_limit_s: float | None = 60.0,
               sub_time_s: float = 20.0, free_sizes: tuple[int, ...] = (2, 3, 5, 8), pool_size: int = 30,
               anchors: int = 3, donors: int = 2, seed: int = 0, t_lower: float = 0.0,
               should_stop=None) -> tuple[np.ndarray, dict]:
    """Large-neighbourhood search with the scenario MIP: pick an anchor (one of the
    ``anchors`` cameras whose failure costs most), free the k selected cameras sharing
    the most targets with it (k from ``free_sizes``), keep the others fixed, and solve the
    scenario MIP over a pool of the ``pool_size`` candidates that see the most still-needed
    targets of the freed cameras' rows (plus the freed cameras), with ``sub_time_s``.
    Accept when (W, nominal cost) drops lexicographically and start over from the worst
    camera; stop when every (anchor, k) pair fails, at the time limit or on should_stop.
    Deterministic for a seed when no sub-MIP hits its time limit."""
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    V = problem.V
    Vf = V.astype(np.float64)
    sel = np.unique(np.asarray(start, np.int64))
    best = _key(problem, sel)
    eps = 0.1 * float(np.min(problem.weights[problem.weights > 0], initial=1.0)) / max(problem.normalizer, 1.0)
    tries = accepted = 0
    attempt = 0
    history: list[dict] = []
    stopped_by = "converged"
    n_try = anchors * len(free_sizes)
    while attempt < n_try and len(sel):
        left = None if time_limit_s is None else time_limit_s - (time.perf_counter() - t0)
        if left is not None and left <= 0.5:
            stopped_by = "time_limit"
            break
        if stopped(should_stop):
            stopped_by = "interrupted"
            break
        loss = removal_losses(problem, sel)
        order = np.lexsort((sel, -loss))
        a = int(sel[order[attempt % min(anchors, len(sel))]])
        k = min(free_sizes[attempt // anchors], len(sel))
        ind = np.zeros(problem.n_targets)
        ind[V.indices[V.indptr[a]:V.indptr[a + 1]]] = 1.0
        ov = np.asarray(Vf[sel] @ ind).ravel()
        ov[sel == a] = np.inf
        free = sel[np.lexsort((sel, -ov))[:k]]
        if donors:  # and the cameras whose failure costs least: moving one may back up the anchor
            rest = np.flatnonzero(~np.isin(sel, free))
            free = np.r_[free, sel[rest[np.lexsort((sel[rest], loss[rest]))[:donors]]]]
        fixed = np.setdiff1d(sel, free)
        cov_fixed = problem.coverage(fixed)
        need = np.zeros(problem.n_targets)
        rows_free = np.unique(np.concatenate([V.indices[V.indptr[i]:V.indptr[i + 1]] for i in free[:k]]))
        need[rows_free] = problem.weights[rows_free] * (problem.gamma[rows_free] + 1 - cov_fixed[rows_free] > 0)
        score = np.asarray(Vf @ need).ravel() + rng.random(problem.n_candidates) * 1e-3  # seeded tie-break
        score[np.isin(problem.location_ids, problem.location_ids[fixed])] = -np.inf
        cand = np.flatnonzero(np.isfinite(score) & (score > 0.5))
        cand = cand[np.argsort(-score[cand], kind="stable")[:pool_size]]
        pool = np.union1d(cand, free)
        sub = None if left is None else min(sub_time_s, left)
        res = scenario_mip(problem, sel, pool=pool, fixed=fixed, time_limit_s=sub, eps=eps, t_lower=t_lower,
                           mip_rel_gap=1e-6, should_stop=should_stop, highs_options=FAST_SUB_MIP)
        tries += 1
        key = (res.worst_case, res.cost)
        history.append({"anchor": a, "free": int(k), "pool": int(len(pool)), "status": res.status,
                        "worst_case": res.worst_case, "cost": res.cost, "seconds": round(res.info["seconds"], 2)})
        if _better(key, best):
            sel, best = res.selected, key
            accepted += 1
            attempt = 0
        else:
            attempt += 1
    return sel, {"tries": tries, "accepted": accepted, "stopped": stopped_by, "history": history,
                 "seconds": time.perf_counter() - t0}


def essential_from_folder(out_dir) -> tuple[list[dict], dict]:
    """``essential_cameras`` for a run's output folder (visibility.npz + placement.json):
    (ranking with each camera's candidate_id, position and type, summary dict)."""
    import json
    from pathlib import Path

    from camplace.core.errors import InputError
    from camplace.problem.instance import load_problem_npz

    out = Path(out_dir)
    for name in ("visibility.npz", "placement.json"):
        if not (out / name).is_file():
            raise InputError(f"{out}: {name} not found (expected the output folder of camplace run / evaluate)")
    try:
        pdict = json.loads((out / "placement.json").read_text())
        cams = pdict["cameras"]
        ids = [c["candidate_id"] for c in cams]
    except (ValueError, KeyError, TypeError) as err:
        raise InputError(f"{out / 'placement.json'}: not a camplace placement ({err})") from None
    if any(i is None for i in ids):
        raise InputError(f"{out / 'placement.json'}: some cameras are not rows of V (candidate_id null); "
                         "score the placement with `camplace evaluate` first")
    problem, _ = load_problem_npz(out / "visibility.npz", len(ids))
    sel = np.asarray(ids, np.int64)
    if len(sel) and (sel.min() < 0 or sel.max() >= problem.n_candidates):
        raise InputError(f"{out / 'placement.json'}: candidate_id outside the rows of visibility.npz")
    ranking = essential_cameras(problem, sel)
    by_id = {int(c["candidate_id"]): c for c in cams}
    for r in ranking:
        c = by_id[r["candidate_id"]]
        r.update(position=c.get("position"), yaw_deg=c.get("yaw_deg"), pitch_deg=c.get("pitch_deg"),
                 camera=c.get("camera"))
    w, who = worst_case(problem, sel)
    cost = problem.cost(sel)
    return ranking, {"cost": cost, "worst_case_cost": w, "worst_failure_candidate": who,
                     "coverage_gap": cost / problem.normalizer if problem.normalizer > 0 else 0.0}


__all__ = ["RobustResult", "ScenarioResult", "essential_from_folder", "essential_cameras", "mean_failure_bound",
           "removal_losses", "robust_bound", "robust_lns", "robust_placement", "robust_search", "scenario_mip",
           "worst_case"]
