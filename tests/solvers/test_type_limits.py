"""Per-type limits (issue 17): at most n cameras of a camera type, kept by every solver."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp

from camplace.core.errors import InputError
from camplace.problem.model import PlacementProblem, brute_force_optimum, reduce_problem
from camplace.solvers import SOLVERS, solve

WIDE, FISHEYE = 0, 1


def fisheye_problem(limit: int | None = 2) -> PlacementProblem:
    """Nine targets (Γ = 1) in three groups of three. Fisheyes F0, F1, F2 each see one whole
    group, F3 sees target 0 only; wides W0, W1, W2 each see two targets of one group. Budget
    3: without a limit the optimum is F0 F1 F2 (cost 0, three fisheyes); with at most two
    fisheyes it is two fisheyes and the wide of the third group (one target short: cost 1)."""
    rows = [[0, 1, 2], [3, 4, 5], [6, 7, 8], [0], [0, 1], [3, 4], [6, 7]]
    dense = np.zeros((7, 9), np.uint8)
    for i, r in enumerate(rows):
        dense[i, r] = 1
    types = np.array([FISHEYE] * 4 + [WIDE] * 3)
    return PlacementProblem(sp.csr_matrix(dense), np.ones(9, np.int64), np.ones(9), 3, np.arange(7),
                            type_ids=types, type_limits=None if limit is None else {FISHEYE: limit})


def test_unconstrained_optimum_uses_three_fisheyes():
    cost, sel = brute_force_optimum(fisheye_problem(None))
    assert cost == 0.0 and sel.tolist() == [0, 1, 2]


@pytest.mark.parametrize("name", ["mip", "greedy", "tabu"])
def test_limit_two_fisheyes(name):
    problem = fisheye_problem(2)
    p = solve(problem, name, time_limit_s=5.0)
    sel = p.selected
    assert int(np.sum(problem.type_ids[sel] == FISHEYE)) == 2
    assert problem.type_ok(sel)
    assert p.objective == pytest.approx(1.0)  # two whole groups + two of the third
    wides = sel[problem.type_ids[sel] == WIDE]
    assert len(wides) == 1  # the wide of the group no fisheye covers
    group = {4: {0, 1, 2}, 5: {3, 4, 5}, 6: {6, 7, 8}}[int(wides[0])]
    fish_targets = set(problem.V[sel[problem.type_ids[sel] == FISHEYE]].indices.tolist())
    assert not group & fish_targets


@pytest.mark.parametrize("name", sorted(SOLVERS))
def test_every_solver_keeps_the_limit(name):
    problem = fisheye_problem(2)
    kw = {"time_limit_s": 5.0}
    if SOLVERS[name].tags.needs_positions:
        rng = np.random.default_rng(0)
        problem = replace(problem, candidate_positions=rng.uniform(0, 10, (7, 3)),
                          target_positions=rng.uniform(0, 10, (9, 3)))
    if SOLVERS[name].tags.needs_start:
        kw["nominal"] = solve(problem, "greedy")
    p = solve(problem, name, **kw)
    assert problem.type_ok(p.selected), (name, p.selected)


def test_limit_zero_forbids_the_type():
    problem = fisheye_problem(0)
    p = solve(problem, "greedy")
    assert p.selected.tolist() == [4, 5, 6] and p.objective == pytest.approx(3.0)


def test_helpers_and_feasibility():
    problem = fisheye_problem(2)
    assert problem.type_counts(np.array([0, 1, 4])) == {FISHEYE: 2}
    assert problem.type_full(np.array([0, 1])).tolist() == [True] * 4 + [False] * 3
    assert not problem.type_ok(np.array([0, 1, 2]))
    with pytest.raises(ValueError, match="per type"):
        problem.check_feasible(np.array([0, 1, 2]))
    A, limits = problem.type_rows()
    assert A.shape == (1, 7) and A.toarray().tolist() == [[1, 1, 1, 1, 0, 0, 0]] and limits.tolist() == [2.0]
    with pytest.raises(InputError, match="type_ids"):
        replace(problem, type_ids=None)
    with pytest.raises(InputError, match="type_limits"):
        replace(problem, type_limits={FISHEYE: -1})


def test_reduction_keeps_types_and_dominance_respects_them():
    # location 0: a wide seeing {0} and a fisheye seeing {0, 1}; location 1: a fisheye seeing
    # {1, 2}. With fisheyes limited the fisheye may not stand in for the wide (it would use
    # the limit), so all three stay
    V = sp.csr_matrix(np.array([[1, 0, 0], [1, 1, 0], [0, 1, 1]], np.uint8))
    base = PlacementProblem(V, np.ones(3, np.int64), np.ones(3), 2, np.array([0, 0, 1]),
                            type_ids=np.array([WIDE, FISHEYE, FISHEYE]))
    assert reduce_problem(base).candidates.tolist() == [1, 2]  # no limit: the wide is dominated
    limited = replace(base, type_limits={FISHEYE: 1})
    red = reduce_problem(limited)
    assert red.candidates.tolist() == [0, 1, 2]
    assert red.problem.type_ids.tolist() == [WIDE, FISHEYE, FISHEYE] and red.problem.type_limits == {FISHEYE: 1}
    # optimum with one fisheye: the wide at location 0 and the fisheye at location 1 (cost 0)
    p = solve(limited, "mip")
    assert p.objective == 0.0 and p.selected.tolist() == [0, 2]
