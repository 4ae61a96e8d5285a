"""The triangulation-aware greedy (camplace.solvers.greedy_triangulated): positions come with the problem."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp

from camplace.core.errors import InputError
from camplace.problem.triangulation import effective_coverage
from camplace.problem.model import build_problem, shortfall_cost
from camplace.solvers import solve

FACING = np.array([[-2.0, 0.0, 1.0], [2.0, 0.0, 1.0]])  # two cameras facing each other across (0, 0, 1)
P = np.array([0.0, 0.0, 1.0])


def test_triangulated_greedy_prefers_a_usable_pair():
    # target at P, Γ = 2. Candidates: 0 and 1 face each other (180 deg), 2 is above.
    cands = np.r_[FACING, [[0.0, 0.0, 3.0]]]
    V = sp.csr_matrix(np.ones((3, 1), np.uint8))
    prob = replace(build_problem(V, np.array([2]), None, 2), candidate_positions=cands, target_positions=P[None])
    p = solve(prob, "greedy-triangulated")
    assert 2 in p.selected.tolist()  # a facing pair would leave the effective coverage at 0
    assert p.info["triangulated_cost"] == 0.0
    eff = effective_coverage(V[p.selected], cands[p.selected], P[None])
    assert eff.tolist() == [2]


def test_triangulated_greedy_beats_plain_greedy_on_its_own_cost(demo_run):
    r = demo_run
    vis = r.visibility
    prob = replace(r.problem, budget=6)
    plain = solve(prob, "greedy").selected
    assert prob.candidate_positions is not None and prob.target_positions is not None  # set by the workflow
    tri = solve(prob, "greedy-triangulated")
    prob.check_feasible(tri.selected)
    eff_plain = effective_coverage(vis.V[plain], vis.candidates.positions[plain], vis.targets.positions)
    eff_tri = effective_coverage(vis.V[tri.selected], vis.candidates.positions[tri.selected], vis.targets.positions)
    assert tri.info["triangulated_cost"] == shortfall_cost(prob.gamma, prob.weights, eff_tri)
    assert tri.info["triangulated_cost"] <= shortfall_cost(prob.gamma, prob.weights, eff_plain)
    assert tri.objective == prob.cost(tri.selected)


def test_without_positions_names_the_field():
    prob = build_problem(sp.csr_matrix(np.ones((2, 1), np.uint8)), np.array([2]), None, 2)
    with pytest.raises(InputError, match="candidate_positions") as err:
        solve(prob, "greedy-triangulated")
    assert err.value.option == "candidate_positions"


def test_stop_and_time_limit_are_honoured():
    cands = np.r_[FACING, [[0.0, 0.0, 3.0]]]
    prob = replace(build_problem(sp.csr_matrix(np.ones((3, 1), np.uint8)), np.array([2]), None, 2),
                   candidate_positions=cands, target_positions=P[None])
    p = solve(prob, "greedy-triangulated", should_stop=lambda: True)
    assert p.status == "interrupted" and len(p.selected) == 0
    p = solve(prob, "greedy-triangulated", time_limit_s=0.0)
    assert p.status == "time_limit"
