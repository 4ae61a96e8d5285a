"""The scene schema (camplace.spec.schema, .wording, .loading, .resources): one-line errors
with key paths, 'did you mean', resource estimates before allocation, referenced files,
YAML loading."""

from __future__ import annotations

import copy
import math

import pytest
import yaml

from camplace.spec.loading import check_referenced_files, load_scene_file, load_yaml_text, parse_scene
from camplace.spec.resources import check_resources, estimate_resources
from camplace.spec.schema import AngleRange, angle_values
from camplace.core.errors import InputError
from conftest import BASE


def err(d: dict) -> str:
    with pytest.raises(InputError) as e:
        parse_scene(d, "s.yaml")
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("s.yaml: ")
    return msg


def with_(path: str, value) -> dict:
    d = copy.deepcopy(BASE)
    keys = [int(k) if k.isdigit() else k for k in path.split(".")]
    cur = d
    for k in keys[:-1]:
        cur = cur[k]
    cur[keys[-1]] = value
    return d


def test_base_scene_is_valid():
    spec = parse_scene(copy.deepcopy(BASE))
    assert spec.name == "tiny" and spec.mounts[0].camera == "cam"


def test_key_paths_point_at_the_offending_value():
    assert err(with_("mounts.0.yaw_deg.step", 0)).startswith("s.yaml: mounts[0].yaw_deg.step: expected greater than 0")
    assert "cameras[0].resolution[1]: " in err(with_("cameras.0.resolution", [640, -1]))
    assert "room.footprint[2][1]: expected a finite number" in err(
        with_("room.footprint", [[0, 0], [3, 0], [3, math.inf], [0, 3]]))
    assert "obstacles[0].box.max[2]: box max must exceed min" in err(
        with_("obstacles.0.box", {"min": [1, 1, 1], "max": [2, 2, 1]}))


def test_unknown_keys_suggest_the_closest_valid_one():
    assert "unknown key 'hieght' (did you mean 'height'?)" in err(with_("room", {"footprint": BASE["room"]["footprint"],
                                                                                 "hieght": 3}))
    msg = err(with_("mounts.0.pitch_degs", [30]))
    assert "mounts[0].pitch_degs: unknown key 'pitch_degs' (did you mean 'pitch_deg'?)" in msg
    # a key far from every valid one: no suggestion, still one line
    assert "unknown key 'zzzz'" in err(with_("zzzz", 1)) and "did you mean" not in err(with_("zzzz", 1))


def test_cross_reference_errors_name_their_own_path():
    msg = err(with_("mounts.0.camera", "camm"))
    assert msg == "s.yaml: mounts[0].camera: unknown camera 'camm' (did you mean 'cam'?); expected one of 'cam'"
    assert "<top>" not in msg


def test_angles_union_forms():
    spec = parse_scene(with_("mounts.0.yaw_deg", 15))
    assert angle_values(spec.mounts[0].yaw_deg) == [15.0]
    spec = parse_scene(with_("mounts.0.yaw_deg", [0, 90]))
    assert angle_values(spec.mounts[0].yaw_deg) == [0.0, 90.0]
    r = AngleRange(start=0, stop=330, step=30)
    assert r.count() == 12 == len(r.values()) and r.values()[-1] == 330
    assert "mounts[0].yaw_deg[1]: expected a valid number" in err(with_("mounts.0.yaw_deg", [0, "north"]))


def test_booleans_are_not_numbers():
    assert "expected a number, not a boolean" in err(with_("room.height", True))
    assert "cameras[0].resolution[0]" in err(with_("cameras.0.resolution", [True, 480]))


def test_yaml_loader_refuses_duplicate_keys_and_names_the_line():
    with pytest.raises(InputError, match=r"f.yaml: not valid YAML at line 3, column 1: key 'a' appears twice"):
        load_yaml_text("a: 1\nb: 2\na: 3\n", "f.yaml")
    with pytest.raises(InputError, match=r"not valid YAML at line 2"):
        load_yaml_text("a: [1, 2\n", "f.yaml")
    assert load_yaml_text("a: {x: 1}\nb: [1, 2]\n", "f.yaml") == {"a": {"x": 1}, "b": [1, 2]}


def test_load_scene_file_resolves_referenced_files_beside_it(tmp_path):
    d = copy.deepcopy(BASE)
    d["obstacles"] = [{"name": "fixture", "mesh": "parts/fixture.obj"}]
    (tmp_path / "scene.yaml").write_text(yaml.safe_dump(d))
    with pytest.raises(InputError, match=r"obstacles\[0\]\.mesh: file 'parts/fixture.obj' not found"):
        load_scene_file(tmp_path / "scene.yaml")
    spec = parse_scene(d)
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "fixture.obj").write_text("v 0 0 0\n")
    check_referenced_files(spec, tmp_path, "scene.yaml")  # found relative to the scene's folder


def test_resource_estimate_is_an_upper_bound_of_the_real_sizes():
    from camplace.workflows.run import prepare

    spec = parse_scene(copy.deepcopy(BASE))
    est = estimate_resources(spec)
    sc, vis = prepare(spec)
    assert est.count("occupancy cells") >= sc.occupancy.occupied.size
    assert est.count("targets") >= len(vis.targets)
    assert est.count("candidates") >= vis.candidates.info["generated"]


def test_refused_before_allocating_with_the_numbers(monkeypatch):
    import numpy as np

    spec = parse_scene(with_("occupancy_resolution", 0.001))  # 3 x 3 x 3 m at 1 mm: 2.7e10 cells
    calls = []
    real_zeros = np.zeros
    monkeypatch.setattr(np, "zeros", lambda *a, **k: calls.append(a) or real_zeros(*a, **k))
    with pytest.raises(InputError) as e:
        check_resources(spec, "s.yaml", limit_bytes=2 * 1024**3)
    msg = str(e.value)
    assert msg.startswith("s.yaml: occupancy_resolution: 0.001 m would need 2.71e+10 occupancy cells (25.5 GiB")
    assert "limit 2.0 GiB" in msg and "max_memory_bytes" in msg and "--" not in msg
    assert e.value.option == "max_memory_bytes"
    assert not calls
    # the same scene is fine with a coarser grid
    check_resources(parse_scene(with_("occupancy_resolution", 0.05)), "s.yaml", limit_bytes=2 * 1024**3)


def test_total_over_the_limit_lists_the_biggest_parts():
    spec = parse_scene(copy.deepcopy(BASE))
    est = estimate_resources(spec)
    biggest = max(it[3] for it in est.items)
    limit = int((biggest + est.total_bytes) / 2)  # every part fits, the sum does not
    with pytest.raises(InputError, match=r"the scene would need about .* \(occupancy_resolution: "):
        check_resources(spec, "s.yaml", limit_bytes=limit)


def test_builtin_scenes_are_valid_and_fit_in_memory():
    from camplace.spec.builtin import builtin_yaml

    for name in ("demo", "standard-store", "store-a"):
        spec = parse_scene(yaml.safe_load(builtin_yaml(name)), name)
        est = check_resources(spec, name, limit_bytes=1024**3)
        assert est.total_bytes < 100 * 1024**2
