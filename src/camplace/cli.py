"""The ``camplace`` command line: a thin layer over camplace.pipeline (no logic here)."""

from __future__ import annotations

import json
import os
import signal
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Optional

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.markup import escape
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


class _StopFlag:
    """Ctrl-C handling: the first SIGINT only sets a flag (polled by the pipeline and the
    solver, which then return the best placement so far); the second aborts."""

    def __init__(self) -> None:
        self.count = 0

    def __call__(self) -> bool:
        return self.count > 0

    def _handler(self, signum, frame) -> None:  # noqa: ARG002 - signal handler signature
        self.count += 1
        if self.count > 1:
            raise KeyboardInterrupt

    @contextmanager
    def installed(self):
        try:
            prev = signal.signal(signal.SIGINT, self._handler)
        except ValueError:  # not the main thread: leave Ctrl-C alone
            yield self
            return
        try:
            yield self
        finally:
            signal.signal(signal.SIGINT, prev)


class _RichProgress:
    """Renders pipeline progress callbacks as rich progress bars (one plain line per
    stage when stderr is not a terminal, e.g. a log file)."""

    def __init__(self, progress: Progress, stop: _StopFlag | None = None) -> None:
        self.progress = progress
        self.tasks: dict[str, int] = {}
        self.stop = stop
        self.told_stop = False

    def __call__(self, stage: str, done: int, total: int) -> None:
        if self.stop is not None and self.stop() and not self.told_stop:
            self.told_stop = True
            console.print("[yellow]interrupt: stopping; the best placement so far will be written "
                          "(Ctrl-C again to abort)[/yellow]")
        if stage not in self.tasks:
            if not console.is_terminal and not _state["quiet"]:
                console.print(f"stage: {stage}", highlight=False)
            self.tasks[stage] = self.progress.add_task(stage, total=total)
        self.progress.update(self.tasks[stage], completed=done, total=total)
        if done == 0 and total == 1:
            self.progress.update(self.tasks[stage], completed=1)


