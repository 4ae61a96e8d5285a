"""Every bound of camplace.solvers.bounds is <= the brute-force optimum on small random instances."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import small_problems, small_random_problem

from camplace.problem.model import brute_force_optimum, feasible_selections
from camplace.solvers.bounds import (Lagrangian, fixing_bounds, lagrangian_bound, lp_bound, reduce_by_fixing,
                                     solve_reduced_mip)


random_problem = small_random_problem
problems = small_problems()


def brute_force(p):
    """(optimal cost, one optimal selection); enumeration is over at most `budget` cameras."""
    return brute_force_optimum(p, max_candidates=64)


FAST = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@FAST
@given(problems, st.integers(0, 1000))
def test_lagrangian_value_below_optimum_for_any_multipliers(p, seed):
    opt, _ = brute_force(p)
    lg = Lagrangian(p)
    rng = np.random.default_rng(seed)
    for lam in (np.zeros(p.n_targets), lg.initial_multipliers(), rng.uniform(0, 8, p.n_targets)):
        val, g, chosen = lg.evaluate(lam)
        assert val <= opt + 1e-7
        assert chosen.sum() <= p.budget
        assert len(set(p.location_ids[chosen].tolist())) == int(chosen.sum())


@FAST
@given(problems)
def test_lagrangian_bound_below_optimum(p):
    opt, sel = brute_force(p)
    res = lagrangian_bound(p, time_limit_s=2.0, max_iter=300, incumbent_cost=opt, coverage=p.coverage(sel))
    assert res.method == "lagrangian"
    assert 0.0 <= res.bound <= opt + 1e-7


@FAST
@given(problems)
def test_lp_bound_below_optimum(p):
    opt, _ = brute_force(p)
    res = lp_bound(p)
    assert res.info["status"] == "optimal"
    assert res.bound <= opt + 1e-6


@FAST
@given(problems, st.integers(0, 1000))
def test_fixing_bounds_below_restricted_optima(p, seed):
    """bound_in[i] <= best cost with i selected; bound_out[L] <= best cost with L empty."""
    lg = Lagrangian(p)
    lam = np.random.default_rng(seed).uniform(0, 6, p.n_targets)
    b_in, b_out, L = fixing_bounds(lg, lam)
    assert L == pytest.approx(lg.evaluate(lam)[0])
    uniq = np.unique(p.location_ids)
    best_in = np.full(p.n_candidates, np.inf)
    best_out = np.full(len(uniq), np.inf)
    for s in feasible_selections(p):
        c = p.cost(s)
        for i in s:
            best_in[i] = min(best_in[i], c)
        used = np.isin(uniq, p.location_ids[s])
        best_out[~used] = np.minimum(best_out[~used], c)
    assert np.all(b_in <= best_in + 1e-7)
    assert np.all(b_out <= best_out + 1e-7)


@FAST
@given(problems, st.integers(0, 1000))
def test_reduced_mip_bound_below_optimum(p, seed):
    opt, sel = brute_force(p)
    # an upper bound no better than the optimum (an incumbent), and a Lagrangian λ
    ub = opt + float(np.random.default_rng(seed).integers(0, 3))
    res = lagrangian_bound(p, time_limit_s=1.0, max_iter=100, incumbent_cost=ub)
    red = reduce_by_fixing(p, res.multipliers, ub)
    # every optimal selection strictly below ub survives the reduction
    if opt < ub - 1e-9:
        assert np.all(red.keep[sel])
        assert np.all(np.isin(red.forced, p.location_ids[sel]))
    bound, better, info = solve_reduced_mip(p, red, sel if np.all(red.keep[sel]) else None, time_limit_s=10)
    assert bound <= opt + 1e-6
    if better is not None:
        p.check_feasible(better)
        assert p.cost(better) >= opt - 1e-9


def test_lagrangian_reaches_lp_on_a_small_instance():
    """Subgradient ascent gets within 2 % of the LP bound (they share the same dual)."""
    p = random_problem(7, n_g=30, n_p=60, budget=5, n_loc=12, density=0.3)
    lp = lp_bound(p).bound
    lag = lagrangian_bound(p, time_limit_s=5.0, max_iter=3000).bound
    assert lag <= lp + 1e-6
    assert lag >= 0.98 * lp
