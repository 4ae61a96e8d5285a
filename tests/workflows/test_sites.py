"""Real sites (issue 17), hand-checked on one small scene: an 8 m x 4 m x 3 m room split
by a wall at x = 4..4.2 m with a doorway at y = 1.5..2.5 m; the left half is a restroom
(privacy zone, floor to ceiling), targets at 1 m on the right half; a ceiling grid
(1 m) with cameras facing +x, +y, -x, -y at 45° down; voxel 0.5 m."""

from __future__ import annotations

import copy
import importlib.util
import json

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from camplace.spec.loading import parse_scene
from camplace.workflows.run import run
from conftest import SHARED, run_cli

RESTROOM = [[0, 0], [4, 0], [4, 4], [0, 4]]
DOOR_WALL = [{"name": "wall-s", "box": {"min": [4.0, 0.0, 0.0], "max": [4.2, 1.5, 3.0]}},
             {"name": "wall-n", "box": {"min": [4.0, 2.5, 0.0], "max": [4.2, 4.0, 3.0]}}]
CLOSED_WALL = [{"name": "wall", "box": {"min": [4.0, 0.0, 0.0], "max": [4.2, 4.0, 3.0]}}]
SITE = {
    "name": "site", "voxel_size": 0.5, "occupancy_resolution": 0.1,
    "room": {"footprint": [[0, 0], [8, 0], [8, 4], [0, 4]], "height": 3.0},
    "obstacles": DOOR_WALL,
    "targets": [{"name": "walk", "kind": "volume", "heights": [1.0], "coverage": 1}],
    "cameras": [{"name": "cam", "resolution": [64, 48], "fov_deg": [90, 70], "max_range": 10.0}],
    "mounts": [{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0, "yaw_deg": [0, 90, 180, 270],
                "pitch_deg": [45]}],
    "zones": [{"name": "restroom", "polygon": RESTROOM, "privacy": True}],
    "placement": {"budget": 2, "solver": "greedy"},
}


def site(**keys):
    d = copy.deepcopy(SITE)
    d.update(keys)
    return parse_scene(d)


def check_run(out) -> list[str]:
    if not (SHARED / "contract" / "check_run.py").is_file():
        pytest.skip("../shared/contract/check_run.py absent")
    spec = importlib.util.spec_from_file_location("check_run", SHARED / "contract" / "check_run.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.check(out)


def write(r, out):
    from camplace.outputs.write import write_outputs

    write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                  report=False)
    return json.loads((out / "placement.json").read_text()), json.loads((out / "metrics.json").read_text())


def pose_keys(positions, angles) -> set:
    return {tuple(np.round(np.r_[p, a], 3)) for p, a in zip(positions, angles)}


def test_privacy_zone_behind_a_doorway_removes_exactly_the_cameras_that_see_through_it():
    from camplace.workflows.run import prepare

    _, open_vis = prepare(site())
    _, closed_vis = prepare(site(obstacles=CLOSED_WALL))
    for vis in (open_vis, closed_vis):  # no kept camera hangs inside the restroom (every one there sees it)
        assert np.all(vis.candidates.positions[:, 0] >= 4.0)
    c = closed_vis.candidates
    right = pose_keys(c.positions, c.angles_deg)
    assert len(right) == 3 * 3 * 4  # x 5, 6, 7 (x 8: wall clearance) × y 1, 2, 3 × 4 yaws: the wall hides it all
    kept = pose_keys(open_vis.candidates.positions, open_vis.candidates.angles_deg)
    assert kept - right == {(4.0, 2.0, 2.9, 0.0, 45.0, 0.0)}  # in the doorway (no wall there), facing away
    removed = right - kept
    assert (5.0, 2.0, 2.9, 180.0, 45.0, 0.0) in removed  # in front of the doorway, facing it
    assert removed and all(k[3] != 0.0 for k in removed)  # facing +x (90° lens) nothing left of it is seen
    assert all((x, y, z, 180.0, p, r) in removed for (x, y, z, _, p, r) in right if y == 2.0)  # facing the door


def test_the_run_log_counts_the_removed_candidates_and_metrics_report_privacy(tmp_path):
    r = run(site(), budget=2)
    line = next(s for s in r.log if s.startswith("privacy:"))
    assert "see a privacy zone (restroom; " in line and "removed" in line
    p, m = write(r, tmp_path)
    assert m["privacy"]["violations"] == 0 and m["privacy"]["zones"] == ["restroom"]
    assert m["privacy"]["points"] == 8 * 8 * 6  # 4 m x 4 m / 0.5 m voxels, 6 layers floor to ceiling
    assert check_run(tmp_path) == []


