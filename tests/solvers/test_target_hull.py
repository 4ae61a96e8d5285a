"""The per-target decomposition bound (camplace.solvers.target_hull): ≤ the brute-force
optimum for any prices, ≥ the coverage-row Lagrangian at its start, never above the LP,
and the per-target convex hull of the shortfall adds nothing to the LP (docs/certify.md §10)."""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp
from conftest import small_problems, small_random_problem
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog

from camplace.problem.model import PlacementProblem, brute_force_optimum
from camplace.solvers.bounds import Lagrangian, tight_model_arrays
from camplace.solvers.target_hull import TargetDecomposition, target_hull_bound

FAST = settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _lp(c, A_ub, b_ub, A_eq=None, b_eq=None, n=0) -> float:
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=[(0, 1)] * n, method="highs")
    assert res.status == 0
    return float(res.fun)


def standard_lp(p: PlacementProblem) -> float:
    """The convex model's LP (certify.md §0, §5) by scipy's HiGHS."""
    A, cost, _, _, row_lo, row_hi, _ = tight_model_arrays(p)
    A = sp.csr_matrix(A)
    up, down = np.isfinite(row_hi), np.isfinite(row_lo)
    A_ub = sp.vstack([A[up], -A[down]])
    b_ub = np.concatenate([row_hi[up], -row_lo[down]])
    return _lp(cost, A_ub, b_ub, n=len(cost))


def hull_lp(p: PlacementProblem) -> float:
    """The LP with each target's shortfall replaced by its convex hull over the target's
    own feasible copies X_j (all subsets of the candidates seeing j, ≤ N, ≤ 1 per
    location), linked to x ∈ conv X: columns x (N_g), then θ_js per target and copy."""
    V = sp.csc_matrix(p.V)
    n_g = p.n_candidates
    cost, eq_rows, eq_b, cols = [0.0] * n_g, [], [], n_g
    blocks = []
    for j in range(p.n_targets):
        cand = V.indices[V.indptr[j]:V.indptr[j + 1]]
        copies = [s for k in range(min(len(cand), p.budget) + 1) for s in itertools.combinations(cand, k)
                  if len({int(p.location_ids[i]) for i in s}) == len(s)]
        blocks.append((cand, copies, cols))
        cost += [p.weights[j] * max(int(p.gamma[j]) - len(s), 0) ** 2 for s in copies]
        cols += len(copies)
    A_eq = np.zeros((0, cols))
    for cand, copies, c0 in blocks:
        row = np.zeros(cols)
        row[c0:c0 + len(copies)] = 1.0
        eq_rows.append(row), eq_b.append(1.0)  # Σ_s θ_js = 1
        for i in cand:
            row = np.zeros(cols)
            row[c0:c0 + len(copies)] = [float(i in s) for s in copies]
            row[i] = -1.0
            eq_rows.append(row), eq_b.append(0.0)  # Σ_s θ_js [i ∈ s] = x_i
    A_eq = np.array(eq_rows) if eq_rows else A_eq
    _, loc = np.unique(p.location_ids, return_inverse=True)
    A_ub = np.zeros((1 + loc.max() + 1, cols))
    A_ub[0, :n_g] = 1.0
    A_ub[1 + loc, np.arange(n_g)] = 1.0
    b_ub = np.concatenate([[p.budget], np.ones(loc.max() + 1)])
    return _lp(np.array(cost), A_ub, b_ub, A_eq, np.array(eq_b), n=cols)


@FAST
@given(small_problems(), st.integers(0, 1000))
def test_bound_below_optimum_for_any_prices(p, seed):
    opt = brute_force_optimum(p)[0]
    dec = TargetDecomposition.of(p)
    rng = np.random.default_rng(seed)
    lam = rng.uniform(0, 6, p.n_targets)
    for mu in (dec.initial_prices(lam), rng.normal(0, 4, len(dec.ent_cand)), np.zeros(len(dec.ent_cand))):
        value, g = dec.evaluate(mu)
        assert value <= opt + 1e-9
        assert g.shape == mu.shape and set(np.unique(g)) <= {-1.0, 0.0, 1.0}


@FAST
@given(small_problems(), st.integers(0, 1000))
def test_ascent_between_lagrangian_and_lp(p, seed):
    lam = np.random.default_rng(seed).uniform(0, 6, p.n_targets)
    L = Lagrangian(p).evaluate(lam)[0]
    res = target_hull_bound(p, lam, time_limit_s=2.0, max_iter=200)
    assert res.info["start"] >= L - 1e-9  # μ_ij = λ_j: never below L(λ)
    assert res.bound >= res.info["start"] - 1e-9 or res.bound == 0.0
    assert res.bound <= brute_force_optimum(p)[0] + 1e-9
    assert res.bound <= standard_lp(p) + 1e-6  # its maximum is the LP (§10)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 10**6), st.integers(1, 6), st.integers(1, 5), st.integers(0, 3), st.integers(1, 4),
       st.floats(0.2, 0.8), st.booleans())
def test_per_target_hull_is_the_lp(seed, n_g, n_p, budget, n_loc, density, weighted):
    """§10's theorem: the shortfall's piecewise-linear model is already the convex hull of
    each target's cost over its feasible copies, so the hull LP equals the standard LP."""
    p = small_random_problem(seed, n_g=n_g, n_p=n_p, budget=budget, n_loc=n_loc, density=density, weighted=weighted)
    assert abs(hull_lp(p) - standard_lp(p)) <= 1e-6 * max(1.0, standard_lp(p))


def test_copy_respects_the_budget_by_hand():
    """One target (Γ = 2) seen from two locations, budget 1: OPT = 1. At μ = 0 a copy
    of ≤ N = 1 camera leaves deficit 1, so the bound is 1 (the LP is 1 as well)."""
    V = sp.csr_matrix(np.array([[1], [1]], np.uint8))
    p = PlacementProblem(V, np.array([2]), np.array([1.0]), 1, np.array([0, 1]))
    dec = TargetDecomposition.of(p)
    value, _ = dec.evaluate(np.zeros(2))
    assert value == 1.0 == brute_force_optimum(p)[0]
    # prices that charge the copy 0.5 a camera and pay it back through x: still ≤ 1
    assert dec.evaluate(np.array([0.5, 0.5]))[0] <= 1.0


def test_start_lifts_a_target_seen_from_fewer_locations_than_gamma():
    """Γ = 3, one location sees the target, budget 2, λ = 1: the Lagrangian's u-part buys
    no unit (slope 1 is not below λ), u-part = λΓ = 3, x-part = 1, L = 2; the copy can hold
    one camera only: h = min(9, (3 − 1)² + 1) = 5, bound 5 − 1 = 4 = OPT (deficit 2)."""
    V = sp.csr_matrix(np.array([[1]], np.uint8))
    p = PlacementProblem(V, np.array([3]), np.array([1.0]), 2, np.array([0]))
    lam = np.array([1.0])
    dec = TargetDecomposition.of(p)
    assert Lagrangian(p).evaluate(lam)[0] == 2.0
    assert dec.evaluate(dec.initial_prices(lam))[0] == 4.0 == brute_force_optimum(p)[0]
