"""``camplace bench``: the paper's experiments (every method at every budget on one V)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer
from rich.markup import escape

from camplace.cli.common import (THREADS_OPT, RichProgress, StopFlag, check_options, console, progress_bars,
                                 solver_option_values, state)


def bench(scene: str = typer.Argument(..., help="Scene YAML file or built-in name."),
          budgets: str = typer.Option("20,30,40,50,60,80", "--budgets", help="Comma-separated camera budgets N_s."),
          methods: str = typer.Option(",".join(("greedy", "mip", "paper-mip", "zhao", "horster")), "--methods",
                                      help="Comma-separated solvers (greedy+ls = greedy with 1-swap)."),
          time_limit: float = typer.Option(60.0, "--time-limit", help="Time limit per solver run, seconds."),
          threads: Optional[int] = THREADS_OPT,
          targets: str = typer.Option("volume", "--targets", help="volume (the paper's walkable grid) or all."),
          certify: Optional[float] = typer.Option(None, "--certify", help="Also run solver 'certify' for SECONDS per "
                                                  "budget: best placement, proven bound and gap."),
          out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default camplace-out/bench-<scene>)."),
          option: Optional[list[str]] = typer.Option(None, "--option", "-o", metavar="KEY=VALUE",
                                                     help="A solver option (repeatable), given to every method that "
                                                          "takes it; camplace solvers lists them."),
          seed: Optional[int] = typer.Option(None, "--seed", help="Seed of randomized solvers (methods that take "
                                             "seed: all).")) -> None:
    """The paper's experiments: every method at every budget on the same V; writes bench.csv,
    bench.md (beside the paper's Tables I/II) and bench.png (gap and % non-triangulatable)."""
    from camplace.workflows.bench import parse_budgets, run_bench, write_bench

    check_options(None, time_limit, None, out)
    budget_list = parse_budgets(budgets)
    method_list = [m.strip() for m in methods.split(",") if m.strip()]
    out_dir = out or Path("camplace-out") / f"bench-{Path(scene).stem}"
    stop = StopFlag()
    with stop.installed(), progress_bars() as prog:
        name, info, rows = run_bench(scene, budget_list, method_list, time_limit_s=time_limit, threads=threads,
                                     targets=targets, progress=RichProgress(prog, stop), should_stop=stop,
                                     on_row=lambda rows: write_bench(out_dir, Path(scene).stem, {}, rows),
                                     certify_s=certify, options=solver_option_values(option, seed))
    paths = write_bench(out_dir, name, info, rows)
    if state["json"]:
        from dataclasses import asdict

        typer.echo(json.dumps({"scene": name, "rows": [asdict(r) for r in rows], "out_dir": str(out_dir),
                               "files": {k: str(v) for k, v in paths.items()}}, indent=2, default=str))
    elif not state["quiet"]:
        typer.echo((out_dir / "bench.md").read_text())
    for p in paths.values():
        console.print(f"wrote {escape(str(p))}", highlight=False)