def test_forbidden_polygon_holds_no_selected_or_refined_camera():
    forbid = [[4.5, 0], [6.5, 0], [6.5, 4], [4.5, 4]]
    r = run(site(mount_rules={"forbid": [forbid]}), budget=2, refine=True, refine_time_s=5.0)
    poly = Polygon(forbid)
    assert not shapely.intersects_xy(poly, r.visibility.candidates.positions[:, 0],
                                     r.visibility.candidates.positions[:, 1]).any()  # no candidate or refined row
    sel = r.visibility.candidates.positions[r.placement.selected]
    assert len(sel) == 2 and not shapely.intersects_xy(poly, sel[:, 0], sel[:, 1]).any()
    assert r.placement.info["refine"]["trials"] > 0 and r.metrics.privacy["violations"] == 0
    line = next(s for s in r.log if s.startswith("mount rules:"))
    assert line.startswith("mount rules: 6 mount positions")  # x 5, 6 × y 1, 2, 3 (y 0, 4: wall clearance)


def test_allow_and_explicit_points(tmp_path):
    (tmp_path / "drops.csv").write_text("x,y,z\n7,2,2.9\n6,1,2.9\n1,1,2.9\n")
    d = copy.deepcopy(SITE)
    d["mount_rules"] = {"points": "drops.csv", "allow": [[[5.5, 0], [8, 0], [8, 4], [5.5, 4]]]}
    (tmp_path / "s.yaml").write_text(json.dumps(d))
    r = run(tmp_path / "s.yaml", budget=1)
    pos = {tuple(p) for p in np.round(r.visibility.candidates.positions, 3)}
    assert pos <= {(7.0, 2.0, 2.9), (6.0, 1.0, 2.9)}  # (1, 1) is outside 'allow' (and in the restroom)


def test_existing_camera_covering_a_zone_fully_gets_no_new_camera_spent_there(tmp_path):
    aisle = [[6.5, 1.5], [7.5, 1.5], [7.5, 2.5], [6.5, 2.5]]
    e1 = {"id": "E1", "camera": "cam", "position": [5.5, 2.0, 2.9], "yaw_deg": 0, "pitch_deg": 45}
    s = site(targets=[{"name": "walk", "kind": "volume", "heights": [1.0], "coverage": 0}],
             zones=SITE["zones"] + [{"name": "aisle", "polygon": aisle, "coverage": 1}], existing=[e1])
    r = run(s, budget=2)
    assert r.metrics.regions["aisle"]["targets"] == 4 and r.metrics.regions["aisle"]["cost"] == 0.0
    p, m = write(r, tmp_path)
    new = [c for c in p["cameras"] if not c["existing"]]
    assert [c["id"] for c in p["cameras"] if c["existing"]] == ["E1"]
    assert new == [] and p["budget"] == 2 and p["n_existing"] == 1  # nothing left to cover: no camera spent
    assert m["existing"]["ids"] == ["E1"] and m["cost"] == 0.0
    assert check_run(tmp_path) == []


def test_existing_coverage_is_the_solvers_start_and_the_cost_is_unchanged(tmp_path):
    e1 = {"id": "E1", "camera": "cam", "position": [5.5, 2.0, 2.9], "yaw_deg": 0, "pitch_deg": 45}
    r = run(site(existing=[e1]), budget=1)
    V, sel = r.visibility.V, r.placement.selected
    cov = np.bincount(V[sel].indices, minlength=V.shape[1])
    w, g = r.visibility.targets.weights, r.visibility.targets.gamma
    assert r.placement.objective == pytest.approx(float((w * np.maximum(g - cov, 0) ** 2).sum()))
    assert r.metrics.cost == pytest.approx(r.placement.objective) and len(sel) == 2
    p, _ = write(r, tmp_path)
    assert check_run(tmp_path) == []


def test_overlapping_zones_later_wins():
    a = {"name": "a", "polygon": [[5, 0], [8, 0], [8, 4], [5, 4]], "coverage": 2}
    b = {"name": "b", "polygon": [[6, 1], [7, 1], [7, 3], [6, 3]], "coverage": 3, "weight": 2.0}
    from camplace.scene.build import build_scene
    from camplace.targets.build import build_targets

    def counts(zones):
        t = build_targets(build_scene(site(zones=SITE["zones"] + zones)))
        return {n: (int((t.region_ids == k).sum()), sorted(set(t.gamma[t.region_ids == k].tolist())))
                for k, n in enumerate(t.region_names)}

    # right half 4.2..8: x centres 4.25..7.75 (8 columns) × 8 rows; the restroom has no targets
    assert counts([a, b]) == {"walk": (16, [1]), "a": (40, [2]), "b": (8, [3])}
    assert counts([b, a]) == {"walk": (16, [1]), "b": (0, []), "a": (48, [2])}


