"""`essential` on a run's output folder: the ranking, its summary and the CLI command."""

from __future__ import annotations

import subprocess
import sys

import pytest

from camplace.workflows.essential import essential_from_folder


def test_essential_on_a_run_folder(demo_out):
    ranking, summary = essential_from_folder(demo_out)
    assert len(ranking) >= 1 and ranking[0]["rank"] == 1
    assert summary["worst_case_cost"] == pytest.approx(ranking[0]["cost_if_fails"])
    out = subprocess.run([sys.executable, "-m", "camplace.cli.app", "essential", str(demo_out), "--top", "2"],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "essential cameras" in out.stdout
    from camplace.core.errors import InputError

    with pytest.raises(InputError, match="not found"):
        essential_from_folder(demo_out / "nope")
