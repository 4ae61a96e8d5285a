"""Calibration files (camplace.cameras.calibration): OpenCV FileStorage, ROS and JSON,
relative paths in a scene file, bad files named with their key."""

from __future__ import annotations

import json

import pytest

from camplace.cameras.calibration import load_calibration
from camplace.cameras.models import camera_from_spec
from camplace.core.errors import InputError
from camplace.spec.loading import parse_scene


OPENCV_YAML = """%YAML:1.0
---
image_width: 1280
image_height: 720
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 910.5, 0., 640.2, 0., 912.25, 359.8, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ -0.31, 0.11, 0.001, -0.002, -0.02 ]
"""


ROS_YAML = """image_width: 800
image_height: 600
camera_name: fish
camera_matrix:
  rows: 3
  cols: 3
  data: [300.0, 0.0, 400.0, 0.0, 301.0, 300.0, 0.0, 0.0, 1.0]
distortion_model: equidistant
distortion_coefficients:
  rows: 1
  cols: 4
  data: [0.02, -0.01, 0.001, 0.0]
"""


def test_load_opencv_filestorage_yaml(tmp_path):
    f = tmp_path / "cam.yaml"
    f.write_text(OPENCV_YAML)
    cal = load_calibration(f)
    assert (cal["fx"], cal["fy"], cal["cx"], cal["cy"]) == (910.5, 912.25, 640.2, 359.8)
    assert cal["distortion"] == [-0.31, 0.11, 0.001, -0.002, -0.02] and cal["resolution"] == [1280, 720]


def test_load_ros_and_json_calibrations(tmp_path):
    f = tmp_path / "ros.yaml"
    f.write_text(ROS_YAML)
    cal = load_calibration(f)
    assert cal["model"] == "fisheye" and cal["resolution"] == [800, 600] and cal["fx"] == 300.0
    j = tmp_path / "cam.json"
    j.write_text(json.dumps({"K": [[500, 0, 320], [0, 502, 240], [0, 0, 1]], "D": [0.1, -0.05, 0, 0, 0],
                             "image_size": [640, 480]}))
    cal = load_calibration(j)
    assert (cal["fx"], cal["fy"], cal["cx"], cal["cy"]) == (500, 502, 320, 240) and cal["resolution"] == [640, 480]
    j2 = tmp_path / "flat.json"
    j2.write_text(json.dumps({"fx": 400, "fy": 400, "cx": 300, "cy": 200, "distortion": [0, 0, 0, 0],
                              "width": 600, "height": 400}))
    assert load_calibration(j2)["resolution"] == [600, 400]


def test_calibration_in_scene_file_relative_path(tmp_path):
    (tmp_path / "calib").mkdir()
    (tmp_path / "calib" / "cam.yaml").write_text(OPENCV_YAML)
    (tmp_path / "ros.yaml").write_text(ROS_YAML)
    spec = parse_scene({
        "name": "cal", "room": {"footprint": [[0, 0], [4, 0], [4, 4], [0, 4]], "height": 3},
        "targets": [{"name": "w", "kind": "volume", "heights": [1.0], "coverage": 1}],
        "cameras": [{"name": "a", "model": "opencv", "calibration": "calib/cam.yaml"},
                    {"name": "b", "calibration": "ros.yaml", "max_range": 6}],
        "mounts": [{"kind": "ceiling_grid", "camera": "a"}]})
    a = camera_from_spec(spec.cameras[0], tmp_path)
    b = camera_from_spec(spec.cameras[1], tmp_path)
    assert (a.model, a.width, a.height, a.fx) == ("opencv", 1280, 720, 910.5)
    assert (b.model, b.width, b.fx, b.max_range) == ("fisheye", 800, 300.0, 6)
    with pytest.raises(InputError, match="calibration file not found"):
        camera_from_spec(spec.cameras[0], tmp_path / "nowhere")


def test_bad_calibration_file(tmp_path):
    f = tmp_path / "bad.yaml"
    f.write_text("camera_matrix: [1, 2, 3]\n")
    with pytest.raises(InputError, match="camera_matrix"):
        load_calibration(f)
    g = tmp_path / "bad.json"
    g.write_text("{not json")
    with pytest.raises(InputError, match="not valid JSON"):
        load_calibration(g)