def test_keep_reproduces_a_runs_cameras_and_adds_the_budget(tmp_path):
    first = run(site(), budget=2)
    p1, _ = write(first, tmp_path / "one")
    second = run(site(), budget=1, keep=tmp_path / "one" / "placement.json")
    p2, m2 = write(second, tmp_path / "two")
    kept = [c for c in p2["cameras"] if c["existing"]]
    assert sorted(map(tuple, (c["position"] for c in kept))) == sorted(map(tuple, (c["position"] for c in
                                                                               p1["cameras"])))
    assert sorted(c["id"] for c in kept) == sorted(str(c["candidate_id"]) for c in p1["cameras"])
    assert len(p2["cameras"]) == 3 and p2["budget"] == 1
    assert m2["cost"] <= json.loads((tmp_path / "one" / "metrics.json").read_text())["cost"] + 1e-9
    assert check_run(tmp_path / "two") == []
    third = run(site(), budget=1, keep=tmp_path / "two" / "placement.csv")  # the CSV works too
    assert len(third.placement.info["existing_ids"]) == 3 and len(third.placement.selected) <= 4


def test_min_cameras_answers_how_many_more():
    e1 = {"id": "E1", "camera": "cam", "position": [5.5, 2.0, 2.9], "yaw_deg": 0, "pitch_deg": 45}
    plain = run(site(), budget=8, solver="min-cameras")
    more = run(site(existing=[e1]), budget=8, solver="min-cameras")
    n_plain = len(plain.placement.selected)
    n_more = len(more.placement.selected) - 1
    assert n_more <= n_plain


def test_evaluate_strict_fails_on_a_placement_that_sees_the_restroom(tmp_path, monkeypatch, capsys):
    d = copy.deepcopy(SITE)
    (tmp_path / "s.yaml").write_text(json.dumps(d))
    (tmp_path / "p.csv").write_text("id,x,y,z,yaw,pitch,roll,lens\nA,7,1,2.9,0,45,0,cam\n"
                                    "B,5,2,2.9,180,45,0,cam\n")
    code, out = run_cli(["evaluate", tmp_path / "s.yaml", tmp_path / "p.csv", "--out", tmp_path / "ev",
                         "--strict", "--no-plan"], monkeypatch, capsys)
    assert code == 1 and "B" in out and "privacy" in out
    m = json.loads((tmp_path / "ev" / "metrics.json").read_text())
    assert m["privacy"]["violations"] == 1 and m["privacy"]["camera_ids"] == ["B"]
    code, _ = run_cli(["evaluate", tmp_path / "s.yaml", tmp_path / "p.csv", "--out", tmp_path / "ev2", "--no-plan"],
                      monkeypatch, capsys)
    assert code == 0


def test_existing_camera_that_violates_privacy_is_reported_not_removed(tmp_path):
    bad = {"id": "PEEK", "camera": "cam", "position": [5.0, 2.0, 2.9], "yaw_deg": 180, "pitch_deg": 45}
    r = run(site(existing=[bad]), budget=1)
    assert any("PEEK" in s and "privacy" in s for s in r.log)
    p, m = write(r, tmp_path)
    assert [c["id"] for c in p["cameras"] if c["existing"]] == ["PEEK"]
    assert m["privacy"]["camera_ids"] == ["PEEK"]


def test_the_report_view_carries_privacy_zones_and_forbidden_mount_areas():
    from camplace.outputs.figures import SceneView, coverage_slices, slice_figures_png
    from camplace.scene.build import build_scene
    from camplace.targets.build import build_targets

    sc = build_scene(site(mount_rules={"forbid": [[[6, 0], [7, 0], [7, 4], [6, 4]]]}))
    view = SceneView.from_scene(sc)
    assert [k for k, _ in view.areas] == ["privacy", "forbid"] and view.areas[0][1].shape == (4, 2)
    t = build_targets(sc)
    png = slice_figures_png(coverage_slices(view, t.positions, t.is_surface, np.zeros(len(t), np.int64)), view)
    assert len(png) == 1 and png[0][:4] == b"\x89PNG"
