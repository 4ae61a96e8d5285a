"""Run option robust=1: the placement that minimises the worst single-failure cost, with a bound."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from camplace.problem.model import PlacementProblem
from camplace.solvers.base import Placement, stopped
from camplace.solvers.robust.bounds import _round_up, mean_failure_bound, robust_bound
from camplace.solvers.robust.failures import _better, _key, worst_case
from camplace.solvers.robust.lns import robust_lns
from camplace.solvers.robust.scenario import scenario_mip
from camplace.solvers.robust.search import robust_search

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


def robust_placement(problem: PlacementProblem, nominal: Placement, *, time_limit_s: float | None = 60.0,
                     bound_time_s: float = 10.0, pool: int = 24, max_stall: int = 20, method: str = "auto",
                     exact_max_nnz: int = 200_000, bound_mip_s: float = 0.0, mean_bound_s: float = 60.0,
                     seed: int = 0, should_stop=None, end: float = float("inf")) -> RobustResult:
    """Run option robust=1 from the nominal placement, with figures for both placements and a
    lower bound on the optimal worst case. method 'auto': the swap/tabu heuristic
    (``robust_search``, 30 % of the time), then the exact scenario MIP on the whole problem
    when V has at most ``exact_max_nnz`` nonzeros (half of the time left; optimal when it
    finishes), then, unless that proved optimality, the scenario-MIP large-neighbourhood
    search (``robust_lns``) with the rest of the time. info['method'] says which ran.
    'heuristic': the swap/tabu search alone. The bound is the best of the Lagrangian bound
    of the problem with one camera fewer (``bound_time_s``), the mean-failure LP bound
    (``mean_failure_bound``, ``mean_bound_s``) and the scenario-MIP dual bound (from the
    exact solve, or from ``bound_mip_s`` seconds of it on the whole problem). The bounds come
    first, each with its own time limit; ``time_limit_s`` is for the search. ``end``: a
    perf_counter() deadline for all of it (bounds capped at shares of the time left before
    it: 15 % the Lagrangian, 25 % the LP; the search ends by it; the MIP bound within it)."""
    if method not in ("auto", "heuristic"):
        raise ValueError(f"robust_placement: method must be 'auto' or 'heuristic', got {method!r}")
    t0 = time.perf_counter()
    bounds: dict[str, float] = {}
    lag = None
    if np.isfinite(end):
        bound_time_s = min(bound_time_s, 0.15 * max(0.0, end - t0))
        mean_bound_s = min(mean_bound_s, 0.25 * max(0.0, end - t0))
    if bound_time_s > 0:  # hint: the nominal placement minus its worst camera is a feasible (N_s − 1) selection
        start = np.asarray(nominal.selected, np.int64)
        w_now, who = worst_case(problem, start)
        lag = robust_bound(problem, problem.coverage(start[start != who]), bound_time_s, w_now)
        if lag is not None:
            bounds["lagrangian_fewer_camera"] = _round_up(problem, lag)
    if mean_bound_s > 0 and not stopped(should_stop):
        mb = mean_failure_bound(problem, time_limit_s=mean_bound_s, end=min(end, time.perf_counter() + mean_bound_s))
        if mb is not None:
            bounds["mean_failure_lp"] = mb
    lag = max(bounds.values()) if bounds else None  # t >= lag in every scenario MIP below
    t_search = time.perf_counter()  # the time limit is for the search; the bounds have their own
    outer = end
    end = min(end, float("inf") if time_limit_s is None else t_search + time_limit_s)
    span = None if not np.isfinite(end) else max(0.0, end - t_search)
    left = lambda: None if span is None else max(0.0, end - time.perf_counter())  # noqa: E731
    share = None if span is None else (span if method == "heuristic" else 0.3 * span)
    sel, info = robust_search(problem, nominal.selected, time_limit_s=share, pool=pool,
                              should_stop=should_stop, max_stall=max_stall)
    problem.check_feasible(sel)
    info = {"heuristic": dict(info, cost=problem.cost(sel), worst_case_cost=worst_case(problem, sel)[0])}
    used = "heuristic"
    exact_done = False
    if method == "auto" and len(sel) and not stopped(should_stop):
        if problem.V.nnz <= exact_max_nnz:  # exact first, with half of the time left
            half = None if span is None else 0.5 * left()
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
        cap = bound_mip_s if not np.isfinite(outer) else min(bound_mip_s, max(0.0, outer - time.perf_counter()))
        res = scenario_mip(problem, sel, time_limit_s=cap, t_lower=lag or 0.0, seed=seed,
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


__all__ = ["RobustResult", "robust_placement"]
