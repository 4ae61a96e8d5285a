"""camplace.workflows.bench: the paper's comparison on the small demo scene."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from camplace.workflows.bench import PAPER_TABLES, parse_budgets, rows_markdown, run_bench, write_bench
from camplace.core.errors import InputError


@pytest.fixture(scope="module")
def demo_bench():
    return run_bench("demo", [3, 6], ["greedy", "mip", "horster"], time_limit_s=3, threads=1)


def test_bench_rows_score_every_method_on_the_same_problem(demo_bench):
    name, info, rows = demo_bench
    assert name == "demo" and info["target_set"] == "volume"
    assert len(rows) == 6
    by = {(r.method, r.budget): r for r in rows}
    for b in (3, 6):
        assert by["mip", b].cost <= by["greedy", b].cost + 1e-9  # warm-started from greedy
        for r in (by[m, b] for m in ("greedy", "mip", "horster")):
            assert r.cameras <= b
            assert 0 <= r.coverage_gap <= 1 and 0 <= r.non_triangulatable_pct <= 100
    assert by["greedy", 6].coverage_gap < by["greedy", 3].coverage_gap


def test_bench_writes_csv_markdown_png(demo_bench, tmp_path):
    name, info, rows = demo_bench
    paths = write_bench(tmp_path, name, info, rows)
    with open(paths["csv"]) as f:
        got = list(csv.DictReader(f))
    assert len(got) == 6 and {"method", "budget", "coverage_gap", "non_triangulatable_pct", "bound",
                              "proven_gap", "status", "seconds"} <= set(got[0])
    md = paths["markdown"].read_text()
    assert "| Proposed MIP |" in md and "N_s=6" in md
    assert paths["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    from camplace.workflows.bench import read_csv

    back = read_csv(paths["csv"])
    assert [(r.method, r.budget, r.status) for r in back] == [(r.method, r.budget, r.status) for r in rows]
    assert back[0].cost == pytest.approx(rows[0].cost, rel=1e-5)


def test_markdown_shows_the_paper_rows():
    from camplace.workflows.bench import BenchRow

    rows = [BenchRow("standard-store", 20, "mip", 20, 1.0, 0.2, 30.0, 0.5, 0.5, "time_limit", 60.0)]
    md = rows_markdown("standard-store", {}, rows)
    assert "*paper: Proposed MIP* | 0.16" in md
    assert PAPER_TABLES["store-a"]["zhao"][20] == 0.41


def test_volume_restriction_drops_surface_targets():
    _, info_all, _ = run_bench("demo", [2], ["greedy"], targets="all")
    _, info_vol, _ = run_bench("demo", [2], ["greedy"], targets="volume")
    assert info_vol["targets"] < info_all["targets"]


def test_bad_options_are_input_errors():
    with pytest.raises(InputError, match="^budgets: ") as err:  # the library names the parameter; the CLI the flag
        parse_budgets("20,x")
    assert err.value.option == "budgets"
    with pytest.raises(InputError, match="^methods: unknown method"):
        run_bench("demo", [2], ["nope"])
    assert parse_budgets("20, 30,40") == [20, 30, 40]
    assert np.all(np.array(parse_budgets("5")) == 5)


def test_cli_bench_writes_the_three_files(tmp_path, monkeypatch, capsys):
    import subprocess
    import sys

    from conftest import run_cli

    out = tmp_path / "b"
    r = subprocess.run([sys.executable, "-m", "camplace.cli.app", "bench", "demo", "--budgets", "2,4", "--methods",
                        "greedy,horster", "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "| Proposed Greedy |" in r.stdout
    assert {p.name for p in out.iterdir()} >= {"bench.csv", "bench.md", "bench.png"}
    code, text = run_cli(["bench", "demo", "--budgets", "x"], monkeypatch, capsys)  # in-process: no 2nd start-up
    assert code == 2 and "--budgets" in text and "Traceback" not in text


def test_bench_certify_adds_a_row_with_a_proven_bound():
    _, _, rows = run_bench("demo", [3], ["greedy"], certify_s=3.0)
    assert [r.method for r in rows] == ["greedy", "certify"]
    cert = rows[1]
    assert cert.bound is not None and 0.0 <= cert.bound <= cert.cost + 1e-6
    assert cert.cost <= rows[0].cost + 1e-9  # tabu starts from greedy and never returns worse
    assert cert.seconds < 20
    with pytest.raises(InputError, match="^certify_s: ") as err:
        run_bench("demo", [2], ["greedy"], certify_s=0.0)
    assert err.value.option == "certify_s"


def test_cli_bench_certify_bad_value_is_a_one_line_error(tmp_path, monkeypatch, capsys):
    from conftest import run_cli

    code, text = run_cli(["bench", "demo", "--budgets", "2", "--methods", "greedy", "--certify", "-1", "--out",
                          tmp_path / "b"], monkeypatch, capsys)
    assert code == 2
    assert "--certify" in text and "Traceback" not in text
    assert not (tmp_path / "b").exists()
