"""The public conformance suite for solvers (like scikit-learn's check_estimator).

    from camplace.solvers.testing import check_solver, parametrize_with_checks
    check_solver(my_solver)                       # raises AssertionError on the first broken promise

    @parametrize_with_checks(SOLVERS)             # one pytest case per (solver, check)
    def test_conformance(solver, check):
        check(solver)

Checks are chosen by the solver's tags (camplace.solvers.contract.Tags); each runs on tiny
random problems (at most 8 candidates, brute force gives the optimum) with short time limits:
feasible selection (budget, one camera per location, money budget when tagged), objective ==
problem.cost(selected), Placement.solver == the solver's name, bound <= the brute-force
optimum, exact solvers reach it, a stop request gives status 'interrupted', a 0.5 s time
limit kept within 2 s on a moderate problem and reported as status 'time_limit' when the
solve ran past it, on_incumbent called with improving objectives and valid bounds, zero
budget, same seed -> same result, unknown option and badly typed option values refused
(InputError naming the option), a money budget refused by a solver not tagged money_budget,
per-type limits kept (two camera types, a limit that binds: every selection keeps it,
exact solvers reach the constrained optimum). Solvers tagged needs_positions get random
positions, needs_start a greedy start.

Every check runs under a time limit of its own (``CHECK_TIME_S``): past it the solver's
should_stop() turns true, and a check still running CHECK_GRACE_S later fails (the solve
is left behind in a daemon thread), so a solver that ignores its limits fails the check
instead of hanging the suite.
"""

from __future__ import annotations

import threading
import time
from dataclasses import fields, replace
from typing import Any, Callable, Iterable, Mapping

import numpy as np
import scipy.sparse as sp

from camplace.core.errors import InputError
from camplace.problem.model import PlacementProblem, brute_force_optimum
from camplace.solvers.base import Placement
from camplace.solvers.contract import COMMON_FIELDS, Hooks, Solver, _field_types, split_options
from camplace.solvers.greedy import solve_greedy

STATUSES = frozenset({"optimal", "feasible", "time_limit", "interrupted", "heuristic"})
TIME_LIMIT_S = 2.0  # per solve; tiny problems finish long before
CHECK_TIME_S = 90.0  # per check: then should_stop() turns true ...
CHECK_GRACE_S = 30.0  # ... and a check still running this much later fails
SEEDS = (0, 1, 2)
Check = Callable[[Solver], None]
_check_end = threading.local()  # perf_counter() at which the running check's solves are asked to stop


def random_problem(seed: int, n_g: int = 8, n_p: int = 10, budget: int = 3, n_loc: int = 5,
                   density: float = 0.4, priced: bool = False) -> PlacementProblem:
    """A random problem small enough for brute force, with positions (m) in a 10 m box;
    ``priced``: candidate prices in {1, 2, 3} and a money budget of 4."""
    rng = np.random.default_rng(seed)
    V = sp.csr_matrix((rng.random((n_g, n_p)) < density).astype(np.uint8))
    prices = rng.integers(1, 4, n_g).astype(np.float64) if priced else None
    return PlacementProblem(V, rng.integers(0, 4, n_p), rng.uniform(0.5, 2.0, n_p), budget,
                            rng.integers(0, n_loc, n_g), prices, 4.0 if priced else None,
                            candidate_positions=rng.uniform(0, 10, (n_g, 3)),
                            target_positions=rng.uniform(0, 10, (n_p, 3)))


def run_solver(solver: Solver, problem: PlacementProblem, hooks: Hooks | None = None, **options: Any) -> Placement:
    """solver.solve with time_limit_s = TIME_LIMIT_S (unless given) and, for a solver
    tagged needs_start, the greedy placement as ``nominal``. Inside a check, should_stop()
    also turns true when the check's own time runs out."""
    options.setdefault("time_limit_s", TIME_LIMIT_S)
    if solver.tags.needs_start and "nominal" not in options:
        options["nominal"] = solve_greedy(problem)
    end = getattr(_check_end, "end", None)
    if end is not None:
        h = Hooks() if hooks is None else hooks
        user = h.should_stop
        hooks = replace(h, should_stop=lambda: time.perf_counter() > end or bool(user is not None and user()))
    return solver.solve(problem, solver.options(**options), hooks)


