"""Repeatability: the same inputs and options give byte-identical placement.json and
metrics.json, across runs, processes (another hash seed) and 1 vs several workers.

metrics.json holds wall-clock ``timings_s`` (required by the contract); ``--repeatable``
(or CAMPLACE_REPEATABLE=1) writes them as 0.0 so the whole file is byte-identical.
Without it, everything but the timing values is identical. placement.json never holds a
wall-clock value, so it is byte-identical either way.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import run_cli

FILES = ("placement.json", "metrics.json", "placement.csv")  # the same bytes with and without --no-plan


def _bytes(out: Path) -> dict[str, bytes]:
    return {f: (out / f).read_bytes() for f in FILES}


def _without_timings(metrics: bytes) -> dict:
    m = json.loads(metrics)
    assert set(m["timings_s"]) >= {"scene", "targets", "candidates", "visibility", "solve", "metrics", "report"}
    m["timings_s"] = {k: 0 for k in m["timings_s"]}
    return m


@pytest.fixture(scope="module")
def subprocess_run(tmp_path_factory):
    """The demo in another process (another PYTHONHASHSEED), 2 visibility workers, --repeatable."""
    out = tmp_path_factory.mktemp("repeat-sub") / "out"
    env = dict(os.environ, PYTHONHASHSEED="12345", CAMPLACE_CACHE=str(out.parent / "cache"))
    r = subprocess.run([sys.executable, "-m", "camplace.cli.app", "run", "demo", "--out", str(out), "--no-cache",
                        "--repeatable", "--workers", "2"], capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr
    return out


def test_same_run_twice_is_byte_identical(tmp_path, monkeypatch, capsys, subprocess_run):
    monkeypatch.setenv("CAMPLACE_CACHE", str(tmp_path / "cache"))
    outs, pages = [], []
    for k in range(2):
        out = tmp_path / f"out{k}"
        code, text = run_cli(["run", "demo", "--out", out, "--no-cache", "--repeatable"], monkeypatch, capsys)
        assert code == 0, text
        outs.append(_bytes(out))
        pages.append((out / "report.html").read_bytes())
    assert outs[0] == outs[1]
    assert pages[0] == pages[1], "report.html differs between two --repeatable runs"
    assert (subprocess_run / "report.html").read_bytes() == pages[0]
    # another process, another hash seed, 2 worker processes for visibility: same bytes
    assert _bytes(subprocess_run) == outs[0]
    m = json.loads(outs[0]["metrics.json"])
    assert set(m["timings_s"].values()) == {0.0}


def test_cached_visibility_gives_the_same_bytes(tmp_path, monkeypatch, capsys, subprocess_run):
    monkeypatch.setenv("CAMPLACE_CACHE", str(tmp_path / "cache"))
    for k in range(2):  # a cold then a warm cache
        out = tmp_path / f"out{k}"
        code, text = run_cli(["run", "demo", "--out", out, "--repeatable", "--no-plan"], monkeypatch, capsys)
        assert code == 0, text
        assert _bytes(out) == _bytes(subprocess_run)


def test_without_repeatable_only_timings_differ(tmp_path, monkeypatch, capsys, subprocess_run):
    monkeypatch.setenv("CAMPLACE_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "out"
    code, text = run_cli(["run", "demo", "--out", out, "--no-cache", "--no-plan"], monkeypatch, capsys)
    assert code == 0, text
    a, b = _bytes(out), _bytes(subprocess_run)
    # refined (the CLI's default) and not --repeatable: placement.json holds no timing at all
    assert "refine" in json.loads(a["placement.json"])
    assert a["placement.json"] == b["placement.json"]
    assert a["placement.csv"] == b["placement.csv"]
    assert _without_timings(a["metrics.json"]) == _without_timings(b["metrics.json"])
    timings = json.loads(a["metrics.json"])["timings_s"]
    assert timings["refine"] > 0  # the refinement's seconds live here


def test_repeatable_env_variable(tmp_path, monkeypatch, capsys, subprocess_run):
    monkeypatch.setenv("CAMPLACE_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("CAMPLACE_REPEATABLE", "1")
    out = tmp_path / "out"
    code, text = run_cli(["run", "demo", "--out", out, "--no-cache", "--no-plan"], monkeypatch, capsys)
    assert code == 0, text
    assert _bytes(out) == _bytes(subprocess_run)


def test_mip_is_repeatable(tmp_path):
    """HiGHS (fixed seed) on a problem it solves to optimality: same placement bytes."""
    from camplace.workflows.run import run
    from camplace.outputs.write import write_outputs

    outs = []
    for k in range(2):
        r = run("demo", solver="mip", budget=4)
        out = tmp_path / f"out{k}"
        write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                      report=False, repeatable=True)
        outs.append(_bytes(out))
    assert outs[0] == outs[1]
    assert json.loads(outs[0]["placement.json"])["solver"] == "mip"
