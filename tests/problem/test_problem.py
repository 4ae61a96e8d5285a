"""camplace.problem.model: cost, feasibility and the optimum-preserving reductions."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from camplace.problem.model import (PlacementProblem, brute_force_optimum, build_problem, dominated_candidates,
                              reduce_problem)


def optimum(problem: PlacementProblem) -> float:
    return brute_force_optimum(problem)[0]


@st.composite
def problems(draw):
    n_g = draw(st.integers(1, 7))
    n_p = draw(st.integers(1, 8))
    dense = draw(st.lists(st.lists(st.booleans(), min_size=n_p, max_size=n_p), min_size=n_g, max_size=n_g))
    gamma = np.array(draw(st.lists(st.integers(0, 3), min_size=n_p, max_size=n_p)))
    weights = np.array(draw(st.lists(st.sampled_from([0.0, 1.0, 2.5]), min_size=n_p, max_size=n_p)))
    locs = np.array(draw(st.lists(st.integers(0, 2), min_size=n_g, max_size=n_g)))
    costs = np.array(draw(st.lists(st.sampled_from([1.0, 2.0]), min_size=n_g, max_size=n_g)))
    money = draw(st.sampled_from([None, 3.0]))
    return PlacementProblem(sp.csr_matrix(np.array(dense, np.uint8)), gamma, weights, draw(st.integers(0, 4)), locs,
                            costs, money)


@settings(max_examples=60, deadline=None)
@given(problem=problems())
def test_reductions_never_change_the_optimum(problem):
    red = reduce_problem(problem)
    assert optimum(red.problem) == pytest.approx(optimum(problem))
    assert red.problem.normalizer == pytest.approx(problem.normalizer)


@settings(max_examples=60, deadline=None)
@given(problem=problems(), data=st.data())
def test_lifted_selection_has_the_same_cost_and_stays_feasible(problem, data):
    red = reduce_problem(problem)
    n = red.problem.n_candidates
    sel = np.array(sorted(data.draw(st.sets(st.integers(0, max(0, n - 1)), max_size=min(n, 3)))), np.int64)
    if n == 0:
        sel = sel[:0]
    lifted = red.lift(sel)
    assert problem.cost(lifted) == pytest.approx(red.problem.cost(sel))
    try:
        red.problem.check_feasible(sel)
    except ValueError:
        return
    problem.check_feasible(lifted)


def test_merge_identical_columns_sums_weights():
    V = sp.csr_matrix(np.array([[1, 1, 0, 1], [0, 0, 1, 0]], np.uint8))
    # targets 0, 1, 3 have the same column; 3 needs Γ = 2 so it stays apart
    red = reduce_problem(build_problem(V, np.array([1, 1, 1, 2]), np.array([1.0, 2.0, 1.0, 1.0]), 1))
    assert red.problem.n_targets == 3
    assert red.info["merged_targets"] == 1
    assert sorted(red.problem.weights.tolist()) == [1.0, 1.0, 3.0]
    assert red.target_map[0] == red.target_map[1] != red.target_map[3]


def test_drop_blind_and_zero_targets():
    V = sp.csr_matrix(np.array([[1, 0, 0], [0, 0, 0], [0, 1, 0]], np.uint8))
    red = reduce_problem(build_problem(V, np.array([2, 0, 1]), None, 2))
    # target 1 has Γ = 0: dropped; then candidates 1 and 2 see nothing; target 2 (seen by
    # nobody) stays: its cost is a constant that the normalizer and the cost must keep
    assert red.info["dropped_zero_targets"] == 1
    assert red.info["dropped_blind_candidates"] == 2
    assert red.candidates.tolist() == [0]
    assert red.info["candidates_before"] == 3 and red.info["candidates_after"] == 1
    assert red.info["targets_before"] == 3 and red.info["targets_after"] == 2
    assert red.problem.cost(np.array([0])) == 2.0  # (2 - 1)² + (1 - 0)²


def test_dominance_only_within_a_location():
    V = sp.csr_matrix(np.array([[1, 1, 0], [1, 0, 0], [1, 0, 0], [1, 1, 1]], np.uint8))
    # 1 ⊆ 0 at location 0: dropped; 2 ⊆ 3 but at another location than 3: kept
    dom = dominated_candidates(V, np.array([0, 0, 1, 2]), np.ones(4))
    assert dom.tolist() == [False, True, False, False]
    # identical rows at one location: the lower id survives; a pricier superset does not dominate
    V2 = sp.csr_matrix(np.array([[1, 0], [1, 0], [1, 1]], np.uint8))
    dom = dominated_candidates(V2, np.zeros(3, np.int64), np.array([1.0, 1.0, 5.0]))
    assert dom.tolist() == [False, True, False]


def test_cost_and_feasibility():
    V = sp.csr_matrix(np.array([[1, 1], [0, 1]], np.uint8))
    p = build_problem(V, np.array([3, 1]), np.array([1.0, 2.0]), 1, np.array([0, 0]))
    assert p.normalizer == 9 + 2
    assert p.cost(np.array([0])) == 4.0
    with pytest.raises(ValueError):
        p.check_feasible(np.array([0, 1]))
