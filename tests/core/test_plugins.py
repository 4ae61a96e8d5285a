"""Plugins by entry points (camplace.core.plugins): a distribution on the path registers
solvers; one that breaks (import error, contract error, wrong object, taken name) is
reported once and skipped, never taking the others down."""

from __future__ import annotations

import sys
import textwrap
import warnings

import pytest

from camplace.core.plugins import PluginWarning, Registry, source_entry_points
from conftest import plugin_dist
from camplace.solvers.registry import check_plugin

GROUP = "camplace.test-plugins"

PLUGIN = '''
import numpy as np
from camplace.solvers import Placement
from camplace.solvers.contract import make_solver


def solve_first(problem, *, time_limit_s: float | None = None, threads: int | None = None, seed: int = 0,
                should_stop=None, progress=None, on_incumbent=None, count: int = 1) -> Placement:
    sel = np.arange(min(count, problem.n_candidates), dtype=np.int64)
    return Placement(sel, problem.cost(sel), None, "heuristic", "first", 0.0)


FIRST = make_solver("first", solve_first)
NOT_A_SOLVER = 42
'''

BROKEN_CONTRACT = '''
from camplace.solvers.contract import make_solver


def solve_catchall(problem, *, time_limit_s=None, threads=None, seed=0, should_stop=None, progress=None,
                   on_incumbent=None, **kwargs):
    raise AssertionError("never called")


CATCHALL = make_solver("catchall", solve_catchall)   # a contract mistake: fails at import
'''


def dist(root, name: str, entry_points: dict[str, str], modules: dict[str, str]) -> None:
    """A distribution ``name`` installed in ``root`` with entry points of GROUP and ``modules``."""
    plugin_dist(root, name, {GROUP: entry_points}, modules)


@pytest.fixture()
def plugins(tmp_path, monkeypatch):
    dist(tmp_path, "good-plugins", {"first": "cp_plugin_good:FIRST", "wrong-name": "cp_plugin_good:FIRST",
                                    "not-a-solver": "cp_plugin_good:NOT_A_SOLVER",
                                    "missing": "cp_plugin_good:NOTHING"}, {"cp_plugin_good": PLUGIN})
    dist(tmp_path, "zz-bad-plugins", {"catchall": "cp_plugin_bad:CATCHALL", "broken-import": "cp_no_such_module:X",
                                      "first": "cp_plugin_good:FIRST"}, {"cp_plugin_bad": BROKEN_CONTRACT})
    monkeypatch.syspath_prepend(str(tmp_path))
    yield Registry(GROUP, check_plugin)
    for name in [m for m in sys.modules if m.startswith("cp_plugin_")]:
        del sys.modules[name]


def test_good_plugins_load_and_broken_ones_are_skipped_with_one_warning_each(plugins):
    with pytest.warns(PluginWarning) as caught:
        names = list(plugins)
    assert names == ["first"]
    assert plugins["first"].name == "first" and plugins.distribution("first") == "good-plugins"
    text = [str(w.message) for w in caught]
    for name, why in (("wrong-name", "named 'first', the entry point 'wrong-name'"),
                      ("not-a-solver", "expected a camplace.solvers.Solver"), ("missing", "NOTHING"),
                      ("catchall", "no *args / **kwargs"), ("broken-import", "cp_no_such_module"),
                      ("first", "the name is taken by the one from good-plugins")):
        hits = [t for t in text if f"plugin '{name}'" in t]
        assert len(hits) == 1 and why in hits[0], (name, text)
    assert {(n, d) for n, d, _ in plugins.problems} >= {("catchall", "zz-bad-plugins"), ("wrong-name", "good-plugins")}
    with warnings.catch_warnings():
        warnings.simplefilter("error", PluginWarning)  # reported once: later uses warn no more
        assert "first" in plugins and len(plugins) == 1


def test_reload_reads_the_entry_points_again(plugins, tmp_path):
    with pytest.warns(PluginWarning):
        assert len(plugins) == 1
    fixed = textwrap.dedent(PLUGIN).replace('FIRST = make_solver("first"', 'CATCHALL = make_solver("catchall"')
    (tmp_path / "cp_plugin_bad.py").write_text(fixed.replace('"heuristic", "first"', '"heuristic", "catchall"'))
    plugins.reload()
    with pytest.warns(PluginWarning):
        assert sorted(plugins) == ["catchall", "first"]


def test_the_built_ins_are_declared_once_in_pyproject():
    from camplace.solvers import SOLVERS
    from camplace.visibility import ENGINES

    eps = source_entry_points("camplace.solvers")
    assert eps is not None, "camplace runs from its source tree here"
    assert [e.name for e in eps] == [n for n in SOLVERS if SOLVERS.distribution(n) == "camplace"]
    assert [e.name for e in source_entry_points("camplace.engines")] == [
        n for n in ENGINES if ENGINES.distribution(n) == "camplace"]
    assert SOLVERS.problems == [] and ENGINES.problems == []


def test_registering_in_process_is_checked_the_same_way(plugins):
    with pytest.warns(PluginWarning):
        first = plugins["first"]
    plugins["again"] = first.__class__("again", first.fn, first.options, first.tags)
    assert plugins.distribution("again") == "(registered in this process)"
    with pytest.raises(TypeError, match="named 'first', the entry point 'other'"):
        plugins["other"] = first
    del plugins["again"]
    assert list(plugins) == ["first"]


def test_an_entry_point_object_put_back_keeps_its_distribution(monkeypatch):
    """A test that swaps a built-in and puts it back (monkeypatch.setitem) leaves it a built-in."""
    import dataclasses

    from camplace.solvers import SOLVERS

    real = SOLVERS["greedy"]
    with monkeypatch.context() as m:
        m.setitem(SOLVERS, "greedy", dataclasses.replace(real, summary="a stand-in"))
        assert SOLVERS.distribution("greedy") == "(registered in this process)"
    assert SOLVERS["greedy"] is real and SOLVERS.distribution("greedy") == "camplace"
