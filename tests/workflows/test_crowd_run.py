"""Crowds in a run (camplace.workflows.crowd): density 0 changes nothing, the crowd-aware
problem is optimal on its own crowds, refinement keeps the contract, evaluate scores the
same crowds the same way (issue 28)."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from camplace.spec.loading import parse_scene
from camplace.workflows.run import prepare, problem_from_visibility, run

SCENE = {"name": "crowd-room", "voxel_size": 0.5, "occupancy_resolution": 0.1,
         "room": {"footprint": [[0, 0], [6, 0], [6, 4], [0, 4]], "height": 3.0},
         "obstacles": [{"name": "shelf", "box": {"min": [2.5, 1.5, 0.0], "max": [3.5, 2.5, 1.5]}}],
         "targets": [{"name": "walk", "kind": "volume", "heights": [1.0, 1.5], "coverage": 2}],
         "cameras": [{"name": "cam", "resolution": [640, 480], "fov_deg": [90, 70], "max_range": 8.0}],
         "mounts": [{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0,
                     "yaw_deg": {"start": 0, "stop": 270, "step": 90}, "pitch_deg": [45]}],
         "placement": {"budget": 3, "solver": "mip", "time_limit_s": 30},
         "crowd": {"density": 1.0, "samples": 4, "score_samples": 8}}


def spec_with(d: dict, **crowd):
    """The scene ``d`` with these crowd keys."""
    d = copy.deepcopy(d)
    d["crowd"].update(crowd)
    return parse_scene(d)


def spec(**crowd):
    return spec_with(SCENE, **crowd)


@pytest.fixture(scope="module")
def empty_store():
    return run(spec())


def test_density_0_equals_the_run_without_a_crowd(empty_store):
    d = copy.deepcopy(SCENE)
    del d["crowd"]
    plain = run(parse_scene(d), solver="greedy")
    zero = run(spec(density=0.0, optimise=True), solver="greedy")
    assert np.array_equal(plain.placement.selected, zero.placement.selected)
    assert plain.placement.objective == zero.placement.objective
    a, b = plain.metrics.to_dict(), zero.metrics.to_dict()
    c = b.pop("crowd")
    assert {k: v for k, v in a.items() if k != "timings_s"} == {k: v for k, v in b.items() if k != "timings_s"}
    assert c["coverage_gap"]["mean"] == a["coverage_gap"] and c["coverage_gap"]["std"] == 0.0
    assert c["triangulatable_pct"]["mean"] == 100.0 - a["non_triangulatable_pct"]
    exact = run(spec(density=0.0, optimise=True))  # the exact solver keeps its bound too
    assert np.array_equal(exact.placement.selected, empty_store.placement.selected)
    assert (exact.placement.objective, exact.placement.bound) == (empty_store.placement.objective,
                                                                  empty_store.placement.bound)


def test_density_0_with_refinement_equals_the_run_without_a_crowd():
    """The golden check of issue 36: a crowd-aware run at density 0 offers no steep views,
    builds no people problem and refines the same poses as the run without a crowd."""
    d = copy.deepcopy(SCENE)
    del d["crowd"]
    plain = run(parse_scene(d), solver="greedy", refine=True, refine_time_s=60.0)
    zero = run(spec(density=0.0, optimise=True), solver="greedy", refine=True, refine_time_s=60.0)
    assert plain.placement.info["refine"]["stopped"] == "converged"  # not cut by the clock: comparable
    assert np.array_equal(plain.placement.selected, zero.placement.selected)
    assert plain.placement.objective == zero.placement.objective
    assert np.array_equal(plain.visibility.candidates.positions, zero.visibility.candidates.positions)
    assert np.array_equal(plain.visibility.candidates.angles_deg, zero.visibility.candidates.angles_deg)
    assert (plain.visibility.V != zero.visibility.V).nnz == 0
    c = zero.metrics.crowd.to_dict()["people"]
    assert c["persons"]["max"] == 0 and c["seen_by_2_pct"]["mean"] == 0.0


def test_crowd_aware_is_optimal_on_its_own_crowds(empty_store):
    from camplace.workflows.crowd import crowd_problem

    aware = run(spec(optimise=True, people_cost="squared"))  # the exact solver's placement, no count step
    opt = aware.placement.info["crowd"]
    assert aware.placement.status == "optimal" and opt["samples"] == 4
    assert aware.placement.objective == aware.problem.cost(aware.placement.selected)  # the contract: empty-store cost
    sc, vis = prepare(spec(), extra_pitches=spec(optimise=True).crowd.offers_steep())  # the run's steep views too
    assert len(vis.candidates) == len(aware.visibility.candidates)
    cp = crowd_problem(sc, vis, problem_from_visibility(vis, 3), spec().crowd)
    assert cp.problem.n_targets == vis.V.shape[1] + 2 * int(cp.crowds.counts.sum())  # torso and head of each
    assert abs(cp.problem.cost(aware.placement.selected) - opt["objective"]) < 1e-9
    assert cp.problem.cost(empty_store.placement.selected) >= opt["objective"] - 1e-9
    assert aware.metrics.crowd.to_dict()["optimised"] and not empty_store.metrics.crowd.to_dict()["optimised"]


def test_the_count_step_sees_more_people_of_its_crowds():
    """people_cost count (the default): the greedy placement, then the swap descent of
    camplace.improve.people; the crowd objective stays the squared crowd cost of the result."""
    from camplace.improve.people import PeopleCountObjective
    from camplace.workflows.crowd import crowd_problem

    squared = run(spec(optimise=True, people_cost="squared"), solver="greedy")
    count = run(spec(optimise=True), solver="greedy")
    step, = count.placement.info["crowd"]["count_steps"]  # no refinement: one step, on the grid
    assert "count_steps" not in squared.placement.info["crowd"] and "people_count" not in count.placement.info
    assert step["people_seen"] >= step["people_seen_before"] and step["people"] == int(count.placement.info[
        "crowd"]["persons"]["mean"] * 4)  # 4 crowds, the same count in each at density 1
    sc, vis = prepare(spec(), extra_pitches=spec(optimise=True).crowd.offers_steep())
    cp = crowd_problem(sc, vis, problem_from_visibility(vis, 3), spec(optimise=True).crowd)
    start = cp.problem.n_targets - len(cp.people.targets)
    obj = PeopleCountObjective(cp.problem, start, 2, spec().crowd.people_count_weight)
    J = [obj.value(cp.problem.coverage(r.placement.selected)) for r in (squared, count)]
    assert J[1] <= J[0] + 1e-12  # the same greedy placement, then a descent on J
    assert abs(cp.problem.cost(count.placement.selected) - count.placement.info["crowd"]["objective"]) < 1e-9
    refined = run(spec(optimise=True), solver="greedy", refine=True, refine_time_s=5.0)
    grid, again = refined.placement.info["crowd"]["count_steps"]  # on the grid, then among the refined poses too
    assert again["people_seen"] >= again["people_seen_before"] and grid["people"] == again["people"]
    assert refined.placement.objective == refined.problem.cost(refined.placement.selected)  # the contract


def test_the_cost_cap_holds_through_the_descents_and_the_refinement():
    """max_cost_rise 0: the final placement's empty-store cost (the contract's objective, full Γ)
    is at most that of the greedy grid solve of the empty-store part (the reference, in the
    crowd problem's weights (1 − people_weight) × w), after the descent (which without the cap
    goes above it here) and after both descents and the refinement."""
    lam = spec().crowd.people_weight
    free = run(spec(optimise=True, max_cost_rise=None, people_count_weight=3.0), solver="greedy")
    capped = run(spec(optimise=True, max_cost_rise=0.0, people_count_weight=3.0), solver="greedy")
    cap = capped.placement.info["crowd"]["cost_cap"]
    assert cap["max_cost_rise"] == 0.0 and cap["limit"] == cap["reference_cost"] > 0
    assert "cost_cap" not in free.placement.info["crowd"]
    assert (1 - lam) * free.placement.objective > cap["limit"] >= (1 - lam) * capped.placement.objective
    r = run(spec(optimise=True, max_cost_rise=0.0, people_count_weight=3.0), solver="greedy", refine=True,
            refine_time_s=3.0)
    assert (1 - lam) * r.placement.objective <= r.placement.info["crowd"]["cost_cap"]["limit"] * (1 + 1e-9)
    assert "cost_cap" not in run(spec(optimise=True, people_cost="squared"), solver="greedy").placement.info["crowd"]


def test_steep_views_are_offered_only_to_a_crowd_aware_run_with_people(empty_store):
    aware = run(spec(optimise=True), solver="greedy")
    pitches = lambda r: set(np.round(r.visibility.candidates.angles_deg[:, 1], 6))  # noqa: E731
    assert {75.0, 90.0} <= pitches(aware) and not {75.0, 90.0} & pitches(empty_store)
    assert spec(density=0.0, optimise=True).crowd.offers_steep() == ()


def test_crowd_aware_refinement_scores_poses_on_the_crowds():
    r = run(spec(optimise=True, people_cost="squared"), refine=True, refine_time_s=2.0)  # it lowers that cost
    info = r.placement.info
    assert info["crowd"]["refined_cost"] <= info["crowd"]["refine_grid_cost"] + 1e-9
    assert r.placement.objective == r.problem.cost(r.placement.selected) and r.placement.bound is None
    assert info["refine"]["grid_cost"] == r.metrics.grid_cost  # empty-store costs in the written figures


def test_evaluate_scores_the_same_held_out_crowds(empty_store, tmp_path):
    from camplace.outputs.write import write_outputs
    from camplace.workflows.evaluate import evaluate

    r = empty_store
    write_outputs(tmp_path, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                  report=False)
    ev = evaluate(spec(), tmp_path / "placement.json")
    assert ev.metrics.crowd.to_dict()["coverage_gap"] == r.metrics.crowd.to_dict()["coverage_gap"]
    other = evaluate(spec(), tmp_path / "placement.json", crowd={"seed": 5})
    assert other.metrics.crowd.to_dict()["coverage_gap"] != r.metrics.crowd.to_dict()["coverage_gap"]


def test_existing_cameras_see_the_same_people():
    """The crowd objective of a run with an existing camera, recomputed by hand from the
    selected cameras' (existing ones folded in) views of the people: the offset keeps the
    full mixed cost (module doc of camplace.problem.people)."""
    from camplace.problem.gains import shortfall_cost
    from camplace.targets.crowd import sample_crowds
    from camplace.targets.people import people_targets
    from camplace.visibility.crowd import people_grid
    from camplace.visibility.people import people_rows
    from camplace.visibility.voxel import VoxelEngine

    d = copy.deepcopy(SCENE)
    d["existing"] = [{"id": "E1", "camera": "cam", "position": [0.5, 0.5, 2.9], "yaw_deg": 45, "pitch_deg": 45}]
    r = run(spec_with(d, optimise=True), solver="greedy")
    opt = r.placement.info["crowd"]
    vis, sel = r.visibility, r.placement.selected  # existing rows folded in and selected
    c = r.scene.spec.crowd
    crowds = sample_crowds(r.scene, c)
    people = people_targets(crowds, vis.targets, c.people_heights, c.people_gamma)
    seen = people_rows(VoxelEngine(), r.scene.occupancy, people, vis.candidates.subset(sel),
                       people_grid(crowds, np.zeros(2), np.array([6.0, 4.0])))
    pt, t = people.targets, vis.targets
    norm = float(np.dot(t.weights, t.gamma ** 2))
    w_p = pt.weights / crowds.n_samples
    lam = c.people_weight
    want = ((1 - lam) * shortfall_cost(t.gamma, t.weights, np.asarray(vis.V[sel].sum(axis=0)).ravel())
            + lam * norm / float(np.dot(w_p, pt.gamma ** 2))
            * shortfall_cost(pt.gamma, w_p, np.asarray(seen.sum(axis=0)).ravel()))
    assert abs(opt["objective"] - want) < 1e-9 * max(1.0, want)
    assert abs(opt["coverage_gap"] - want / norm) < 1e-12


def test_a_ctrl_c_while_sampling_the_crowds_drops_them():
    """should_stop() turning true between V_s's blocks: the crowds are dropped, the solver
    leaves at once with its best, the held-out crowds are not scored (the contract files
    come first after a Ctrl-C)."""
    calls = []

    def progress(stage, done, total):
        calls.append(stage)

    def should_stop():
        return "crowd" in calls

    r = run(spec(optimise=True), solver="greedy", progress=progress, should_stop=should_stop)
    assert "crowd-aware: skipped (interrupted while sampling the crowds)" in r.log
    assert "crowd: held-out crowds not scored (interrupted)" in r.log
    assert r.metrics.crowd is None and r.placement.status == "interrupted"
