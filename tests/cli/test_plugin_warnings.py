"""A broken solver plugin on the path: every command still works, and the plugin is one
'warning:' line naming it (camplace solvers lists it as skipped)."""

from __future__ import annotations

import sys

import pytest
import yaml

from conftest import BASE, run_cli


@pytest.fixture()
def broken_plugin(tmp_path):
    from camplace.solvers import SOLVERS

    info = tmp_path / "site" / "bad_plug-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: bad-plug\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[camplace.solvers]\noops = cp_bad_plug:X\n")
    (tmp_path / "site" / "cp_bad_plug.py").write_text(
        "from camplace.solvers.contract import make_solver\n\n\ndef f(problem, **kwargs):\n    pass\n\n\n"
        "X = make_solver('oops', f)  # a contract mistake: fails at import\n")
    sys.path.insert(0, str(tmp_path / "site"))
    SOLVERS.reload()
    yield
    sys.path.remove(str(tmp_path / "site"))
    sys.modules.pop("cp_bad_plug", None)
    SOLVERS.reload()


def test_a_broken_plugin_is_one_warning_and_takes_nothing_down(broken_plugin, tmp_path, monkeypatch, capsys):
    scene = tmp_path / "scene.yaml"
    scene.write_text(yaml.safe_dump(BASE, sort_keys=False))
    code, text = run_cli(["run", scene, "--solver", "greedy", "--out", tmp_path / "out", "--no-plan", "--no-cache",
                          "--grid-only"], monkeypatch, capsys)
    assert code == 0, text
    lines = [ln for ln in text.splitlines() if "plugin 'oops'" in ln]
    assert lines == ["warning: camplace.solvers plugin 'oops' (from bad-plug) skipped: TypeError: f: a solver must "
                     "take the keywords time_limit_s, threads, seed, should_stop, progress, on_incumbent"], text
    assert (tmp_path / "out" / "placement.json").is_file()
    code, text = run_cli(["solvers"], monkeypatch, capsys)
    assert code == 0 and "skipped: camplace.solvers plugin 'oops' from bad-plug" in text and "  greedy: " in text
