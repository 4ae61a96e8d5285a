"""``camplace demo``: the whole pipeline on the built-in standard-store."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from camplace.cli.common import (CACHE_OPT, FRAME_OPT, NO_CACHE_OPT, NO_PLAN_OPT, OPTION_OPT, PAPER_OPT,
                                 REPEATABLE_OPT, SCHEDULER_OPT, SEED_OPT, TIME_LIMIT_OPT, WORKERS_OPT, scale_options,
                                 solver_option_values)
from camplace.cli.run import REFINE_OPT, run_pipeline


def demo(out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default camplace-out/standard-store)."),
         budget: int = typer.Option(40, "--budget", help="Number of cameras N_s."),
         solver: str = typer.Option("greedy", "--solver", help="Solver name."),
         workers: int = WORKERS_OPT, scheduler: Optional[str] = SCHEDULER_OPT,
         cache: Optional[Path] = CACHE_OPT, no_cache: bool = NO_CACHE_OPT,
         time_limit: Optional[float] = TIME_LIMIT_OPT, repeatable: bool = REPEATABLE_OPT,
         frame: str = FRAME_OPT, no_plan: bool = NO_PLAN_OPT, paper: str = PAPER_OPT,
         refine: Optional[bool] = REFINE_OPT, option: Optional[list[str]] = OPTION_OPT,
         seed: Optional[int] = SEED_OPT) -> None:
    """Run the whole pipeline on the built-in standard-store and print a summary (the grid
    solution refined off the grid unless --grid-only)."""
    run_pipeline("standard-store", budget, solver, out, time_limit, repeatable=repeatable, frame=frame,
                 plan=not no_plan, paper=paper,
                 **scale_options(workers, scheduler, cache, no_cache),
                 **({"refine": True} if refine is not False else {}), options=solver_option_values(option, seed))
