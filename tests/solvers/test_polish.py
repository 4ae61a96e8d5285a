"""greedy-polish: never worse than greedy, feasible, and its bound (full-problem
Lagrangian) is below the true optimum."""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp

from camplace.problem.model import build_problem
from camplace.solvers.greedy_fast import solve_greedy_fast
from camplace.solvers.polish import restricted_candidates, solve_greedy_polish


def _problem(seed, n_g=40, n_p=50, budget=4, n_loc=14, density=0.15):
    rng = np.random.default_rng(seed)
    V = sp.random(n_g, n_p, density=density, format="csr", random_state=rng, data_rvs=lambda k: np.ones(k))
    return build_problem(V.astype(np.uint8), rng.integers(1, 4, n_p), None, budget, rng.integers(0, n_loc, n_g))


def _optimum(p):
    best = p.normalizer
    for k in range(1, p.budget + 1):
        for c in itertools.combinations(range(p.n_candidates), k):
            sel = np.array(c)
            if len(set(p.location_ids[sel])) == k:
                best = min(best, p.cost(sel))
    return best


def test_restricted_set_holds_selection_and_best_others():
    p = _problem(0)
    g = solve_greedy_fast(p)
    R = restricted_candidates(p, g.selected, 5)
    assert np.all(np.isin(g.selected, R)) and np.all(np.diff(R) > 0)
    at = np.isin(p.location_ids, p.location_ids[g.selected])
    assert np.all(np.isin(np.flatnonzero(at), R))  # every pose at a chosen location
    assert (~at[R]).sum() <= 5


def test_never_worse_than_greedy_and_bound_below_optimum():
    for seed in range(4):
        p = _problem(seed, n_g=14, n_p=20, budget=3, n_loc=8, density=0.25)
        g = solve_greedy_fast(p)
        out = solve_greedy_polish(p, mip_time_s=5, bound_time_s=1)
        p.check_feasible(out.selected)
        assert out.objective == p.cost(out.selected) <= g.objective
        opt = _optimum(p)
        assert out.objective >= opt - 1e-9
        if out.bound is not None:
            assert out.bound <= opt + 1e-6
        if out.status == "optimal":
            assert out.objective == opt


def test_small_warehouse():
    from camplace.workflows.run import prepare, problem_from_visibility
    from camplace.solvers import solve

    _, vis = prepare("warehouse:200")
    p = problem_from_visibility(vis, 10)
    g = solve(p, "greedy-fast")
    out = solve(p, "greedy-polish", mip_time_s=2, bound_time_s=1)
    assert out.objective <= g.objective
    assert out.bound is None or out.bound <= out.objective
