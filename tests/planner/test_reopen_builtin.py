"""A run of a parameterised built-in scene reopens in camplace serve with no --scene
(issue 35): placement.json names the built-in as the run was given it (builtin_scene)."""

from __future__ import annotations

import json

import camplace
from camplace.outputs.write import write_outputs
from camplace.planner.opening import open_start, scene_of_run


def test_scene_of_run_prefers_the_built_in_as_given(tmp_path):
    assert scene_of_run(tmp_path, {"scene": "warehouse-1000", "builtin_scene": "warehouse:1000"}, None) \
        == "warehouse:1000"
    assert scene_of_run(tmp_path, {"scene": "demo"}, None) == "demo"  # older runs: the name, when it is one


def test_a_warehouse_run_reopens_by_itself(tmp_path):
    r = camplace.run("warehouse:200", budget=1, solver="greedy")
    write_outputs(tmp_path, r.scene.name, r.visibility, r.placement, 1, r.metrics, {}, scene=r.scene, report=False)
    placed = json.loads((tmp_path / "placement.json").read_text())
    assert placed["scene"] == "warehouse-200" and placed["builtin_scene"] == "warehouse:200"
    opened = open_start(tmp_path)
    assert opened.scene_ref == "warehouse:200" and len(opened.cameras) == 1


def test_a_run_made_with_a_cache_reopens_from_it(tmp_path):
    """The planner reads V from the block cache the run filled: no chunk is raycast again,
    and the V is the run's, entry for entry."""
    cache = tmp_path / "cache"
    r = camplace.run("warehouse:200", budget=1, solver="greedy", cache_dir=cache)
    out = tmp_path / "run"
    write_outputs(out, r.scene.name, r.visibility, r.placement, 1, r.metrics, {}, scene=r.scene, report=False)
    opened = open_start(out, cache_dir=cache)
    info = opened.vis.info
    assert info["cached_chunks"] == info["chunks"] > 0
    assert (opened.vis.V != r.visibility.V).nnz == 0
    fresh = open_start(out)  # no cache: raycast anew, the same V
    assert fresh.vis.info["cached_chunks"] == 0 and (fresh.vis.V != opened.vis.V).nnz == 0
