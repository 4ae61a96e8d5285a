"""The "Proposed MIP" in its tight convex form, solved by HiGHS.

The squared shortfall max(Γ_j − c_j, 0)² of an integer coverage c_j is convex in
c_j, so its piecewise-linear form needs no binary piece selectors: with continuous
u_jk ∈ [0, 1], k = 1..Γ_j (u_jk = 1: "the k-th missing view"),

    min  Σ_j w_j Σ_k (2k − 1) u_jk
    s.t. Σ_i V_ij x_i + Σ_k u_jk >= Γ_j        (one row per target with Γ_j >= 1)
         Σ_i x_i <= N_s                        (budget)
         Σ_i cost_i x_i <= money_budget         (only when the problem has one)
         Σ_{i of type t} x_i <= limit_t         (one row per limited camera type)
         Σ_{i at location l} x_i <= 1           (one row per location with >= 2 poses)
         x ∈ {0, 1}^{N_g},  u ∈ [0, 1]

Since the slopes 2k − 1 increase with k, an optimal u fills the cheapest units
first, so for integer x the objective equals Σ_j w_j max(Γ_j − c_j, 0)² exactly.
Same optimum as the paper's model (eq. 6–7), far tighter LP relaxation.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import highspy
import numpy as np
import scipy.sparse as sp

from camplace.problem.model import PlacementProblem
from camplace.solvers.base import OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, trivial_placement
from camplace.solvers.contract import Tags, make_solver
from camplace.solvers.highs_util import (INF, MilpArrays, convex_model_nnz, highs_from_arrays, location_rows,
                                        model_fits, run_highs, target_rows)


@dataclass
class TightLayout:
    """Column layout of the tight model: columns [0, n_x) are x; then u columns.
    u_target: (n_u,) int64 target j of each u column; u_k: (n_u,) int64 its k (1-based);
    cover_targets: (n_t,) int64 target of each coverage row (rows [0, n_t))."""

    n_x: int
    u_target: np.ndarray
    u_k: np.ndarray
    cover_targets: np.ndarray


def tight_model_arrays(problem: PlacementProblem) -> tuple[MilpArrays, TightLayout]:
    """The tight convex MILP of the module docstring as arrays (rows: coverage rows
    first, then budget, [money budget], location rows, [per-type limit rows])."""
    V = problem.V
    n_g = problem.n_candidates
    gamma = np.asarray(problem.gamma, np.int64)
    targets = np.nonzero(gamma > 0)[0]
    g = gamma[targets]
    n_t = len(targets)
    u_row = np.repeat(np.arange(n_t), g)
    starts = np.cumsum(g) - g
    u_k = np.arange(int(g.sum())) - np.repeat(starts, g) + 1
    u_target = targets[u_row]
    n_u = len(u_row)
    cover_x = target_rows(V, targets)  # (n_t, N_g)
    cover_u = sp.csr_matrix((np.ones(n_u), (u_row, np.arange(n_u))), shape=(n_t, n_u))
    blocks = [[cover_x, cover_u], [sp.csr_matrix(np.ones((1, n_g))), None]]
    lower = [g.astype(np.float64), [-INF]]
    upper = [np.full(n_t, INF), [float(problem.budget)]]
    if problem.money_budget is not None:
        blocks.append([sp.csr_matrix(problem.costs.reshape(1, -1)), None])
        lower.append([-INF])
        upper.append([float(problem.money_budget)])
    L = location_rows(problem.location_ids)
    if L.shape[0]:
        blocks.append([L, None])
        lower.append(np.full(L.shape[0], -INF))
        upper.append(np.ones(L.shape[0]))
    if problem.has_type_limits:
        T, limits = problem.type_rows()
        blocks.append([T, None])
        lower.append(np.full(len(limits), -INF))
        upper.append(limits)
    A = sp.bmat(blocks, format="csc") if n_u else sp.vstack([b[0] for b in blocks], format="csc")
    if A.shape[1] != n_g + n_u:  # bmat drops an all-None column block when n_u == 0
        A = sp.hstack([A, sp.csc_matrix((A.shape[0], n_g + n_u - A.shape[1]))], format="csc")
    c = np.concatenate([np.zeros(n_g), problem.weights[u_target] * (2 * u_k - 1)])
    col_lower = np.zeros(n_g + n_u)
    col_upper = np.ones(n_g + n_u)
    integrality = np.concatenate([np.ones(n_g, np.int32), np.zeros(n_u, np.int32)])
    arrays = MilpArrays(c, A, np.concatenate([np.asarray(x, np.float64) for x in lower]),
                        np.concatenate([np.asarray(x, np.float64) for x in upper]), col_lower, col_upper,
                        integrality, n_g)
    return arrays, TightLayout(n_g, u_target.astype(np.int64), u_k.astype(np.int64), targets.astype(np.int64))


def skipped_placement(problem: PlacementProblem, start: np.ndarray, name: str, t0: float, info: dict,
                      reason: str) -> Placement:
    """The start placement with status 'time_limit', when a phase cannot fit the time left."""
    best = np.sort(np.asarray(start, np.int64))
    info["skipped"] = reason
    return Placement(best, problem.cost(best), None, "time_limit", name, time.perf_counter() - t0, info)


def build_tight_model(problem: PlacementProblem, integer: bool = True) -> highspy.Highs:
    """A silent highspy.Highs with the tight model (integer=False: its LP relaxation,
    whose optimum is a lower bound on the optimal cost). Columns: x first (N_g), then u."""
    arrays, _ = tight_model_arrays(problem)
    return highs_from_arrays(arrays, integer=integer)


def tight_start(problem: PlacementProblem, layout: TightLayout, selected: np.ndarray) -> np.ndarray:
    """Full column vector of the tight model for a selection (u_jk = 1 for k <= deficit)."""
    x = np.zeros(layout.n_x)
    x[np.asarray(selected, np.int64)] = 1.0
    deficit = np.maximum(problem.gamma - problem.coverage(selected), 0)
    u = (layout.u_k <= deficit[layout.u_target]).astype(np.float64)
    return np.concatenate([x, u])


def selection_from_x(values: np.ndarray, n_x: int) -> np.ndarray:
    return np.nonzero(np.asarray(values[:n_x]) > 0.5)[0].astype(np.int64)


def better_selection(problem: PlacementProblem, start: np.ndarray, found: np.ndarray | None, info: dict,
                     reject_key: str) -> tuple[np.ndarray, float]:
    """(selection, cost): the solver's selection when it is feasible and strictly cheaper
    than the start, else the start (info[reject_key] = True if it was infeasible)."""
    best = np.sort(np.asarray(start, np.int64))
    best_cost = problem.cost(best)
    if found is not None:
        try:
            problem.check_feasible(found)
        except ValueError:
            info[reject_key] = True
            return best, best_cost
        c = problem.cost(found)
        if c < best_cost - 1e-9 * max(1.0, best_cost):
            return np.sort(found), c
    return best, best_cost


def solve_highs_model(problem: PlacementProblem, h: highspy.Highs, start_cols: np.ndarray | None,
                      start_sel: np.ndarray, n_x: int, name: str, *, time_limit_s: float | None,
                      threads: int | None, seed: int, should_stop: ShouldStop | None,
                      on_incumbent: OnIncumbent | None, mip_rel_gap: float | None, verbose: bool,
                      t0: float, info: dict, end: float = float("inf")) -> Placement:
    """Run HiGHS on a model whose optimum is the placement cost, keep the better of
    its incumbent and the start, and report bound / gap / status. ``end``: the solve's
    perf_counter() deadline (HiGHS gets only the time left before it)."""
    left = None if time_limit_s is None else max(0.01, time_limit_s - (time.perf_counter() - t0))
    out = run_highs(h, time_limit_s=left, threads=threads, seed=seed, should_stop=should_stop,
                    on_incumbent=on_incumbent, start=start_cols, mip_rel_gap=mip_rel_gap, verbose=verbose, end=end)
    if out.model_status.startswith("skipped"):
        info["skipped"] = out.model_status
    found = None if out.values is None else selection_from_x(out.values, n_x)
    best, best_cost = better_selection(problem, start_sel, found, info, "highs_solution_rejected")
    bound = out.bound
    if bound is not None:
        bound = min(max(bound, 0.0), best_cost)
    status = out.status  # 'optimal': proven within HiGHS' mip_rel_gap (Placement.gap has the exact gap)
    if status.startswith("other") or status == "infeasible":
        info["highs_status"] = out.model_status
        status = "feasible"
    info.update(highs_seconds=out.seconds, nodes=out.nodes, highs_status=out.model_status,
                highs_objective=out.objective)
    return Placement(best, best_cost, bound, status, name, time.perf_counter() - t0, info)


def solve_mip(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
              seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
              on_incumbent: OnIncumbent | None = None, warm_start: bool = True, local_search: bool = True,
              fixing: bool = True, mip_rel_gap: float | None = None, verbose: bool = False) -> Placement:
    """Tight convex MIP on HiGHS, warm-started from greedy (+ 1-swap when local_search).

    With `fixing` (default; not with a money budget) the warm start is improved by a short
    tabu search and the model is first shrunk by Lagrangian fixing against it
    (docs/certify.md §2–3: candidates that cannot be in any cheaper selection are dropped,
    locations every cheaper selection uses are forced), an optimum-preserving reduction;
    HiGHS then solves the reduced model. Status: 'optimal' (proven within mip_rel_gap,
    default 1e-4), 'time_limit' or 'interrupted' (best placement returned either way),
    'feasible'."""
    from camplace.solvers.greedy import solve_greedy

    t0 = time.perf_counter()
    if (easy := trivial_placement(problem, "mip", t0)) is not None:
        return easy
    end = deadline(time_limit_s)
    info: dict = {}
    start = np.zeros(0, np.int64)
    if warm_start:
        ws_limit = None if time_limit_s is None else 0.2 * time_limit_s
        g = solve_greedy(problem, time_limit_s=ws_limit, should_stop=should_stop, local_search=local_search)
        start = g.selected
        info["warm_start_objective"] = g.objective
        if on_incumbent:
            on_incumbent(g.objective, None)
        if g.status == "interrupted":
            return Placement(start, g.objective, None, "interrupted", "mip", time.perf_counter() - t0, info)
    if progress:
        progress("mip", 0, 1)
    if fixing and warm_start and problem.money_budget is None:
        p = _solve_fixed(problem, start, end=end, time_limit_s=time_limit_s, threads=threads, seed=seed,
                         should_stop=should_stop, on_incumbent=on_incumbent,
                         mip_rel_gap=1e-4 if mip_rel_gap is None else mip_rel_gap, info=info)
    elif not model_fits(end, convex_model_nnz(problem)):
        p = skipped_placement(problem, start, "mip", t0, info, "no time left to build the tight model")
    else:
        tb = time.perf_counter()
        arrays, layout = tight_model_arrays(problem)
        h = highs_from_arrays(arrays)
        info.update(build_seconds=time.perf_counter() - tb, columns=arrays.shape[1], rows=arrays.shape[0],
                    nonzeros=int(arrays.A.nnz))
        start_cols = tight_start(problem, layout, start) if warm_start else None
        left = None if time_limit_s is None else max(0.01, end - time.perf_counter())
        p = solve_highs_model(problem, h, start_cols, start, layout.n_x, "mip", time_limit_s=left, threads=threads,
                              seed=seed, should_stop=should_stop, on_incumbent=on_incumbent,
                              mip_rel_gap=mip_rel_gap, verbose=verbose, t0=time.perf_counter(), info=info,
                              end=end)
    if progress:
        progress("mip", 1, 1)
    return Placement(p.selected, p.objective, p.bound, p.status, "mip", time.perf_counter() - t0, p.info)


LP_DUALS_MAX_NNZ = 400_000  # above this the exact LP takes too long to pay for its better fixing


def _solve_fixed(problem: PlacementProblem, start: np.ndarray, *, end: float, time_limit_s: float | None,
                 threads: int | None, seed: int, should_stop: ShouldStop | None,
                 on_incumbent: OnIncumbent | None, mip_rel_gap: float, info: dict) -> Placement:
    """Tabu polish of the start, Lagrangian bound and fixing, then HiGHS on the reduced
    model. Every selection cheaper than the incumbent survives the fixing, so the reduced
    model's dual bound (capped by the incumbent) is a bound for the whole problem."""
    from camplace.solvers.bounds import (Lagrangian, Reduction, lagrangian_bound, lp_bound, reduce_by_fixing,
                                         solve_reduced_mip)
    from camplace.solvers.tabu import solve_tabu

    def share(frac: float, cap: float) -> float:
        if time_limit_s is None:
            return cap
        return max(0.0, min(cap, frac * time_limit_s, end - time.perf_counter()))

    t_tabu = share(0.1, 2.0)
    best = np.sort(np.asarray(start, np.int64))
    best_cost = problem.cost(best)
    if t_tabu > 0:
        ts = solve_tabu(problem, time_limit_s=t_tabu, seed=seed, should_stop=should_stop, initial=best,
                        max_stall_restarts=15)
        if ts.objective < best_cost - 1e-9 * max(1.0, best_cost):
            best, best_cost = np.sort(ts.selected), ts.objective
            if on_incumbent:
                on_incumbent(best_cost, None)
        info["tabu_objective"] = ts.objective
    lagr = Lagrangian(problem)
    lb = lagrangian_bound(problem, time_limit_s=share(0.1, 3.0), incumbent_cost=best_cost,
                          coverage=problem.coverage(best), should_stop=should_stop, lagr=lagr)
    red = reduce_by_fixing(problem, lb.multipliers, best_cost, lagr)
    bound = min(best_cost, lb.bound)
    if on_incumbent:
        on_incumbent(best_cost, bound)
    if problem.V.nnz <= LP_DUALS_MAX_NNZ and not (should_stop is not None and should_stop()):
        # the exact LP's duals are Lagrange multipliers too (certify.md §1); their fixing
        # differs from the subgradient's, and intersecting two valid reductions is valid
        lp = lp_bound(problem, time_limit_s=share(0.15, 10.0) or None, threads=threads, end=end,
                      should_stop=should_stop)
        if lp.info.get("status") == "optimal":
            lam = np.maximum(lp.info["row_dual"][:problem.n_targets], 0.0)
            red2 = reduce_by_fixing(problem, lam, best_cost, lagr)
            red = Reduction(red.keep & red2.keep, np.union1d(red.forced, red2.forced), red.ub,
                            max(red.lagrangian, red2.lagrangian))
            bound = max(bound, min(best_cost, lp.bound))
            info["lp_bound"] = lp.bound
    info.update(lagrangian_bound=lb.bound, fixing_kept=int(red.keep.sum()), fixing_forced=int(len(red.forced)),
                candidates=int(problem.n_candidates))
    stopped = should_stop is not None and should_stop()
    if best_cost - bound > mip_rel_gap * best_cost and not stopped:
        left = 1e9 if time_limit_s is None else end - time.perf_counter()
        if left > 0.05:
            b, sel, sub = solve_reduced_mip(problem, red, best, time_limit_s=left, threads=threads, seed=seed,
                                            should_stop=should_stop, mip_rel_gap=mip_rel_gap, end=end)
            info["reduced_mip"] = sub
            bound = max(bound, min(b, best_cost))
            if sel is not None:
                cand, c = better_selection(problem, best, sel, info, "highs_solution_rejected")
                if c < best_cost:
                    best, best_cost = cand, c
                    if on_incumbent:
                        on_incumbent(best_cost, bound)
    bound = min(bound, best_cost)
    if best_cost - bound <= mip_rel_gap * best_cost + 1e-9:
        status = "optimal"
    elif should_stop is not None and should_stop():
        status = "interrupted"
    else:
        status = "time_limit" if time_limit_s is not None else "feasible"
    return Placement(best, best_cost, bound, status, "mip", 0.0, info)


MIP = make_solver("mip", solve_mip, Tags(exact=True, gives_bound=True), summary="The tight MIP (HiGHS), exact")
