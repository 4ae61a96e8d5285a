"""The region-decomposition bound (camplace.solvers.region_bound) is <= the brute-force
optimum on small random instances, for any prices, and beats the LP where it should."""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import small_problems, small_random_problem

from camplace.problem.model import PlacementProblem, brute_force_optimum
from camplace.solvers.bounds import Lagrangian, lp_bound
from camplace.solvers.region_bound import RegionDecomposition, max_over_x, region_bound, target_regions


random_problem = small_random_problem
problems = small_problems()


def brute_force(p: PlacementProblem) -> float:
    return brute_force_optimum(p)[0]


FAST = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@FAST
@given(problems, st.integers(1, 4), st.integers(0, 1000))
def test_decomposition_below_optimum_for_any_prices(p, k, seed):
    opt = brute_force(p)
    labels = target_regions(p, k, seed=seed)
    dec = RegionDecomposition(p, labels)
    rng = np.random.default_rng(seed)
    lam = rng.uniform(0, 6, p.n_targets)
    price_sets = [dec.initial_prices(lam)] + [[rng.normal(0, 4, len(r.cand)) for r in dec.regions] for _ in range(2)]
    for mus in price_sets:
        value, ys, x0, n_opt = dec.evaluate(mus, region_time_s=5.0)
        assert value <= opt + 1e-6
        # the HiGHS models are re-used across prices: a fresh decomposition gives the same value
        fresh, _, _, n_fresh = RegionDecomposition(p, labels).evaluate(mus, region_time_s=5.0)
        if n_opt == n_fresh == len(dec.regions):
            assert abs(fresh - value) <= 1e-6 * max(1.0, abs(value))
        assert x0.sum() <= p.budget
        for r, y in zip(dec.regions, ys):
            assert y.shape == (len(r.cand),)


@FAST
@given(problems, st.integers(1, 3), st.integers(0, 1000))
def test_region_bound_below_optimum_and_above_its_lagrangian(p, k, seed):
    opt = brute_force(p)
    lam = np.random.default_rng(seed).uniform(0, 6, p.n_targets)
    res = region_bound(p, lam=lam, n_regions=k, time_limit_s=10.0, max_iter=6, seed=seed)
    assert res.bound <= opt + 1e-6
    # started from μ_R = V_R λ_R the first evaluation is never below L(λ)
    L = Lagrangian(p).evaluate(lam)[0]
    assert res.info["first"] is None or res.info["first"] >= L - 1e-6
    assert res.bound >= max(L, 0.0) * (1 - 1e-7) - 1e-6  # (shaved by 1e-7 relative)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 8), st.integers(1, 4), st.integers(0, 3))
def test_max_over_x_is_exact(seed, n, n_loc, budget):
    rng = np.random.default_rng(seed)
    r = rng.normal(0, 2, n)
    loc = rng.integers(0, n_loc, n)
    val, x = max_over_x(r, loc, n_loc, budget)
    best = 0.0
    for k in range(budget + 1):
        for comb in itertools.combinations(range(n), k):
            if len(set(loc[list(comb)].tolist())) == k:
                best = max(best, float(r[list(comb)].sum()))
    assert abs(val - best) < 1e-9
    assert abs(float(np.dot(r, x)) - val) < 1e-9 and x.sum() <= budget
    assert len(set(loc[x > 0].tolist())) == int(x.sum())


def hand_built() -> PlacementProblem:
    """7 candidates on 5 locations, 6 targets, budget 2: the LP spreads fractions of
    cameras and reaches 15, every placement costs at least 16."""
    V = np.array([[0, 1, 1, 1, 0, 1], [1, 1, 0, 0, 0, 1], [0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 1, 1],
                  [1, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0], [1, 0, 1, 0, 0, 1]], np.uint8)
    return PlacementProblem(sp.csr_matrix(V), np.array([3, 2, 1, 2, 1, 2]), np.array([3.0, 2, 2, 2, 3, 1]), 2,
                            np.array([2, 1, 0, 4, 1, 1, 4]))


