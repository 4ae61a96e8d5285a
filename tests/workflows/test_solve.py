"""Solving a saved instance (camplace.workflows.solve): re-solve a visibility.npz, write
placement.json and metrics.json (the contract keys), and the CLI ``solve`` command."""

from __future__ import annotations

import json

import numpy as np
import pytest

from camplace.problem.instance import save_problem_npz
from camplace.workflows.solve import instance_name, solve_instance, write_instance_outputs
from tests.solvers.test_bounds import random_problem


def test_solve_saved_demo_output(demo_out, tmp_path):
    """The demo run's visibility.npz re-solves to the same greedy cost and writes the contract files."""
    problem, placement, metrics, arrays, timings = solve_instance(demo_out / "visibility.npz", 4, "greedy")
    out = write_instance_outputs(tmp_path, instance_name(demo_out / "visibility.npz"), problem, placement, metrics,
                                 arrays, timings)
    pj = json.loads(out["placement.json"].read_text())
    mj = json.loads(out["metrics.json"].read_text())
    assert pj["solver"] == "greedy" and pj["budget"] == 4 and pj["objective"] == problem.cost(placement.selected)
    assert len(pj["cameras"]) == len(placement.selected)
    cam = pj["cameras"][0]
    assert cam["position"] is not None and len(cam["rotation"]) == 3
    assert mj["cost"] == pytest.approx(pj["objective"])
    assert set(mj["regions"]) == {str(n) for n in arrays["region_names"]}


def test_certify_keys_in_placement_json(tmp_path):
    p = random_problem(6, n_g=30, n_p=40, budget=3, n_loc=10)
    path = save_problem_npz(tmp_path / "visibility.npz", p)
    problem, placement, metrics, arrays, timings = solve_instance(path, 3, "certify", time_limit_s=3, threads=1)
    out = write_instance_outputs(tmp_path / "o", "x", problem, placement, metrics, arrays, timings)
    pj = json.loads(out["placement.json"].read_text())
    assert pj["bound"] <= pj["objective"] and pj["gap"] is not None
    assert pj["bound_method"] and pj["incumbent_method"]
    assert pj["cameras"][0]["position"] is None  # no geometry in this file
    assert pj["objective"] == problem.cost(np.array([c["candidate_id"] for c in pj["cameras"]]))


def test_cli_solve_writes_contract_files(tmp_path, monkeypatch, capsys):
    import subprocess
    import sys

    from conftest import run_cli

    p = random_problem(8, n_g=25, n_p=30, budget=3, n_loc=9)
    path = save_problem_npz(tmp_path / "visibility.npz", p)
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "camplace.cli.app", "--json", "solve", str(path), "--budget", "3",
                        "--certify", "2", "--threads", "1", "--out", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout)
    pj = json.loads((out / "placement.json").read_text())
    assert summary["cost"] == pj["objective"] and pj["solver"] == "certify"
    assert pj["bound"] <= pj["objective"]
    code, text = run_cli(["solve", tmp_path / "missing.npz", "--budget", "3"], monkeypatch, capsys)  # in-process
    assert code == 2 and "not found" in text and "Traceback" not in text
