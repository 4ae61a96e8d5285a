"""Frames a user can map back: input_from_scene (camplace.scene.frames), --frame input on
the outputs, and a camera given in a scan's own frame that comes back at the same pose."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

from camplace.cameras.candidates import rotation_from_ypr, ypr_from_rotation
from camplace.core.errors import InputError
from camplace.scene.frames import input_from_scene, invert, map_poses, rotation_part, scene_from_file
from camplace.spec.loading import parse_scene
from camplace.spec.schema import CloudTransform
from tests.conftest import box_room

CHECK_RUN = Path(__file__).resolve().parents[2] / ".." / "shared" / "contract" / "check_run.py"

# the file's frame: y up (a phone scan), turned 30° about the up axis and moved away
FILE_FROM_BOX = np.eye(4)
FILE_FROM_BOX[:3, :3] = Rotation.from_euler("zx", [30.0, -90.0], degrees=True).as_matrix()
FILE_FROM_BOX[:3, 3] = [10.0, -3.0, 2.0]


def _spec(obstacles):
    return parse_scene({"name": "f", "room": {"footprint": [[0, 0], [4, 0], [4, 4], [0, 4]], "height": 3.0},
                        "obstacles": obstacles, "targets": [{"name": "t", "kind": "volume", "heights": [1.0], "coverage": 1}],
                        "cameras": [{"name": "c", "resolution": [64, 48], "fov_deg": [90, 70]}],
                        "mounts": [{"kind": "ceiling_grid", "camera": "c"}]})


# ----------------------------------------------------------------------------- unit tests


def test_input_from_scene_inverts_the_obstacle_transform():
    tf = {"scale": 0.001, "rotate_deg": [10.0, -20.0, 35.0], "translate": [1.0, 2.0, -0.5]}
    spec = _spec([{"name": "b", "box": {"min": [1, 1, 0], "max": [2, 2, 1]}},
                  {"name": "scan", "point_cloud": "x.ply", "transform": tf},
                  {"name": "other", "point_cloud": "y.ply", "transform": {"translate": [5.0, 0.0, 0.0]}}])
    T = input_from_scene(spec)
    assert T.dtype == np.float64 and T.shape == (4, 4)
    p_file = np.array([[1200.0, -300.0, 2500.0], [0.0, 0.0, 0.0]])  # millimetres
    # the scene's points are the loader's: R @ (s p) + t (camplace.scene.loaders.cleanup)
    R = Rotation.from_euler("xyz", tf["rotate_deg"], degrees=True).as_matrix()
    p_scene = (0.001 * p_file) @ R.T + tf["translate"]
    back = np.c_[p_scene, np.ones(2)] @ T.T  # p_input = T @ [p_scene, 1]
    assert np.allclose(back[:, :3], p_file, atol=1e-9) and np.allclose(back[:, 3], 1.0)
    assert np.allclose(invert(T) @ T, np.eye(4), atol=1e-12)
    assert np.allclose(rotation_part(T), R.T, atol=1e-12)  # the first file obstacle defines the frame


def test_identity_for_box_scenes_and_files_without_transform():
    assert np.array_equal(input_from_scene(_spec([{"name": "b", "box": {"min": [1, 1, 0], "max": [2, 2, 1]}}])),
                          np.eye(4))
    assert np.array_equal(input_from_scene(_spec([{"name": "m", "mesh": "room.obj"}])), np.eye(4))


def test_level_floor_matrix_from_the_load_report():
    level = np.eye(4)
    level[:3, :3] = Rotation.from_euler("x", 90.0, degrees=True).as_matrix()
    level[2, 3] = -0.7
    spec = _spec([{"name": "scan", "point_cloud": "x.ply",
                   "transform": {"translate": [1.0, 0.0, 0.0], "level_floor": True, "up": "+y"}}])
    report = {"scan": {"cleanup": [{"step": "transform"}, {"step": "level_floor", "matrix": level.tolist()}]}}
    T = input_from_scene(spec, report)
    expected = level @ scene_from_file(CloudTransform(translate=(1.0, 0.0, 0.0)))
    assert np.allclose(T, np.linalg.inv(expected), atol=1e-12)


@settings(max_examples=150, deadline=None)
@given(st.floats(-180, 180), st.floats(-89.9, 89.9), st.floats(-179, 179), st.floats(-180, 180),
       st.floats(-180, 180), st.floats(-180, 180))
@example(0.0, 89.9, 0.0, 90.0, 0.0, 0.0)  # the moved camera looks almost straight down its new z
def test_yaw_pitch_roll_of_a_moved_pose_give_it_back(yaw, pitch, roll, a, b, c):
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", [a, b, c], degrees=True).as_matrix()
    T[:3, 3] = [1.0, -2.0, 3.0]
    R = rotation_from_ypr(yaw, pitch, roll)
    pos, moved = map_poses(T, [[0.5, 0.5, 2.5]], R)
    assert np.allclose(moved[0].T @ moved[0], np.eye(3), atol=1e-12) and np.linalg.det(moved[0]) > 0
    assert np.allclose(rotation_from_ypr(*ypr_from_rotation(moved)[0])[0], moved[0], atol=1e-6)
    assert np.allclose(ypr_from_rotation(R)[0][1], pitch, atol=1e-6)
    assert np.allclose(pos[0], T[:3, :3] @ [0.5, 0.5, 2.5] + T[:3, 3], atol=1e-12)


def test_frame_names_are_checked():
    from camplace.outputs.write import check_frame

    with pytest.raises(InputError, match="frame: expected 'scene' or 'input', got 'file'") as e:
        check_frame("file")
    assert e.value.option == "frame"


# ----------------------------------------------------------------------------- round trip


@pytest.fixture(scope="module")
def scanned(tmp_path_factory):
    """A synthetic scan of a box room written in FILE_FROM_BOX's frame (y up, turned, moved),
    imported with `camplace scene import --up +y`."""
    from camplace.cli.app import app
    from camplace.scene.build import build_scene
    from camplace.scene.loaders.pointcloud import write_point_cloud
    from camplace.workflows.scan import scan_scene

    d = tmp_path_factory.mktemp("frames")
    room = build_scene(box_room(obstacles=[{"name": "crate", "box": {"min": [2.5, 2.5, 0.0], "max": [3.5, 3.5, 1.0]}}]))
    cloud = scan_scene(room, viewpoints=np.array([[1.0, 1.0, 1.6], [3.0, 1.5, 1.6], [1.5, 3.2, 1.6]]),
                       step_deg=1.0, noise=0.0)
    move = lambda p: p @ FILE_FROM_BOX[:3, :3].T + FILE_FROM_BOX[:3, 3]  # noqa: E731
    ply = write_point_cloud(d / "room.ply", move(cloud.points), move(cloud.viewpoints))
    res = CliRunner().invoke(app, ["-q", "scene", "import", str(ply), "--out", str(d / "room.yaml"), "--up", "+y",
                                   "--heights", "1.0", "--coverage", "1", "--budget", "2"])
    assert res.exit_code == 0, res.output
    return d


def _camera_in_file_frame():
    """A camera 2.5 m up in the box room, looking at the crate, given in the file's frame."""
    R_box = rotation_from_ypr(40.0, 35.0, 5.0)[0]
    pos, rot = map_poses(FILE_FROM_BOX, [[1.0, 1.2, 2.5]], R_box[None])
    return pos[0], rot[0]


