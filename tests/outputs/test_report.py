"""camplace.outputs.write.write_outputs: the contract files land first (together), the report after."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import numpy as np
import pytest

from camplace.core.errors import Interrupted
from camplace.workflows.run import placement_metrics
from camplace.outputs.write import write_outputs

from conftest import SHARED

CHECK_RUN = SHARED / "contract" / "check_run.py"
CONTRACT = ("visibility.npz", "placement.json", "placement.csv", "metrics.json")


def _check_run(out) -> None:
    if not CHECK_RUN.is_file():  # pragma: no cover
        pytest.skip("../shared/contract/check_run.py is absent: contract check skipped")
    r = subprocess.run([sys.executable, str(CHECK_RUN), str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def _older_run(r, out) -> None:
    """An earlier run's full output set in out: the same scene with one camera fewer."""
    sel = np.asarray(r.placement.selected)[:-1]
    m = placement_metrics(r.visibility, r.problem, sel)
    p = dataclasses.replace(r.placement, selected=sel, objective=m.cost, bound=None)
    write_outputs(out, r.scene.name, r.visibility, p, r.problem.budget, m, r.timings_s, scene=r.scene)
    assert (out / "report.html").is_file()


@pytest.mark.parametrize("error", [KeyboardInterrupt, OSError])
def test_report_failure_keeps_the_new_contract_files(tmp_path, demo_run, monkeypatch, error):
    """A report step that is interrupted (a second Ctrl-C) or fails comes after the
    contract files: they are the new run's, complete and valid; the earlier run's
    report.html (another placement) is gone; no temporary files are left."""
    r = demo_run
    out = tmp_path / "out"
    _older_run(r, out)
    old = json.loads((out / "placement.json").read_text())

    def broken(*a, **k):
        raise error()

    monkeypatch.setattr("camplace.outputs.report_html.write_report", broken)
    with pytest.raises(Interrupted if error is KeyboardInterrupt else error) as info:
        write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                      scene=r.scene)
    if error is KeyboardInterrupt:
        assert "placement.json" in str(info.value) and str(out) in str(info.value)
        assert info.value.exit_code == 130
    assert all((out / f).is_file() for f in CONTRACT)
    new = json.loads((out / "placement.json").read_text())
    assert len(new["cameras"]) == len(old["cameras"]) + 1 == len(r.placement.selected)
    assert json.loads((out / "metrics.json").read_text())["cost"] == pytest.approx(r.metrics.cost)
    assert not (out / "report.html").exists()
    assert not [f for f in out.iterdir() if f.name.endswith(".tmp")]
    _check_run(out)


def test_contract_files_are_written_before_the_report(tmp_path, demo_run, monkeypatch):
    """When the report starts, the new contract files are already in place; metrics.json
    is rewritten at the end with the whole time in timings_s.report."""
    import camplace.outputs.report_html

    r = demo_run
    out = tmp_path / "out"
    real = camplace.outputs.report_html.write_report
    seen = {}

    def watching(out_dir, *a, **k):
        seen.update({f: (out_dir / f).is_file() for f in CONTRACT})
        seen["n_cameras"] = json.loads((out_dir / "placement.json").read_text())["n_cameras"]
        return real(out_dir, *a, **k)

    monkeypatch.setattr("camplace.outputs.report_html.write_report", watching)
    paths = write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                          scene=r.scene)
    assert all(seen[f] for f in CONTRACT) and seen["n_cameras"] == len(r.placement.selected)
    assert "report.html" in paths and all(f in paths for f in CONTRACT)
    t = json.loads((out / "metrics.json").read_text())["timings_s"]
    assert set(t) >= set(r.timings_s) | {"report"} and t["report"] > 0
    _check_run(out)


def test_repeatable_metrics_are_byte_identical(tmp_path, demo_run):
    r = demo_run
    texts = []
    for k in range(2):
        write_outputs(tmp_path / str(k), r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics,
                      r.timings_s, repeatable=True, report=k == 0)
        texts.append((tmp_path / str(k) / "metrics.json").read_bytes())
    assert texts[0] == texts[1]
