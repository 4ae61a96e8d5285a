"""``camplace solve``: re-solve a saved instance (visibility.npz) with no geometry."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer
from rich.console import Console
from rich.table import Table

from camplace.cli.common import (OPTION_OPT, THREADS_OPT, RichProgress, StopFlag, certify_solver, check_options,
                                 progress_bars, solver_option_values, state)


def _table(name: str, p, budget: int, metrics, out_dir: Path) -> Table:
    t = Table(title=f"camplace solve - {name}", show_header=False)
    t.add_row("solver / status", f"{p.solver} / {p.status}")
    t.add_row("cameras (budget)", f"{len(p.selected)} ({budget})")
    t.add_row("cost", f"{p.objective:.6g}" + (f"  ({p.info['incumbent_method']})" if "incumbent_method" in p.info
                                             else ""))
    t.add_row("bound", "-" if p.bound is None else f"{p.bound:.6g} (gap {100 * (p.gap or 0):.2f} %)"
              + (f"  ({p.info['bound_method']})" if "bound_method" in p.info else ""))
    t.add_row("coverage gap (eq. 8)", f"{metrics.coverage_gap:.4f}")
    t.add_row("outputs", str(out_dir))
    return t


def solve_cmd(visibility: Path = typer.Argument(..., help="A saved instance: visibility.npz (CSR arrays, gamma, "
                                               "location_ids; weights and geometry optional)."),
              budget: int = typer.Option(..., "--budget", help="Number of cameras N_s."),
              solver: str = typer.Option("greedy", "--solver", help="Solver name."),
              certify: Optional[float] = typer.Option(None, "--certify", help="Solver 'certify' for SECONDS: "
                                                      "placement and proven bound."),
              time_limit: Optional[float] = typer.Option(None, "--time-limit", help="Solver time limit, seconds."),
              threads: Optional[int] = THREADS_OPT,
              seed: int = typer.Option(0, "--seed", help="Seed of randomized solvers."),
              option: Optional[list[str]] = OPTION_OPT,
              out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default "
                                                 "camplace-out/<instance>-solved).")) -> None:
    """Re-solve a saved instance with no geometry; writes the contract files and every registered output."""
    from camplace.solvers import build_options
    from camplace.workflows.solve import instance_name, solve_instance, write_instance_outputs

    check_options(budget, time_limit, None, out)
    solver, time_limit = certify_solver(certify, solver, time_limit)
    opts = {**solver_option_values(option, seed),
            **{k: v for k, v in {"time_limit_s": time_limit, "threads": threads}.items() if v is not None}}
    build_options(solver, **opts)  # a bad solver or option value: one line before the instance is read
    stop = StopFlag()
    with stop.installed(), progress_bars() as prog:
        bars = RichProgress(prog, stop)
        problem, placement, metrics, arrays, timings = solve_instance(
            visibility, budget, solver, progress=bars, on_incumbent=bars.incumbent, should_stop=stop, **opts)
    name = instance_name(visibility)
    out_dir = out or Path("camplace-out") / f"{name}-solved"
    paths = write_instance_outputs(out_dir, name, problem, placement, metrics, arrays, timings, visibility)
    p = placement
    if state["json"]:
        typer.echo(json.dumps({"instance": str(visibility), "solver": p.solver, "status": p.status,
                               "budget": budget, "cost": p.objective, "bound": p.bound, "gap": p.gap,
                               **{k: p.info[k] for k in ("incumbent_method", "bound_method") if k in p.info},
                               "files": {k: str(v) for k, v in paths.items()}}, indent=2))
    elif state["quiet"]:
        typer.echo(str(out_dir))
    else:
        Console().print(_table(name, p, budget, metrics, out_dir))
    if stop():
        raise typer.Exit(130)
