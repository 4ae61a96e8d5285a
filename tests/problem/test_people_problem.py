"""The crowd-aware problem (camplace.problem.people, issue 36): the mixed cost by hand."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from hypothesis import given, settings, strategies as st

from camplace.problem.gains import shortfall_cost
from camplace.problem.model import PlacementProblem
from camplace.problem.people import mixed_rows, people_problem


def problem(V) -> PlacementProblem:
    V = sp.csr_matrix(np.asarray(V, np.uint8))
    return PlacementProblem(V, np.full(V.shape[1], 2, np.int64), np.ones(V.shape[1]), 2, np.arange(V.shape[0]))


def test_known_mixed_cost():
    p = problem([[1, 0], [0, 1], [1, 1]])  # N = 2 · 4 = 8
    P = sp.csr_matrix(np.array([[1], [1], [0]], np.uint8))  # one person point, Γ 2, weight 1: N^p = 4
    m = people_problem(p, P, np.array([2]), np.array([1.0]), 0.5)
    assert m.n_targets == 3 and m.normalizer == 8.0
    # {0, 1}: empty store 1 + 1 = 2, person covered twice (0); {2}: empty 1 + 1, person 4 -> 0.5 · 2 · 4 = 4
    assert m.cost(np.array([0, 1])) == 0.5 * 2 and m.cost(np.array([2])) == 0.5 * 2 + 0.5 * 2 * 4
    only = people_problem(p, P, np.array([2]), np.array([1.0]), 1.0)
    assert only.n_targets == 1 and only.cost(np.array([0, 1])) == 0.0 and only.cost(np.array([2])) == 8.0
    assert mixed_rows(p.V[:1], P[:1], 1.0).toarray().tolist() == [[1]]
    assert mixed_rows(p.V[:1], P[:1], 0.3).toarray().tolist() == [[1, 0, 1]]


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 1.0))
def test_mixed_cost_is_the_weighted_sum_of_both_parts(seed, lam):
    rng = np.random.default_rng(seed)
    V = rng.random((6, 9)) < 0.4
    P = sp.csr_matrix((rng.random((6, 5)) < 0.4).astype(np.uint8))
    g_p, w_p = rng.integers(1, 4, 5), rng.random(5) + 0.1
    p = problem(V)
    m = people_problem(p, P, g_p, w_p, lam)
    x = np.flatnonzero(rng.random(6) < 0.5)
    n, n_p = p.normalizer, float(np.dot(w_p, g_p ** 2))
    want = (1 - lam) * p.cost(x) + lam * n / n_p * shortfall_cost(g_p, w_p, np.asarray(P[x].sum(axis=0)).ravel())
    assert abs(m.cost(x) - want) <= 1e-9 * max(1.0, want)
    assert abs(m.normalizer - n) <= 1e-9 * n
