"""The ``camplace`` command line: a thin layer over camplace.pipeline (no logic here)."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Optional

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from camplace.builtin import BUILTIN_SCENES, builtin_yaml
from camplace.errors import CamplaceError

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="camplace: choose where to mount cameras so every place gets the coverage it needs.")
console = Console(stderr=True)
_state = {"debug": False, "quiet": False}


@app.callback()
def _main(debug: bool = typer.Option(False, "--debug", help="Show Python tracebacks on errors."),
          quiet: bool = typer.Option(False, "--quiet", "-q", help="Only errors and the output paths.")) -> None:
    _state["debug"] = debug
    _state["quiet"] = quiet


class _RichProgress:
    """Renders pipeline progress callbacks as rich progress bars."""

    def __init__(self, progress: Progress) -> None:
        self.progress = progress
        self.tasks: dict[str, int] = {}

    def __call__(self, stage: str, done: int, total: int) -> None:
        if stage not in self.tasks:
            self.tasks[stage] = self.progress.add_task(stage, total=total)
        self.progress.update(self.tasks[stage], completed=done, total=total)
        if done == 0 and total == 1:
            self.progress.update(self.tasks[stage], completed=1)


def _progress() -> Progress:
    return Progress(TextColumn("[bold]{task.description:<11}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                    TimeElapsedColumn(), TimeRemainingColumn(), console=console, transient=True,
                    disable=_state["quiet"])


def _summary(result, out_dir: Path) -> None:
    from camplace.report import write_outputs

    p, m = result.placement, result.metrics
    paths = write_outputs(out_dir, result.scene.name, result.visibility, p, result.problem.budget, m,
                          result.timings_s)
    if _state["quiet"]:
        typer.echo(str(out_dir))
        return
    for line in result.log:
        console.print(f"[dim]{line}[/dim]")
    t = Table(title=f"camplace - {result.scene.name}", show_header=False)
    t.add_row("solver / status", f"{p.solver} / {p.status}")
    t.add_row("cameras (budget)", f"{len(p.selected)} ({result.problem.budget})")
    t.add_row("cost", f"{p.objective:.6g}")
    t.add_row("bound", "-" if p.bound is None else f"{p.bound:.6g} (gap {100 * (p.gap or 0):.2f} %)")
    t.add_row("coverage gap (eq. 8)", f"{m.coverage_gap:.4f}")
    t.add_row("non-triangulatable", f"{m.non_triangulatable_pct:.2f} %")
    for name, r in m.regions.items():
        t.add_row(f"  region {name}", f"{r['targets']} targets, gap {r['coverage_gap']:.4f}, "
                                     f"non-tri {r['non_triangulatable_pct']:.1f} %")
    t.add_row("timings (s)", ", ".join(f"{k} {v:.2f}" for k, v in result.timings_s.items()))
    t.add_row("outputs", str(out_dir))
    Console().print(t)


def _run(scene: str, budget: Optional[int], solver: Optional[str], out: Optional[Path]) -> None:
    from camplace.pipeline import run

    with _progress() as prog:
        result = run(scene, budget=budget, solver=solver, progress=_RichProgress(prog))
    out_dir = out or Path("camplace-out") / result.scene.name
    _summary(result, out_dir)


@app.command()
def demo(out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default camplace-out/standard-store)."),
         budget: int = typer.Option(40, "--budget", help="Number of cameras N_s."),
         solver: str = typer.Option("greedy", "--solver", help="Solver name.")) -> None:
    """Run the whole pipeline on the built-in standard-store and print a summary."""
    _run("standard-store", budget, solver, out)


@app.command("run")
def run_cmd(scene: str = typer.Argument(..., help="Scene YAML file or built-in name (demo, standard-store, store-a)."),
            budget: Optional[int] = typer.Option(None, "--budget", help="Number of cameras N_s (default: the scene's)."),
            solver: Optional[str] = typer.Option(None, "--solver", help="Solver (default: the scene's)."),
            out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default camplace-out/<scene>).")) -> None:
    """Run the whole pipeline on a scene and write placement.json, metrics.json, visibility.npz."""
    if budget is not None and budget < 0:
        raise CamplaceInputErrorProxy(f"--budget: expected a non-negative integer, got {budget}")
    _run(scene, budget, solver, out)


@app.command()
def scenes(show: Optional[str] = typer.Option(None, "--show", help="Print the YAML of this built-in scene.")) -> None:
    """List the built-in scenes (or print one as a scene-file example)."""
    if show:
        typer.echo(builtin_yaml(show))
        return
    for name in BUILTIN_SCENES:
        typer.echo(name)


def CamplaceInputErrorProxy(msg: str) -> CamplaceError:  # noqa: N802 - reads like a class at call sites
    from camplace.errors import InputError

    return InputError(msg)


def main() -> None:
    """Entry point: run the app, turning CamplaceError into one line + exit code."""
    try:
        app(standalone_mode=False)
    except CamplaceError as err:
        if _state["debug"]:
            raise
        console.print(f"[bold red]error:[/bold red] {err}", highlight=False, soft_wrap=True)
        sys.exit(err.exit_code)
    except KeyboardInterrupt:
        console.print("[bold red]interrupted[/bold red]")
        sys.exit(130)
    except Exception as err:  # click usage errors and the like
        import click

        if isinstance(err, click.exceptions.ClickException):
            err.show()
            sys.exit(2)
        if isinstance(err, click.exceptions.Exit):
            sys.exit(err.exit_code)
        if isinstance(err, click.exceptions.Abort):
            sys.exit(130)
        raise


if __name__ == "__main__":  # pragma: no cover
    main()
