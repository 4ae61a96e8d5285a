"""Pose refinement: cost deltas, the location rule of appended poses, and a short
refinement on the demo scene checked by a fresh raycast."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from camplace.problem.model import build_problem, shortfall_cost
from camplace.improve.refine import angle_step, append_candidates, pose_box, refine_placement, target_gains
from camplace.solvers.base import Placement
from camplace.visibility.voxel import compute_visibility


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_cost_delta_of_one_row(seed):
    rng = np.random.default_rng(seed)
    n_p = 30
    gamma = rng.integers(0, 4, n_p)
    w = rng.uniform(0.5, 2.0, n_p)
    cov_o = rng.integers(0, 4, n_p)
    row = np.flatnonzero(rng.random(n_p) < 0.4)
    prob = build_problem(sp.csr_matrix((1, n_p)), gamma, w, 1)
    g = target_gains(prob, cov_o)
    c2 = cov_o.copy()
    c2[row] += 1
    assert shortfall_cost(gamma, w, c2) == pytest.approx(shortfall_cost(gamma, w, cov_o) - g[row].sum())


def test_angle_step():
    from camplace.spec.schema import AngleRange

    assert angle_step([30.0, 45.0, 60.0]) == 15.0
    assert angle_step([0.0]) == 0.0
    assert angle_step(AngleRange(start=0, stop=330, step=30)) == 30.0


def test_append_candidates_location_rule(demo_run):
    vis, sc = demo_run.visibility, demo_run.scene
    i = int(demo_run.placement.selected[0])
    same_place = np.r_[vis.candidates.positions[i], vis.candidates.angles_deg[i] + [7.0, 3.0, 0.0]]
    new_place = same_place.copy()
    new_place[0] += 0.3
    vis2, ids = append_candidates(vis, sc.occupancy, np.array([same_place, new_place, new_place]),
                                  np.array([vis.candidates.camera_ids[i]] * 3))
    assert ids.tolist() == [vis.V.shape[0], vis.V.shape[0] + 1, vis.V.shape[0] + 2]
    loc = vis2.candidates.location_ids
    assert loc[ids[0]] == vis.candidates.location_ids[i]  # same position: same location
    assert loc[ids[1]] not in set(vis.candidates.location_ids.tolist())  # new position: new location
    assert loc[ids[1]] == loc[ids[2]]
    assert vis2.V.shape == (vis.V.shape[0] + 3, vis.V.shape[1])
    assert (vis2.V[: vis.V.shape[0]] != vis.V).nnz == 0  # old rows unchanged


def test_refinement_lowers_cost_and_fresh_raycast_agrees(demo_run):
    r = demo_run
    sel = np.asarray(r.placement.selected[:3], np.int64)
    start = Placement(sel, r.problem.cost(sel), None, "heuristic", "greedy", 0.0)
    res = refine_placement(r.scene, r.visibility, r.problem, start, time_limit_s=20.0, levels=2, max_sweeps=2)
    assert res.refined_cost <= res.grid_cost
    assert res.refined_cost < res.grid_cost  # demo: the grid is never locally optimal for these cameras
    assert res.placement.objective == pytest.approx(res.problem.cost(res.placement.selected))
    res.problem.check_feasible(res.placement.selected)
    # every refined pose lies in its box around the grid pose
    cands = res.visibility.candidates
    orig = sorted(sel.tolist())
    for new_id, old_id in zip(sorted(res.placement.selected.tolist()), orig):
        box = pose_box(r.scene, r.visibility.candidates, old_id)
        if new_id == old_id:
            continue
        d = np.r_[cands.positions[new_id], cands.angles_deg[new_id]] - box.centre
        d[3] = (d[3] + 180.0) % 360.0 - 180.0
        assert np.all(np.abs(d) <= box.half + 1e-9)
    # fresh raycast of the refined poses (new Candidates, the chunked visibility path)
    fresh = compute_visibility(r.scene.occupancy, r.visibility.targets, cands.subset(res.placement.selected))
    cov = np.asarray(fresh.V.sum(axis=0)).ravel().astype(np.int64)
    assert shortfall_cost(r.problem.gamma, r.problem.weights, cov) == pytest.approx(res.refined_cost)


def test_refined_output_keeps_the_contract(demo_run, tmp_path):
    import json

    from camplace.outputs.write import write_outputs

    r = demo_run
    sel = np.asarray(r.placement.selected[:2], np.int64)
    start = Placement(sel, r.problem.cost(sel), None, "heuristic", "greedy", 0.0)
    res = refine_placement(r.scene, r.visibility, r.problem, start, time_limit_s=10.0, levels=1, max_sweeps=1)
    from camplace.metrics.coverage import compute_metrics

    m = compute_metrics(res.problem, res.placement.selected)
    write_outputs(tmp_path, r.scene.name, res.visibility, res.placement, 2, m, {}, report=False)
    p = json.loads((tmp_path / "placement.json").read_text())
    assert p["refine"]["grid_cost"] == pytest.approx(res.grid_cost)
    assert p["refine"]["refined_cost"] == pytest.approx(p["objective"])
    from conftest import SHARED

    if not (SHARED / "contract" / "check_run.py").is_file():
        pytest.skip("../shared/contract/check_run.py absent")
    import importlib.util

    spec = importlib.util.spec_from_file_location("check_run", SHARED / "contract" / "check_run.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert mod.check(tmp_path) == []


def test_run_with_refine_and_adaptive_options():
    from camplace.workflows.run import run

    r = run("demo", budget=2, refine=True, refine_time_s=3.0, adaptive=1)
    p = r.placement
    assert p.solver.endswith("+adaptive+refine")
    assert p.info["refine"]["refined_cost"] <= p.info["refine"]["grid_cost"]
    assert p.info["adaptive"]["rounds"][0]["cost"] == p.info["adaptive"]["grid_cost"]
    assert p.info["refine"]["grid_cost"] <= p.info["adaptive"]["grid_cost"]
    assert r.metrics.cost == pytest.approx(p.objective)  # metrics from the extended V
    assert r.visibility.V.shape[0] == r.problem.n_candidates > 0
    assert p.info["refine"]["stopped"] in ("converged", "time_limit")


def test_wall_cameras_only_turn():
    from conftest import box_room

    from camplace.workflows.run import prepare

    spec = box_room(mounts=[{"kind": "wall", "camera": "cam", "height": 2.5, "spacing": 1.0, "pitch_deg": [20, 40]},
                            {"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0, "yaw_deg": [0, 90],
                             "pitch_deg": [45]}])
    sc, vis = prepare(spec)
    c = vis.candidates
    wall = np.flatnonzero(np.isclose(c.positions[:, 2], 2.5))
    ceil = np.flatnonzero(np.isclose(c.positions[:, 2], 2.9))
    assert len(wall) and len(ceil)
    bw, bc = pose_box(sc, c, int(wall[0])), pose_box(sc, c, int(ceil[0]))
    assert bw.half[:3].tolist() == [0, 0, 0] and bw.half[4] == pytest.approx(0.499 * 20)
    assert bc.half[:2].tolist() == pytest.approx([0.499, 0.499]) and bc.half[3] == pytest.approx(0.499 * 90)


def test_a_moved_pose_keeps_the_mount_clearance():
    """Issue 25: a refined camera 1 mm from a wall face. The box around the grid point
    x = 2 reaches x = 2.499, 1 mm from the wall at x = 2.5: a move closer than the
    clearance (0.1 m) is refused, and no refined pose of a run breaks it."""
    from conftest import box_room

    from camplace.cameras.mount_rules import CEILING_BACK, occupied_distance
    from camplace.improve.refine import _valid_positions
    from camplace.workflows.run import run

    spec = box_room([{"name": "wall", "box": {"min": [2.5, 0.0, 0.0], "max": [2.7, 2.5, 3.0]}}],
                    mounts=[{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0, "yaw_deg": [0, 180],
                             "pitch_deg": [45]}])
    r = run(spec, budget=3, refine=True, refine_time_s=5.0)
    c = r.visibility.candidates
    i = int(np.flatnonzero(np.all(np.isclose(c.positions, [2.0, 1.0, 2.9]), axis=1))[0])
    box = pose_box(r.scene, c, i)
    assert box.centre[0] + box.half[0] > 2.49 and box.clearance == 0.1
    trial = np.array([np.r_[x, 1.0, 2.9, c.angles_deg[i]] for x in (2.499, 2.45, 2.35, 2.0)])
    assert _valid_positions(box, r.scene.occupancy, trial).tolist() == [False, False, True, True]
    sel = r.placement.selected
    d = occupied_distance(r.scene.occupancy, c.positions[sel], CEILING_BACK, reach=0.1)
    assert np.all(d >= 0.1 - 1e-6)


@pytest.mark.parametrize("mode, params", [("pixel", {"stride": 16}), ("voxel", {"probe": 1.0})])
def test_refined_rows_follow_the_runs_engine(mode, params):
    """A pixel-mode run and a probe-1 run: every row refinement added to V equals the run's
    engine's own rows for those poses (not the voxel engine's defaults)."""
    from conftest import box_room

    from camplace.visibility import compute_visibility as engine_visibility, get_engine
    from camplace.workflows.run import run

    spec = box_room(obstacles=[{"name": "box", "box": {"min": [1.5, 1.5, 0.0], "max": [2.5, 2.5, 1.5]}}],
                    targets=[{"name": "walkable", "kind": "volume", "heights": [1.0], "coverage": 2}],
                    cameras=[{"name": "cam", "resolution": [320, 240], "fov_deg": [60, 45], "max_range": 6.0}],
                    mounts=[{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0, "yaw_deg": [0, 90, 180, 270],
                             "pitch_deg": [45]}])
    r = run(spec, budget=3, visibility_mode=mode, refine=True, refine_time_s=2.0, **params)
    vis = r.visibility
    engine = get_engine(mode, **params)
    assert vis.engine == engine
    n_grid = vis.V.shape[0] - vis.info.get("appended", 0)
    new = np.asarray([i for i in r.placement.selected if i >= n_grid], np.int64)
    assert len(new), "refinement moved no camera: the test would check nothing"
    own = engine_visibility(engine, r.scene.occupancy, vis.targets, vis.candidates.subset(new)).V
    assert (vis.V[new] != own).nnz == 0
    default = engine_visibility(get_engine("voxel"), r.scene.occupancy, vis.targets, vis.candidates.subset(new)).V
    assert (default != own).nnz > 0  # the rule matters here: rows under the voxel defaults would differ


def test_polled_rows_past_their_cap_still_answer_a_poll_of_old_and_new_poses():
    from camplace.improve.refine import _PolledRows

    def cast(trial):  # row n sees target int(trial[n, 0]) and target 9
        return sp.csr_matrix((np.ones(2 * len(trial)), (np.repeat(np.arange(len(trial)), 2),
                                                        np.c_[trial[:, 0], np.full(len(trial), 9)].ravel())),
                             shape=(len(trial), 10))

    polled = _PolledRows(10, max_entries=5)
    a = np.array([[1.0, 0], [2.0, 0]])
    assert polled.get(0, a, cast)[1] == 2
    b = np.array([[2.0, 0], [3.0, 0], [4.0, 0]])  # one pose seen before, two new: past the cap of 5 entries
    R, n = polled.get(0, b, cast)
    assert n == 2 and (R != cast(b)).nnz == 0
    assert polled.entries <= 6 and polled.get(0, b, cast)[1] == 0  # this poll's poses are kept