def assert_valid(solver: Solver, problem: PlacementProblem, p: Placement) -> None:
    """The Placement contract: status, sorted unique int ids, feasibility (the camera
    budget unless tagged ignores_camera_budget, the money budget when tagged money_budget),
    objective == problem.cost(selected), bound <= objective."""
    name = solver.name
    assert p.status in STATUSES, f"{name}: status {p.status!r}"
    assert p.solver == name, f"{name}: Placement.solver is {p.solver!r}, expected the solver's name {name!r}"
    sel = np.asarray(p.selected)
    assert sel.dtype.kind == "i", f"{name}: selected must be integer ids"
    assert np.all(np.diff(sel) > 0), f"{name}: selected must be sorted and unique"
    assert len(sel) == 0 or (sel.min() >= 0 and sel.max() < problem.n_candidates), f"{name}: id out of range"
    locs = problem.location_ids[sel]
    assert len(np.unique(locs)) == len(locs), f"{name}: two cameras at one location"
    if not solver.tags.ignores_camera_budget:
        assert len(sel) <= problem.budget, f"{name}: {len(sel)} cameras over the budget {problem.budget}"
    if solver.tags.money_budget and problem.money_budget is not None and len(sel):
        assert problem.costs[sel].sum() <= problem.money_budget + 1e-9, f"{name}: over the money budget"
    if problem.has_type_limits:
        assert problem.type_ok(sel), f"{name}: cameras per type {problem.type_counts(sel)} over {problem.type_limits}"
    assert abs(p.objective - problem.cost(sel)) <= 1e-9 * max(1.0, abs(p.objective)), \
        f"{name}: objective {p.objective} != cost {problem.cost(sel)}"
    assert p.seconds >= 0, f"{name}: negative seconds"
    if p.bound is not None:
        assert p.bound <= p.objective + 1e-6 * max(1.0, p.objective), f"{name}: bound above the objective"


def check_feasible_and_objective(solver: Solver) -> None:
    """Valid placements on plain and priced tiny problems."""
    for seed in SEEDS:
        for priced in ((False, True) if solver.tags.money_budget else (False,)):
            problem = random_problem(seed, priced=priced)
            assert_valid(solver, problem, run_solver(solver, problem))


def check_bound_below_optimum(solver: Solver) -> None:
    """A reported bound never exceeds the brute-force optimum; with tag gives_bound some
    bound is reported."""
    for seed in SEEDS:
        problem = random_problem(seed)
        optimum, _ = brute_force_optimum(problem)
        p = run_solver(solver, problem)
        if solver.tags.gives_bound:
            assert p.bound is not None, f"{solver.name}: tagged gives_bound but reported no bound"
        if p.bound is not None:
            assert p.bound <= optimum + 1e-6 * max(1.0, optimum), f"{solver.name}: bound {p.bound} > optimum {optimum}"
        if not solver.tags.ignores_camera_budget:
            assert p.objective >= optimum - 1e-9, f"{solver.name}: cost {p.objective} below the optimum {optimum}"


def check_exact_reaches_optimum(solver: Solver) -> None:
    """Tag exact: status 'optimal' and the brute-force optimum (with and without prices)."""
    for seed in SEEDS:
        for priced in ((False, True) if solver.tags.money_budget else (False,)):
            problem = random_problem(seed, priced=priced)
            optimum, _ = brute_force_optimum(problem)
            p = run_solver(solver, problem, time_limit_s=None)
            assert p.status == "optimal", f"{solver.name}: status {p.status!r} on a tiny problem"
            assert abs(p.objective - optimum) <= 1e-6 * max(1.0, optimum), \
                f"{solver.name}: cost {p.objective} != optimum {optimum}"


