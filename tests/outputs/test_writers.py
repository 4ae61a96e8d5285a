"""Output files as plugins (issue 35): every registered writer runs through one function
after the contract files, report.html links what each returned, a broken writer is one
warning naming it and the others still write; Placement.info reaches placement.json as
JSON-safe ``solver_info``."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from camplace.outputs.write import json_safe, solver_info, write_outputs
from camplace.outputs.writers import OUTPUTS, file_list
from conftest import box_room
from plugin_kit import installed


@pytest.fixture(scope="module")
def small_run():
    import camplace

    return camplace.run(box_room(), budget=2, solver="greedy")


@pytest.fixture()
def plugin(tmp_path):
    yield from installed(tmp_path / "site")


def write(result, out, **kw):
    return write_outputs(out, result.scene.name, result.visibility, result.placement, result.problem.budget,
                         result.metrics, result.timings_s, scene=result.scene, problem=result.problem, plan=False,
                         **kw)


def test_file_list_puts_the_contract_first_and_folders_once():
    names = ["scene.glb", "opencv/camera_1.yaml", "metrics.json", "opencv/camera_2.yaml", "report.html",
             "placement.csv", "bom.csv", "visibility.npz", "placement.json", "colmap/images.txt"]
    assert file_list(names) == ["placement.csv", "placement.json", "metrics.json", "visibility.npz", "bom.csv",
                                "colmap/", "opencv/", "scene.glb"]


def test_returned_paths_are_named_relative_to_the_output_folder(tmp_path, monkeypatch):
    from camplace.outputs.writers import OutputResult, write_registered

    monkeypatch.chdir(tmp_path)
    (tmp_path / "rel" / "sub").mkdir(parents=True)
    monkeypatch.setitem(OUTPUTS, "pair", lambda out, result: [(out / "a.txt").write_text("a") and out / "a.txt",
                                                               "sub/b.txt", (tmp_path / "rel" / "sub" / "b.txt")])
    (tmp_path / "rel" / "sub" / "b.txt").write_text("b")
    got = write_registered("rel", OutputResult({"cameras": []}, {}, "x"))
    assert set(got) == {"a.txt", "sub/b.txt"} and got["a.txt"] == Path("rel/a.txt")


def test_camplaces_own_writer_is_registered():
    assert list(OUTPUTS)[0] == "bom" and OUTPUTS.distribution("bom") == "camplace"


def test_every_writer_runs_and_report_html_links_what_it_wrote(plugin, small_run, tmp_path):
    assert any("plugin 'not-callable' (from rooms-plugin)" in t for t in plugin)  # one warning at load
    with pytest.warns(UserWarning) as caught:
        paths = write(small_run, tmp_path / "out")
    failed = [str(w.message) for w in caught if "failed" in str(w.message)]
    assert failed == ["camplace.outputs plugin 'fails' (from rooms-plugin) failed: RuntimeError: disk on fire"]
    assert (tmp_path / "out" / "count.txt").read_text() == f"2 {small_run.metrics.cost}"  # given placement, metrics
    assert {"count.txt", "bom.csv", "placement.json", "report.html"} <= set(paths)
    page = (tmp_path / "out" / "report.html").read_text()
    assert "<a href='count.txt'>count.txt</a>" in page and "<a href='bom.csv'>bom.csv</a>" in page


def test_without_the_plugin_its_file_is_neither_written_nor_linked(small_run, tmp_path):
    paths = write(small_run, tmp_path / "out", report=False)
    assert "count.txt" not in paths and not (tmp_path / "out" / "count.txt").exists() and "bom.csv" in paths


def test_placement_info_is_written_as_solver_info(small_run, tmp_path):
    info = {"iterations": np.int64(7), "order": np.arange(3), "big": np.zeros(5000), "seconds": 1.5,
            "phase": {"moves": 2, "build_seconds": 0.1}, "bound_method": "lp", "gap": float("nan"),
            "existing_ids": {0: "a"}}
    result = replace(small_run, placement=replace(small_run.placement, info=info))
    write(result, tmp_path / "out", report=False)
    pdict = json.loads((tmp_path / "out" / "placement.json").read_text())
    assert pdict["solver_info"] == {"iterations": 7, "order": [0, 1, 2], "big": {"shape": [5000], "dtype": "float64"},
                                    "phase": {"moves": 2}, "gap": None}
    assert pdict["bound_method"] == "lp"  # a key of its own, not repeated


values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=5)
    | hnp.arrays(st.sampled_from([np.int32, np.float64, np.bool_]), st.integers(0, 4))
    | hnp.from_dtype(np.dtype(np.float32)) | st.tuples(st.integers(), st.floats()),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=4) | st.integers(), inner,
                                                                   max_size=4),
    max_leaves=12)


@settings(max_examples=150, deadline=None)
@given(values)
def test_json_safe_gives_strict_json_of_anything(value):
    text = json.dumps(json_safe(value), allow_nan=False)  # no NaN, no numpy, no tuples left
    assert json.loads(text) == json_safe(value)
    info = solver_info({"x": value, "seconds": 1.0})
    json.dumps(info, allow_nan=False)
    assert not any(k == "seconds" or k.endswith("_seconds") for k in keys_of(info))


def keys_of(value) -> list[str]:
    """Every dict key at any depth."""
    if isinstance(value, dict):
        return [*value, *(k for v in value.values() for k in keys_of(v))]
    return [k for v in value for k in keys_of(v)] if isinstance(value, list) else []


def test_json_safe_keeps_finite_numbers_by_hand():
    assert json_safe({"a": np.float32(0.5), 1: (np.int8(3), math.inf)}) == {"a": 0.5, "1": [3, None]}
