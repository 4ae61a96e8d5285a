"""Planner fixtures: the demo run's contract files in a folder, opened once per module."""

from __future__ import annotations

import pytest

from camplace.planner.opening import open_start


@pytest.fixture(scope="module")
def demo_dir(tmp_path_factory, demo_run):
    """The demo run's contract files (grid placement, no report) in a folder."""
    from camplace.outputs.write import write_outputs

    out = tmp_path_factory.mktemp("planner-demo")
    r = demo_run
    write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                  scene=r.scene, report=False)
    return out


@pytest.fixture(scope="module")
def opened(demo_dir):
    return open_start(demo_dir)