def test_region_bound_strictly_above_lp_on_hand_built_instance():
    p = hand_built()
    opt = brute_force(p)
    lp = lp_bound(p).bound
    assert opt == 16.0 and lp < 15.0 + 1e-6  # a real integrality gap
    lpr = lp_bound(p)
    lam = np.maximum(lpr.info["row_dual"][:p.n_targets], 0.0)  # the LP duals: L(λ) is the LP bound
    assert abs(Lagrangian(p).evaluate(lam)[0] - lp) < 1e-5
    labels = np.array([0, 1, 0, 1, 0, 1])  # two regions of three targets
    res = region_bound(p, lam=lam, labels=labels, time_limit_s=20.0, max_iter=60, incumbent_cost=opt)
    assert res.info["first"] >= lp - 1e-6  # at the LP duals the decomposition is never below the LP
    assert res.bound <= opt + 1e-6
    assert res.bound > lp + 0.5  # strictly past the LP: each region's subproblem is integer
    assert np.ceil(res.bound - 1e-6) == opt  # integer costs: rounded up, it proves the optimum


def test_one_region_at_zero_prices_is_the_exact_optimum():
    # with a single region and μ = 0 the decomposition is the MIP itself
    p = hand_built()
    labels = np.zeros(p.n_targets, np.int64)
    dec = RegionDecomposition(p, labels)
    value, _, _, n_opt = dec.evaluate([np.zeros(len(dec.regions[0].cand))], region_time_s=10.0)
    assert n_opt == 1 and abs(value - brute_force(p)) < 1e-6


def test_deterministic():
    p = random_problem(7, n_g=9, n_p=10, budget=3)
    a = region_bound(p, n_regions=2, time_limit_s=30.0, max_iter=8, seed=3)
    b = region_bound(p, n_regions=2, time_limit_s=30.0, max_iter=8, seed=3)
    assert a.bound == b.bound and a.info["history"] == b.info["history"]


def test_certify_with_region_bound_proves_the_hand_built_optimum():
    from camplace.solvers.certify import solve_certify
    from camplace.solvers.region_bound import METHOD, PARTIAL_METHOD

    p = hand_built()
    res = solve_certify(p, time_limit_s=8.0, threads=1, seed=0, region=True, reduced_mip=False)
    assert res.objective == p.cost(res.selected) == 16.0
    assert res.bound <= 16.0 + 1e-9
    assert res.status == "optimal"  # the LP alone proves only 15
    assert res.info["bound_method"] in (METHOD, PARTIAL_METHOD)
    assert res.info["region"]["start"] == "lp duals"
    assert max(res.info["region"]["bound"] or 0.0, res.info["region"]["partial_bound"]) \
        > res.info["region"]["start_bound"] + 0.5


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems, st.booleans())
def test_certify_with_region_bound_below_optimum(p, use_lp):
    from camplace.solvers.certify import solve_certify

    opt = brute_force(p)
    res = solve_certify(p, time_limit_s=1.0, threads=1, seed=0, region=True, lp=use_lp, reduced_mip=False)
    assert res.bound <= opt + 1e-6
    assert res.objective == p.cost(res.selected) and res.objective >= opt - 1e-9


@FAST
@given(problems, st.integers(0, 1000))
def test_partial_lagrangian_below_optimum_and_above_lagrangian(p, seed):
    from camplace.solvers.region_bound import costly_region, partial_lagrangian_bound

    opt = brute_force(p)
    rng = np.random.default_rng(seed)
    lam = rng.uniform(0, 6, p.n_targets)
    L = Lagrangian(p).evaluate(lam)[0]
    for region in (rng.random(p.n_targets) < 0.5, costly_region(p, lam, share=0.5, n_regions=2, seed=seed)):
        res = partial_lagrangian_bound(p, lam, region, time_limit_s=5.0)
        assert res.bound <= opt + 1e-6
        assert res.bound >= max(L, 0.0) * (1 - 1e-7) - 1e-6


def test_partial_lagrangian_strictly_above_lp_on_hand_built_instance():
    from camplace.solvers.region_bound import partial_lagrangian_bound

    p = hand_built()
    lpr = lp_bound(p)
    lam = np.maximum(lpr.info["row_dual"][:p.n_targets], 0.0)
    res = partial_lagrangian_bound(p, lam, np.array([1, 3, 5]), time_limit_s=10.0)
    assert lpr.bound < 15.0 + 1e-6 and res.bound <= 16.0 + 1e-9
    assert res.bound > lpr.bound + 0.5  # targets 1, 3, 5 exact with the budget: the optimum, 16
