"""camplace.solvers.local_search: the one swap search (first / best improvement) keeps every
rule (budget, one camera per location, money budget), never raises the cost, and stops at a
1-swap local optimum (checked by brute force over every single move)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from camplace.problem.model import PlacementProblem
from camplace.solvers.local_search import NominalObjective, swap_search


def _problem(seed: int, money: float | None) -> PlacementProblem:
    rng = np.random.default_rng(seed)
    n_g, n_p = 14, 20
    V = sp.csr_matrix((rng.random((n_g, n_p)) < 0.3).astype(np.uint8))
    return PlacementProblem(V, rng.integers(0, 4, n_p), rng.uniform(0.5, 2, n_p), 3, rng.integers(0, 8, n_g),
                            rng.choice([1.0, 2.0], n_g), money)


def _feasible(problem: PlacementProblem, sel) -> bool:
    try:
        problem.check_feasible(np.array(sorted(sel), np.int64))
    except ValueError:
        return False
    return True


def _single_moves(problem: PlacementProblem, sel: list[int]):
    """Every selection one add or one swap away."""
    outs = list(sel) + ([None] if len(sel) < problem.budget else [])
    for a in outs:
        for b in range(problem.n_candidates):
            if b in sel:
                continue
            s2 = [i for i in sel if i != a] + [b]
            if _feasible(problem, s2):
                yield s2


@pytest.mark.parametrize("first", [True, False])
@pytest.mark.parametrize("seed", range(6))
def test_swap_search_reaches_a_feasible_one_swap_optimum(seed, first):
    problem = _problem(seed, 4.0 if seed % 2 else None)
    sel, info = swap_search(problem, [], NominalObjective(problem), first_improvement=first)
    assert _feasible(problem, sel) and info["stopped"] == "converged"
    cost = problem.cost(np.array(sel, np.int64))
    assert cost <= problem.normalizer
    assert all(problem.cost(np.array(s2, np.int64)) >= cost - 1e-9 for s2 in _single_moves(problem, sel))


def test_swap_search_stops_on_request_and_at_max_passes():
    problem = _problem(1, None)
    _, info = swap_search(problem, [], NominalObjective(problem), should_stop=lambda: True)
    assert info["stopped"] == "interrupted" and info["moves"] == 0
    _, info = swap_search(problem, [], NominalObjective(problem), max_passes=1)
    assert info["stopped"] == "max_passes" and info["moves"] == 1
    with pytest.raises(ValueError):
        swap_search(problem, [], NominalObjective(problem), max_stall=3)
