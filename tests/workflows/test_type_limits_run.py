"""mount_rules.max_per_type through a run (issue 17): at most n new cameras of a type."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.spec.loading import parse_scene
from camplace.workflows.run import run

ROOM = {
    "name": "two-types", "voxel_size": 0.5, "occupancy_resolution": 0.1,
    "room": {"footprint": [[0, 0], [10, 0], [10, 6], [0, 6]], "height": 3.0},
    "targets": [{"name": "walk", "kind": "volume", "heights": [1.0], "coverage": 2}],
    "cameras": [{"name": "fisheye", "model": "fisheye", "resolution": [64, 64], "fov_deg": [180, 180],
                 "max_range": 5.0},
                {"name": "narrow", "resolution": [64, 48], "fov_deg": [60, 45], "max_range": 8.0}],
    "mounts": [{"kind": "ceiling_grid", "camera": "fisheye", "spacing": 2.0, "yaw_deg": [0], "pitch_deg": [90]},
               {"kind": "ceiling_grid", "camera": "narrow", "spacing": 2.0, "yaw_deg": [0, 90, 180, 270],
                "pitch_deg": [45]}],
    "placement": {"budget": 4, "solver": "greedy"},
}


def scene(limit: int | None):
    d = dict(ROOM)
    if limit is not None:
        d["mount_rules"] = {"max_per_type": {"fisheye": limit}}
    return parse_scene(d)


def fisheyes(r) -> int:
    c = r.visibility.candidates
    names = np.array([c.cameras[k].name for k in c.camera_ids[r.placement.selected]])
    return int(np.sum(names == "fisheye"))


@pytest.mark.parametrize("solver", ["greedy", "mip", "tabu"])
def test_run_keeps_max_per_type(solver):
    free = run(scene(None), solver=solver, time_limit_s=10)
    assert fisheyes(free) == 4  # the ceiling fisheyes win without a limit
    r = run(scene(2), solver=solver, time_limit_s=10)
    assert fisheyes(r) == 2
    assert r.problem.type_limits and r.problem.type_ok(r.placement.selected)
    assert r.placement.objective >= free.placement.objective - 1e-9


def test_refined_run_keeps_max_per_type():
    r = run(scene(2), solver="greedy", refine=True, refine_time_s=5)
    assert fisheyes(r) == 2 and r.problem.type_ok(r.placement.selected)