def check_stop_request(solver: Solver) -> None:
    """Tag anytime: a stop request already set gives a valid placement, status
    'interrupted' (or 'optimal' when the optimum was proven before the first poll). The
    problem needs more greedy steps (40) than a solver may take between two polls."""
    problem = random_problem(7, n_g=120, n_p=200, budget=40, n_loc=100, density=0.05)
    seen: list = []
    hooks = Hooks(should_stop=lambda: True, progress=lambda *a: seen.append(a), on_incumbent=lambda o, b: None)
    p = run_solver(solver, problem, hooks, time_limit_s=20.0)
    assert_valid(solver, problem, p)
    assert p.status in ("interrupted", "optimal"), f"{solver.name}: status {p.status!r} after a stop request"


def check_time_limit_kept(solver: Solver) -> None:
    """Tag anytime: with time_limit_s = 0.5 on a moderate problem (400 x 2,000, about 40 k
    nonzeros) the solve call returns within the limit + 2 s, with a valid placement; a
    solve that ran past the limit reports status 'time_limit' (or 'optimal')."""
    problem = random_problem(8, n_g=400, n_p=2000, budget=20, n_loc=200, density=0.05)
    limit = 0.5
    start = {"nominal": solve_greedy(problem)} if solver.tags.needs_start else {}  # not on the solver's clock
    t0 = time.perf_counter()
    p = run_solver(solver, problem, time_limit_s=limit, **start)
    wall = time.perf_counter() - t0
    assert_valid(solver, problem, p)
    assert wall <= limit + 2.0, f"{solver.name}: {wall:.2f} s for a {limit} s time limit"
    if wall > limit + 0.1:
        assert p.status in ("time_limit", "optimal"), \
            f"{solver.name}: ran {wall:.2f} s on a {limit} s time limit but reported status {p.status!r}"


def check_incumbents_improve(solver: Solver) -> None:
    """on_incumbent(objective, bound): the objectives reported never rise and never go below
    the returned objective; every finite bound reported is <= the brute-force optimum."""
    for seed in SEEDS:
        problem = random_problem(20 + seed, n_g=8, n_p=14, budget=3)
        optimum, _ = brute_force_optimum(problem)
        calls: list[tuple[float, float | None]] = []
        p = run_solver(solver, problem, Hooks(on_incumbent=lambda o, b: calls.append((float(o), b))))
        assert_valid(solver, problem, p)
        objs = [o for o, _ in calls]
        tol = 1e-9 * max(1.0, abs(p.objective))
        worse = [(a, b) for a, b in zip(objs, objs[1:]) if b > a + tol]
        assert not worse, f"{solver.name}: on_incumbent objectives rose: {worse[0][0]} -> {worse[0][1]}"
        assert not objs or min(objs) >= p.objective - tol or solver.tags.robust_objective, \
            f"{solver.name}: on_incumbent reported {min(objs)}, better than the returned objective {p.objective}"
        bad = [b for _, b in calls if b is not None and np.isfinite(b) and b > optimum + 1e-6 * max(1.0, optimum)]
        assert not bad, f"{solver.name}: on_incumbent bound {bad[0]} above the optimum {optimum}"


def check_zero_budget(solver: Solver) -> None:
    """Budget 0: no camera, cost = Σ w Γ² (unless tagged ignores_camera_budget); nothing
    to cover: cost 0."""
    problem = random_problem(4, budget=0)
    p = run_solver(solver, problem)
    assert_valid(solver, problem, p)
    if not solver.tags.ignores_camera_budget:
        assert len(p.selected) == 0 and p.objective == problem.normalizer, f"{solver.name}: cameras at budget 0"
    empty = replace(random_problem(5), gamma=np.zeros(10, np.int64))
    p = run_solver(solver, empty)
    assert_valid(solver, empty, p)
    assert p.objective == 0.0, f"{solver.name}: cost {p.objective} with nothing to cover"


