"""Round trips (issue 5 acceptance, on the small demo scene): box scene -> synthetic scan
(PLY, noise + occlusion) / mesh export / OctoMap export -> loaded back -> placement ->
scored on the ORIGINAL box scene: within 0.02 of the placement made on the box scene.
benchmarks/roundtrip.py runs the same on standard-store."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from camplace.spec.builtin import resolve_scene
from camplace.scene.loaders.pointcloud import write_point_cloud
from camplace.workflows.run import run
from camplace.scene.build import build_scene
from camplace.workflows.scan import evaluate_selection, export_mesh, export_octomap, roundtrip_spec, scan_scene


@pytest.fixture(scope="module")
def demo(demo_run):
    spec, base, src = resolve_scene("demo")
    box = build_scene(spec, base, src)
    return spec, box, demo_run  # demo_run: run("demo"), once per session (conftest)


def test_evaluate_selection_reproduces_the_direct_gap(demo):
    _, box, direct = demo
    m = evaluate_selection(box, direct.visibility.candidates, direct.placement.selected)
    assert abs(m.coverage_gap - direct.metrics.coverage_gap) < 1e-12


@pytest.mark.parametrize("kind", ["point_cloud", "mesh", "octomap"])
def test_round_trip_gap_within_002(tmp_path, demo, kind):
    spec, box, direct = demo
    if kind == "point_cloud":
        cloud = scan_scene(box, step_deg=0.5, noise=0.01)
        path = write_point_cloud(tmp_path / "scan.ply", cloud.points, cloud.viewpoints)
    elif kind == "mesh":
        path = export_mesh(box, tmp_path / "scene.obj")
    else:
        path = export_octomap(box, tmp_path / "scene.bt")
    r = run(roundtrip_spec(spec, kind, path))
    assert len(r.placement.selected) == direct.problem.budget
    m = evaluate_selection(box, r.visibility.candidates, r.placement.selected)
    assert abs(m.coverage_gap - direct.metrics.coverage_gap) <= 0.02, (kind, m.coverage_gap, direct.metrics.coverage_gap)


def test_cli_run_from_a_cloud(tmp_path, demo):
    from camplace.cli.app import app

    _, box, _ = demo
    cloud = scan_scene(box, step_deg=0.6, noise=0.005)
    write_point_cloud(tmp_path / "room.pcd", cloud.points, cloud.viewpoints)
    r = CliRunner().invoke(app, ["run", "--cloud", str(tmp_path / "room.pcd"), "--budget", "4", "--no-plan",
                                 "--save-scene", str(tmp_path / "room.yaml"), "--out", str(tmp_path / "out")])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "out" / "placement.json").is_file()
    spec, _, _ = resolve_scene(str(tmp_path / "room.yaml"))
    assert abs(spec.room.height - 3.0) < 0.05
    fp = np.asarray(spec.room.footprint)
    assert np.allclose(fp.min(0), [0, 0], atol=0.1) and np.allclose(fp.max(0), [6, 5], atol=0.1)
    assert spec.mounts[0].kind == "ceiling_grid"


def test_cli_run_needs_scene_or_cloud(tmp_path):
    from camplace.cli.app import app

    r = CliRunner().invoke(app, ["run"])
    assert r.exit_code != 0


def test_cli_round_trip_scored_with_camplace_evaluate(tmp_path, demo):
    """The acceptance through the CLI: scan -> scene file -> run -> camplace evaluate on the box scene."""
    import json

    import yaml

    from camplace.cli.app import app

    spec, _, direct = demo
    cli = CliRunner()
    r = cli.invoke(app, ["-q", "scan", "demo", "--out", str(tmp_path / "demo.ply"), "--step", "0.5"])
    assert r.exit_code == 0, r.output
    rs = roundtrip_spec(spec, "point_cloud", "demo.ply")  # relative to the scene file
    (tmp_path / "scan.yaml").write_text(yaml.safe_dump(rs.model_dump(mode="json", exclude_defaults=True)))
    r = cli.invoke(app, ["-q", "run", str(tmp_path / "scan.yaml"), "--grid-only", "--no-plan",
                         "--out", str(tmp_path / "run")])
    assert r.exit_code == 0, r.output
    r = cli.invoke(app, ["-q", "evaluate", "demo", str(tmp_path / "run" / "placement.json"),
                         "--out", str(tmp_path / "eval"), "--no-plan"])
    assert r.exit_code == 0, r.output
    gap = json.loads((tmp_path / "eval" / "metrics.json").read_text())["coverage_gap"]
    assert abs(gap - direct.metrics.coverage_gap) <= 0.02
