"""The scripts in examples/ double as documentation: each runs and prints what it promises."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parents[2] / "examples").glob("*.py"))


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs(script):
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "cost" in r.stdout and "Traceback" not in r.stderr


def test_examples_exist():
    assert {p.stem for p in EXAMPLES} >= {"quick_run", "stage_by_stage"}