def check_same_seed_same_result(solver: Solver) -> None:
    """Tag deterministic_with_seed: two runs with one seed give the same selection."""
    for seed in SEEDS[:2]:
        problem = random_problem(10 + seed)
        a = run_solver(solver, problem, seed=seed)
        b = run_solver(solver, problem, seed=seed)
        assert np.array_equal(a.selected, b.selected), f"{solver.name}: seed {seed} gave two selections"


def check_unknown_option_refused(solver: Solver) -> None:
    """An option the solver does not declare is an InputError naming it."""
    from camplace.solvers.contract import split_options

    try:
        split_options(solver, {"no_such_option": 1})
    except InputError as err:
        assert err.option == "no_such_option" and "no_such_option" in str(err), str(err)
    else:
        raise AssertionError(f"{solver.name}: accepted an unknown option")
    try:
        solver(random_problem(0), no_such_option=1)
    except InputError:
        pass
    else:
        raise AssertionError(f"{solver.name}: solved with an unknown option")


def check_option_values_checked(solver: Solver) -> None:
    """Every option has a declared type, and a value that does not fit it is an InputError
    naming the option (from keywords as from the options type)."""
    types = _field_types(solver.options)
    for f in fields(solver.options):
        assert types.get(f.name, Any) is not Any, f"{solver.name}: option '{f.name}' has no type hint"
        if f.name in COMMON_FIELDS or types[f.name] is object:
            continue
        try:
            split_options(solver, {f.name: _NotAnOption()})
        except InputError as err:
            assert err.option == f.name and f.name in str(err), f"{solver.name}: {err}"
        else:
            raise AssertionError(f"{solver.name}: option '{f.name}' accepted a value of the wrong type")
    for key, bad in (("seed", "x"), ("time_limit_s", "soon"), ("threads", 1.5)):
        try:
            solver.options(**{key: bad})
        except InputError as err:
            assert err.option == key, f"{solver.name}: {err}"
        else:
            raise AssertionError(f"{solver.name}: {key}={bad!r} accepted")


class _NotAnOption:
    """A value no declared option type accepts."""

    def __repr__(self) -> str:
        return "<not an option>"


def check_money_budget_refused(solver: Solver) -> None:
    """Not tagged money_budget: a problem with a money budget is refused (InputError)."""
    problem = random_problem(0, priced=True)
    try:
        run_solver(solver, problem)
    except InputError as err:
        assert err.option == "solver", str(err)
    else:
        raise AssertionError(f"{solver.name}: tagged money_budget=False but solved a problem with a money budget")


def typed_problem(seed: int) -> PlacementProblem:
    """A random tiny problem with two camera types (ids 0, 1) and a limit on type 0 that
    binds: one camera fewer of it than the unconstrained optimum uses, and the optimum
    with the limit costs more (the first such problem from ``seed`` on)."""
    for s in range(seed, seed + 200):
        base = random_problem(s, n_g=8, n_p=12, budget=4, n_loc=6, density=0.45)
        types = np.random.default_rng(1000 + s).integers(0, 2, base.n_candidates)
        free = replace(base, type_ids=types)
        cost, sel = brute_force_optimum(free)
        n0 = int(np.sum(types[sel] == 0))
        if n0 == 0:
            continue
        limited = replace(free, type_limits={0: n0 - 1})
        if brute_force_optimum(limited)[0] > cost + 1e-9:
            return limited
    raise AssertionError(f"no problem with a binding type limit from seed {seed}")  # pragma: no cover


