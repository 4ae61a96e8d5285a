"""A plan format and an output file from another distribution, through the command line
(issue 35): camplace run of a '.rooms' plan makes its rooms zones, the plugin's writer's
file lands in the run folder, linked from report.html and listed in the summary, and
evaluate and solve write it too; solve writes the contract files; the broken plugins are
one warning line each."""

from __future__ import annotations

import json

import pytest

from conftest import import_and_evaluate, run_cli
from plugin_kit import installed, write_rooms


@pytest.fixture(scope="module")
def plugin(tmp_path_factory):
    yield from installed(tmp_path_factory.mktemp("rooms") / "site")


def cli(args, monkeypatch, capsys):
    return run_cli([str(a) for a in args], monkeypatch, capsys)


def test_run_evaluate_and_solve_of_a_plugin_plan(plugin, tmp_path, monkeypatch, capsys):
    from camplace.outputs.writers import OUTPUTS
    from camplace.scene.formats import IMPORTERS

    IMPORTERS.reload()  # read at the command's first use, as in a new process
    OUTPUTS.reload()
    plan = write_rooms(tmp_path / "two.rooms")
    run = tmp_path / "run"
    code, text = cli(["run", plan, "--budget", "3", "--out", run, "--no-plan", "--no-cache", "--grid-only"],
                     monkeypatch, capsys)
    assert code == 0, text
    for name in ("no-suffix", "not-callable", "fails"):  # each broken plugin: one warning line naming it
        assert len([ln for ln in text.splitlines() if ln.startswith("warning:") and f"'{name}'" in ln]) == 1, text
    assert (run / "count.txt").read_text().startswith("3 ")
    assert "<a href='count.txt'>count.txt</a>" in (run / "report.html").read_text()
    assert "count.txt" in text  # the summary's file list
    metrics = json.loads((run / "metrics.json").read_text())
    assert {"Office", "Lab"} <= set(metrics["regions"])  # the importer's rooms became zones

    ev = import_and_evaluate(plan, run / "placement.json", tmp_path, monkeypatch, capsys)
    assert (ev / "count.txt").read_text() == (run / "count.txt").read_text()

    code, text = cli(["solve", run / "visibility.npz", "--budget", "2", "--out", tmp_path / "sv"], monkeypatch, capsys)
    assert code == 0, text
    sv = tmp_path / "sv"
    assert {p.name for p in sv.iterdir()} >= {"placement.json", "metrics.json", "placement.csv", "visibility.npz",
                                               "count.txt"}
    assert not (sv / "bom.csv").exists()  # camplace's bom needs camera types: solve has none
    assert (sv / "visibility.npz").read_bytes() == (run / "visibility.npz").read_bytes()  # the instance solved
    placed = json.loads((sv / "placement.json").read_text())
    assert (sv / "placement.csv").read_text().count("\n") == 1 + len(placed["cameras"]) == 3


def test_an_option_a_plugin_format_does_not_take_is_one_line_in_flags(plugin, tmp_path, monkeypatch, capsys):
    code, text = cli(["run", write_rooms(tmp_path / "two.rooms"), "--scale", "1:100", "--out", tmp_path / "o"],
                     monkeypatch, capsys)
    assert code == 2 and "Traceback" not in text, text
    assert "error: --scale: not an option of rooms plans (it takes --wall-height, --heights, --coverage, --budget)" \
        in text
    assert not (tmp_path / "o").exists()


def test_scene_import_help_lists_the_plugin_format(plugin, monkeypatch, capsys):
    code, text = cli(["scene", "import", "--help"], monkeypatch, capsys)
    assert code == 0 and "rooms (.rooms)" in " ".join(text.replace("│", " ").split()), text