def _progress() -> Progress:
    return Progress(TextColumn("[bold]{task.description:<11}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                    TimeElapsedColumn(), TimeRemainingColumn(), console=console, transient=True,
                    disable=_state["quiet"])


def _summary(result, out_dir: Path, repeatable: bool = False) -> None:
    from camplace.report import write_outputs

    p, m = result.placement, result.metrics
    paths = write_outputs(out_dir, result.scene.name, result.visibility, p, result.problem.budget, m,
                          result.timings_s, repeatable=repeatable)
    for line in result.log:
        if line.startswith("warning:"):
            console.print(f"[yellow]{escape(line)}[/yellow]", soft_wrap=True)
        elif not _state["quiet"]:
            console.print(f"[dim]{escape(line)}[/dim]")
    if _state["quiet"]:
        typer.echo(str(out_dir))
        return
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


_WORKERS_OPT = typer.Option(1, "--workers", min=1, help="Local worker processes for visibility (1 = in-process).")
_SCHEDULER_OPT = typer.Option(None, "--scheduler", envvar="CAMPLACE_SCHEDULER",
                              help="Dask scheduler address (tcp://host:port) to run visibility on a cluster.")
_CACHE_OPT = typer.Option(None, "--cache", help="Visibility cache folder (default $CAMPLACE_CACHE or ~/.cache/camplace).")
_NO_CACHE_OPT = typer.Option(False, "--no-cache", help="Neither reuse nor store visibility blocks.")


def _scale_options(workers: int, scheduler: Optional[str], cache: Optional[Path], no_cache: bool) -> dict:
    from camplace.cache import default_cache_dir

    return {"workers": workers, "scheduler": scheduler or None,
            "cache_dir": None if no_cache else (cache or default_cache_dir())}


def _check_options(budget: Optional[int], time_limit: Optional[float], max_memory_gb: Optional[float],
                   out: Optional[Path]) -> None:
    """CLI options, checked before any work (InputError naming the option)."""
    import math

    from camplace.errors import InputError

    if budget is not None and budget < 0:
        raise InputError(f"--budget: expected a non-negative integer, got {budget}")
    if time_limit is not None and not (time_limit > 0 and math.isfinite(time_limit)):
        raise InputError(f"--time-limit: expected a positive number of seconds, got {time_limit}")
    if max_memory_gb is not None and not (max_memory_gb > 0 and math.isfinite(max_memory_gb)):
        raise InputError(f"--max-memory-gb: expected a positive number of GiB, got {max_memory_gb}")
    if out is not None:
        if out.exists() and not out.is_dir():
            raise InputError(f"--out: '{out}' is a file; expected a folder")
        parent = next((a for a in [out, *out.parents] if a.exists()), Path("."))
        if not parent.is_dir() or not os.access(parent, os.W_OK):
            raise InputError(f"--out: cannot create or write into '{parent}'")


def _run(scene: str, budget: Optional[int], solver: Optional[str], out: Optional[Path],
         time_limit: Optional[float] = None, require_feasible: bool = False, max_memory_gb: Optional[float] = None,
         repeatable: bool = False, **scale) -> None:
    from camplace.pipeline import run

    _check_options(budget, time_limit, max_memory_gb, out)
    repeatable = repeatable or os.environ.get("CAMPLACE_REPEATABLE", "") not in ("", "0")
    stop = _StopFlag()
    with stop.installed():  # first Ctrl-C: finish with the best placement so far; second: abort
        with _progress() as prog:
            result = run(scene, budget=budget, solver=solver, progress=_RichProgress(prog, stop),
                         time_limit_s=time_limit, should_stop=stop, require_feasible=require_feasible,
                         max_memory_bytes=None if max_memory_gb is None else int(max_memory_gb * 1024**3), **scale)
        out_dir = out or Path("camplace-out") / result.scene.name
        _summary(result, out_dir, repeatable)
    if stop():
        console.print(f"[yellow]interrupted: wrote the best placement found so far (status "
                      f"'{result.placement.status}') to {escape(str(out_dir))}[/yellow]")
        _exit_if_solver_left_running(130)
        raise typer.Exit(130)


def _exit_if_solver_left_running(code: int) -> None:
    """A solver thread that ignored the interrupt (camplace.pipeline.solve_stoppable) may
    still run native code; interpreter shutdown under it can abort the process. The
    outputs are written (atomically, fsynced), so leave at once with ``code``."""
    import threading

    if any(t.is_alive() and t.name.startswith("camplace-solve-") for t in threading.enumerate()):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


_TIME_LIMIT_OPT = typer.Option(None, "--time-limit", help="Solver time limit in seconds (default: the scene's "
                               "placement.time_limit_s); the best placement found is written.")
_REQUIRE_FEASIBLE_OPT = typer.Option(False, "--require-feasible", help="Fail (exit 2) when some targets cannot "
                                     "reach their coverage (default: a warning that names them).")
_MAX_MEMORY_OPT = typer.Option(None, "--max-memory-gb", help="Refuse scenes whose grids would need more memory "
                               "(default: CAMPLACE_MAX_MEMORY_GB or 80 % of RAM).")
_REPEATABLE_OPT = typer.Option(False, "--repeatable", help="Write timings as 0 so that identical runs give "
                               "byte-identical metrics.json (also CAMPLACE_REPEATABLE=1).")


@app.command()
def demo(out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default camplace-out/standard-store)."),
         budget: int = typer.Option(40, "--budget", help="Number of cameras N_s."),
         solver: str = typer.Option("greedy", "--solver", help="Solver name."),
         workers: int = _WORKERS_OPT, scheduler: Optional[str] = _SCHEDULER_OPT,
         cache: Optional[Path] = _CACHE_OPT, no_cache: bool = _NO_CACHE_OPT,
         time_limit: Optional[float] = _TIME_LIMIT_OPT, repeatable: bool = _REPEATABLE_OPT) -> None:
    """Run the whole pipeline on the built-in standard-store and print a summary."""
    _run("standard-store", budget, solver, out, time_limit, repeatable=repeatable,
         **_scale_options(workers, scheduler, cache, no_cache))


