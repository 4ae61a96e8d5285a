"""CELF greedy: optimal where greedy provably is, consistent cost, constraints held."""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from camplace.problem.model import build_problem
from camplace.solvers import solve


def brute_force(problem):
    best = (problem.cost([]), ())
    n = problem.n_candidates
    for k in range(1, problem.budget + 1):
        for sel in itertools.combinations(range(n), k):
            if len(set(problem.location_ids[list(sel)])) < k:
                continue
            c = problem.cost(list(sel))
            if c < best[0]:
                best = (c, sel)
    return best


def random_problem(seed, n_g=7, n_p=12, budget=3, n_loc=None, gamma_max=3, density=0.35):
    rng = np.random.default_rng(seed)
    V = sp.csr_matrix((rng.random((n_g, n_p)) < density).astype(np.uint8))
    gamma = rng.integers(0, gamma_max + 1, n_p)
    weights = rng.integers(1, 4, n_p).astype(float)
    loc = rng.integers(0, n_loc, n_g) if n_loc else None
    return build_problem(V, gamma, weights, budget, loc)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6))
def test_budget_one_greedy_is_optimal(seed):
    p = random_problem(seed, budget=1)
    assert solve(p, "greedy").objective == brute_force(p)[0]


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6), st.integers(1, 4))
def test_disjoint_views_gamma_one_greedy_is_optimal(seed, budget):
    # every target seen by one candidate only and Γ <= 1: the cost is modular, greedy is exact
    rng = np.random.default_rng(seed)
    n_g, n_p = 6, 15
    owner = rng.integers(0, n_g, n_p)
    V = sp.csr_matrix((np.ones(n_p, np.uint8), (owner, np.arange(n_p))), shape=(n_g, n_p))
    p = build_problem(V, rng.integers(0, 2, n_p), rng.integers(1, 5, n_p).astype(float), budget)
    assert solve(p, "greedy").objective == brute_force(p)[0]


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10**6), st.integers(0, 5), st.sampled_from([None, 3, 5]))
def test_greedy_feasible_and_cost_recomputes(seed, budget, n_loc):
    p = random_problem(seed, n_g=10, budget=budget, n_loc=n_loc)
    pl = solve(p, "greedy")
    p.check_feasible(pl.selected)
    assert pl.objective == p.cost(pl.selected)
    assert pl.objective <= p.cost([])


def test_greedy_respects_one_camera_per_location():
    # two candidates at one location each see everything; the third sees half
    V = sp.csr_matrix(np.array([[1, 1, 1, 1], [1, 1, 1, 1], [1, 1, 0, 0]], np.uint8))
    p = build_problem(V, np.array([2, 2, 2, 2]), None, 3, np.array([0, 0, 1]))
    pl = solve(p, "greedy")
    assert sorted(pl.selected.tolist()) == [0, 2]
    assert pl.objective == 1 + 1  # targets 2, 3 short by one each: 1² + 1²


def test_greedy_lazy_equals_eager():
    for seed in range(30):
        p = random_problem(seed, n_g=12, n_p=30, budget=4, n_loc=8)
        lazy = solve(p, "greedy")
        # eager reference: recompute every gain every step
        cov = np.zeros(p.n_targets, np.int64)
        chosen, locs = [], set()
        for _ in range(p.budget):
            d = np.maximum(p.gamma - cov, 0)
            g = p.V @ np.where(d > 0, p.weights * (2 * d - 1), 0.0)
            g[[i for i in range(p.n_candidates) if p.location_ids[i] in locs or i in chosen]] = -1
            i = int(np.argmax(g))
            if g[i] <= 0:
                break
            chosen.append(i)
            locs.add(p.location_ids[i])
            cov += p.V[i].toarray()[0]
        assert lazy.objective == p.cost(chosen)
