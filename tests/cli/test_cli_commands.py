"""The commands of camplace.cli: every --help, `scene import` of a scan, a mesh and an
OctoMap into a scene that `camplace run` accepts, `run SPACEFILE` directly, bad space
files (exit 2, one line, nothing written) and library errors worded with the flag."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from camplace.cli.app import app
from camplace.cli.common import word_error
from camplace.cli.space import mesh_surface_points, octomap_points, space_kind
from camplace.core.errors import InputError
from camplace.scene.loaders.mesh import Mesh, write_mesh
from camplace.scene.loaders.octomap import write_octomap
from camplace.spec.loading import load_scene_file

from conftest import run_cli  # noqa: E402 - shared with other test modules

COMMANDS = [["run"], ["demo"], ["bench"], ["solve"], ["evaluate"], ["compare-visibility"], ["render"], ["scan"],
            ["essential"], ["scenes"], ["scene"], ["scene", "import"]]


@pytest.mark.parametrize("cmd", COMMANDS, ids=[" ".join(c) for c in COMMANDS])
def test_every_command_has_help(cmd):
    r = CliRunner().invoke(app, [*cmd, "--help"])
    assert r.exit_code == 0, r.output
    assert "Usage" in r.output


def test_run_help_hides_the_scan_options():
    out = CliRunner().invoke(app, ["run", "--help"]).output
    for flag in ("--cloud", "--save-scene", "--up", "--no-level-floor", "--crop", "--heights", "--wall-mounts"):
        assert flag not in out
    imp = CliRunner().invoke(app, ["scene", "import", "--help"]).output
    for flag in ("--up", "--no-level-floor", "--crop", "--downsample", "--heights", "--coverage", "--wall-mounts",
                 "--viewpoint", "--out"):
        assert flag in imp


@pytest.fixture(scope="module")
def scan_ply(tmp_path_factory):
    """A synthetic scan of the demo room (camplace.workflows.scan), as PLY with viewpoints."""
    from camplace.scene.build import build_scene
    from camplace.scene.loaders.pointcloud import write_point_cloud
    from camplace.spec.builtin import resolve_scene
    from camplace.workflows.scan import scan_scene

    spec, base, src = resolve_scene("demo")
    cloud = scan_scene(build_scene(spec, base, src), step_deg=0.6, noise=0.005)
    return write_point_cloud(tmp_path_factory.mktemp("scan") / "room.ply", cloud.points, cloud.viewpoints)


def _room_mesh(w: float = 6.0, d: float = 5.0, h: float = 3.0) -> Mesh:
    """The inner surfaces of a w x d x h room (floor, ceiling, four walls: one quad each)
    and a 1 m crate, as a scanned room mesh has them."""
    c = np.array([[0, 0, 0], [w, 0, 0], [w, d, 0], [0, d, 0], [0, 0, h], [w, 0, h], [w, d, h], [0, d, h]], float)
    crate = np.array([[2, 2, 0], [3, 2, 0], [3, 3, 0], [2, 3, 0], [2, 2, 1], [3, 2, 1], [3, 3, 1], [2, 3, 1]], float)
    quads = [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    quads += [tuple(i + 8 for i in q) for q in quads[1:]]  # the crate: no bottom face
    faces = [t for a, b, cc, dd in quads for t in ([a, b, cc], [a, cc, dd])]
    return Mesh(np.r_[c, crate], np.array(faces, np.int64))


def _room_octomap(path, w: float = 6.0, d: float = 5.0, h: float = 3.0, res: float = 0.1):
    """An OctoMap of a room: one-cell floor, ceiling and walls occupied, the inside free."""
    n = (round(w / res) + 2, round(d / res) + 2, round(h / res) + 2)
    occ = np.zeros(n, bool)
    occ[[0, -1]] = True
    occ[:, [0, -1]] = True
    occ[:, :, [0, -1]] = True
    return write_octomap(path, occ, ~occ, np.array([-res, -res, -res]), res)


def _run_ok(args, monkeypatch, capsys) -> str:
    monkeypatch.setattr("camplace.outputs.report_html.write_report", lambda *a, **k: {})  # speed: no HTML report
    code, text = run_cli(args, monkeypatch, capsys)
    assert code == 0, text
    return text


def test_scene_import_of_a_scan_gives_a_scene_run_accepts(scan_ply, tmp_path, monkeypatch, capsys):
    scene = tmp_path / "room.yaml"
    text = _run_ok(["scene", "import", scan_ply, "--out", scene, "--heights", "0.5,1.0", "--coverage", "1",
                    "--budget", "3"], monkeypatch, capsys)
    assert "scan:" in text and "room.yaml" in text
    data = yaml.safe_load(scene.read_text())
    assert data["targets"][0]["heights"] == [0.5, 1.0] and data["targets"][0]["coverage"] == 1
    assert data["placement"]["budget"] == 3 and "point_cloud" in data["obstacles"][0]
    assert scene.read_text().startswith("# camplace scene built from a space file")
    spec = load_scene_file(scene)
    assert abs(spec.room.height - 3.0) < 0.05
    _run_ok(["-q", "run", scene, "--out", tmp_path / "out", "--no-cache", "--no-plan"], monkeypatch, capsys)
    assert (tmp_path / "out" / "placement.json").is_file()


def test_run_takes_a_scan_directly(scan_ply, tmp_path, monkeypatch, capsys):
    import json

    _run_ok(["-q", "run", scan_ply, "--budget", "3", "--out", tmp_path / "out", "--no-cache", "--no-plan"], monkeypatch,
            capsys)
    p = json.loads((tmp_path / "out" / "placement.json").read_text())
    assert len(p["cameras"]) == 3


def test_scene_import_of_a_mesh_and_run(tmp_path, monkeypatch, capsys):
    write_mesh(tmp_path / "room.obj", _room_mesh())
    write_mesh(tmp_path / "room.ply", _room_mesh())
    assert space_kind(tmp_path / "room.ply") == "mesh" and space_kind(tmp_path / "room.obj") == "mesh"
    scene = tmp_path / "room.yaml"
    text = _run_ok(["scene", "import", tmp_path / "room.ply", "--out", scene], monkeypatch, capsys)
    assert "mesh:" in text
    ob = yaml.safe_load(scene.read_text())["obstacles"][0]
    assert ob["mesh"] == str((tmp_path / "room.ply").resolve()) and "point_cloud" not in ob
    spec = load_scene_file(scene)
    assert abs(spec.room.height - 3.0) < 0.05
    fp = np.asarray(spec.room.footprint)
    assert np.allclose(fp.min(0), [0, 0], atol=0.1) and np.allclose(fp.max(0), [6, 5], atol=0.1)
    _run_ok(["-q", "run", tmp_path / "room.obj", "--budget", "3", "--out", tmp_path / "out", "--no-cache", "--no-plan"],
            monkeypatch, capsys)
    assert (tmp_path / "out" / "placement.json").is_file()


def test_scene_import_of_an_octomap_and_run(tmp_path, monkeypatch, capsys):
    bt = _room_octomap(tmp_path / "room.bt")
    assert space_kind(bt) == "octomap"
    scene = tmp_path / "room.yaml"
    text = _run_ok(["scene", "import", bt, "--out", scene], monkeypatch, capsys)
    assert "OctoMap:" in text and "moved to z = 0" in text
    ob = yaml.safe_load(scene.read_text())["obstacles"][0]
    assert ob["octomap"] == str(bt.resolve()) and "rotate_deg" not in ob.get("transform", {})
    load_scene_file(scene)
    _run_ok(["-q", "run", scene, "--budget", "3", "--out", tmp_path / "out", "--no-cache", "--no-plan"], monkeypatch,
            capsys)
    code, text = run_cli(["scene", "import", bt, "--out", tmp_path / "b.yaml", "--up", "+y"], monkeypatch, capsys)
    assert code == 2 and "--up" in text and not (tmp_path / "b.yaml").exists()


def test_a_scan_ply_is_not_a_mesh(scan_ply):
    assert space_kind(scan_ply) == "point_cloud"
    assert space_kind("scene.yaml") is None and space_kind("demo") is None


BAD_FILES = [
    ("garbage.ply", b"this is not a ply file\n", ["garbage.ply", "PLY"]),
    ("empty.pcd", b"", ["empty.pcd", "empty"]),
    ("broken.obj", b"garbage\n", ["broken.obj", "no triangles"]),
    ("broken.bt", b"garbage\x00\x01\n", ["broken.bt", "not an OctoMap"]),
    ("missing.las", None, ["missing.las", "not found"]),
    ("scan.e57", b"whatever", ["scan.e57", "not a space file", ".ply"]),
]


@pytest.mark.parametrize("name,data,expect", BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_bad_space_file_exits_2_one_line_nothing_written(name, data, expect, tmp_path, monkeypatch, capsys):
    src = tmp_path / "in"
    src.mkdir()
    if data is not None:
        (src / name).write_bytes(data)
    out = tmp_path / "out"
    out.mkdir()
    for args in (["scene", "import", src / name, "--out", out / "s.yaml"],
                 *([["run", src / name, "--out", out / "run"]] if name != "scan.e57" else [])):
        code, text = run_cli(args, monkeypatch, capsys)
        lines = [ln for ln in text.splitlines() if ln.strip()]
        assert code == 2, text
        assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in text, text
        for s in expect:
            assert s in text, f"{s!r} not in message:\n{text}"
        assert not any(out.iterdir()), "nothing may be written"


@pytest.mark.parametrize("args,expect", [
    (["--crop", "1,2,3"], "--crop: expected 6 comma-separated numbers"),
    (["--up", "up"], "--up: expected one of"),
    (["--heights", "low"], "--heights: expected comma-separated numbers"),
    (["--viewpoint", "1,2"], "--viewpoint: expected 3"),
])
def test_scene_import_bad_options(args, expect, scan_ply, tmp_path, monkeypatch, capsys):
    code, text = run_cli(["scene", "import", scan_ply, "--out", tmp_path / "s.yaml", *args], monkeypatch, capsys)
    assert code == 2 and expect in text, text
    assert not (tmp_path / "s.yaml").exists()


def test_scene_import_out_must_be_a_yaml_file(scan_ply, tmp_path, monkeypatch, capsys):
    code, text = run_cli(["scene", "import", scan_ply, "--out", tmp_path], monkeypatch, capsys)
    assert code == 2 and "--out" in text and "folder" in text
    code, text = run_cli(["scene", "import", scan_ply, "--out", tmp_path / "s.txt"], monkeypatch, capsys)
    assert code == 2 and "--out" in text and ".yaml" in text


def test_deprecated_cloud_alias_and_save_scene(scan_ply, tmp_path, monkeypatch, capsys):
    text = _run_ok(["run", "--cloud", scan_ply, "--save-scene", tmp_path / "s.yaml", "--budget", "3",
                    "--out", tmp_path / "out", "--no-cache", "--no-plan"], monkeypatch, capsys)
    assert "deprecated" in text and (tmp_path / "s.yaml").is_file() and (tmp_path / "out" / "placement.json").is_file()
    code, text = run_cli(["run", "demo", "--save-scene", tmp_path / "t.yaml"], monkeypatch, capsys)
    assert code == 2 and "scene import" in text and not (tmp_path / "t.yaml").exists()


@pytest.mark.parametrize("err,line", [
    (InputError("workers: expected at least 1, got 0", option="workers"), "--workers: expected at least 1, got 0"),
    (InputError("max_memory_bytes: expected > 0", option="max_memory_bytes"), "--max-memory-gb: expected > 0"),
    (InputError("scene.yaml: targets: unmet (require_feasible)", option="require_feasible"),
     "scene.yaml: targets: unmet (--require-feasible)"),
    (InputError("expected a positive number of seconds", option="time_limit_s"),
     "--time-limit: expected a positive number of seconds"),
    (InputError("scan x.ply: no floor; give another up= or level_floor=False", option="up"),
     "--up: scan x.ply: no floor; give another --up or --no-level-floor"),
    (InputError("scan x.ply: too low (try up='+y' for phone scans)", option="up"),
     "--up: scan x.ply: too low (try --up +y for phone scans)"),
    (InputError("cloud: x.ply: the file is empty", option="cloud"), "x.ply: the file is empty"),
    (InputError("coverage_gap: solver 'mip' takes no option 'coverage_gap'", option="coverage_gap"),
     "--coverage-gap: solver 'mip' takes no option '--coverage-gap'"),
    (InputError("scene.yaml: voxel_size: expected > 0"), "scene.yaml: voxel_size: expected > 0"),
    (InputError("nothing to word here", option="not_a_cli_parameter"), "nothing to word here"),
])
def test_word_error_names_the_flag(err, line):
    assert word_error(err) == line


def test_library_error_with_option_is_worded_with_the_flag(tmp_path, monkeypatch, capsys):
    def fail(*a, **k):
        raise InputError("coverage_gap: solver 'greedy' does not take it; min-cameras does", option="coverage_gap")

    monkeypatch.setattr("camplace.workflows.run.run", fail)
    code, text = run_cli(["run", "demo", "--out", tmp_path / "o"], monkeypatch, capsys)
    assert code == 2
    assert text.strip() == "error: --coverage-gap: solver 'greedy' does not take it; min-cameras does"


def test_points_of_a_mesh_and_an_octomap():
    v = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]], float)
    p = mesh_surface_points(v, np.array([[0, 1, 2], [0, 2, 3]]))
    assert len(p) >= 20_000 and np.allclose(p[:, 2], 0) and p[:, :2].min() >= 0 and p[:, 0].max() <= 2
    lo, size = np.array([[0, 0, 0], [1, 0, 0]], float), np.array([0.1, 0.4])
    q = octomap_points(lo, size, 0.1)
    assert len(q) == 1 + 4**3 and np.allclose(q.min(0), [0.05, 0.05, 0.05])
