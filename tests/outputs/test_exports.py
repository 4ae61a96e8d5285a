"""Exports: OpenCV camera YAML and COLMAP text model round-trip poses and intrinsics."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from camplace.cameras.candidates import rotation_from_ypr
from camplace.outputs.exports import (colmap_texts, qvec_to_rotmat, read_colmap_text, read_opencv_yaml, rodrigues,
                              rotmat_to_qvec, world_to_camera, write_exports)

INTR = {"model": "pinhole", "width": 1780, "height": 720, "fx": 1234.5678901234, "fy": 1100.25, "cx": 889.5, "cy": 359.5}


def _cam(cid, pos, ypr, intr=INTR, name="wide"):
    return {"candidate_id": cid, "position": list(pos), "camera": name, "intrinsics": dict(intr),
            "yaw_deg": ypr[0], "pitch_deg": ypr[1], "roll_deg": ypr[2],
            "rotation": rotation_from_ypr(*ypr)[0].tolist()}


def test_world_to_camera_maps_centre_to_origin_and_forward_to_z():
    cam = _cam(3, [1.0, 2.0, 2.9], (90.0, 0.0, 0.0))  # looking along +y
    R, t = world_to_camera(cam["rotation"], cam["position"])
    assert np.allclose(R @ np.array(cam["position"]) + t, 0, atol=1e-12)
    ahead = np.array([1.0, 5.0, 2.9])  # 3 m ahead of the camera
    assert np.allclose(R @ ahead + t, [0, 0, 3.0], atol=1e-12)
    above = np.array([1.0, 2.0, 3.9])  # up in the world = -y in the OpenCV camera
    assert (R @ above + t)[1] < -0.99


def test_quaternion_of_known_rotation():
    # 90 deg about z: q = (cos 45, 0, 0, sin 45)
    Rz = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    assert np.allclose(rotmat_to_qvec(Rz), [np.sqrt(0.5), 0, 0, np.sqrt(0.5)], atol=1e-15)
    assert np.allclose(rodrigues(Rz), [0, 0, np.pi / 2], atol=1e-15)
    # 180 deg about x: trace -1 branch
    Rx = np.diag([1.0, -1.0, -1.0])
    assert np.allclose(np.abs(rotmat_to_qvec(Rx)), [0, 1, 0, 0], atol=1e-15)


@settings(max_examples=200, deadline=None)
@given(st.floats(-180, 180), st.floats(-89, 89), st.floats(-180, 180))
def test_quaternion_round_trip(yaw, pitch, roll):
    R = rotation_from_ypr(yaw, pitch, roll)[0]
    q = rotmat_to_qvec(R)
    assert q[0] >= 0 and abs(np.linalg.norm(q) - 1) < 1e-12
    assert np.allclose(qvec_to_rotmat(q), R, atol=1e-12)


def _cameras():
    dist = dict(INTR, model="opencv", distortion=[-0.12, 0.034, 1e-05, -2e-4, 0.0012])
    fish = dict(INTR, model="fisheye", distortion=[0.01, -0.002, 3e-4, -1e-5])
    return [_cam(6, [1.0, 2.0, 2.9], (60.0, 30.0, 0.0)),
            _cam(42, [3.3, 0.1 + 0.2, 2.9000000000000004], (137.25, 45.0, 5.5)),
            _cam(7, [0.5, 4.75, 2.5], (315.0, 60.0, -3.0), intr=dist, name="distorted"),
            _cam(8, [0.25, 1.75, 2.5], (10.0, 89.0, 0.0), intr=fish, name="fish")]


def test_opencv_yaml_round_trip(tmp_path):
    cams = _cameras()
    paths = write_exports(tmp_path, cams)
    assert {f"opencv/camera_{c['candidate_id']}.yaml" for c in cams} <= set(paths)
    for cam in cams:
        text = (tmp_path / f"opencv/camera_{cam['candidate_id']}.yaml").read_text()
        assert text.startswith("%YAML:1.0\n---\n") and "!!opencv-matrix" in text
        d = read_opencv_yaml(tmp_path / f"opencv/camera_{cam['candidate_id']}.yaml")
        intr = cam["intrinsics"]
        assert (d["width"], d["height"]) == (intr["width"], intr["height"])
        for k in ("fx", "fy", "cx", "cy"):
            assert abs(d[k] - intr[k]) <= 1e-9
        assert np.allclose(d["position"], cam["position"], atol=1e-9, rtol=0)
        assert np.allclose(d["rotation"], cam["rotation"], atol=1e-9, rtol=0)
        want = intr.get("distortion", [0.0] * 5)
        assert d["model"] == intr["model"]
        assert np.allclose(d["dist"], want, atol=1e-12, rtol=0) and len(d["dist"]) == len(want)
        R, t = world_to_camera(cam["rotation"], cam["position"])
        assert np.allclose(d["R"], R, atol=1e-12) and np.allclose(d["t"], t, atol=1e-12)


def test_colmap_round_trip(tmp_path):
    cams = _cameras()
    write_exports(tmp_path, cams)
    imgs = read_colmap_text(tmp_path / "colmap")
    assert len(imgs) == len(cams)
    assert (tmp_path / "colmap" / "points3D.txt").exists()
    for img, cam in zip(imgs, cams):
        intr = cam["intrinsics"]
        assert (img["width"], img["height"]) == (intr["width"], intr["height"])
        for k in ("fx", "fy", "cx", "cy"):
            assert abs(img[k] - intr[k]) <= 1e-9
        assert np.allclose(img["position"], cam["position"], atol=1e-9, rtol=0)
        assert np.allclose(img["rotation"], cam["rotation"], atol=1e-9, rtol=0)
        assert str(cam["candidate_id"]) in img["name"]
    assert [i["model"] for i in imgs] == ["PINHOLE", "PINHOLE", "FULL_OPENCV", "OPENCV_FISHEYE"]
    assert np.allclose(imgs[2]["dist"][:5], cams[2]["intrinsics"]["distortion"], atol=1e-12)
    assert np.allclose(imgs[2]["dist"][5:], 0) and np.allclose(imgs[3]["dist"], cams[3]["intrinsics"]["distortion"])
    # COLMAP puts the centre of the top-left pixel at (0.5, 0.5)
    assert imgs[0]["params"][2] == pytest.approx(INTR["cx"] + 0.5)


def test_colmap_image_line_has_world_to_camera_translation():
    cam = _cam(1, [2.0, 0.0, 0.0], (0.0, 0.0, 0.0))  # looking along +x from x = 2
    _, images, _ = colmap_texts([cam])
    line = [ln for ln in images.splitlines() if ln and not ln.startswith("#")][0].split()
    t = np.array([float(v) for v in line[5:8]])
    # world origin lies 2 m behind the camera: camera-frame z = -2
    assert np.allclose(t, [0, 0, -2.0], atol=1e-12)


def test_exports_of_a_run_round_trip(demo_run, tmp_path):
    from camplace.outputs.write import placement_dict

    r = demo_run
    cams = placement_dict(r.scene.name, r.placement, r.problem.budget, r.visibility.candidates)["cameras"]
    cams = json.loads(json.dumps(cams))  # exactly what placement.json holds
    write_exports(tmp_path, cams)
    imgs = read_colmap_text(tmp_path / "colmap")
    for img, cam in zip(imgs, cams):
        d = read_opencv_yaml(tmp_path / f"opencv/camera_{cam['candidate_id']}.yaml")
        for got in (img, d):
            assert np.abs(got["position"] - cam["position"]).max() <= 1e-9
            assert np.abs(got["rotation"] - np.array(cam["rotation"])).max() <= 1e-9
            assert abs(got["fx"] - cam["intrinsics"]["fx"]) <= 1e-9


def test_stale_yaml_files_are_removed(tmp_path):
    cams = _cameras()
    write_exports(tmp_path, cams)
    write_exports(tmp_path, cams[:1])
    assert sorted(p.name for p in (tmp_path / "opencv").iterdir()) == ["camera_6.yaml"]


def test_bad_files_raise_input_error(tmp_path):
    from camplace.core.errors import InputError

    (tmp_path / "x.yaml").write_text("%YAML:1.0\n---\nfoo: 1\n")
    with pytest.raises(InputError, match="camera_matrix"):
        read_opencv_yaml(tmp_path / "x.yaml")
    (tmp_path / "cameras.txt").write_text("1 WEIRD 10 10 1 1 1 1\n")
    (tmp_path / "images.txt").write_text("")
    with pytest.raises(InputError, match="cameras.txt:1"):
        read_colmap_text(tmp_path)


def test_exports_in_the_input_frame_see_the_world_as_before(tmp_path):
    """Cameras moved into another frame (camplace.outputs.write.cameras_in_frame, as
    --frame input writes them): the exports read back the moved poses, and a world point
    lands at the same camera coordinates in either frame."""
    from scipy.spatial.transform import Rotation

    from camplace.outputs.write import cameras_in_frame

    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("zx", [25.0, -90.0], degrees=True).as_matrix()  # y up
    T[:3, 3] = [4.0, -1.5, 12.25]
    cams = _cameras()
    moved = json.loads(json.dumps(cameras_in_frame(cams, T)))
    write_exports(tmp_path, moved)
    imgs = read_colmap_text(tmp_path / "colmap")
    x_scene = np.array([1.5, 2.5, 1.0])
    x_input = T[:3, :3] @ x_scene + T[:3, 3]
    for img, cam, mv in zip(imgs, cams, moved):
        d = read_opencv_yaml(tmp_path / f"opencv/camera_{cam['candidate_id']}.yaml")
        assert np.allclose(mv["position"], T[:3, :3] @ cam["position"] + T[:3, 3], atol=1e-12)
        R, t = world_to_camera(cam["rotation"], cam["position"])
        for got in (img, d):
            assert np.allclose(got["position"], mv["position"], atol=1e-9)
            assert np.allclose(got["R"] @ x_input + got["t"], R @ x_scene + t, atol=1e-9)
        assert np.allclose(rotation_from_ypr(mv["yaw_deg"], mv["pitch_deg"], mv["roll_deg"])[0], mv["rotation"],
                           atol=1e-6)
        assert mv["intrinsics"] == cam["intrinsics"] and mv["candidate_id"] == cam["candidate_id"]
