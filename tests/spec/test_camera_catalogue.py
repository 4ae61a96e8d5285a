"""Camera catalogues (issue 27): CSV and YAML price lists as the scene's camera types, the
shipped example and the built-in scene that uses it, one-line errors naming file, row and
column, and a fixed-focal catalogue that reproduces today's scene keys."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.spec.builtin import resolve_scene
from camplace.spec.catalogue import read_catalogue
from camplace.spec.loading import load_scene_file, parse_scene
from conftest import REPO, box_room

TYPICAL = REPO / "src" / "camplace" / "spec" / "scenes" / "cameras-typical.csv"
HEAD = "name,kind,resolution,pixel_um,focal_mm,focal_steps,price,bitrate_mbps,ir_range_m\n"


def _scene(cameras) -> dict:
    d = box_room().model_dump(exclude_none=True)
    d["cameras"] = cameras
    return d


def test_the_example_catalogue_and_the_built_in_scene():
    rows = read_catalogue(TYPICAL)
    assert len(rows) == 7 and all("price" in r and "bitrate_mbps" in r for r in rows)
    vari = next(r for r in rows if r["name"] == "vari-4mp-2.8-12")
    assert vari == {"name": "vari-4mp-2.8-12", "model": "pinhole", "resolution": [2688, 1520], "pixel_um": 2.0,
                    "focal_mm": [2.8, 12.0], "focal_steps": 4, "price": 2.4, "bitrate_mbps": 6.0, "ir_range_m": 50.0}
    fish = rows[-1]
    assert fish["model"] == "fisheye" and fish["price"] == 3.0 and fish["max_fov_deg"] == 180.0
    spec, _, _ = resolve_scene("lens-store")  # the catalogue beside the built-in scenes, its models: but the fisheye
    assert [c.name for c in spec.cameras] == [r["name"] for r in rows[:-1]] and spec.recording.retention_days == 30
    assert spec.cameras[-1].focal_range_mm == (2.8, 12.0)
    assert spec.mounts[0].camera_names == [c.name for c in spec.cameras]



def test_csv_and_yaml_catalogues_give_the_same_cameras(tmp_path):
    (tmp_path / "cams.csv").write_text("# my price list\n" + HEAD + "vf,pinhole,1920x1080,2.9,2.8-12,3,2.5,4,30\n"
                                       "fix,fisheye,1280x1280,3.0,1.4,,1.6,,\n")
    (tmp_path / "cams.yaml").write_text(
        "- {name: vf, kind: pinhole, resolution: [1920, 1080], pixel_um: 2.9, focal_mm: [2.8, 12], focal_steps: 3,\n"
        "   price: 2.5, bitrate_mbps: 4, ir_range_m: 30}\n"
        "- {name: fix, kind: fisheye, resolution: 1280x1280, pixel_um: 3.0, focal_mm: 1.4, price: 1.6}\n")
    d = _scene({"catalogue": "cams.csv", "models": ["fix", "vf"]})
    d["mounts"][0]["camera"] = "vf"
    (tmp_path / "s.yaml").write_text(__import__("yaml").safe_dump(d))
    from_csv = load_scene_file(tmp_path / "s.yaml")
    assert [c.name for c in from_csv.cameras] == ["fix", "vf"]  # models: that subset, in that order
    from_yaml = parse_scene(dict(d, cameras={"catalogue": "cams.yaml", "models": ["fix", "vf"]}), "s", tmp_path)
    assert from_yaml.cameras == from_csv.cameras
    assert from_csv.cameras[1].focal_range_mm == (2.8, 12.0) and from_csv.cameras[1].cost == 2.5


@pytest.mark.parametrize("row, message", [
    ("vf,pinhole,1920x1080,2.9,12-2.8,,1,,", r"row 3, column focal_mm: expected \[min, max\] with min <= max"),
    ("vf,pinhole,1920x1080,0,4,,1,,", r"row 3, column pixel_um: expected .*greater than 0"),
    ("vf,dome,1920x1080,2.9,4,,1,,", r"row 3, column kind: expected 'pinhole', 'opencv' or 'fisheye'"),
    ("vf,pinhole,1920x1080,2.9,four,,1,,", r"row 3, column focal_mm: expected a number, got 'four'"),
    ("vf,pinhole,1920,2.9,4,,1,,", r"row 3, column resolution: expected WIDTHxHEIGHT"),
])
def test_bad_rows_are_one_line_errors_naming_file_row_and_column(tmp_path, row, message):
    path = tmp_path / "cams.csv"
    path.write_text("# comment\n" + HEAD + row + "\n")
    with pytest.raises(InputError, match=message) as e:
        parse_scene(_scene({"catalogue": "cams.csv"}), "s.yaml", tmp_path)
    assert str(e.value).startswith(f"{path}: ") and "\n" not in str(e.value)


def test_catalogue_file_and_model_errors(tmp_path):
    (tmp_path / "c.csv").write_text(HEAD + "cam,pinhole,640x480,2,4,,1,,\ncam,pinhole,640x480,2,4,,1,,\n")
    with pytest.raises(InputError, match=r"c.csv: row 3, column name: duplicate name 'cam' \(already row 2\)"):
        parse_scene(_scene({"catalogue": "c.csv"}), "s", tmp_path)
    (tmp_path / "d.csv").write_text("name,kind,focal,pixel_um\n")
    with pytest.raises(InputError, match=r"column 'focal' is not a catalogue column \(did you mean 'focal_mm'\?\)"):
        parse_scene(_scene({"catalogue": "d.csv"}), "s", tmp_path)
    (tmp_path / "e.csv").write_text(HEAD + "cam,pinhole,640x480,2,4,,1,,\n")
    with pytest.raises(InputError, match=r"s: cameras.models\[0\]: 'cma' is not in the catalogue \(did you mean"):
        parse_scene(_scene({"catalogue": "e.csv", "models": ["cma"]}), "s", tmp_path)
    with pytest.raises(InputError, match=r"s: cameras.catalogue: file 'nope.csv' not found"):
        parse_scene(_scene({"catalogue": "nope.csv"}), "s", tmp_path)


def test_a_fixed_focal_catalogue_reproduces_todays_results(tmp_path):
    """A camera type given today by fov_deg and the same lens bought from a catalogue
    (focal 2.9 mm on 2.9 µm pixels: f = 1000 px, the same range) give the same V and placement."""
    from camplace.workflows.run import run

    fov = [2 * math.degrees(math.atan(n / 2 / 1000.0)) for n in (1280, 720)]
    today = box_room(cameras=[{"name": "cam", "resolution": [1280, 720], "fov_deg": fov, "max_range": 6.0}])
    (tmp_path / "c.csv").write_text("name,resolution,pixel_um,focal_mm,max_range\ncam,1280x720,2.9,2.9,6\n")
    bought = parse_scene(_scene({"catalogue": "c.csv"}), "s", tmp_path)
    a, b = run(today, budget=3), run(bought, budget=3)
    assert b.visibility.candidates.cameras[0].fx == pytest.approx(1000.0, rel=1e-12)
    assert (a.visibility.V != b.visibility.V).nnz == 0
    assert np.array_equal(a.placement.selected, b.placement.selected) and a.metrics.cost == b.metrics.cost