@app.command("run")
def run_cmd(scene: str = typer.Argument(..., help="Scene YAML file or built-in name (demo, standard-store, store-a, warehouse[:AREA_M2])."),
            budget: Optional[int] = typer.Option(None, "--budget", help="Number of cameras N_s (default: the scene's)."),
            solver: Optional[str] = typer.Option(None, "--solver", help="Solver (default: the scene's)."),
            out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default camplace-out/<scene>)."),
            workers: int = _WORKERS_OPT, scheduler: Optional[str] = _SCHEDULER_OPT,
            cache: Optional[Path] = _CACHE_OPT, no_cache: bool = _NO_CACHE_OPT,
            time_limit: Optional[float] = _TIME_LIMIT_OPT, require_feasible: bool = _REQUIRE_FEASIBLE_OPT,
            max_memory_gb: Optional[float] = _MAX_MEMORY_OPT, repeatable: bool = _REPEATABLE_OPT) -> None:
    """Run the whole pipeline on a scene and write placement.json, metrics.json, visibility.npz.

    Ctrl-C during the solve writes the best placement found so far (status 'interrupted',
    exit code 130); a second Ctrl-C aborts without writing."""
    _run(scene, budget, solver, out, time_limit, require_feasible, max_memory_gb, repeatable,
         **_scale_options(workers, scheduler, cache, no_cache))


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
        rc = app(standalone_mode=False)  # typer.Exit(code) comes back as the return value here
        if isinstance(rc, int) and not isinstance(rc, bool) and rc != 0:
            sys.exit(rc)
    except CamplaceError as err:
        if _state["debug"]:
            raise
        label = "interrupted" if err.exit_code == 130 else "error"
        console.print(f"[bold red]{label}:[/bold red] {escape(str(err))}", highlight=False, soft_wrap=True)
        sys.exit(err.exit_code)
    except KeyboardInterrupt:
        if _state["debug"]:
            raise
        console.print("[bold red]interrupted[/bold red] (second Ctrl-C): stopped without writing outputs")
        sys.exit(130)
    except Exception as err:  # click usage errors and the like
        kind = _click_kind(err)
        if kind == "usage":
            err.show()  # type: ignore[attr-defined] - one usage line + the problem
            sys.exit(2)
        if kind == "exit":
            sys.exit(err.exit_code)  # type: ignore[attr-defined]
        if kind == "abort":
            sys.exit(130)
        if _state["debug"]:
            raise
        if isinstance(err, OSError):  # disk full, permission denied, ...: the user can act on it
            console.print(f"[bold red]error:[/bold red] {escape(str(err))}", highlight=False, soft_wrap=True)
            sys.exit(1)
        console.print(f"[bold red]internal error:[/bold red] {type(err).__name__}: {escape(str(err))} "
                      f"(a bug in camplace: run with --debug for the traceback and report it)",
                      highlight=False, soft_wrap=True)
        sys.exit(1)


def _click_kind(err: BaseException) -> str | None:
    """'usage', 'exit', 'abort' for click's exceptions (typer may vendor click), else None."""
    mods = []
    try:
        import click.exceptions as ce

        mods.append(ce)
    except ImportError:  # pragma: no cover
        pass
    try:
        import typer._click.exceptions as te  # typer >= 0.20 ships its own click

        mods.append(te)
    except ImportError:
        pass
    if any(isinstance(err, getattr(m, "ClickException", ())) for m in mods):
        return "usage"
    name = type(err).__name__  # click's and typer's own Exit / Abort classes
    if name == "Exit" and hasattr(err, "exit_code"):
        return "exit"
    return "abort" if name == "Abort" else None


if __name__ == "__main__":  # pragma: no cover
    main()
