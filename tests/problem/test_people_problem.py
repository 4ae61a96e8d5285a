"""The crowd-aware problem (camplace.problem.people, issue 36): the mixed cost by hand."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from hypothesis import given, settings, strategies as st

from camplace.problem.gains import shortfall_cost
from camplace.problem.model import PlacementProblem
from camplace.problem.people import mixed_rows, people_problem, persons_completed, persons_seen


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


def test_people_seen_and_completed_by_hand():
    """Two people, torso and head, Γ 2. Person 0 is one view short at its torso, person 1
    two views short at its torso: a camera completes person 0 only if it sees its torso."""
    cov = np.array([1, 2, 0, 1])
    gamma = np.full(4, 2)
    V = sp.csr_matrix(np.array([[1, 0, 0, 0],    # person 0's torso: completes it
                                [0, 1, 0, 0],    # person 0's head: already at Γ
                                [0, 0, 1, 1],    # person 1: torso 0 -> 1, not enough
                                [1, 1, 1, 1]], np.uint8))
    assert persons_seen(cov, gamma, 2) == 0 and persons_seen(cov + 1, gamma, 2) == 1
    assert persons_completed(V, cov, gamma, 2).tolist() == [1, 0, 0, 1]
    assert persons_completed(V, np.array([2, 2, 1, 1]), gamma, 2).tolist() == [0, 0, 1, 1]


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(1, 3))
def test_completed_is_the_count_after_adding_the_row(seed, H):
    rng = np.random.default_rng(seed)
    n_persons = int(rng.integers(0, 6))
    gamma = rng.integers(0, 4, n_persons * H)
    cov = rng.integers(0, 4, n_persons * H)
    V = sp.csr_matrix((rng.random((5, n_persons * H)) < 0.5).astype(np.uint8))
    got = persons_completed(V, cov, gamma, H)
    want = [persons_seen(cov + V[i].toarray().ravel(), gamma, H) - persons_seen(cov, gamma, H) for i in range(5)]
    assert got.tolist() == want
