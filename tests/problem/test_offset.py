"""The coverage offset of a part of a problem (camplace.problem.offset)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from camplace.problem.gains import shortfall_cost
from camplace.problem.model import PlacementProblem
from camplace.problem.offset import offset_gamma, offset_subproblem


def test_offset_gamma_clips_at_zero():
    assert offset_gamma(np.array([3, 1, 0, 2]), np.array([1, 4, 0, 2])).tolist() == [2, 0, 0, 0]


def test_part_cost_plus_outside_constant_is_the_full_cost():
    for seed in range(20):
        rng = np.random.default_rng(seed)
        n_g, n_p = 12, 30
        V = sp.csr_matrix((rng.random((n_g, n_p)) < 0.3).astype(np.uint8))
        p = PlacementProblem(V, rng.integers(0, 4, n_p), rng.uniform(0.5, 2, n_p), 6, np.arange(n_g),
                             rng.integers(1, 3, n_g).astype(float), 10.0)
        rows = np.sort(rng.choice(n_g, 5, replace=False))
        cols = np.unique(V[rows].indices)
        fixed = np.setdiff1d(rng.choice(n_g, 3, replace=False), rows)
        cov_out = p.coverage(fixed)
        sub = offset_subproblem(p, rows, cols, cov_out, budget=2, money_budget=3.0)
        assert sub.V.shape == (5, len(cols)) and sub.budget == 2 and sub.money_budget == 3.0
        assert np.array_equal(sub.costs, p.costs[rows])
        rest = np.setdiff1d(np.arange(n_p), cols)
        const = shortfall_cost(p.gamma[rest], p.weights[rest], cov_out[rest])
        for k in range(4):
            local = np.sort(rng.choice(5, k, replace=False))
            full = p.cost(np.union1d(fixed, rows[local]))
            assert abs(sub.cost(local) + const - full) <= 1e-9 * max(1.0, full)
