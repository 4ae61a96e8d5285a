"""camplace.problem.gains: numpy and numba gains, losses and costs against brute force
(the cost recomputed from scratch), on small hypothesis-drawn problems with the edges:
Γ = 0, coverage above Γ, zero weights, empty rows."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from camplace.problem import gains
from camplace.problem.model import PlacementProblem


def _cost(problem: PlacementProblem, cov: np.ndarray) -> float:
    """Brute force: Σ_j w_j max(Γ_j − c_j, 0)² by a Python loop."""
    return float(sum(w * max(int(g) - int(c), 0) ** 2 for g, w, c in zip(problem.gamma, problem.weights, cov)))


@st.composite
def problems(draw):
    """(problem, selection, coverage (N_p,) int64 with extra views on top of the selection's)."""
    n_g = draw(st.integers(1, 7))
    n_p = draw(st.integers(1, 9))
    dense = np.array(draw(st.lists(st.booleans(), min_size=n_g * n_p, max_size=n_g * n_p)), np.uint8)
    V = sp.csr_matrix(dense.reshape(n_g, n_p))
    gamma = np.array(draw(st.lists(st.integers(0, 4), min_size=n_p, max_size=n_p)), np.int64)
    weights = np.array(draw(st.lists(st.sampled_from([0.0, 0.5, 1.0, 1.75, 3.0]), min_size=n_p, max_size=n_p)))
    problem = PlacementProblem(V, gamma, weights, n_g, np.arange(n_g, dtype=np.int64))
    sel = np.flatnonzero(draw(st.lists(st.booleans(), min_size=n_g, max_size=n_g))).astype(np.int64)
    extra = np.array(draw(st.lists(st.integers(0, 5), min_size=n_p, max_size=n_p)), np.int64)
    return problem, sel, problem.coverage(sel) + extra


def _nb_args(problem: PlacementProblem):
    V = problem.V
    return V.indptr.astype(np.int64), V.indices.astype(np.int64), problem.gamma, problem.weights.astype(np.float64)


@settings(max_examples=120, deadline=None)
@given(problems())
def test_costs_match_brute_force(drawn):
    problem, sel, cov = drawn
    assert gains.shortfall_cost(problem.gamma, problem.weights, cov) == pytest.approx(_cost(problem, cov))
    assert gains.target_costs(problem.gamma, problem.weights, cov).sum() == pytest.approx(_cost(problem, cov))
    assert problem.cost(sel) == pytest.approx(_cost(problem, problem.coverage(sel)))
    assert np.all(gains.shortfall(problem.gamma, cov) >= 0)


@settings(max_examples=120, deadline=None)
@given(problems())
def test_add_gains_numpy_numba_brute_force(drawn):
    problem, _, cov = drawn
    indptr, indices, gamma, w = _nb_args(problem)
    vec = gains.marginal_gains(problem, cov)
    assert vec.shape == (problem.n_candidates,)
    base = _cost(problem, cov)
    for i in range(problem.n_candidates):
        after = cov.copy()
        after[gains.row(problem.V, i)] += 1
        brute = base - _cost(problem, after)
        assert vec[i] == pytest.approx(brute)
        assert gains.row_gain(problem, i, cov) == pytest.approx(brute)
        assert gains.row_gain_nb(i, indptr, indices, gamma, w, cov) == pytest.approx(brute)
    tg = gains.target_gains(problem.gamma, problem.weights, cov)
    nb = np.array([gains.target_gain_nb(w[j], gamma[j], cov[j]) for j in range(problem.n_targets)])
    assert np.array_equal(tg, nb)  # the same numbers, bit for bit
    assert np.all(tg >= 0) and np.all(tg[(problem.gamma <= cov) | (problem.weights == 0)] == 0)


@settings(max_examples=120, deadline=None)
@given(problems())
def test_removal_losses_numpy_numba_brute_force(drawn):
    problem, sel, _ = drawn
    cov = problem.coverage(sel)
    indptr, indices, gamma, w = _nb_args(problem)
    losses = gains.removal_losses(problem, sel)
    assert losses.shape == (len(sel),)
    assert np.array_equal(losses, gains.removal_losses(problem, sel, cov))
    for k, i in enumerate(sel):
        brute = problem.cost(np.delete(sel, k)) - problem.cost(sel)
        assert losses[k] == pytest.approx(brute)
        assert gains.row_loss_nb(i, indptr, indices, gamma, w, cov) == pytest.approx(brute)
    tl = gains.target_losses(problem.gamma, problem.weights, cov)
    assert np.array_equal(tl, gains.target_gains(problem.gamma, problem.weights, cov - 1))


def test_edges_empty_rows_zero_gamma_and_no_selection():
    V = sp.csr_matrix(np.array([[0, 0, 0], [1, 1, 0]], np.uint8))
    problem = PlacementProblem(V, np.array([0, 2, 1]), np.array([1.0, 0.0, 2.0]), 2, np.arange(2))
    cov = np.zeros(3, np.int64)
    assert gains.marginal_gains(problem, cov).tolist() == [0.0, 0.0]  # empty row; Γ = 0; zero weight
    assert gains.row_gain(problem, 0, cov) == 0.0
    assert gains.removal_losses(problem, np.zeros(0, np.int64)).shape == (0,)
    assert gains.shortfall_cost(problem.gamma, problem.weights, np.array([5, 5, 5])) == 0.0
    assert gains.target_gains(problem.gamma, problem.weights, np.array([0, 0, 0])).tolist() == [0.0, 0.0, 2.0]
