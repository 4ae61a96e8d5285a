"""Camera catalogue: money budget in every solver, one camera per location whatever its
type, cost recomputation, cost-scaled greedy by hand, the built-in catalogue scene."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from camplace.core.errors import InputError
from camplace.problem.model import PlacementProblem
from camplace.solvers import SOLVERS, solve
from camplace.solvers.catalogue import repair_to_money_budget, solve_catalogue_greedy


def _mixed_problem(seed: int = 0, money: float = 7.0) -> PlacementProblem:
    """30 locations, each with a cheap (price 1) and a dear (price 2.5) camera type."""
    rng = np.random.default_rng(seed)
    n_g, n_p = 60, 150
    V = sp.csr_matrix((rng.random((n_g, n_p)) < 0.08).astype(np.uint8))
    price = np.where(np.arange(n_g) % 2 == 0, 1.0, 2.5)
    return PlacementProblem(V, rng.integers(1, 3, n_p), np.ones(n_p), 8, np.arange(n_g) // 2, price, money,
                            candidate_positions=rng.uniform(0, 10, (n_g, 3)),
                            target_positions=rng.uniform(0, 10, (n_p, 3)))


def _check(prob: PlacementProblem, placement, solver: str) -> None:
    sel = placement.selected
    assert prob.costs[sel].sum() <= prob.money_budget + 1e-9, solver
    locs = prob.location_ids[sel]
    assert len(np.unique(locs)) == len(locs), solver
    if not SOLVERS[solver].tags.ignores_camera_budget:
        assert len(sel) <= prob.budget, solver
    assert placement.objective == pytest.approx(prob.cost(sel)), solver  # reported cost == recomputed cost


@pytest.mark.parametrize("solver", sorted(SOLVERS))
def test_every_solver_keeps_the_money_budget(solver):
    prob = _mixed_problem()
    p = solve(prob, solver, time_limit_s=2.0)
    _check(prob, p, solver)
    if p.bound is not None:
        assert p.bound <= p.objective + 1e-6


def test_cost_scaled_greedy_by_hand():
    # target block A (10 targets) seen only by candidate 0 (price 10); blocks B, C (6 each) by
    # candidates 1, 2 (price 1). Money 2: candidate 0 is unaffordable, so both variants pick 1 and 2.
    n_p = 22
    V = np.zeros((3, n_p), np.uint8)
    V[0, :10] = 1
    V[1, 10:16] = 1
    V[2, 16:22] = 1
    prob = PlacementProblem(sp.csr_matrix(V), np.ones(n_p, np.int64), np.ones(n_p), 3, np.arange(3),
                            np.array([10.0, 1.0, 1.0]), 2.0)
    p = solve_catalogue_greedy(prob)
    assert p.selected.tolist() == [1, 2] and p.objective == 10.0
    # one dear camera worth more than the cheap one: ratio greedy takes the cheap one first and
    # can then no longer afford the dear one; the best-of rule keeps the plain greedy's answer
    V2 = np.zeros((2, 11), np.uint8)
    V2[0, :10] = 1
    V2[1, 10] = 1
    prob2 = PlacementProblem(sp.csr_matrix(V2), np.ones(11, np.int64), np.ones(11), 2, np.arange(2),
                             np.array([2.0, 0.1]), 2.0)
    p2 = solve(prob2, "greedy")
    assert p2.selected.tolist() == [0] and p2.objective == 1.0 and p2.info["variant"] == "plain"


def test_money_budget_feasibility_check():
    prob = _mixed_problem(money=3.5)
    with pytest.raises(ValueError, match="money budget"):
        prob.check_feasible(np.array([1, 3]))  # 2.5 + 2.5 > 3.5
    prob.check_feasible(np.array([0, 3]))  # 1 + 2.5 = 3.5
    with pytest.raises(InputError):
        PlacementProblem(prob.V, prob.gamma, prob.weights, 3, prob.location_ids, prob.camera_costs, -1.0)


def test_repair_fits_any_selection():
    prob = _mixed_problem(money=5.0)
    too_dear = np.arange(1, 16, 2)[:8]  # eight price-2.5 cameras
    fixed = repair_to_money_budget(prob, too_dear)
    _check(prob, type("P", (), {"selected": fixed, "objective": prob.cost(fixed)})(), "greedy")


def test_scene_money_budget_key():
    from camplace.spec.builtin import resolve_scene
    from camplace.spec.loading import parse_scene
    import yaml
    from camplace.spec.builtin import builtin_yaml

    spec, _, _ = resolve_scene("catalogue-store")
    assert spec.placement.money_budget == 10.0
    assert {c.name for c in spec.cameras} == {"wide", "narrow", "fisheye"}
    data = yaml.safe_load(builtin_yaml("catalogue-store"))
    data["placement"]["money_budget"] = -1
    with pytest.raises(InputError, match="money_budget"):
        parse_scene(data)


def test_catalogue_scene_runs_within_budget(tmp_path):
    from camplace.workflows.run import run
    from camplace.outputs.write import write_outputs

    r = run("catalogue-store", solver="greedy", money_budget=6.0)
    prob, p = r.problem, r.placement
    assert prob.money_budget == 6.0
    _check(prob, p, "greedy")
    cands = r.visibility.candidates
    # candidates of different types at one grid point share a location
    types_per_loc = {}
    for loc, cid in zip(cands.location_ids, cands.camera_ids):
        types_per_loc.setdefault(int(loc), set()).add(int(cid))
    assert max(len(t) for t in types_per_loc.values()) >= 2
    write_outputs(tmp_path, r.scene.name, r.visibility, p, prob.budget, r.metrics, r.timings_s, report=False)
    from conftest import SHARED

    if (SHARED / "contract" / "check_run.py").is_file():
        import importlib.util

        spec = importlib.util.spec_from_file_location("check_run", SHARED / "contract" / "check_run.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        assert mod.check(tmp_path) == []
