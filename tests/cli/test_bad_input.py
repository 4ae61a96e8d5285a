"""Bad input never crashes: each case runs the CLI in-process (camplace.cli.app.main) and
asserts exit code 2, a one-line message naming the file / key path / option and what
is wrong, no traceback, and no output written."""

from __future__ import annotations

import copy
import sys

import pytest
import yaml

import camplace.cli.app

from conftest import BASE, run_cli  # noqa: E402 - shared with other test modules


def _set(d: dict, path: str, value) -> dict:
    """Set d[path] where path is like 'mounts.0.yaw_deg.step' (None value: delete the key)."""
    keys = [int(k) if k.isdigit() else k for k in path.split(".")]
    cur = d
    for k in keys[:-1]:
        cur = cur[k]
    if value is _DELETE:
        del cur[keys[-1]]
    else:
        cur[keys[-1]] = value
    return d


_DELETE = object()


def mutate(*pairs) -> dict:
    d = copy.deepcopy(BASE)
    for path, value in pairs:
        _set(d, path, value)
    return d


# (id, scene (dict | raw text | None = the base scene), extra CLI args, substrings the message must contain)
CASES = [
    ("empty-file", "", [], ["scene.yaml", "empty"]),
    ("only-comments", "# nothing here\n", [], ["scene.yaml", "empty"]),
    ("not-yaml", "name: [tiny\nroom: {", [], ["scene.yaml", "not valid YAML", "line"]),
    ("not-a-mapping", "- 1\n- 2\n", [], ["scene.yaml", "mapping", "list"]),
    ("duplicate-yaml-key", yaml.safe_dump(BASE, sort_keys=False) + "name: again\n", [],
     ["scene.yaml", "'name' appears twice"]),
    ("unknown-top-key", mutate(("voxel_sise", 0.5)), [], ["voxel_sise", "did you mean 'voxel_size'"]),
    ("unknown-nested-key", mutate(("mounts.0.yaw_deg", {"start": 0, "stop": 90, "stpe": 90})), [],
     ["mounts[0].yaw_deg", "unknown key 'stpe'", "did you mean 'step'"]),
    ("missing-key", mutate(("room.height", _DELETE)), [], ["room.height", "required"]),
    ("wrong-type-string", mutate(("room.height", "three")), [], ["room.height", "number", "'three'"]),
    ("wrong-type-bool", mutate(("voxel_size", True)), [], ["voxel_size", "boolean"]),
    ("wrong-type-list", mutate(("room.footprint", "square")), [], ["room.footprint", "list"]),
    ("nan", mutate(("voxel_size", float("nan"))), [], ["voxel_size", "finite"]),
    ("inf", mutate(("cameras.0.max_range", float("inf"))), [], ["cameras[0].max_range", "finite"]),
    ("negative-size", mutate(("voxel_size", -0.25)), [], ["voxel_size", "greater than 0", "-0.25"]),
    ("zero-height", mutate(("room.height", 0)), [], ["room.height", "greater than 0"]),
    ("zero-spacing", mutate(("mounts.0.spacing", 0)), [], ["mounts[0].spacing", "greater than 0"]),
    ("inverted-box", mutate(("obstacles.0.box", {"min": [2, 1, 0], "max": [1, 2, 1]})), [],
     ["obstacles[0].box.max[0]", "max must exceed min", "axis x"]),
    ("box-outside-room", mutate(("obstacles.0.box", {"min": [10, 10, 0], "max": [11, 11, 1]})), [],
     ["obstacles[0].box", "outside the room"]),
    ("self-intersecting-footprint", mutate(("room.footprint", [[0, 0], [3, 3], [3, 0], [0, 3]])), [],
     ["room.footprint", "simple polygon", "Self-intersection"]),
    ("degenerate-footprint", mutate(("room.footprint", [[0, 0], [1, 1], [2, 2]])), [],
     ["room.footprint"]),
    ("two-point-footprint", mutate(("room.footprint", [[0, 0], [3, 3]])), [], ["room.footprint", "at least 3"]),
    ("height-above-room", mutate(("targets.0.heights", [1.0, 4.5])), [],
     ["targets[0].heights[1]", "outside the room", "(0, 3.0)"]),
    ("height-below-floor", mutate(("targets.0.heights", [-1.0])), [], ["targets[0].heights[0]", "outside the room"]),
    ("duplicate-height", mutate(("targets.0.heights", [1.0, 1.0])), [], ["targets[0].heights[1]", "duplicate"]),
    ("coverage-negative", mutate(("targets.0.coverage", -1)), [], ["targets[0].coverage", "greater than or equal to 0"]),
    ("coverage-fraction", mutate(("targets.0.coverage", 1.5)), [], ["targets[0].coverage", "integer", "1.5"]),
    ("coverage-bool", mutate(("targets.0.coverage", True)), [], ["targets[0].coverage", "integer"]),
    ("coverage-all-zero", mutate(("targets.0.coverage", 0)), [], ["targets", "every region has coverage 0"]),
    ("fov-180", mutate(("cameras.0.fov_deg", [180, 70])), [], ["cameras[0].fov_deg", "180"]),
    ("fov-zero", mutate(("cameras.0.fov_deg", [0, 70])), [], ["cameras[0].fov_deg[0]", "greater than 0"]),
    ("fov-negative", mutate(("cameras.0.fov_deg", [90, -5])), [], ["cameras[0].fov_deg[1]", "greater than 0"]),
    ("zero-resolution", mutate(("cameras.0.resolution", [0, 480])), [], ["cameras[0].resolution[0]", "greater than 0"]),
    ("unknown-camera-model", mutate(("cameras.0.model", "fisheeye")), [],
     ["cameras[0].model", "'fisheeye'", "did you mean 'fisheye'"]),
    ("unknown-target-kind", mutate(("targets.0.kind", "volum")), [], ["targets[0].kind", "did you mean 'volume'"]),
    ("unknown-mount-kind", mutate(("mounts.0.kind", "celing_grid")), [], ["mounts[0].kind", "did you mean 'ceiling_grid'"]),
    ("unknown-solver-in-scene", mutate(("placement.solver", "mpi")), [],
     ["placement.solver", "unknown solver 'mpi'", "did you mean 'mip'"]),
    ("unknown-solver-option", None, ["--solver", "gredy"], ["solver", "unknown solver 'gredy'", "did you mean 'greedy'"]),
    ("crowd-negative-density", mutate(("crowd", {"density": -0.5})), [], ["crowd.density", "greater than or equal to 0"]),
    ("crowd-radius-above-room", mutate(("crowd", {"radius": 2.0})), [], ["crowd.radius", "does not fit in the room"]),
    ("unknown-camera-reference", mutate(("mounts.0.camera", "camm")), [],
     ["mounts[0].camera", "unknown camera 'camm'", "did you mean 'cam'"]),
    ("unknown-obstacle-reference",
     mutate(("targets", [{"name": "faces", "kind": "surface", "of": ["crat"], "coverage": 1}])), [],
     ["targets[0].of[0]", "unknown obstacle 'crat'", "did you mean 'crate'"]),
    ("duplicate-camera-name", mutate(("cameras", [BASE["cameras"][0], BASE["cameras"][0]])), [],
     ["cameras[1].name", "duplicate name 'cam'"]),
    ("duplicate-region-name", mutate(("targets", [BASE["targets"][0], BASE["targets"][0]])), [],
     ["targets[1].name", "duplicate name 'walk'"]),
    ("missing-mesh-file", mutate(("obstacles", [{"name": "fixture", "mesh": "nothere.obj"}])), [],
     ["obstacles[0].mesh", "'nothere.obj' not found"]),
    ("missing-calibration-file", mutate(("cameras.0", {"name": "cam", "calibration": "calib/cam0.yaml"})), [],
     ["cameras[0].calibration", "'calib/cam0.yaml' not found"]),
    ("two-lens-definitions", mutate(("cameras.0.intrinsics", {"fx": 500, "fy": 500, "cx": 320, "cy": 240})), [],
     ["cameras[0]", "exactly one of 'fov_deg', 'intrinsics', 'calibration'"]),
    ("pinhole-distortion", mutate(("cameras.0.distortion", [0.1, 0.01, 0, 0])), [],
     ["cameras[0].distortion", "model: opencv"]),
    ("occupancy-grid-too-fine", mutate(("occupancy_resolution", 0.0001)), [],
     ["occupancy_resolution", "0.0001", "occupancy cells", "GiB", "limit"]),
    ("target-grid-too-fine", mutate(("voxel_size", 0.00001)), [], ["voxel_size", "targets", "GiB", "limit"]),
    ("too-many-candidates", mutate(("mounts.0.spacing", 0.00001)), [],
     ["mounts[0].spacing", "candidates", "GiB", "limit"]),
    ("memory-limit-option", None, ["--max-memory-gb", "0.00001"], ["occupancy_resolution", "occupancy cells", "limit"]),
    ("angle-step-too-small", mutate(("mounts.0.yaw_deg", {"start": 0, "stop": 359, "step": 0.001})), [],
     ["mounts[0].yaw_deg.step", "359001 angles", "at most 3600"]),
    ("angle-range-inverted", mutate(("mounts.0.yaw_deg", {"start": 90, "stop": 0, "step": 30})), [],
     ["mounts[0].yaw_deg.stop", "must be >= start"]),
    ("empty-angle-list", mutate(("mounts.0.pitch_deg", [])), [], ["mounts[0].pitch_deg", "at least 1"]),
    ("no-targets", mutate(("targets", [])), [], ["targets", "at least 1"]),
    ("no-target-in-free-space",
     mutate(("obstacles.0.box", {"min": [-1, -1, 0], "max": [4, 4, 2]})), [], ["targets", "free space"]),
    ("no-candidate-in-free-space",
     mutate(("obstacles.0.box", {"min": [-1, -1, 2.5], "max": [4, 4, 3.5]})), [], ["no candidate pose", "free space"]),
    ("no-candidate-sees-a-target", mutate(("cameras.0.max_range", 0.01)), [], ["no candidate pose sees any target"]),
    ("mount-above-ceiling", mutate(("mounts.0.offset_below_ceiling", 3.5)), [],
     ["mounts[0].offset_below_ceiling", "not below the ceiling"]),
    ("wall-mount-above-ceiling", mutate(("mounts.0", {"kind": "wall", "camera": "cam", "height": 3.2})), [],
     ["mounts[0].height", "outside the room"]),
    ("wall-mount-without-height", mutate(("mounts.0", {"kind": "wall", "camera": "cam"})), [],
     ["mounts[0].height", "needs 'height'"]),
    ("incidence-over-90", mutate(("targets", [{"name": "faces", "kind": "surface", "of": ["crate"], "coverage": 1,
                                               "max_incidence_deg": 120}])), [],
     ["targets[0].max_incidence_deg", "less than or equal to 90"]),
    ("zero-weight", mutate(("targets.0.weight", 0)), [], ["targets[0].weight", "greater than 0"]),
    ("budget-negative-in-scene", mutate(("placement.budget", -1)), [], ["placement.budget", "greater than or equal to 0"]),
    ("budget-negative-option", None, ["--budget", "-1"], ["--budget", "non-negative"]),
    ("budget-not-a-number", None, ["--budget", "many"], ["--budget", "integer"]),
    ("time-limit-zero", None, ["--time-limit", "0"], ["--time-limit", "positive"]),
    ("time-limit-negative", None, ["--time-limit", "-5"], ["--time-limit", "positive"]),
    ("unknown-option", None, ["--bugdet", "3"], ["--bugdet"]),
    ("solver-option-bad-value-in-scene",
     mutate(("placement", {"budget": 2, "solver": "tabu", "options": {"chunk": "many"}})), [],
     ["scene.yaml: placement.options.chunk", "expected an integer", "'many'"]),
    ("solver-option-unknown-in-scene", mutate(("placement.options", {"restarts": 5})), [],
     ["scene.yaml: placement.options.restarts", "takes no option 'restarts'"]),
    ("solver-time-limit-in-options", mutate(("placement.options", {"time_limit_s": 5})), [],
     ["placement.options.time_limit_s", "placement.time_limit_s"]),
    ("solver-option-bad-value", None, ["--solver", "tabu", "--option", "chunk=x"],
     ["--option chunk: expected an integer (solver 'tabu'), got 'x'"]),
    ("solver-option-unknown", None, ["--option", "restarts=5"], ["--option restarts", "takes no option 'restarts'"]),
    ("solver-option-malformed", None, ["--option", "restarts"], ["--option", "KEY=VALUE", "'restarts'"]),
    ("solver-option-not-an-option", None, ["--option", "budget=3"], ["--option", "'budget'", "--budget"]),
    ("seed-not-an-integer", None, ["--seed", "x"], ["--seed"]),
    ("infeasible-targets-required",
     mutate(("targets.0.coverage", 5)), ["--require-feasible"],
     ["targets", "fewer mount locations than their required coverage", "walk:", "--require-feasible"]),
]


