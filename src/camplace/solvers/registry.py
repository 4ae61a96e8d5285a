"""The solver registry: every solver by name, the options builder and ``solve``.

    SOLVERS["mip"].solve(problem, build_options("mip", time_limit_s=10), Hooks(should_stop=f))
    solve(problem, "mip", time_limit_s=10, should_stop=f)        # the same, on the reduced problem

Adding a solver is one ``make_solver`` line here (camplace.solvers.contract; docs/solvers.md),
and camplace.solvers.testing.check_solver is the proof that it keeps the contract.
"""

from __future__ import annotations

import time
from dataclasses import replace
from functools import partial
from typing import Any

from camplace.core.errors import InputError
from camplace.problem.model import PlacementProblem
from camplace.solvers.base import Placement
from camplace.solvers.certify import solve_certify
from camplace.solvers.contract import HOOK_FIELDS, Options, Solver, Tags, make_solver, split_options
from camplace.solvers.greedy import solve_catalogue_greedy, solve_greedy
from camplace.solvers.greedy_fast import solve_greedy_fast
from camplace.solvers.greedy_triangulated import solve_greedy_triangulated
from camplace.solvers.horster import solve_horster
from camplace.solvers.min_cameras import solve_min_cameras
from camplace.solvers.mip import solve_mip
from camplace.solvers.paper_mip import solve_paper_mip
from camplace.solvers.polish import solve_greedy_polish
from camplace.solvers.reduction import solve_reduced
from camplace.solvers.robust_solver import solve_robust
from camplace.solvers.tabu import solve_tabu
from camplace.solvers.zhao import solve_zhao
from camplace.solvers.zones import solve_zones

_EXACT = Tags(exact=True, gives_bound=True)

SOLVERS: dict[str, Solver] = {s.name: s for s in [
    make_solver("greedy", solve_greedy, summary="The paper's greedy (lazy CELF); local_search: 1-swap after"),
    make_solver("greedy-ls", partial(solve_greedy, local_search=True), summary="Greedy, then 1-swap local search"),
    make_solver("greedy-fast", solve_greedy_fast, summary="Greedy with numba gains (same selection as greedy)"),
    make_solver("greedy-money", solve_catalogue_greedy,
                summary="Best of cost-scaled and plain greedy under a money budget"),
    make_solver("greedy-polish", solve_greedy_polish, Tags(gives_bound=True),
                summary="Greedy, then the MIP on a restricted candidate set, Lagrangian bound"),
    make_solver("greedy-triangulated", solve_greedy_triangulated, Tags(needs_positions=True),
                summary="Greedy counting only well-triangulating pairs (needs positions)"),
    make_solver("mip", solve_mip, _EXACT, summary="The tight MIP (HiGHS), exact"),
    make_solver("paper-mip", solve_paper_mip, _EXACT, summary="The paper's MIP model (CBC or HiGHS), exact"),
    make_solver("zhao", solve_zhao, summary="Zhao et al. baseline"),
    make_solver("horster", solve_horster, summary="Hörster's greedy baseline"),
    make_solver("min-cameras", solve_min_cameras, Tags(ignores_camera_budget=True),
                summary="Fewest cameras that reach a coverage target (coverage_gap / max_cost)"),
    make_solver("tabu", solve_tabu, summary="Tabu search from greedy"),
    make_solver("certify", solve_certify, Tags(gives_bound=True),
                summary="Tabu incumbent and proven bounds (Lagrangian, LP, reduced MIP)"),
    make_solver("robust", solve_robust, Tags(needs_start=True, robust_objective=True),
                summary="Best worst case over single camera failures, from a nominal start"),
    make_solver("zones", solve_zones, Tags(gives_bound=True, needs_positions=True),
                summary="Zone sweeps: tight MIP / tabu per floor tile, budget moves, Lagrangian bound (needs positions)"),
]}


def get_solver(name: str) -> Solver:
    """The registered Solver ``name``; InputError(option='solver') when there is none."""
    try:
        return SOLVERS[name]
    except (KeyError, TypeError):
        raise InputError(f"solver: unknown solver {name!r}; expected one of {', '.join(sorted(SOLVERS))}",
                         option="solver") from None


def solvers_taking(option: str) -> list[str]:
    """Sorted names of the solvers that take ``option``."""
    return sorted(n for n, s in SOLVERS.items() if option in s.option_names)


def build_options(name: str, **kwargs: Any) -> Options:
    """The options of solver ``name`` from keywords (common ones and the solver's own);
    InputError(option=key) for a key it does not take, naming the solvers that do."""
    solver = get_solver(name)
    hooks = [k for k in kwargs if k in HOOK_FIELDS]
    if hooks:
        raise InputError(f"{hooks[0]}: a callback, not an option; pass it in Hooks", option=hooks[0])
    opts, _ = split_options(solver, kwargs, solvers_taking)
    return opts


def solve(problem: PlacementProblem, solver: str = "greedy", *, reduce: bool = True, **options: Any) -> Placement:
    """Run the named solver: options and hooks (should_stop, progress, on_incumbent) as
    keywords, checked against the solver (InputError for one it does not take). With
    reduce=True (default) the solver sees camplace.problem.model.reduce_problem(problem)
    (same optimum, fewer rows/columns; camplace.solvers.reduction.solve_reduced), except
    solvers tagged needs_positions or needs_start, which always see ``problem``."""
    s = get_solver(solver)
    opts, hooks = split_options(s, options, solvers_taking)
    if not reduce or s.tags.needs_positions or s.tags.needs_start:
        return s.solve(problem, opts, hooks)
    t0 = time.perf_counter()

    def run_reduced(red: PlacementProblem) -> Placement:  # the reduction's time counts against the limit
        if opts.time_limit_s is None:
            return s.solve(red, opts, hooks)
        left = max(0.01, opts.time_limit_s - (time.perf_counter() - t0))
        return s.solve(red, replace(opts, time_limit_s=left), hooks)

    return solve_reduced(problem, run_reduced)


__all__ = ["SOLVERS", "build_options", "get_solver", "solve", "solvers_taking"]