def check_type_limits_kept(solver: Solver) -> None:
    """Per-type limits (problem.type_limits): every selection keeps them; no cost below the
    constrained optimum (unless tagged ignores_camera_budget); tag exact: reaches it."""
    for seed in SEEDS:
        problem = typed_problem(10 * seed)
        optimum, _ = brute_force_optimum(problem)
        p = run_solver(solver, problem, time_limit_s=None if solver.tags.exact else TIME_LIMIT_S)
        assert_valid(solver, problem, p)
        if not solver.tags.ignores_camera_budget:
            assert p.objective >= optimum - 1e-9, f"{solver.name}: cost {p.objective} below the optimum {optimum}"
        if solver.tags.exact:
            assert abs(p.objective - optimum) <= 1e-6 * max(1.0, optimum), \
                f"{solver.name}: cost {p.objective} != constrained optimum {optimum}"


def checks_for(solver: Solver) -> list[Check]:
    """The checks that apply to ``solver`` by its tags."""
    out: list[Check] = [check_feasible_and_objective, check_bound_below_optimum, check_zero_budget,
                        check_unknown_option_refused, check_option_values_checked, check_type_limits_kept,
                        check_incumbents_improve]
    if not solver.tags.money_budget:
        out.append(check_money_budget_refused)
    if solver.tags.exact:
        out.append(check_exact_reaches_optimum)
    if solver.tags.anytime:
        out += [check_stop_request, check_time_limit_kept]
    if solver.tags.deterministic_with_seed:
        out.append(check_same_seed_same_result)
    return out


def run_check(check: Check, solver: Solver, time_s: float = CHECK_TIME_S, grace_s: float = CHECK_GRACE_S) -> None:
    """``check(solver)`` in a daemon thread: after ``time_s`` its solves are asked to stop
    (should_stop), and if it still runs ``grace_s`` later an AssertionError is raised here
    (the thread is left behind). The check's own AssertionError is re-raised."""
    out: dict[str, BaseException] = {}

    def work() -> None:
        _check_end.end = time.perf_counter() + time_s
        try:
            check(solver)
        except BaseException as err:  # noqa: BLE001 - handed to the calling thread
            out["error"] = err

    th = threading.Thread(target=work, name=f"camplace-check-{solver.name}", daemon=True)
    th.start()
    th.join(time_s + grace_s)
    if th.is_alive():
        raise AssertionError(f"{solver.name}: {getattr(check, '__name__', 'check')} did not finish within "
                             f"{time_s + grace_s:g} s (a solve that ignores its time limit and stop request?)")
    if "error" in out:
        raise out["error"]


def check_solver(solver: Solver, checks: Iterable[Check] | None = None, time_s: float = CHECK_TIME_S) -> None:
    """Run every applicable check (or ``checks``) on ``solver``, each under ``time_s``
    (:func:`run_check`); AssertionError on the first failure."""
    for check in (checks_for(solver) if checks is None else checks):
        run_check(check, solver, time_s)


def parametrize_with_checks(solvers: Mapping[str, Solver] | Iterable[Solver]):
    """pytest.mark.parametrize("solver, check") over every (solver, applicable check) pair,
    ids 'name-check'; each ``check(solver)`` call runs under its own time limit (:func:`run_check`)."""
    import pytest

    items = list(solvers.values()) if isinstance(solvers, Mapping) else list(solvers)
    cases = [(s, _limited(c)) for s in items for c in checks_for(s)]
    return pytest.mark.parametrize("solver, check", cases,
                                   ids=[f"{s.name}-{c.__name__.removeprefix('check_')}" for s, c in cases])


def _limited(check: Check) -> Check:
    """``check`` run by :func:`run_check` (same name)."""
    def limited(solver: Solver) -> None:
        run_check(check, solver)

    limited.__name__ = check.__name__
    return limited


__all__ = ["CHECK_TIME_S", "STATUSES", "assert_valid", "check_solver", "checks_for", "parametrize_with_checks",
           "random_problem", "run_check", "run_solver", "typed_problem"]