@pytest.mark.parametrize("case_id,scene,args,expect", CASES, ids=[c[0] for c in CASES])
def test_bad_input_exits_2_with_one_clear_line(case_id, scene, args, expect, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("CAMPLACE_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("CAMPLACE_MAX_MEMORY_GB", raising=False)
    path = tmp_path / "scene.yaml"
    if scene is None:
        scene = BASE
    path.write_text(scene if isinstance(scene, str) else yaml.safe_dump(scene, sort_keys=False))
    out = tmp_path / "out"
    code, text = run_cli(["run", path, "--out", out, "--no-cache", *args], monkeypatch, capsys)
    assert code == 2, f"exit code {code}, output:\n{text}"
    assert "Traceback" not in text
    for s in expect:
        assert s in text, f"{s!r} not in message:\n{text}"
    assert not out.exists(), "a failed run must not write outputs"


def test_there_are_at_least_30_distinct_bad_inputs():
    assert len({c[0] for c in CASES}) == len(CASES) >= 30


def test_error_is_one_line_naming_file_and_key(tmp_path, monkeypatch, capsys):
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(mutate(("mounts.0.yaw_deg", {"start": 0, "stop": 90, "step": -30}))))
    code, text = run_cli(["run", path, "--out", tmp_path / "o"], monkeypatch, capsys)
    lines = [ln for ln in text.splitlines() if ln.strip()]
    assert code == 2
    assert lines == [f"error: {path}: mounts[0].yaw_deg.step: expected greater than 0 (got -30)"]


def test_missing_scene_file_and_unknown_builtin(tmp_path, monkeypatch, capsys):
    code, text = run_cli(["run", tmp_path / "nope.yaml"], monkeypatch, capsys)
    assert code == 2 and "nope.yaml: scene file not found" in text
    code, text = run_cli(["run", "standard-stor"], monkeypatch, capsys)
    assert code == 2 and "did you mean 'standard-store'" in text and "Traceback" not in text
    code, text = run_cli(["run", tmp_path], monkeypatch, capsys)
    assert code == 2 and "folder" in text


def test_binary_scene_file(tmp_path, monkeypatch, capsys):
    path = tmp_path / "scene.yaml"
    path.write_bytes(bytes(range(256)) * 4)
    code, text = run_cli(["run", path], monkeypatch, capsys)
    assert code == 2 and "not a text file" in text


def test_out_is_a_file(tmp_path, monkeypatch, capsys):
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(BASE))
    code, text = run_cli(["run", path, "--out", path], monkeypatch, capsys)
    assert code == 2 and "--out" in text and "is a file" in text
    assert yaml.safe_load(path.read_text()) == yaml.safe_load(yaml.safe_dump(BASE))


