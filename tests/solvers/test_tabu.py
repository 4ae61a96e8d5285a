"""Tabu search: feasible incumbents, exact reported costs, reproducible for a seed."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from camplace.problem.model import PlacementProblem
from camplace.solvers import SOLVERS, solve
from camplace.solvers.greedy import solve_greedy
from camplace.solvers.tabu import TabuSearch, solve_tabu
from tests.solvers.test_bounds import brute_force, problems, random_problem

FAST = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@FAST
@given(problems, st.integers(0, 100))
def test_incumbent_feasible_and_cost_exact(p: PlacementProblem, seed):
    r = solve_tabu(p, max_iterations=60, seed=seed)
    p.check_feasible(r.selected)
    assert r.objective == p.cost(r.selected)
    opt, _ = brute_force(p)
    assert r.objective >= opt - 1e-9


@FAST
@given(problems)
def test_tiny_instances_solved_to_optimum(p):
    """On instances this small 300 iterations with restarts find the brute-force optimum."""
    opt, _ = brute_force(p)
    r = solve_tabu(p, max_iterations=300, seed=1)
    assert r.objective <= opt + 1e-9


def test_incremental_state_matches_recomputation():
    """After many moves the kept coverage, gains and cost equal a fresh computation."""
    p = random_problem(3, n_g=60, n_p=80, budget=8, n_loc=20, density=0.2, weighted=True)
    ts = TabuSearch(p, seed=5, stall_limit=15)
    ts.run(200)
    sel = np.flatnonzero(ts.sel)
    assert np.array_equal(ts.cov, p.coverage(sel))
    assert abs(ts.fst[0] - p.cost(sel)) < 1e-6
    d = np.maximum(p.gamma - ts.cov, 0)
    unit = np.where(d > 0, p.weights * (2 * d - 1), 0.0)
    assert np.allclose(ts.gain, p.V @ unit)
    assert abs(ts.best_cost - p.cost(ts.best_selected)) < 1e-6
    assert ts.restarts > 0


def test_same_seed_same_result_and_no_worse_than_greedy():
    p = random_problem(11, n_g=120, n_p=150, budget=10, n_loc=40, density=0.1)
    a = solve_tabu(p, max_iterations=150, seed=3)
    b = solve_tabu(p, max_iterations=150, seed=3)
    assert np.array_equal(a.selected, b.selected) and a.objective == b.objective
    assert a.objective <= solve_greedy(p).objective
    p.check_feasible(a.selected)


def test_registered_and_time_limited():
    assert "tabu" in SOLVERS
    p = random_problem(2, n_g=40, n_p=50, budget=5, n_loc=15)
    seen = []
    r = solve(p, "tabu", time_limit_s=0.3, on_incumbent=lambda o, b: seen.append(o), max_stall_restarts=None)
    assert r.seconds < 5 and r.status == "time_limit"
    assert seen and seen[-1] == r.objective and seen == sorted(seen, reverse=True)
    stop = solve_tabu(p, should_stop=lambda: True)
    assert stop.status == "interrupted"
    p.check_feasible(stop.selected)


def test_zero_budget_and_empty():
    p = random_problem(1, budget=0)
    r = solve_tabu(p, max_iterations=10)
    assert len(r.selected) == 0 and r.objective == p.normalizer


def test_stops_when_converged():
    """On a tiny instance the search stops long before a generous time limit."""
    p = random_problem(12, n_g=8, n_p=10, budget=2, n_loc=4)
    r = solve_tabu(p, time_limit_s=30, max_stall_restarts=20)
    assert r.seconds < 10 and r.status == "heuristic"
    assert r.objective == brute_force(p)[0]