def _invoke(args):
    from camplace.cli.app import app

    res = CliRunner().invoke(app, ["-q", *map(str, args)])
    assert res.exit_code == 0, res.output
    return res


def _contract_holds(out: Path) -> None:
    if not CHECK_RUN.is_file():
        pytest.skip("../shared/contract/check_run.py is absent")
    res = subprocess.run([sys.executable, str(CHECK_RUN), str(out)], capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr


def test_scene_frame_is_levelled_and_maps_back_to_the_file(scanned):
    from camplace.scene.build import build_scene
    from camplace.spec.loading import load_scene_file

    sc = build_scene(load_scene_file(scanned / "room.yaml"), scanned)
    T = sc.input_from_scene
    assert not np.allclose(T, np.eye(4), atol=0.1)  # the scene frame is not the file's
    box_from_scene = np.linalg.inv(FILE_FROM_BOX) @ T  # the scene frame seen from the box room's
    assert np.allclose(box_from_scene[2, :3], [0, 0, 1], atol=1e-3)  # both z up (RANSAC floor)
    assert abs(box_from_scene[2, 3]) < 0.05  # floors at z = 0 (to the floor detection's 2 cm bins)
    scan_in_file = sc.points @ T[:3, :3].T + T[:3, 3]  # the scene's cleaned points, back in the file
    floor = np.abs(scan_in_file @ np.linalg.inv(FILE_FROM_BOX)[:3, :3].T + np.linalg.inv(FILE_FROM_BOX)[:3, 3])
    assert np.min(floor[:, 2]) < 0.01


def test_a_camera_given_in_the_file_frame_comes_back_at_the_same_pose(scanned, tmp_path):
    pos, rot = _camera_in_file_frame()
    ypr = ypr_from_rotation(rot)[0]
    cams = [{"id": "door", "position": pos.tolist(), "rotation": rot.tolist(), "camera": "wide"}]
    (tmp_path / "cams.json").write_text(json.dumps({"cameras": cams}))
    (tmp_path / "cams.csv").write_text("id,x,y,z,yaw,pitch,roll,lens\n" + ",".join(
        ["door", *(repr(float(v)) for v in (*pos, *ypr)), "wide"]) + "\n")
    scene = scanned / "room.yaml"
    for name in ("cams.json", "cams.csv"):
        out = tmp_path / f"out-{name}"
        _invoke(["evaluate", scene, tmp_path / name, "--frame", "input", "--out", out, "--no-plan"])
        p = json.loads((out / "placement.json").read_text())
        assert p["frame"] == "input"
        cam = p["cameras"][0]
        assert np.allclose(cam["position"], pos, atol=1e-6)
        assert np.allclose(cam["rotation"], rot, atol=1e-9)
        assert np.allclose(rotation_from_ypr(cam["yaw_deg"], cam["pitch_deg"], cam["roll_deg"])[0], rot, atol=1e-6)
        _contract_holds(out)
    # the same camera in the scene frame, evaluated there, sees the same targets
    T = np.asarray(p["input_from_scene"])
    spos, srot = map_poses(invert(T), [pos], rot[None])
    (tmp_path / "scene.json").write_text(json.dumps([{"position": spos[0].tolist(), "rotation": srot[0].tolist(),
                                                      "camera": "wide"}]))
    _invoke(["evaluate", scene, tmp_path / "scene.json", "--out", tmp_path / "out-scene", "--no-plan"])
    ps = json.loads((tmp_path / "out-scene" / "placement.json").read_text())
    assert ps["frame"] == "scene" and np.allclose(ps["input_from_scene"], T, atol=0)
    back, back_rot = map_poses(T, [ps["cameras"][0]["position"]], np.asarray([ps["cameras"][0]["rotation"]]))
    assert np.allclose(back[0], pos, atol=1e-6) and np.allclose(back_rot[0], rot, atol=1e-9)
    m_in = json.loads((tmp_path / "out-cams.json" / "metrics.json").read_text())
    m_sc = json.loads((tmp_path / "out-scene" / "metrics.json").read_text())
    assert m_in["cost"] == m_sc["cost"] and m_in["coverage_histogram"] == m_sc["coverage_histogram"]
    assert m_sc["coverage_histogram"].get("1", 0) > 0  # the camera sees part of the room
    with np.load(tmp_path / "out-cams.json" / "visibility.npz") as a, np.load(tmp_path / "out-scene" / "visibility.npz") as b:
        assert np.allclose(a["candidate_positions"], spos) and np.array_equal(a["indices"], b["indices"])


def test_run_writes_every_output_in_the_input_frame(scanned, tmp_path):
    from camplace.outputs.exports import read_colmap_text, read_opencv_yaml

    scene = scanned / "room.yaml"
    _invoke(["run", scene, "--frame", "input", "--out", tmp_path / "in", "--no-cache", "--repeatable"])
    _invoke(["run", scene, "--out", tmp_path / "sc", "--no-cache", "--repeatable"])
    pin = json.loads((tmp_path / "in" / "placement.json").read_text())
    psc = json.loads((tmp_path / "sc" / "placement.json").read_text())
    T = np.asarray(pin["input_from_scene"])
    assert pin["frame"] == "input" and psc["frame"] == "scene" and psc["input_from_scene"] == pin["input_from_scene"]
    assert [c["candidate_id"] for c in pin["cameras"]] == [c["candidate_id"] for c in psc["cameras"]]
    with np.load(tmp_path / "in" / "visibility.npz") as z:  # V and its poses stay in the scene frame
        sel = [c["candidate_id"] for c in pin["cameras"]]
        scene_pos = z["candidate_positions"][sel]
        pos, rot = map_poses(T, scene_pos, z["rotations"][sel])
    for k, (a, b) in enumerate(zip(pin["cameras"], psc["cameras"])):
        assert np.allclose(a["position"], pos[k], atol=1e-9) and np.allclose(a["rotation"], rot[k], atol=1e-12)
        assert b["position"] == scene_pos[k].tolist()  # the scene-frame output: V's poses as they are
        assert np.allclose(rotation_from_ypr(a["yaw_deg"], a["pitch_deg"], a["roll_deg"])[0], rot[k], atol=1e-6)
        cv = read_opencv_yaml(tmp_path / "in" / "opencv" / f"camera_{a['candidate_id']}.yaml")
        assert np.allclose(cv["position"], pos[k], atol=1e-9) and np.allclose(cv["rotation"], rot[k], atol=1e-9)
    colmap = read_colmap_text(tmp_path / "in" / "colmap")
    assert np.allclose([c["position"] for c in colmap], pos, atol=1e-9)
    rows = (tmp_path / "in" / "placement.csv").read_text().splitlines()[1:]
    assert np.allclose([[float(v) for v in r.split(",")[1:4]] for r in rows], pos, atol=1e-9)
    assert json.loads((tmp_path / "in" / "metrics.json").read_text()) == \
        json.loads((tmp_path / "sc" / "metrics.json").read_text())
    _contract_holds(tmp_path / "in")
    _contract_holds(tmp_path / "sc")


@pytest.mark.parametrize("cmd", [["run", "demo"], ["demo"], ["evaluate", "demo", "p.json"]])
def test_a_bad_frame_is_refused_before_any_work(cmd, tmp_path, monkeypatch, capsys):
    from tests.conftest import run_cli

    (tmp_path / "p.json").write_text(json.dumps([{"position": [1, 1, 2], "yaw_deg": 0, "pitch_deg": 30}]))
    monkeypatch.chdir(tmp_path)
    code, text = run_cli([*cmd, "--frame", "file", "--out", tmp_path / "o"], monkeypatch, capsys)
    assert code == 2 and "--frame: expected 'scene' or 'input', got 'file'" in text and "Traceback" not in text
    assert not (tmp_path / "o").exists()


def test_box_scenes_write_the_identity(tmp_path):
    _invoke(["run", "demo", "--budget", "2", "--frame", "input", "--out", tmp_path / "o", "--no-cache", "--no-plan"])
    p = json.loads((tmp_path / "o" / "placement.json").read_text())
    assert p["frame"] == "input" and p["input_from_scene"] == np.eye(4).tolist()
    _contract_holds(tmp_path / "o")


def test_level_floor_in_the_scene_file_maps_back_too(scanned):
    """A hand-written scene with ``transform: {level_floor: true, up: +y}``: the levelling
    found at load time (reported with its matrix) is part of input_from_scene."""
    import yaml
    from scipy.spatial import cKDTree

    from camplace.scene.build import build_scene
    from camplace.scene.loaders.pointcloud import load_point_cloud

    data = yaml.safe_load((scanned / "room.yaml").read_text())
    data["obstacles"][0]["transform"] = {"level_floor": True, "up": "+y"}
    # the levelled file lies in x 8..13.5, y -2..3.5 (FILE_FROM_BOX turned back up)
    data["room"] = {"footprint": [[6, -4], [16, -4], [16, 6], [6, 6]], "height": 3.5}
    sc = build_scene(parse_scene(data, "<level_floor scene>"), scanned)
    T = sc.input_from_scene
    assert not np.allclose(T[:3, :3], np.eye(3), atol=0.1)
    back = sc.points @ T[:3, :3].T + T[:3, 3]
    d, _ = cKDTree(load_point_cloud(scanned / "room.ply").points).query(back[::50])
    assert np.max(d) < 0.03  # on the file's points, to the 2 cm downsampling
