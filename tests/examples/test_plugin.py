"""The example plugin package (examples/camplace-example-plugin: the solver 'random-restarts',
the engine 'frustum', GeoJSON plans and camera_coverage.csv) installed with pip into a folder
on the path: it shows up in ``camplace solvers``, passes both conformance suites and runs from
the command line with its own options, from the CLI and from a scene file; bad values get one
line naming the option; ``camplace run plan.geojson`` makes its rooms zones, and run and
evaluate write camera_coverage.csv, linked from report.html (docs/design.md "How to add a
plan format", "How to add an output")."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from conftest import BASE, box_room, import_and_evaluate, run_cli

PLUGIN = Path(__file__).resolve().parents[2] / "examples" / "camplace-example-plugin"


def pip_install(src: Path, target: Path) -> None:
    """pip install --no-deps --target (no build isolation when the build tools are here,
    else pip fetches them as for camplace itself); the source is copied first so the build
    leaves nothing in the repository."""
    tree = target.parent / "src"
    shutil.copytree(src, tree)
    base = [sys.executable, "-m", "pip", "install", "--no-deps", "--quiet", "--target", str(target)]
    r = subprocess.run([*base, "--no-build-isolation", str(tree)], capture_output=True, text=True)
    if r.returncode != 0:
        r = subprocess.run([*base, str(tree)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


@pytest.fixture(scope="module")
def plugin(tmp_path_factory):
    """The example plugin installed into a fresh folder put on sys.path; the registries read
    the entry points again, and again after it is gone."""
    from camplace.outputs.writers import OUTPUTS
    from camplace.scene.formats import IMPORTERS
    from camplace.solvers import SOLVERS
    from camplace.visibility import ENGINES

    registries = (SOLVERS, ENGINES, IMPORTERS, OUTPUTS)
    target = tmp_path_factory.mktemp("plugin") / "site"
    pip_install(PLUGIN, target)
    sys.path.insert(0, str(target))
    for registry in registries:
        registry.reload()
    yield target
    sys.path.remove(str(target))
    for name in [m for m in sys.modules if m.startswith("camplace_example_plugin")]:
        del sys.modules[name]
    for registry in registries:
        registry.reload()


def test_the_plugin_shows_up_in_camplace_solvers(plugin, monkeypatch, capsys):
    code, text = run_cli(["solvers"], monkeypatch, capsys)
    assert code == 0, text
    assert "random-restarts: Best of several randomised greedy fills (example plugin)  [plugin: " \
           "camplace-example-plugin]" in text
    assert "options: restarts: int = 20" in text
    assert "frustum: Range and image tests only, no occlusion" in text
    assert "parameters: range_scale: float = 1.0, chunk_size: int = 256" in text
    assert "skipped" not in text


def test_the_plugin_solver_passes_the_conformance_suite(plugin):
    from camplace.solvers import SOLVERS
    from camplace.solvers.testing import check_solver

    assert SOLVERS.distribution("random-restarts") == "camplace-example-plugin"
    check_solver(SOLVERS["random-restarts"])


def test_the_plugin_engine_passes_the_conformance_suite(plugin, tmp_path):
    from camplace.cameras.candidates import build_candidates
    from camplace.cameras.models import camera_from_spec
    from camplace.scene.build import build_scene
    from camplace.targets.build import build_targets
    from camplace.visibility import compute_visibility, get_engine
    from camplace.visibility.testing import check_engine

    spec = box_room(obstacles=[{"name": "box", "box": {"min": [1.5, 1.5, 0.0], "max": [2.5, 2.5, 1.5]}}],
                    targets=[{"name": "walkable", "kind": "volume", "heights": [1.0], "coverage": 1},
                             {"name": "box", "kind": "surface", "of": ["box"], "coverage": 1}])
    sc = build_scene(spec)
    t, c = build_targets(sc), build_candidates(sc, {x.name: camera_from_spec(x) for x in spec.cameras})
    engine = get_engine("frustum", chunk_size=8)
    checks = check_engine(engine, sc.occupancy, t, c, tmp_path)
    assert all(k.status in ("ok", "skipped") for k in checks)
    # no occlusion: an upper bound of the voxel engine's V
    free, blocked = compute_visibility(engine, sc.occupancy, t, c).V, compute_visibility(
        get_engine("voxel"), sc.occupancy, t, c).V
    assert blocked.multiply(free).nnz == blocked.nnz < free.nnz


def test_the_plugin_runs_from_the_cli_with_its_options(plugin, tmp_path, monkeypatch, capsys):
    import json

    scene = tmp_path / "scene.yaml"
    scene.write_text(yaml.safe_dump(BASE, sort_keys=False))
    out = tmp_path / "cli"
    code, text = run_cli(["run", scene, "--solver", "random-restarts", "--option", "restarts=3", "--seed", "5",
                          "--visibility", "frustum", "--out", out, "--no-plan", "--no-cache"], monkeypatch, capsys)
    assert code == 0, text
    assert "solver random-restarts: restarts=3, seed=5" in text  # the values as the solver read them
    assert json.loads((out / "placement.json").read_text())["solver"] == "random-restarts+refine"
    data = dict(BASE, placement={"budget": 2, "solver": "random-restarts", "options": {"restarts": 2}})
    scene.write_text(yaml.safe_dump(data, sort_keys=False))
    out = tmp_path / "scene"
    code, text = run_cli(["run", scene, "--out", out, "--no-plan", "--no-cache", "--grid-only"], monkeypatch, capsys)
    assert code == 0, text
    assert "solver random-restarts: restarts=2" in text
    assert json.loads((out / "placement.json").read_text())["solver"] == "random-restarts"


@pytest.mark.parametrize("scene_options, args, expect", [
    (None, ["--option", "restarts=many"], "--option restarts: expected an integer (solver 'random-restarts'), got 'many'"),
    (None, ["--option", "tries=3"], "--option tries: solver 'random-restarts' takes no option 'tries'"),
    ({"restarts": "many"}, [], "scene.yaml: placement.options.restarts: expected an integer (solver "
                                "'random-restarts'), got 'many'"),
    ({"restarts": 3}, ["--visibility", "frustum", "--probe", "1"], "--probe: the frustum engine takes no probe"),
])
def test_bad_plugin_options_are_one_line(plugin, scene_options, args, expect, tmp_path, monkeypatch, capsys):
    data = dict(BASE, placement={"budget": 2, "solver": "random-restarts", **(
        {"options": scene_options} if scene_options is not None else {})})
    scene = tmp_path / "scene.yaml"
    scene.write_text(yaml.safe_dump(data, sort_keys=False))
    code, text = run_cli(["run", scene, "--out", tmp_path / "out", "--no-cache", *args], monkeypatch, capsys)
    assert code == 2 and expect in text and "Traceback" not in text, text
    assert not (tmp_path / "out").exists()


def test_python_refuses_bad_plugin_options_alike(plugin):
    from camplace.core.errors import InputError
    from camplace.solvers import solve
    from camplace.solvers.testing import random_problem

    with pytest.raises(InputError, match=r"^restarts: expected an integer \(solver 'random-restarts'\)") as err:
        solve(random_problem(0), "random-restarts", restarts="many")
    assert err.value.option == "restarts"
    assert solve(random_problem(0), "random-restarts", restarts="4").info["restarts"] == 4


GEOJSON = {"type": "FeatureCollection", "features": [
    {"type": "Feature", "properties": {"kind": "room", "name": "Office"},
     "geometry": {"type": "Polygon", "coordinates": [[[0, 0], [3, 0], [3, 4], [0, 4], [0, 0]]]}},
    {"type": "Feature", "properties": {"kind": "room", "name": "Lab"},
     "geometry": {"type": "Polygon", "coordinates": [[[3, 0], [6, 0], [6, 4], [3, 4], [3, 0]]]}},
    {"type": "Feature", "properties": {"kind": "wall"},  # between the rooms, a 1 m doorway at y 3..4
     "geometry": {"type": "Polygon", "coordinates": [[[2.95, 0], [3.05, 0], [3.05, 3], [2.95, 3], [2.95, 0]]]}},
]}


def test_the_plugin_plan_format_and_output_file_through_the_cli(plugin, tmp_path, monkeypatch, capsys):
    """docs/design.md "How to add a plan format" and "How to add an output", step by step."""
    import json

    from camplace.outputs.writers import OUTPUTS
    from camplace.scene.formats import IMPORTERS

    assert IMPORTERS.distribution("geojson") == OUTPUTS.distribution("camera-coverage") == "camplace-example-plugin"
    plan = tmp_path / "plan.geojson"
    plan.write_text(json.dumps(GEOJSON))
    run = tmp_path / "run"
    code, text = run_cli(["run", plan, "--solver", "random-restarts", "--budget", "3", "--out", run, "--no-plan",
                          "--no-cache", "--grid-only"], monkeypatch, capsys)
    assert code == 0, text
    assert "2 rooms, 24.0 m²" in text and "geojson (plugin importer)" in text  # the import summary
    placed = json.loads((run / "placement.json").read_text())
    assert placed["solver"] == "random-restarts" and placed["solver_info"]["restarts"] == 20
    assert {"Office", "Lab"} <= set(json.loads((run / "metrics.json").read_text())["regions"])  # rooms: zones
    rows = (run / "camera_coverage.csv").read_text().splitlines()
    assert rows[0] == "id,camera,targets_seen,seen_only_by_it" and len(rows) == 1 + len(placed["cameras"])
    assert "<a href='camera_coverage.csv'>camera_coverage.csv</a>" in (run / "report.html").read_text()
    ev = import_and_evaluate(plan, run / "placement.json", tmp_path, monkeypatch, capsys)
    assert (ev / "camera_coverage.csv").read_text() == (run / "camera_coverage.csv").read_text()
    code, text = run_cli(["evaluate", plan, run / "placement.json", "--out", tmp_path / "ev2", "--no-plan"],
                         monkeypatch, capsys)  # the plan itself as the scene, as camplace run reads it
    assert code == 0, text
    assert (tmp_path / "ev2" / "camera_coverage.csv").read_text() == (run / "camera_coverage.csv").read_text()