def test_bad_memory_env(tmp_path, monkeypatch, capsys):
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(BASE))
    monkeypatch.setenv("CAMPLACE_MAX_MEMORY_GB", "lots")
    code, text = run_cli(["run", path, "--out", tmp_path / "o", "--no-cache"], monkeypatch, capsys)
    assert code == 2 and "CAMPLACE_MAX_MEMORY_GB" in text and "'lots'" in text


def test_debug_flag_shows_the_traceback(tmp_path, monkeypatch, capsys):
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(mutate(("voxel_size", -1))))
    monkeypatch.setattr(sys, "argv", ["camplace", "--debug", "run", str(path)])
    from camplace.core.errors import InputError

    with pytest.raises(InputError, match="voxel_size"):
        camplace.cli.app.main()


def test_failed_run_leaves_earlier_outputs_intact(tmp_path, monkeypatch, capsys):
    """A good run, then a bad one into the same folder: every earlier file is unchanged,
    and no temporary file is left behind."""
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(BASE))
    out = tmp_path / "out"
    code, text = run_cli(["run", path, "--out", out, "--no-cache"], monkeypatch, capsys)
    assert code == 0, text
    before = {p.name: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert {"placement.json", "metrics.json", "visibility.npz"} <= set(before)
    path.write_text(yaml.safe_dump(mutate(("cameras.0.max_range", 0.01))))
    code, text = run_cli(["run", path, "--out", out, "--no-cache"], monkeypatch, capsys)
    assert code == 2
    after = {p.name: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert after == before


def test_infeasible_targets_are_a_warning_by_default(tmp_path, monkeypatch, capsys):
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(mutate(("targets.0.coverage", 5))))
    code, text = run_cli(["run", path, "--out", tmp_path / "o", "--no-cache"], monkeypatch, capsys)
    assert code == 0, text
    assert "warning:" in text and "fewer mount locations than their required coverage" in text
    assert (tmp_path / "o" / "placement.json").is_file()


def test_loaders_of_real_data_name_the_file(tmp_path, monkeypatch, capsys):
    """A referenced point cloud that is not one: a clean error naming the file."""
    (tmp_path / "scan.ply").write_text("this is not a ply file\n")
    d = mutate(("obstacles", [{"name": "scan", "point_cloud": "scan.ply"}]))
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(d))
    code, text = run_cli(["run", path, "--out", tmp_path / "o", "--no-cache"], monkeypatch, capsys)
    assert code == 2, text
    assert "scan.ply" in text and "Traceback" not in text
    assert not (tmp_path / "o").exists()


