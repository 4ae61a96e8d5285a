"""Solvers: one common suite that every registered solver must pass (like sklearn's
check_estimator), then solver-specific checks against brute force."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from camplace.problem import PlacementProblem, build_problem
from camplace.solvers import SOLVERS, solve

STATUSES = {"optimal", "feasible", "time_limit", "interrupted", "heuristic"}
EXACT = {"mip", "paper-mip"}  # proven optimal on tiny instances without a time limit


def brute_force(problem: PlacementProblem) -> tuple[float, np.ndarray]:
    """Optimal cost and one optimal selection by enumeration (tiny problems only)."""
    best, best_sel = problem.normalizer, np.zeros(0, np.int64)
    for k in range(1, min(problem.budget, problem.n_candidates) + 1):
        for c in itertools.combinations(range(problem.n_candidates), k):
            sel = np.array(c, np.int64)
            try:
                problem.check_feasible(sel)
            except ValueError:
                continue
            cost = problem.cost(sel)
            if cost < best:
                best, best_sel = cost, sel
    return best, best_sel


@st.composite
def tiny_problems(draw, max_g: int = 7, max_p: int = 8) -> PlacementProblem:
    n_g = draw(st.integers(1, max_g))
    n_p = draw(st.integers(1, max_p))
    dense = draw(st.lists(st.lists(st.booleans(), min_size=n_p, max_size=n_p), min_size=n_g, max_size=n_g))
    gamma = draw(st.lists(st.integers(0, 3), min_size=n_p, max_size=n_p))
    weights = draw(st.lists(st.sampled_from([1.0, 2.0, 0.5]), min_size=n_p, max_size=n_p))
    locs = draw(st.lists(st.integers(0, max(0, n_g - 2)), min_size=n_g, max_size=n_g))
    budget = draw(st.integers(0, 4))
    return build_problem(sp.csr_matrix(np.array(dense, np.uint8)), np.array(gamma), np.array(weights), budget,
                         np.array(locs))


def random_problem(rng: np.random.Generator, n_g: int, n_p: int, budget: int, density: float = 0.3,
                   n_loc: int | None = None, max_gamma: int = 3) -> PlacementProblem:
    V = sp.random(n_g, n_p, density=density, format="csr", random_state=rng, data_rvs=lambda k: np.ones(k))
    locs = rng.integers(0, n_loc or max(1, n_g // 3), n_g)
    return build_problem(V.astype(np.uint8), rng.integers(1, max_gamma + 1, n_p), None, budget, locs)


def check_placement(name: str, problem: PlacementProblem, p, optimum: float | None = None) -> None:
    """The common contract of every solver's Placement."""
    assert p.status in STATUSES, p.status
    sel = np.asarray(p.selected)
    assert sel.dtype.kind == "i"
    assert np.all(np.diff(sel) > 0), "selected must be sorted and unique"
    if getattr(SOLVERS[name], "ignores_budget", False):
        assert len(set(problem.location_ids[sel].tolist())) == len(sel)
    else:
        problem.check_feasible(sel)
    assert p.objective == pytest.approx(problem.cost(sel), rel=1e-9, abs=1e-9)
    assert p.seconds >= 0
    if p.bound is not None:
        assert p.bound <= p.objective + 1e-6 * max(1.0, p.objective)
        if optimum is not None:
            assert p.bound <= optimum + 1e-6 * max(1.0, optimum)
    if optimum is not None and not getattr(SOLVERS[name], "ignores_budget", False):
        assert p.objective >= optimum - 1e-9


@pytest.mark.parametrize("name", sorted(SOLVERS))
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problem=tiny_problems())
def test_common_contract(name, problem):
    optimum, _ = brute_force(problem)
    for reduce in (True, False):
        p = solve(problem, name, reduce=reduce, time_limit_s=30, threads=1)
        check_placement(name, problem, p, optimum)
        if name in EXACT:
            assert p.status == "optimal"
            assert p.objective == pytest.approx(optimum, abs=1e-6)


@pytest.mark.parametrize("name", sorted(SOLVERS))
def test_common_accepts_options_and_stop(name):
    """Every solver takes the common keyword options, and a stop request that is already
    set returns a feasible placement marked 'interrupted' (or a finished one)."""
    problem = random_problem(np.random.default_rng(3), 30, 60, 5)
    seen = []
    p = solve(problem, name, time_limit_s=20, threads=1, seed=1, should_stop=lambda: True,
              progress=lambda *a: seen.append(a), on_incumbent=lambda o, b: None, unknown_but_common=1)
    check_placement(name, problem, p)
    assert p.status in {"interrupted", "optimal", "heuristic", "feasible"}


@pytest.mark.parametrize("name", sorted(SOLVERS))
def test_common_zero_budget_and_empty(name):
    problem = random_problem(np.random.default_rng(4), 6, 10, 0)
    p = solve(problem, name)
    check_placement(name, problem, p)
    if not getattr(SOLVERS[name], "ignores_budget", False):
        assert len(p.selected) == 0 and p.objective == problem.normalizer
    zero = build_problem(sp.csr_matrix((3, 4), dtype=np.uint8), np.zeros(4, np.int64), None, 2)
    p = solve(zero, name)
    assert p.objective == 0.0
