"""The swap descent that counts the people seen by Γ^p cameras (camplace.improve.people, issue 36)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from hypothesis import given, settings, strategies as st

from camplace.improve.people import PeopleCountObjective, people_swap
from camplace.problem.gains import target_gains
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


def random_people_problem(seed: int):
    """(problem: 8 candidates, 4 empty-store targets then 3 people of 2 points, budget 3, shared
    locations; start (4); H (2); its greedy selection)."""
    rng = np.random.default_rng(seed)
    n, start, H = 8, 4, 2
    V = sp.csr_matrix((rng.random((n, start + 3 * H)) < 0.4).astype(np.uint8))
    p = PlacementProblem(V, rng.integers(1, 3, V.shape[1]), rng.random(V.shape[1]) + 0.1, 3,
                         rng.integers(0, 5, n))
    return p, start, H, solve(p, "greedy").selected


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 3.0))
def test_the_descent_never_raises_its_objective(seed, beta):
    """Empty-store targets then people (2 points each): J after ≤ J before, the budget and
    one camera per location kept, and the objective's value() is J."""
    p, start, H, start_sel = random_people_problem(seed)
    sel, _ = people_swap(p, start_sel, start, H, beta)
    assert J(p, sel, start, H, beta) <= J(p, start_sel, start, H, beta) + 1e-12
    assert len(sel) <= p.budget and len(np.unique(p.location_ids[sel])) == len(sel)
    obj = PeopleCountObjective(p, start, H, beta)
    assert abs(obj.value(p.coverage(sel)) - J(p, sel, start, H, beta)) < 1e-12


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 3.0))
def test_pose_scores_are_the_drop_of_the_objective(seed, beta):
    """The refinement's pose_score of a row = J(others) − J(others + that row)."""
    rng = np.random.default_rng(seed)
    start, H = 3, 2
    V = sp.csr_matrix((rng.random((6, start + 4 * H)) < 0.4).astype(np.uint8))
    p = PlacementProblem(V, rng.integers(1, 3, V.shape[1]), rng.random(V.shape[1]) + 0.1, 3, np.arange(6))
    obj = PeopleCountObjective(p, start, H, beta)
    cov = p.coverage(np.array([0, 1]))
    got = obj.pose_scores(V[2:], target_gains(p.gamma, p.weights, cov), cov)
    want = [obj.value(cov) - obj.value(cov + V[i].toarray().ravel()) for i in range(2, 6)]
    assert np.allclose(got, want, atol=1e-12)


# the cost cap (issue 36): one empty-store target T (Γ 1, weight 3), then people A and B (Γ 2, one point each);
# cameras 0 and 1 see A and B, camera 2 sees T alone; two cameras
CAPPED = PlacementProblem(sp.csr_matrix(np.array([[0, 1, 1], [0, 1, 1], [1, 0, 0]], np.uint8)),
                          np.array([1, 2, 2], np.int64), np.array([3.0, 1.0, 1.0]), 2, np.arange(3))


def test_the_cap_refuses_a_swap_the_uncapped_descent_takes():
    """From {0, 2} (E = 0, nobody seen twice; J = 2 / 11) swapping 2 for 1 sees A and B twice
    and leaves T unseen: J = 3 / 11 − 1 with β = 1, so the uncapped descent takes it; E rises
    from 0 to 3, so a cap of E ≤ 2 refuses it and one of E ≤ 3 does not."""
    assert people_swap(CAPPED, np.array([0, 2]), 1, 1, 1.0)[0].tolist() == [0, 1]
    sel, info = people_swap(CAPPED, np.array([0, 2]), 1, 1, 1.0, cost_limit=2.0)
    assert sel.tolist() == [0, 2] and info["moves"] == 0
    assert people_swap(CAPPED, np.array([0, 2]), 1, 1, 1.0, cost_limit=3.0)[0].tolist() == [0, 1]
    # the refinement's pose score: camera 1's view joining camera 0 lifts E to 3 (−inf), camera 2's keeps E = 0
    obj = PeopleCountObjective(CAPPED, 1, 1, 1.0, cost_limit=2.0)
    cov = CAPPED.coverage(np.array([0]))
    s = obj.pose_scores(CAPPED.V[1:], target_gains(CAPPED.gamma, CAPPED.weights, cov), cov)
    assert s[0] == -np.inf and np.isfinite(s[1])
    assert (obj.empty_cost(cov), obj.empty_cost_with(CAPPED.V[1:, :1], cov).tolist()) == (3.0, [3.0, 0.0])


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(0.0, 3.0), st.floats(0.0, 2.0))
def test_the_capped_descent_never_ends_above_its_cap(seed, beta, rise):
    """E (the empty-store part's cost) after the capped descent ≤ max(limit, E at the start):
    a start at or below the cap ends at or below it; one above it never rises."""
    p, start, H, start_sel = random_people_problem(seed)
    obj = PeopleCountObjective(p, start, H, beta)
    e0 = obj.empty_cost(p.coverage(start_sel))
    limit = rise * e0  # below the start's E when rise < 1
    sel, _ = people_swap(p, start_sel, start, H, beta, cost_limit=limit)
    assert obj.empty_cost(p.coverage(sel)) <= max(limit, e0) + 1e-9
    assert J(p, sel, start, H, beta) <= J(p, start_sel, start, H, beta) + 1e-12