# ---- placement files (camplace evaluate SCENE PLACEMENT) -------------------------------------

GOOD_CAMERA = {"position": [1.5, 1.5, 2.9], "yaw_deg": 0, "pitch_deg": 45, "roll_deg": 0, "camera": "cam"}
PLACEMENT_CASES = [
    ("placement-missing", None, "p.json", ["p.json", "not found"]),
    ("placement-not-json", "{cameras: [", "p.json", ["p.json", "not valid JSON"]),
    ("placement-empty-list", '{"cameras": []}', "p.json", ["p.json", "empty"]),
    ("placement-cameras-not-a-list", '{"cameras": 3}', "p.json", ["p.json", "cameras", "list"]),
    ("placement-bad-position", '{"cameras": [{"position": [1, 2], "yaw_deg": 0, "pitch_deg": 45}]}', "p.json",
     ["cameras[0].position", "[x, y, z]"]),
    ("placement-nan-position", '{"cameras": [{"position": [1, NaN, 2], "yaw_deg": 0, "pitch_deg": 45}]}', "p.json",
     ["cameras[0].position", "finite"]),
    ("placement-not-a-rotation", '{"cameras": [{"position": [1, 1, 2], "rotation": [[1,0,0],[0,1,0],[0,0,2]]}]}',
     "p.json", ["cameras[0].rotation", "not a rotation"]),
    ("placement-no-orientation", '{"cameras": [{"position": [1, 1, 2]}]}', "p.json", ["cameras[0]", "rotation"]),
    ("placement-unknown-lens", None, "p.json", ["lens 'tele'", "not a camera of the scene", "cam"]),
    ("placement-csv-missing-columns", "id,x,y,z\n0,1,1,2\n", "p.csv", ["p.csv", "header lacks", "yaw"]),
    ("placement-csv-bad-number", "id,x,y,z,yaw,pitch,roll,lens\n0,1,one,2,0,45,0,cam\n", "p.csv",
     ["p.csv: line 2", "column 'y'", "'one'"]),
    ("placement-csv-short-row", "id,x,y,z,yaw,pitch,roll,lens\n0,1,1,2,0\n", "p.csv", ["p.csv: line 2", "fields"]),
    ("placement-wrong-extension", "x", "p.xml", ["p.xml", ".json", ".csv"]),
]


