"""The swap descent that counts the people seen by Γ^p cameras (camplace.improve.people, issue 36)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from hypothesis import given, settings, strategies as st

from camplace.improve.people import PeopleCountObjective, people_swap
from camplace.problem.model import PlacementProblem
from camplace.problem.people import persons_seen
from camplace.solvers import solve


def people_only(V, budget: int) -> PlacementProblem:
    """A people-only crowd problem: one point per person (H = 1), Γ 2, weight 1."""
    V = sp.csr_matrix(np.asarray(V, np.uint8))
    return PlacementProblem(V, np.full(V.shape[1], 2, np.int64), np.ones(V.shape[1]), budget, np.arange(V.shape[0]))


# five people A..E; cameras 0 and 1 both see A and B, cameras 2, 3, 4 see C, D, E alone
HAND = people_only([[1, 1, 0, 0, 0], [1, 1, 0, 0, 0], [0, 0, 1, 0, 0], [0, 0, 0, 1, 0], [0, 0, 0, 0, 1]], 2)


def test_squared_buys_first_views_the_count_buys_triangulations():
    """Squared cost, two cameras: {0, 2} costs 1 + 1 + 1 + 4 + 4 = 11 (nobody seen twice),
    {0, 1} costs 4 · 3 = 12 (A and B seen twice), so greedy takes {0, 2}. With β = 1,
    J({0, 2}) = 11 / 20 and J({0, 1}) = 12 / 20 − 2 / 5: the descent swaps camera 2 for 1."""
    g = solve(HAND, "greedy")
    assert g.selected.tolist() == [0, 2] and g.objective == 11.0
    sel, info = people_swap(HAND, g.selected, 0, 1, 1.0)
    assert sel.tolist() == [0, 1] and HAND.cost(sel) == 12.0
    assert (info["people_seen_before"], info["people_seen"], info["people"], info["moves"]) == (0, 2, 5, 1)
    # β small: one person is worth less than the squared cost the swap adds (1 / 20 > 2 · 0.01 / 5): no move
    assert people_swap(HAND, g.selected, 0, 1, 0.01)[0].tolist() == [0, 2]


def J(problem, sel, start, H, beta):
    cov = problem.coverage(np.asarray(sel, np.int64))
    n_persons = (problem.n_targets - start) // H
    return (problem.cost(np.asarray(sel, np.int64)) / problem.normalizer
            - beta / n_persons * persons_seen(cov[start:], problem.gamma[start:], H))


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 3.0))
def test_the_descent_never_raises_its_objective(seed, beta):
    """Empty-store targets then people (2 points each): J after ≤ J before, the budget and
    one camera per location kept, and the objective's value() is J."""
    rng = np.random.default_rng(seed)
    n, start, H = 8, 4, 2
    V = sp.csr_matrix((rng.random((n, start + 3 * H)) < 0.4).astype(np.uint8))
    p = PlacementProblem(V, rng.integers(1, 3, V.shape[1]), rng.random(V.shape[1]) + 0.1, 3,
                         rng.integers(0, 5, n))
    start_sel = solve(p, "greedy").selected
    sel, _ = people_swap(p, start_sel, start, H, beta)
    assert J(p, sel, start, H, beta) <= J(p, start_sel, start, H, beta) + 1e-12
    assert len(sel) <= p.budget and len(np.unique(p.location_ids[sel])) == len(sel)
    obj = PeopleCountObjective(p, start, H, beta)
    assert abs(obj.value(p.coverage(sel)) - J(p, sel, start, H, beta)) < 1e-12


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 3.0))
def test_pose_scores_are_the_drop_of_the_objective(seed, beta):
    """The refinement's pose_score of a row = J(others) − J(others + that row)."""
    from camplace.problem.gains import target_gains

    rng = np.random.default_rng(seed)
    start, H = 3, 2
    V = sp.csr_matrix((rng.random((6, start + 4 * H)) < 0.4).astype(np.uint8))
    p = PlacementProblem(V, rng.integers(1, 3, V.shape[1]), rng.random(V.shape[1]) + 0.1, 3, np.arange(6))
    obj = PeopleCountObjective(p, start, H, beta)
    cov = p.coverage(np.array([0, 1]))
    got = obj.pose_scores(V[2:], target_gains(p.gamma, p.weights, cov), cov)
    want = [obj.value(cov) - obj.value(cov + V[i].toarray().ravel()) for i in range(2, 6)]
    assert np.allclose(got, want, atol=1e-12)
