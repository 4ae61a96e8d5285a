"""camplace evaluate: score any placement file on a scene with the same metrics as a run."""

from __future__ import annotations

import csv
import io
import json
import subprocess
import sys

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.workflows.evaluate import evaluate, read_placement
from camplace.metrics.coverage import compute_metrics
from camplace.workflows.run import placement_metrics
from camplace.outputs.write import write_outputs

SHARED_CHECK = __import__("pathlib").Path(__file__).resolve().parents[3] / "shared" / "contract" / "check_run.py"


def _metrics_wo_timings(path):
    m = json.loads(path.read_text())
    m.pop("timings_s")
    return m


def _rows(path):
    return list(csv.DictReader(io.StringIO(path.read_text())))


def _write_csv(path, rows):
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    path.write_text(buf.getvalue())


@pytest.mark.parametrize("name", ["placement.json", "placement.csv"])
def test_evaluate_reproduces_the_run_exactly(demo_out, tmp_path, name):
    r = evaluate("demo", demo_out / name)
    out = tmp_path / "ev"
    write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                  scene=r.scene, report=False)
    assert _metrics_wo_timings(out / "metrics.json") == _metrics_wo_timings(demo_out / "metrics.json")
    p = json.loads((out / "placement.json").read_text())
    run_p = json.loads((demo_out / "placement.json").read_text())
    assert p["solver"] == "file" and p["bound"] is None and p["budget"] == len(run_p["cameras"])
    assert [c["candidate_id"] for c in p["cameras"]] == list(range(len(run_p["cameras"])))
    assert p["objective"] == run_p["objective"]
    for a, b in zip(p["cameras"], run_p["cameras"]):
        assert a["position"] == b["position"] and a["camera"] == b["camera"]
        assert np.allclose(a["rotation"], b["rotation"], atol=1e-12)
    z = np.load(out / "visibility.npz")
    assert tuple(z["shape"]) == (len(run_p["cameras"]), r.visibility.V.shape[1])
    if SHARED_CHECK.exists():
        proc = subprocess.run([sys.executable, str(SHARED_CHECK), str(out)], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stdout + proc.stderr


def test_hand_edited_csv_reports_the_new_figures(demo_run, demo_out, tmp_path):
    """Dropping a camera and turning another to a different grid pose gives exactly the
    metrics of that selection on the run's own V (computed independently)."""
    rows = _rows(demo_out / "placement.csv")
    cands = demo_run.visibility.candidates
    # turn the first camera to another yaw of the grid at the same location
    first = int(rows[0]["id"])
    same_loc = np.nonzero((cands.location_ids == cands.location_ids[first])
                          & (np.abs(cands.angles_deg[:, 1] - cands.angles_deg[first, 1]) < 1e-9))[0]
    other = int(next(i for i in same_loc if i != first))
    rows[0]["yaw"] = repr(float(cands.angles_deg[other, 0]))
    dropped = int(rows[-1]["id"])
    rows = rows[:-1]
    _write_csv(tmp_path / "edited.csv", rows)
    r = evaluate("demo", tmp_path / "edited.csv")
    selection = sorted([other] + [int(x["id"]) for x in rows[1:]])
    assert dropped not in selection
    want = compute_metrics(demo_run.problem, np.array(selection), demo_run.visibility.targets.region_ids,
                           demo_run.visibility.targets.region_names).to_dict()
    got = r.metrics.to_dict()
    for k in ("cost", "coverage_gap", "non_triangulatable_pct", "coverage_histogram"):
        assert got[k] == want[k], k
    for name, fig in want["regions"].items():
        assert {k: got["regions"][name][k] for k in fig} == fig
    assert got == placement_metrics(demo_run.visibility, demo_run.problem, np.array(selection)).to_dict()
    assert got["cost"] != demo_run.metrics.cost  # the edit changed the figures


def test_off_grid_pose_is_raycast_afresh(tmp_path):
    """A camera not on the mount grid, hand-checked: 3 m above the centre of the demo
    room's free corner, looking straight down, sees the walkable voxels below it."""
    (tmp_path / "p.csv").write_text("id,x,y,z,yaw,pitch,roll,lens\ncam-A,1.13,3.87,2.95,0,90,0,wide\n")
    r = evaluate("demo", tmp_path / "p.csv")
    t = r.visibility.targets
    vol = ~t.is_surface
    seen = np.zeros(len(t), bool)
    seen[r.visibility.V[0].indices] = True
    # looking down with yaw 0 the image width (71 deg) runs along world y, its height (36 deg) along x
    depth = 2.95 - t.positions[:, 2]
    dx, dy = np.abs(t.positions[:, 0] - 1.13), np.abs(t.positions[:, 1] - 3.87)
    hx, hy = depth * np.tan(np.radians(18.0)), depth * np.tan(np.radians(35.5))
    assert seen[vol].sum() > 50
    assert np.all((dx <= hx + 1e-9) & (dy <= hy + 1e-9) | ~seen | ~vol)  # nothing outside the frustum
    inner = vol & (dx < 0.95 * hx) & (dy < 0.95 * hy)  # free floor there: nothing occludes
    assert inner.sum() > 50 and np.all(seen[inner])
    assert r.placement.solver == "file" and r.placement.info["source_ids"] == ["cam-A"]
    from camplace.outputs.write import placement_dict

    cams = placement_dict("demo", r.placement, 1, r.visibility.candidates)["cameras"]
    assert cams[0]["candidate_id"] == 0 and cams[0]["source_id"] == "cam-A"


def test_json_hand_made_list_and_angle_forms(tmp_path):
    cams = [{"position": [1.0, 1.0, 2.9], "yaw": 45, "pitch": 45, "camera": "wide"},
            {"position": [5.0, 4.0, 2.9], "yaw_deg": 225, "pitch_deg": 45}]
    (tmp_path / "p.json").write_text(json.dumps(cams))
    poses = read_placement(tmp_path / "p.json")
    assert poses.lenses == ("wide", None) and np.allclose(poses.angles_deg[:, 2], 0)
    r = evaluate("demo", tmp_path / "p.json")
    assert r.visibility.V.shape[0] == 2 and r.metrics.cost > 0


def test_camera_inside_an_obstacle_warns(tmp_path):
    (tmp_path / "p.csv").write_text("id,x,y,z,yaw,pitch,roll\nin-shelf,3.0,1.8,1.0,0,30,0\n")
    r = evaluate("demo", tmp_path / "p.csv")
    assert r.visibility.V.nnz == 0
    assert any("in-shelf" in line and "inside an obstacle" in line for line in r.log)


@pytest.mark.parametrize("text, match", [
    ("id,x,y,z,yaw,pitch\n1,0,0,0,0,0\n", "lacks column"),
    ("id,x,y,z,yaw,pitch,roll,lens\n1,0,abc,1,0,0,0,wide\n", r"line 2: column 'y': expected a number"),
    ("id,x,y,z,yaw,pitch,roll,lens\n1,1,1,2,0,30,0,tele\n", "lens 'tele' is not a camera"),
    ("id,x,y,z,yaw,pitch,roll,lens\n", "no camera rows"),
])
def test_bad_csv_raises_one_line_input_error(tmp_path, text, match):
    (tmp_path / "p.csv").write_text(text)
    with pytest.raises(InputError, match=match) as e:
        evaluate("demo", tmp_path / "p.csv")
    assert "\n" not in str(e.value) and "p.csv" in str(e.value)


def test_json_rotation_and_angles_must_agree(demo_out, tmp_path):
    p = json.loads((demo_out / "placement.json").read_text())
    p["cameras"][0]["yaw_deg"] += 30  # hand edit of the angles only
    (tmp_path / "p.json").write_text(json.dumps(p))
    with pytest.raises(InputError, match=r"cameras\[0\]: 'rotation' and the yaw/pitch/roll angles disagree"):
        read_placement(tmp_path / "p.json")
    del p["cameras"][0]["rotation"]  # angles alone are fine
    (tmp_path / "p.json").write_text(json.dumps(p))
    assert read_placement(tmp_path / "p.json").angles_deg[0, 0] == p["cameras"][0]["yaw_deg"]
    with pytest.raises(InputError, match="placement file not found"):
        read_placement(tmp_path / "missing.json")
    (tmp_path / "bad.json").write_text('{"cameras": [{"position": [1, 2]}]}')
    with pytest.raises(InputError, match=r"cameras\[0\].position"):
        read_placement(tmp_path / "bad.json")


def test_cli_evaluate_json_summary(demo_out, tmp_path, monkeypatch, capsys):
    from conftest import run_cli

    proc = subprocess.run([sys.executable, "-m", "camplace.cli.app", "--json", "evaluate", "demo",
                           str(demo_out / "placement.csv"), "--out", str(tmp_path / "ev"), "--no-plan"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    m = _metrics_wo_timings(demo_out / "metrics.json")
    assert summary["solver"] == "file" and summary["cost"] == m["cost"]
    assert summary["coverage_gap"] == m["coverage_gap"] and summary["regions"] == m["regions"]
    for f in ("placement.json", "metrics.json", "visibility.npz", "placement.csv", "report.html"):
        assert (tmp_path / "ev" / f).exists() and f in summary["files"]
    code, text = run_cli(["evaluate", "demo", tmp_path / "nope.csv"], monkeypatch, capsys)  # in-process
    assert code == 2 and "placement file not found" in text and "Traceback" not in text


def test_cli_run_quiet_verbose_json(tmp_path):
    """--json: one JSON document on stdout; --quiet: only the folder; --verbose: files listed."""
    from typer.testing import CliRunner

    from camplace.cli.app import app

    runner = CliRunner()
    out = tmp_path / "run"
    res = runner.invoke(app, ["--json", "run", "demo", "--out", str(out), "--no-cache"])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    m = json.loads((out / "metrics.json").read_text())
    assert summary["cost"] == m["cost"] and summary["n_cameras"] == summary["budget"] == 6
    assert summary["files"]["report.html"] == str(out / "report.html") and "report" in summary["timings_s"]
    res = runner.invoke(app, ["--quiet", "run", "demo", "--out", str(out), "--no-cache", "--no-plan"])
    assert res.exit_code == 0 and res.stdout.strip() == str(out)
    res = runner.invoke(app, ["--verbose", "run", "demo", "--out", str(out), "--no-cache", "--no-plan"])
    assert res.exit_code == 0
    assert "report.html" in res.output and "opencv" in res.output


def test_foreign_lens_from_intrinsics(demo_out, tmp_path):
    """Another tool's camera (a lens the scene lacks) is scored with its own intrinsics: the
    scene's lens written out as intrinsics under another name gives the same V rows; a
    narrower lens sees a subset."""
    p = json.loads((demo_out / "placement.json").read_text())
    for c in p["cameras"]:
        c["camera"] = "their-lens"  # intrinsics (same as the scene's 'wide') stay in the file
    (tmp_path / "same.json").write_text(json.dumps(p))
    base = evaluate("demo", demo_out / "placement.json")
    same = evaluate("demo", tmp_path / "same.json")
    assert (same.visibility.V != base.visibility.V).nnz == 0
    assert same.visibility.candidates.cameras[-1].name == "their-lens"
    for c in p["cameras"]:
        c["intrinsics"]["fx"] *= 2  # half the horizontal field of view
    (tmp_path / "tele.json").write_text(json.dumps(p))
    tele = evaluate("demo", tmp_path / "tele.json")
    assert 0 < tele.visibility.V.nnz < base.visibility.V.nnz
    assert (tele.visibility.V - tele.visibility.V.multiply(base.visibility.V)).nnz == 0  # a subset
    del p["cameras"][0]["intrinsics"]
    (tmp_path / "bad.json").write_text(json.dumps(p))
    with pytest.raises(InputError, match="lens 'their-lens' is not a camera of the scene"):
        evaluate("demo", tmp_path / "bad.json")