@pytest.mark.parametrize("case_id,text,name,expect", PLACEMENT_CASES, ids=[c[0] for c in PLACEMENT_CASES])
def test_bad_placement_file_exits_2(case_id, text, name, expect, tmp_path, monkeypatch, capsys):
    import json

    scene = tmp_path / "scene.yaml"
    scene.write_text(yaml.safe_dump(BASE))
    pfile = tmp_path / name
    if case_id == "placement-unknown-lens":
        text = json.dumps({"cameras": [dict(GOOD_CAMERA, camera="tele")]})
    if text is not None:
        pfile.write_text(text)
    out = tmp_path / "out"
    code, msg = run_cli(["evaluate", scene, pfile, "--out", out], monkeypatch, capsys)
    assert code == 2, msg
    assert "Traceback" not in msg
    for s in expect:
        assert s in msg, f"{s!r} not in message:\n{msg}"
    assert not out.exists()


def test_good_placement_file_is_evaluated(tmp_path, monkeypatch, capsys):
    import json

    monkeypatch.setattr("camplace.outputs.report_html.write_report", lambda *a, **k: {})
    scene = tmp_path / "scene.yaml"
    scene.write_text(yaml.safe_dump(BASE))
    pfile = tmp_path / "p.json"
    pfile.write_text(json.dumps({"cameras": [GOOD_CAMERA]}))
    code, msg = run_cli(["evaluate", scene, pfile, "--out", tmp_path / "out"], monkeypatch, capsys)
    assert code == 0, msg
    assert json.loads((tmp_path / "out" / "placement.json").read_text())["solver"] == "file"


