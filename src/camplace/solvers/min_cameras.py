"""`min-cameras`: the paper's future work — the fewest cameras (or the least total
camera price) whose coverage cost is at most a target.

    min  Σ_i p_i x_i            (p_i = 1: count; p_i = camera_costs: price)
    s.t. Σ_i V_ij x_i + Σ_k u_jk >= Γ_j,   Σ_j w_j Σ_k (2k − 1) u_jk <= target,
         Σ_{i at l} x_i <= 1,  [Σ_i cost_i x_i <= money_budget],  [Σ_{i of type t} x_i <= limit_t],
         x binary, u ∈ [0, 1]

(the tight model of camplace.solvers.mip with cost and budget swapped). target
defaults to 0 (every Γ_j met); coverage_gap=ε sets target = ε · Σ_j w_j Γ_j²
(paper eq. 8); max_cost sets it directly. The problem's camera budget N_s is
ignored (that is the unknown here). When the target cannot be reached at all (e.g.
a target seen from fewer than Γ_j locations), the solver first finds the least
reachable cost with every location available (the `mip` solver) and then the fewest
cameras reaching it; info['target_unreachable'] says so.

The MIP's dual bound gives a proven lower bound on the count (rounded up when the
prices are integral): info['lower_bound'], info['proven_minimal'].
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from camplace.problem.model import PlacementProblem
from camplace.solvers.base import OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, limit_left, stopped
from camplace.solvers.contract import Tags, make_solver
from camplace.solvers.highs_util import INF, convex_model_nnz, highs_from_arrays, model_fits, run_highs, skipped_outcome
from camplace.solvers.mip import tight_model_arrays, tight_start
import scipy.sparse as sp


def location_degree(problem: PlacementProblem) -> np.ndarray:
    """(N_p,) int64: number of distinct locations with a candidate seeing each target.

    The location × target incidence as a CSR with duplicates summed (int32 counts, so no
    entry sums to zero and is pruned): O(nnz) plus a per-row sort, ~25× faster than
    ``np.unique`` over (target, location) keys on 1.5 M pairs."""
    V = problem.V.tocsr()
    _, loc = np.unique(problem.location_ids, return_inverse=True)
    n_loc = int(loc.max()) + 1 if len(loc) else 1
    rows = np.repeat(loc.astype(np.int64), np.diff(V.indptr))
    L = sp.csr_matrix((np.ones(len(V.indices), np.int32), (rows, V.indices)), shape=(n_loc, problem.n_targets))
    L.sum_duplicates()
    return np.bincount(L.indices, minlength=problem.n_targets).astype(np.int64)


def _greedy_order(problem: PlacementProblem, end: float = float("inf")) -> list[int]:
    """The greedy order of candidates with no camera budget (one per location)."""
    from camplace.solvers.greedy import solve_greedy

    n_loc = len(np.unique(problem.location_ids))
    return solve_greedy(replace(problem, budget=n_loc), time_limit_s=limit_left(end)).info["order"]


def _greedy_start(problem: PlacementProblem, target: float, order: list[int]) -> np.ndarray | None:
    """Shortest prefix of the greedy order (no budget, ``order``) whose cost is <= target, or None."""
    V = problem.V
    cov = np.zeros(problem.n_targets, np.int64)
    short = np.maximum(problem.gamma - cov, 0).astype(np.float64)
    cost = float(np.dot(problem.weights, short * short))
    if cost <= target + 1e-9:
        return np.zeros(0, np.int64)
    for n, i in enumerate(order):
        cov[V.indices[V.indptr[i]:V.indptr[i + 1]]] += 1
        short = np.maximum(problem.gamma - cov, 0).astype(np.float64)
        cost = float(np.dot(problem.weights, short * short))
        if cost <= target + 1e-9:
            return np.sort(np.array(order[:n + 1], np.int64))
    return None


def _fewest(problem: PlacementProblem, target: float, prices: np.ndarray, end: float, order: list[int], *,
            threads, seed, should_stop, verbose, integral) -> tuple[np.ndarray | None, np.ndarray | None, object]:
    """Least-price selection with cost <= target: (selection or None, greedy start, HiGHS outcome);
    HiGHS is skipped (outcome 'time_limit') when its model cannot be built and started before ``end``."""
    start = _greedy_start(problem, target, order)
    if not model_fits(end, convex_model_nnz(problem)):
        return start, start, skipped_outcome("no time left to build the model")
    arrays, layout = tight_model_arrays(problem)
    n_t = len(layout.cover_targets)
    n_x = layout.n_x
    u_cost = arrays.c[n_x:].copy()
    arrays.c = np.concatenate([prices, np.zeros(len(u_cost))])
    arrays.row_upper[n_t] = INF  # the camera budget row: not a constraint here
    if target <= 1e-9:
        arrays.col_upper[n_x:] = 0.0
    else:
        row = sp.csr_matrix(np.concatenate([np.zeros(n_x), u_cost]).reshape(1, -1))
        arrays.A = sp.vstack([arrays.A, row], format="csc")
        arrays.row_lower = np.append(arrays.row_lower, -INF)
        arrays.row_upper = np.append(arrays.row_upper, target)
    start_cols = None if start is None else tight_start(problem, layout, start)
    if start_cols is not None and target <= 1e-9:
        start_cols[n_x:] = 0.0
    options = {"mip_abs_gap": 0.999} if integral else {}
    sel = start
    # HiGHS's presolve can return a solution (and bound) the model does not admit (seen with
    # highspy 1.16 on a 6 x 6 model: 'optimal' objective and bound 2 for a 3-camera solution);
    # such an answer is solved again without presolve, so no false bound is reported.
    for extra in ({}, {"presolve": "off"}):
        out = run_highs(highs_from_arrays(arrays), threads=threads, seed=seed, should_stop=should_stop, end=end,
                        start=start_cols, verbose=verbose, options={**options, **extra} or None)
        if out.values is None:
            break
        cand = np.nonzero(out.values[:n_x] > 0.5)[0].astype(np.int64)
        ok = len(np.unique(problem.location_ids[cand])) == len(cand) and problem.type_ok(cand)
        claimed = out.objective if out.objective is not None else prices[cand].sum()
        if not (ok and problem.cost(cand) <= target + 1e-6) or claimed < prices[cand].sum() - 1e-6:
            continue
        if sel is None or prices[cand].sum() <= prices[sel].sum():
            sel = cand
        break
    return sel, start, out


def solve_min_cameras(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                      seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                      on_incumbent: OnIncumbent | None = None, coverage_gap: float | None = None,
                      max_cost: float | None = None, minimize: str | None = None, verbose: bool = False) -> Placement:
    """Fewest cameras (minimize='count') or least price (minimize='price', the default
    when the problem has non-uniform camera_costs) with cost <= target (module docstring)."""
    t0 = time.perf_counter()
    target = 0.0
    if max_cost is not None:
        target = float(max_cost)
    elif coverage_gap is not None:
        target = float(coverage_gap) * problem.normalizer
    prices = problem.costs
    if minimize is None:
        minimize = "price" if problem.camera_costs is not None and np.ptp(prices) > 0 else "count"
    if minimize == "count":
        prices = np.ones(problem.n_candidates)
    info: dict = {"target_cost": target, "minimize": minimize}
    # Reachability: a cheap certificate of unreachability first, else HiGHS says so.
    deg = location_degree(problem)
    floor = float(np.dot(problem.weights, np.maximum(problem.gamma - deg, 0).astype(float) ** 2))
    end = deadline(time_limit_s, t0)
    integral = bool(np.all(np.abs(prices - np.round(prices)) < 1e-9))
    kw = dict(threads=threads, seed=seed, should_stop=should_stop, verbose=verbose, integral=integral)
    sel = start = out = None
    order = _greedy_order(problem, end)
    if floor <= target + 1e-9:
        sel, start, out = _fewest(problem, target, prices, end, order, **kw)
    if sel is None and (out is None or out.status == "infeasible"):
        from camplace.solvers.mip import solve_mip

        n_loc = len(np.unique(problem.location_ids))
        left = limit_left(end)
        left = None if left is None else max(0.01, 0.5 * left)
        best = solve_mip(replace(problem, budget=n_loc), time_limit_s=left, threads=threads, seed=seed,
                         should_stop=should_stop)
        if best.status == "time_limit":  # cut short: the greedy with every location may reach further
            every = np.sort(np.asarray(order, np.int64))
            if problem.cost(every) < best.objective:
                best = replace(best, selected=every, objective=problem.cost(every))
        info.update(target_unreachable=True, requested_target_cost=target, cost_floor=floor,
                    least_reachable_cost=best.objective, least_reachable_bound=best.bound)
        target = best.objective
        info["target_cost"] = target
        sel, start, out = _fewest(problem, target, prices, end, order, **kw)
        if sel is None:
            sel = best.selected
    if sel is None and out is not None and (out.status == "time_limit" or np.isfinite(end)):
        sel = np.sort(np.asarray(order, np.int64))  # HiGHS found nothing in time: the greedy's reach
    if sel is None:
        from camplace.core.errors import InputError

        raise InputError(f"min-cameras: no placement with cost <= {target:g} found (HiGHS: {out.model_status})")
    value = float(prices[sel].sum())
    bound = out.bound if out is not None and out.bound is not None else 0.0
    lower = math.ceil(bound - 1e-6) if integral else bound
    lower = min(lower, value)
    status = out.status if out.status in ("optimal", "time_limit", "interrupted") else "feasible"
    if stopped(should_stop):
        status = "interrupted"
    elif lower >= value - 1e-6:
        status = "optimal"
    info.update(cameras=int(len(sel)), camera_price=value, lower_bound=lower,
                proven_minimal=bool(lower >= value - 1e-6), highs_status=out.model_status, nodes=out.nodes,
                warm_start_cameras=None if start is None else int(len(start)))
    cost = problem.cost(sel)
    if on_incumbent:
        on_incumbent(cost, None)
    return Placement(np.sort(sel), cost, None, status, "min-cameras", time.perf_counter() - t0, info)


MIN_CAMERAS = make_solver("min-cameras", solve_min_cameras, Tags(ignores_camera_budget=True),
                          summary="Fewest cameras that reach a coverage target (coverage_gap / max_cost)")
