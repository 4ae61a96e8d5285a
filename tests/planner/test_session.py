"""The planner session (camplace.planner.session): one row per change, coverage equal to a
full recomputation, evaluate's metrics, undo/redo, snapping, mount rules and privacy."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.planner.errors import ApiError
from camplace.planner.opening import open_start
from camplace.planner.session import Session
from camplace.spec.loading import parse_scene


@pytest.fixture
def session(opened):
    return Session(opened)


def full_coverage(s: Session) -> np.ndarray:
    """Every camera of the session raycast afresh, all at once (no row reused)."""
    from camplace.visibility.engine import compute_visibility
    from camplace.visibility.voxel import VoxelEngine

    vis, _ = s.visibility()
    V = compute_visibility(VoxelEngine(), s.scene.occupancy, s.targets, vis.candidates).V
    return np.bincount(V.indices, minlength=V.shape[1]).astype(np.int64)


def test_opens_the_run_with_its_cameras_and_metrics(session, demo_run):
    assert len(session.cams) == len(demo_run.placement.selected)
    assert session.metrics.cost == pytest.approx(demo_run.metrics.cost)
    assert session.budget == demo_run.problem.budget
    assert np.array_equal(session.cov, full_coverage(session))


def test_a_change_raycasts_one_row_and_keeps_coverage_exact(session, monkeypatch):
    calls = []
    real = session._raycast
    monkeypatch.setattr(session, "_raycast", lambda *a: calls.append(a) or real(*a))
    before = session.cams
    c = before[2]
    state = session.update(c.id, {"yaw_deg": float(c.angles[0]) + 37.0, "pitch_deg": 20.0})
    assert len(calls) == 1
    assert all(a is b for k, (a, b) in enumerate(zip(before, session.cams)) if k != 2)  # other rows untouched
    assert np.array_equal(session.cov, full_coverage(session))
    assert state["version"] == 1 and state["can_undo"] and not state["can_redo"]
    assert set(state["timing_ms"]) >= {"raycast", "metrics", "total"} and state["timing_ms"]["total"] > 0
    session.update(c.id, {"camera": session.lenses[0].name, "position": [3.0, 2.5, 2.9]})
    session.add({"position": [2.0, 3.0], "yaw_deg": 200.0})
    session.delete(session.cams[0].id)
    assert len(calls) == 3  # move + add raycast one row each; delete raycasts nothing
    assert np.array_equal(session.cov, full_coverage(session))


def test_metrics_are_evaluates(session):
    from camplace.planner.save import session_poses
    from camplace.workflows.evaluate import evaluate

    session.update(session.cams[1].id, {"yaw_deg": 123.0, "position": [4.6, 3.1, 2.9]})
    got = evaluate(session.opened.scene_ref, session_poses(session)).metrics.to_dict()
    mine = session.metrics.to_dict()
    got.pop("timings_s"), mine.pop("timings_s")
    assert mine == got


def test_undo_redo(session):
    cost0, cov0 = session.metrics.cost, session.cov.copy()
    session.update(session.cams[0].id, {"yaw_deg": 10.0, "pitch_deg": 60.0})
    cost1, cov1 = session.metrics.cost, session.cov.copy()
    assert cost1 != cost0
    s = session.undo()
    assert session.metrics.cost == cost0 and np.array_equal(session.cov, cov0) and s["can_redo"]
    session.redo()
    assert session.metrics.cost == cost1 and np.array_equal(session.cov, cov1)
    session.undo()
    with pytest.raises(ApiError) as e:
        session.undo()
    assert e.value.field == "undo" and e.value.status == 409


def test_snapping_and_free_positions(session):
    c = session.cams[0]
    session.update(c.id, {"position": [1.13, 2.96, 1.0]})
    got = session.cams[0].position
    others = np.array([o.position for o in session.cams[1:]])
    free = ~(np.abs(session.mounts[:, None] - others[None]).max(2) <= 1e-3).any(1)
    d = np.hypot(*(session.mounts[free, :2] - [1.13, 2.96]).T)
    assert any(np.allclose(got, m) for m in session.mounts) and np.hypot(*(got[:2] - [1.13, 2.96])) == d.min()
    # dropped onto another camera's mount: the nearest free mount instead (one camera per location)
    target = session.cams[1].position.copy()
    session.update(c.id, {"position": target})
    assert not np.allclose(session.cams[0].position, target)
    held = {tuple(np.round(o.position, 3)) for o in session.cams}
    assert len(held) == len(session.cams)
    session.update(c.id, {"position": [1.13, 2.96, 2.5], "snap": False})
    assert np.allclose(session.cams[0].position, [1.13, 2.96, 2.5])
    for bad in ([7.0, 2.0, 2.5], [1.0, 1.0, 3.5]):  # outside the footprint, above the ceiling
        with pytest.raises(ApiError) as e:
            session.update(c.id, {"position": bad, "snap": False})
        assert e.value.field == "position"
    b0, b1 = next(iter(session.scene.boxes.values()))
    inside = [(b0[0] + b1[0]) / 2, (b0[1] + b1[1]) / 2, (b0[2] + b1[2]) / 2]
    with pytest.raises(ApiError, match="obstacle"):
        session.update(c.id, {"position": inside, "snap": False})


def test_locked_cameras_refuse_changes(session):
    c = session.cams[0]
    session.update(c.id, {"locked": True})
    for change, field in (({"yaw_deg": 3.0}, "yaw_deg"), ({"position": [2.0, 2.0, 2.9]}, "position")):
        with pytest.raises(ApiError) as e:
            session.update(c.id, change)
        assert e.value.field == field and e.value.status == 409
    with pytest.raises(ApiError):
        session.delete(c.id)
    session.update(c.id, {"locked": False, "yaw_deg": 3.0})  # unlock and turn in one change
    assert session.cams[0].angles[0] == 3.0 and not session.cams[0].locked


SITE = {
    "name": "planner-site", "voxel_size": 0.25, "occupancy_resolution": 0.05,
    "room": {"footprint": [[0, 0], [6, 0], [6, 4], [0, 4]], "height": 3.0},
    "obstacles": [],
    "targets": [{"name": "floor", "kind": "volume", "heights": [1.0], "coverage": 1}],
    "zones": [{"name": "office", "polygon": [[5, 0], [6, 0], [6, 4], [5, 4]], "privacy": True}],
    "mount_rules": {"forbid": [[[0, 0], [1.5, 0], [1.5, 4], [0, 4]]]},
    "cameras": [{"name": "cam", "resolution": [640, 480], "fov_deg": [80, 60], "max_range": 8.0}],
    "mounts": [{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0, "yaw_deg": [90, 180, 270],
                "pitch_deg": [45]}],
    "placement": {"budget": 2, "solver": "greedy"},
}


def test_mount_rules_and_privacy_refuse_a_pose(tmp_path):
    s = Session(open_start(parse_scene(SITE), root=tmp_path))
    assert np.all(s.mounts[:, 0] > 1.5)  # no allowed mount in the forbid area
    c = s.cams[0]
    with pytest.raises(ApiError, match="mount rules") as e:
        s.update(c.id, {"position": [1.0, 2.0, 2.5], "snap": False})
    assert e.value.field == "position"
    with pytest.raises(ApiError, match="office") as e:  # at x = 4 looking +x into the privacy zone
        s.update(c.id, {"position": [4.0, 2.0, 2.9], "yaw_deg": 0.0, "pitch_deg": 30.0})
    assert e.value.field == "position" and e.value.status == 409
    assert s.version == 0  # nothing changed


def test_a_yaml_run_folder_with_an_existing_camera(tmp_path):
    """A run folder of a YAML scene (found beside the folder) whose existing camera opens
    locked, keeps its id, refuses changes and stays through an optimisation."""
    import yaml

    from camplace.outputs.write import write_outputs
    from camplace.planner import optimize
    from camplace.workflows.run import run

    spec = dict(SITE, zones=[], mount_rules={}, name="yaml-site",
                existing=[{"id": "old-1", "camera": "cam", "position": [0.5, 0.5, 2.9], "yaw_deg": 45.0,
                           "pitch_deg": 40.0}])
    (tmp_path / "site.yaml").write_text(yaml.safe_dump(spec))
    r = run(tmp_path / "site.yaml")
    out = tmp_path / "run"
    write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                  scene=r.scene, report=False)
    s = Session(open_start(out))
    assert s.opened.scene_ref == tmp_path / "site.yaml" and s.budget == 3 and len(s.cams) == 3
    old = next(c for c in s.cams if c.existing)
    assert old.id == "old-1" and old.locked
    with pytest.raises(ApiError):
        s.update("old-1", {"locked": False})
    assert s.metrics.cost == pytest.approx(r.metrics.cost)
    job = optimize.start(s, {"solver": "greedy", "time_limit_s": 10.0, "budget": 3})
    job.thread.join(30)
    assert job.events[-1][0] == "done", job.events[-1]
    assert s.cams[0].id == "old-1" and np.array_equal(s.cams[0].position, old.position) and len(s.cams) == 3
    assert s.metrics.cost <= r.metrics.cost + 1e-9  # greedy on the same grid with the same existing camera
    assert np.array_equal(s.cov, full_coverage(s))


def test_clearance_snaps_away_and_refuses_a_pose_too_close(tmp_path):
    """Issue 25: the grid point (3, 1) lies 0.05 m from a wall face (x = 3.05): no mount
    there, a camera dropped on it snaps to a mount that keeps the clearance, and a free
    position closer than the clearance is refused."""
    from camplace.cameras.mount_rules import CEILING_BACK, occupied_distance

    site = dict(SITE, zones=[], mount_rules={},
                obstacles=[{"name": "wall", "box": {"min": [3.05, 0.0, 0.0], "max": [3.25, 2.5, 3.0]}}])
    s = Session(open_start(parse_scene(site), root=tmp_path))
    assert not np.any(np.all(np.isclose(s.mounts[:, :2], [3.0, 1.0]), axis=1))
    assert np.all(occupied_distance(s.scene.occupancy, s.mounts, CEILING_BACK, reach=0.1) >= 0.1 - 1e-6)
    c = s.cams[0]
    s.update(c.id, {"position": [3.0, 1.0]})
    got = s.cams[0].position
    assert occupied_distance(s.scene.occupancy, got[None], CEILING_BACK, reach=0.1)[0] == np.inf
    with pytest.raises(ApiError, match="clearance") as e:
        s.update(c.id, {"position": [2.98, 1.0, 2.9], "snap": False})
    assert e.value.field == "position"
    s.update(c.id, {"position": [2.9, 1.0, 2.9], "snap": False})  # 0.15 m from the face
    assert np.allclose(s.cams[0].position, [2.9, 1.0, 2.9])


def test_snap_skips_every_taken_mount_as_a_brute_force_search_does(session):
    """The k-d tree of the mounts (issue 37) frees and takes the same mounts as comparing
    every mount with every taken position (to 1 mm on each axis)."""
    rng = np.random.default_rng(3)
    m = session.mounts
    for _ in range(20):
        taken = m[rng.choice(len(m), size=int(rng.integers(1, len(m))), replace=False)]
        taken = taken + rng.uniform(-9e-4, 9e-4, taken.shape)  # within 1 mm: still taken
        free = ~(np.abs(m[:, None, :] - taken[None]).max(2) <= 1e-3).any(1)
        p = np.r_[rng.uniform(m.min(0)[:2], m.max(0)[:2]), m[0, 2]]
        d2 = np.where(free, ((m[:, :2] - p[:2]) ** 2).sum(1), np.inf)
        got = session.snap(p, taken)
        k = int(np.flatnonzero((m == got).all(1))[0])
        assert free[k] and d2[k] <= d2.min() + 1e-9  # a free mount, none free nearer in plan
    with pytest.raises(ApiError):
        session.snap(m[0], m)