# ---- referenced data files that are not what they claim (loaders of scans, meshes, OctoMaps) ----

LOADER_CASES = [
    ("scan.ply", b"", "point_cloud", ["obstacles[0].point_cloud", "scan.ply", "empty"]),
    ("scan.pcd", b"garbage\x00\x01 data\n", "point_cloud", ["obstacles[0].point_cloud", "scan.pcd", "PCD"]),
    ("scan.foo", b"1 2 3\n", "point_cloud", ["obstacles[0].point_cloud", "unknown point cloud format '.foo'"]),
    ("part.obj", b"garbage\n", "mesh", ["obstacles[0].mesh", "part.obj", "no triangles"]),
    ("map.bt", b"garbage\x00\x01\n", "octomap", ["obstacles[0].octomap", "map.bt", "not an OctoMap"]),
]


@pytest.mark.parametrize("name,data,key,expect", LOADER_CASES, ids=[c[0] for c in LOADER_CASES])
def test_bad_data_file_exits_2(name, data, key, expect, tmp_path, monkeypatch, capsys):
    (tmp_path / name).write_bytes(data)
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(mutate(("obstacles", [{"name": "x", key: name}]))))
    out = tmp_path / "out"
    code, msg = run_cli(["run", path, "--out", out, "--no-cache"], monkeypatch, capsys)
    assert code == 2, msg
    assert "Traceback" not in msg
    for s in expect:
        assert s in msg, f"{s!r} not in message:\n{msg}"
    assert not out.exists()


