"""Time limits are promises: every anytime solver ends within time_limit_s + 2 s on a
model too large for HiGHS / CBC to finish (issue 16), and returns a valid placement."""

from __future__ import annotations

import time

import numpy as np
import pytest
import scipy.sparse as sp

from camplace.problem.model import PlacementProblem
from camplace.solvers import SOLVERS, solve

LIMIT_S = 2.0
SLACK_S = 2.0
STATUSES = {"time_limit", "feasible", "optimal", "heuristic"}


def large_problem(n_candidates: int = 4000, n_targets: int = 20000, nnz: int = 1_500_000,
                  poses_per_location: int = 4, seed: int = 0) -> PlacementProblem:
    """A random sparse V (n_candidates x n_targets, about ``nnz`` entries), Γ = 3, unit
    weights, ``poses_per_location`` candidates per location, budget 40."""
    rng = np.random.default_rng(seed)
    rows = rng.integers(0, n_candidates, nnz)
    cols = rng.integers(0, n_targets, nnz)
    V = sp.csr_matrix((np.ones(nnz, np.uint8), (rows, cols)), shape=(n_candidates, n_targets))
    V.data[:] = 1
    return PlacementProblem(V, np.full(n_targets, 3, np.int64), np.ones(n_targets), 40,
                            np.arange(n_candidates) // poses_per_location)


@pytest.fixture(scope="module")
def problem() -> PlacementProblem:
    return large_problem()


TIMED = sorted(n for n, s in SOLVERS.items() if s.tags.anytime and not s.tags.needs_positions)


@pytest.mark.parametrize("name", TIMED)
def test_time_limit_is_kept_on_a_large_model(problem, name):
    t0 = time.perf_counter()
    p = solve(problem, name, time_limit_s=LIMIT_S)
    wall = time.perf_counter() - t0
    assert wall <= LIMIT_S + SLACK_S, f"{name}: {wall:.2f} s for a {LIMIT_S:g} s limit"
    assert p.status in STATUSES
    if SOLVERS[name].tags.ignores_camera_budget:
        assert len(np.unique(problem.location_ids[p.selected])) == len(p.selected)
    else:
        problem.check_feasible(p.selected)
    assert p.objective == pytest.approx(problem.cost(p.selected))
