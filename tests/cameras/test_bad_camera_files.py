"""Bad calibration and placement files (issue 16): a calibration YAML/JSON or a placement
CSV/JSON given to ``evaluate`` (or as ``existing:`` / ``keep``) either reads into finite
values or raises InputError with one line naming the file; never another exception,
never a traceback (hypothesis over mutated bytes of small valid files)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings, strategies as st

from camplace.cameras.calibration import load_calibration
from camplace.cameras.placement_files import read_placement
from camplace.core.errors import InputError

from cameras.test_calibration import OPENCV_YAML, ROS_YAML
from conftest import read_or_one_line

CAMERA = {"position": [1.0, 2.0, 2.9], "yaw_deg": 45.0, "pitch_deg": 30.0, "roll_deg": 0.0, "camera": "wide"}
VALID = {
    "cv.yaml": OPENCV_YAML.encode(),
    "ros.yaml": ROS_YAML.encode(),
    "k.json": json.dumps({"K": [[500, 0, 320], [0, 502, 240], [0, 0, 1]], "D": [0.1, -0.05, 0, 0, 0],
                          "image_size": [640, 480]}).encode(),
    "placement.csv": b"id,x,y,z,yaw,pitch,roll,lens\n1,1.0,2.0,2.9,45,30,0,wide\n2,3.5,1.0,2.9,180,45,0,wide\n",
    "placement.json": json.dumps({"cameras": [CAMERA, dict(CAMERA, position=[3.0, 1.0, 2.9])]}).encode(),
}


def _read(path: Path):
    if path.name.startswith("placement"):
        poses = read_placement(path)
        return np.concatenate([poses.positions.ravel(), poses.rotations.ravel(), poses.angles_deg.ravel()])
    c = load_calibration(path)
    return np.array([c["fx"], c["fy"], c["cx"], c["cy"], *c["distortion"], *c.get("resolution", [])], float)


def _check(path: Path) -> None:
    values = read_or_one_line(_read, path)
    assert values is None or np.all(np.isfinite(values)), values


def _mutate(raw: bytes, kind: str, at: float, junk: bytes) -> bytes:
    i = int(at * len(raw))
    if kind == "truncate":
        return raw[:i]
    if kind == "flip":
        i = min(i, len(raw) - 1)
        return raw[:i] + bytes([raw[i] ^ (junk[0] or 0xFF)]) + raw[i + 1:]
    return raw[:i] + junk + raw[i:]


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.sampled_from(sorted(VALID)), kind=st.sampled_from(["truncate", "flip", "insert"]),
       at=st.floats(0.0, 1.0), junk=st.binary(min_size=1, max_size=16))
@example(name="placement.csv", kind="insert", at=0.99, junk=b"\xff\xfe")        # non-UTF-8 text
@example(name="k.json", kind="insert", at=0.5, junk=b"1e999")                  # inf in JSON
@example(name="cv.yaml", kind="insert", at=0.0, junk=b"\x00\x01")
@example(name="placement.json", kind="truncate", at=0.5, junk=b"x")
def test_mutated_camera_files_read_or_fail_in_one_line(tmp_path_factory, name, kind, at, junk):
    path = tmp_path_factory.mktemp("bad") / name
    path.write_bytes(_mutate(VALID[name], kind, at, junk))
    _check(path)


@pytest.mark.parametrize("name, content", [
    ("cv.yaml", b"%YAML:1.0\n---\ncamera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
                b"  data: [.nan, 0, 1, 0, 1, 1, 0, 0, 1]\n"),
    ("k.json", b'{"fx": Infinity, "fy": 1, "cx": 1, "cy": 1}'),
    ("k.json", b'{"K": [[1, 0], [0, 1]]}'),
    ("k.json", b"[1, 2, 3]"),
    ("k.json", b'{"fx": "wide", "fy": 1, "cx": 1, "cy": 1}'),
    ("placement.csv", b"id,x,y,z,yaw,pitch,roll,lens\n1,nan,2,2.9,0,30,0,wide\n"),
    ("placement.csv", b""),
    ("placement.json", b'{"cameras": [{"position": [1, 2], "yaw_deg": 0}]}'),
    ("placement.json", b'{"cameras": "many"}'),
    ("placement.json", b'{"cameras": [{"position": [1, 2, 3], "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 1e999]]}]}'),
])
def test_each_defect_by_hand_is_one_line(tmp_path, name, content):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(InputError) as err:
        _read(path)
    assert str(path) in str(err.value) and "\n" not in str(err.value)
