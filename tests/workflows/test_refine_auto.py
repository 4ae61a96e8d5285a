"""refine="auto" (the command line's default): refine below site scale, leave it out (with a
log line) when V holds more than AUTO_REFINE_MAX_PAIRS visible pairs."""

from __future__ import annotations

import pytest

import camplace
from camplace.cli.run import refine_default
from camplace.core.errors import InputError
from camplace.workflows import quality
from camplace.workflows.quality import refine_here


def test_refine_here_by_hand():
    log: list[str] = []
    assert refine_here(True, 10**12, log) is True and refine_here(False, 0, log) is False and log == []
    assert refine_here("auto", quality.AUTO_REFINE_MAX_PAIRS, log) is True and log == []
    assert refine_here("auto", quality.AUTO_REFINE_MAX_PAIRS + 1, log) is False
    assert len(log) == 1 and "left out" in log[0]
    with pytest.raises(InputError, match="refine: expected True, False or 'auto'"):
        refine_here("yes", 1, log)


def test_the_command_line_default_is_auto_unless_excluded():
    assert refine_default(None) == "auto" and refine_default(True) is True and refine_default(False) is False
    assert refine_default(None, robust=1) is False and refine_default(None, certify=5.0) is False


def test_auto_refines_a_small_scene_and_leaves_out_a_large_one(monkeypatch):
    small = camplace.run("demo", refine="auto", refine_time_s=2.0)
    assert "refine" in small.timings_s and not any("left out" in line for line in small.log)
    monkeypatch.setattr(quality, "AUTO_REFINE_MAX_PAIRS", 10)  # every scene is "site scale" now
    large = camplace.run("demo", refine="auto", refine_time_s=2.0)
    assert "refine" not in large.timings_s and any("refine: left out" in line for line in large.log)
    assert large.placement.selected.tolist() == camplace.run("demo").placement.selected.tolist()  # the grid's
