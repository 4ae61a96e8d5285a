"""Solver options from one source (the solver's declared keywords): values converted to the
declared type or refused with an InputError naming the option; a money budget refused by a
solver that cannot keep it; the stricter conformance checks catch the solvers that break them."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.solvers import SOLVERS, Placement, build_options, solve
from camplace.solvers.contract import Tags, describe_type, make_solver
from camplace.solvers.testing import (check_incumbents_improve, check_money_budget_refused,
                                      check_option_values_checked, check_solver, check_time_limit_kept,
                                      random_problem, run_check)


def test_values_are_converted_to_the_declared_type():
    o = build_options("tabu", chunk="30", max_stall_restarts="none", seed="3", time_limit_s=2)
    assert (o.chunk, o.max_stall_restarts, o.seed, o.time_limit_s) == (30, None, 3, 2.0)
    assert isinstance(o.time_limit_s, float)
    assert build_options("mip", verbose="true").verbose is True
    assert build_options("zones", initial="[3, 1]").initial == (3, 1)
    assert build_options("paper-mip", engine="highs").engine == "highs"


@pytest.mark.parametrize("solver, key, value, expect", [
    ("tabu", "chunk", "x", "chunk: expected an integer (solver 'tabu'), got 'x'"),
    ("tabu", "k_rcl", 2.5, "k_rcl: expected an integer"),
    ("mip", "mip_rel_gap", "tiny", "mip_rel_gap: expected a number or none"),
    ("mip", "fixing", "maybe", "fixing: expected true or false"),
    ("greedy", "seed", None, "seed: expected an integer"),
    ("greedy", "time_limit_s", "soon", "time_limit_s: expected a number or none"),
])
def test_bad_values_name_the_option_and_the_type(solver, key, value, expect):
    for call in (lambda: build_options(solver, **{key: value}), lambda: SOLVERS[solver].options(**{key: value}),
                 lambda: solve(random_problem(0), solver, **{key: value})):
        with pytest.raises(InputError) as err:
            call()
        assert str(err.value).startswith(expect) and err.value.option == key


def test_unknown_option_names_the_takers():
    with pytest.raises(InputError, match="^coverage_gap: solver 'mip' takes no option 'coverage_gap'; solvers that "
                                         "take it: min-cameras") as err:
        solve(random_problem(0), "mip", coverage_gap=0.1)
    assert err.value.option == "coverage_gap"


def test_describe_type():
    assert describe_type(int | None) == "an integer or none"
    assert describe_type(np.ndarray | None) == "an array or none"
    assert describe_type(tuple) == "a list"


def _fn(body):
    """A tiny solver implementation around ``body(problem, **hooks) -> (ids, status, name)``."""

    def solve_fn(problem, *, time_limit_s: float | None = None, threads: int | None = None, seed: int = 0,
                 should_stop=None, progress=None, on_incumbent=None, tries: int = 3) -> Placement:
        t0 = time.perf_counter()
        sel, status, name = body(problem, time_limit_s=time_limit_s, should_stop=should_stop,
                                 on_incumbent=on_incumbent)
        sel = np.asarray(sorted(sel), np.int64)
        return Placement(sel, problem.cost(sel), None, status, name, time.perf_counter() - t0)

    return solve_fn


def _first(problem):
    """Cameras 0, 1, ... at distinct locations up to the budget, within the money budget."""
    out, locs, spent = [], set(), 0.0
    for i in range(problem.n_candidates):
        price = float(problem.costs[i])
        if len(out) < problem.budget and problem.location_ids[i] not in locs and (
                problem.money_budget is None or spent + price <= problem.money_budget):
            out.append(i)
            locs.add(problem.location_ids[i])
            spent += price
    return out


def test_a_solver_that_cannot_keep_a_money_budget_is_refused():
    s = make_solver("plain", _fn(lambda p, **k: (_first(p), "heuristic", "plain")), Tags(money_budget=False))
    with pytest.raises(InputError, match="^solver: 'plain' cannot keep a money budget") as err:
        s(random_problem(0, priced=True))
    assert err.value.option == "solver"
    check_money_budget_refused(s)
    assert s(random_problem(0)).solver == "plain"  # without a money budget it runs


def test_conformance_catches_a_wrong_solver_name():
    s = make_solver("named", _fn(lambda p, **k: (_first(p), "heuristic", "greedy")))
    with pytest.raises(AssertionError, match="Placement.solver is 'greedy'"):
        check_solver(s)


def test_conformance_catches_rising_incumbents():
    def body(p, on_incumbent=None, **k):
        sel = _first(p)
        if on_incumbent:
            on_incumbent(p.cost(np.asarray(sel[:1], np.int64)), None)
            on_incumbent(p.normalizer + 1.0, None)
        return sel, "heuristic", "rising"

    s = make_solver("rising", _fn(body))
    with pytest.raises(AssertionError, match="objectives rose"):
        check_incumbents_improve(s)


def test_conformance_catches_a_time_limit_reported_as_heuristic():
    def body(p, time_limit_s=None, **k):
        time.sleep(0.7 if time_limit_s == 0.5 else 0.0)
        return _first(p), "heuristic", "slow"

    s = make_solver("slow", _fn(body))
    with pytest.raises(AssertionError, match="reported status 'heuristic'"):
        check_time_limit_kept(s)


def test_a_solver_that_ignores_its_limits_fails_instead_of_hanging():
    release = threading.Event()

    def body(p, **k):
        release.wait(60.0)  # ignores the time limit and should_stop
        return _first(p), "heuristic", "stuck"

    s = make_solver("stuck", _fn(body))
    t0 = time.perf_counter()
    try:
        with pytest.raises(AssertionError, match="did not finish within 1.5 s"):
            run_check(check_time_limit_kept, s, time_s=1.0, grace_s=0.5)
    finally:
        release.set()
    assert time.perf_counter() - t0 < 5.0


def test_conformance_catches_an_untyped_option():
    def solve_untyped(problem, *, time_limit_s: float | None = None, threads: int | None = None, seed: int = 0,
                      should_stop=None, progress=None, on_incumbent=None, tries=3) -> Placement:
        sel = np.asarray(_first(problem), np.int64)
        return Placement(sel, problem.cost(sel), None, "heuristic", "untyped", 0.0)

    with pytest.raises(AssertionError, match="option 'tries' has no type hint"):
        check_option_values_checked(make_solver("untyped", solve_untyped))


def test_a_default_that_does_not_fit_its_type_is_a_contract_error():
    def solve_bad(problem, *, time_limit_s: float | None = None, threads: int | None = None, seed: int = 0,
                  should_stop=None, progress=None, on_incumbent=None, tries: int = "three") -> Placement:
        raise AssertionError("never called")

    with pytest.raises(TypeError, match="bad: the default of option tries: expected an integer"):
        make_solver("bad", solve_bad)