# ---- options of the other commands --------------------------------------------------------------

OPTION_CASES = [
    ("bench-budgets-not-integers", ["bench", "demo", "--budgets", "a,b"], ["--budgets", "'a,b'"]),
    ("bench-budgets-negative", ["bench", "demo", "--budgets", "-3"], ["--budgets", "non-negative"]),
    ("bench-unknown-method", ["bench", "demo", "--budgets", "2", "--methods", "gredy"], ["--methods", "'gredy'"]),
    ("workers-zero", ["run", "demo", "--workers", "0"], ["--workers"]),
    ("crowd-density-negative", ["run", "demo", "--crowd-density", "-1"], ["--crowd-density", "greater than or equal"]),
    ("essential-not-a-run-folder", ["essential", "{tmp}/nothing"], ["visibility.npz not found"]),
    ("render-camera-out-of-range", ["render", "demo", "--camera", "-1"], ["--camera", "out of range"]),
    ("scan-unknown-format", ["scan", "demo", "--out", "{tmp}/x.unknownext"], ["'.unknownext'", ".ply"]),
    ("run-scene-and-cloud", ["run", "demo", "--cloud", "{tmp}/x.ply"], ["either a scene or --cloud"]),
    ("run-quality-unknown", ["run", "demo", "--quality", "best"], ["--quality: expected one of default, high"]),
    ("run-quality-with-adaptive", ["run", "demo", "--quality", "high", "--adaptive", "2"],
     ["--quality: --quality high runs", "leave --adaptive 0 and --robust 0"]),
    ("run-quality-time-zero", ["run", "demo", "--quality", "high", "--quality-time", "0"], ["--quality-time:"]),
    ("demo-solver-option-bad-value", ["demo", "--solver", "tabu", "--option", "k_rcl=2.5"],
     ["--option k_rcl: expected an integer", "2.5"]),
    ("solve-solver-option-bad-value", ["solve", "{tmp}/nothing.npz", "--budget", "2", "--solver", "tabu",
                                       "--option", "chunk=x"], ["--option chunk: expected an integer", "'x'"]),
    ("solve-solver-option-unknown", ["solve", "{tmp}/nothing.npz", "--budget", "2", "--option", "restarts=3"],
     ["--option restarts", "takes no option 'restarts'"]),
    ("bench-option-no-method-takes", ["bench", "demo", "--budgets", "2", "--methods", "greedy,mip", "--option",
                                      "restarts=1"], ["--option restarts", "none of the methods greedy, mip"]),
    ("bench-option-bad-value", ["bench", "demo", "--budgets", "2", "--methods", "greedy,mip", "--option",
                                "mip_rel_gap=tiny"], ["--option mip_rel_gap", "expected a number or none", "'tiny'"]),
]


@pytest.mark.parametrize("case_id,args,expect", OPTION_CASES, ids=[c[0] for c in OPTION_CASES])
def test_bad_command_options_exit_2(case_id, args, expect, tmp_path, monkeypatch, capsys):
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    before = set(tmp_path.iterdir())
    monkeypatch.chdir(tmp_path)
    code, msg = run_cli(args, monkeypatch, capsys)
    assert code == 2, msg
    assert "Traceback" not in msg
    for s in expect:
        assert s in msg, f"{s!r} not in message:\n{msg}"
    assert set(tmp_path.iterdir()) == before, "nothing may be written"
