"""``robust``: the best worst case over any single camera failure, from a nominal start.

A thin adapter of camplace.solvers.robust.robust_placement to the solver contract. The
start is the option ``nominal`` (a Placement, or selected candidate ids); without one the
greedy with 1-swap local search gives it. The objective is the nominal cost of the robust
selection (which it does not minimise, so the status stays 'heuristic'); the robust
figures (nominal / robust cost and worst case, bound, method) are in info['robust'].
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from camplace.problem.model import PlacementProblem
from camplace.solvers.base import OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, stopped
from camplace.solvers.contract import Tags, make_solver
from camplace.solvers.greedy import solve_greedy
from camplace.solvers.robust import robust_placement


def nominal_placement(problem: PlacementProblem, nominal: Placement | np.ndarray | list | None, *,
                      seed: int = 0, should_stop: ShouldStop | None = None,
                      end: float = float("inf")) -> Placement:
    """The start of the robust search: ``nominal`` as given, selected ids wrapped in a
    Placement (solver 'given'), or greedy + 1-swap when None."""
    if isinstance(nominal, Placement):
        return nominal
    if nominal is None:
        return solve_greedy(problem, seed=seed, should_stop=should_stop, local_search=True,
                            time_limit_s=None if np.isinf(end) else 0.4 * max(0.0, end - time.perf_counter()))
    sel = np.unique(np.asarray(nominal, np.int64))
    problem.check_feasible(sel)
    return Placement(sel, problem.cost(sel), None, "heuristic", "given", 0.0, {})


def solve_robust(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                 seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                 on_incumbent: OnIncumbent | None = None, nominal: Placement | np.ndarray | None = None,
                 method: str = "auto", bound_time_s: float = 10.0, mean_bound_s: float = 60.0,
                 bound_mip_s: float = 0.0, pool: int = 24, max_stall: int = 20,
                 exact_max_nnz: int = 200_000) -> Placement:
    """robust_placement(problem, nominal, ...) as a solver; time_limit_s (default 60 s) is
    for the search, the bounds have their own limits (bound_time_s, mean_bound_s,
    bound_mip_s), each capped at time_limit_s and skipped once should_stop() is true.
    A time_limit_s given is for the whole solve (start, bounds and search within it: the
    bounds get shares of it, robust_placement's ``end``).
    Status 'heuristic', or 'interrupted' when should_stop() turned true."""
    t0 = time.perf_counter()
    limit = 60.0 if time_limit_s is None else float(time_limit_s)
    end = deadline(time_limit_s, t0)
    start = nominal_placement(problem, nominal, seed=seed, should_stop=should_stop, end=end)
    cap = 0.0 if stopped(should_stop) else limit
    rr = robust_placement(problem, start, time_limit_s=limit, bound_time_s=min(bound_time_s, cap), pool=pool,
                          max_stall=max_stall, method=method, exact_max_nnz=exact_max_nnz,
                          bound_mip_s=min(bound_mip_s, cap), mean_bound_s=min(mean_bound_s, cap),
                          seed=seed, should_stop=should_stop, end=end)
    p = rr.placement
    if on_incumbent is not None:
        on_incumbent(p.objective, None)
    status = "interrupted" if stopped(should_stop) else p.status
    seconds = p.seconds if isinstance(nominal, Placement) else time.perf_counter() - t0
    return replace(p, status=status, seconds=seconds, solver="robust", info=dict(p.info, nominal_solver=start.solver))


def describe_robust(info: dict) -> str:
    """One log line from a robust Placement's info['robust']."""
    nom, rob, bound = info["nominal"], info["robust"], info.get("worst_case_bound")
    return (f"robust: nominal {nom['cost']:.6g} -> {rob['cost']:.6g}, worst single failure "
            f"{nom['worst_case_cost']:.6g} -> {rob['worst_case_cost']:.6g}"
            + ("" if bound is None else f" (lower bound {bound:.6g}, {info['bound_method']})")
            + f" by {info['method']}; coverage gap {nom['coverage_gap']:.4f} -> "
            f"{rob['coverage_gap']:.4f}, worst-case gap {nom['worst_case_gap']:.4f} -> "
            f"{rob['worst_case_gap']:.4f}")


ROBUST = make_solver("robust", solve_robust, Tags(needs_start=True, robust_objective=True),
                     summary="Best worst case over single camera failures, from a nominal start")


__all__ = ["ROBUST", "describe_robust", "nominal_placement", "solve_robust"]
