"""What every command shares: the global state (--debug/--quiet/--verbose/--json), the
console, rich progress bars, the Ctrl-C stop flag, shared options, option checks, the
OPTION -> FLAG table that words library errors, and the entry point's error handling."""

from __future__ import annotations

import math
import os
import re
import signal
import sys
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Optional

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from camplace.cli.crowd import FLAGS as CROWD_FLAGS
from camplace.core.errors import CamplaceError, InputError

console = Console(stderr=True)
state = {"debug": False, "quiet": False, "verbose": False, "json": False}

# library parameter (InputError.option) -> the flag the user typed
FLAGS = {
    "workers": "--workers", "scheduler": "--scheduler", "cache_dir": "--cache", "max_memory_bytes": "--max-memory-gb",
    "time_limit_s": "--time-limit", "coverage_gap": "--coverage-gap", "budget": "--budget", "solver": "--solver",
    "threads": "--threads", "seed": "--seed", "require_feasible": "--require-feasible",
    "visibility_mode": "--visibility", "stride": "--stride", "probe": "--probe", "local_search": "--local-search",
    "refine": "--refine", "refine_time_s": "--refine-time", "adaptive": "--adaptive", "robust": "--robust",
    "quality": "--quality", "quality_time_s": "--quality-time",
    "money_budget": "--money-budget", "triangulation_deg": "--tri-angle", "well_triangulated": "--well-triangulated",
    "certify_s": "--certify", "budgets": "--budgets", "methods": "--methods", "targets": "--targets",
    "camera_id": "--camera", "width": "--width", "placement": "--placement",
    "up": "--up", "level_floor": "--no-level-floor", "crop": "--crop", "downsample": "--downsample",
    "heights": "--heights", "coverage": "--coverage", "wall_mount_height": "--wall-mounts",
    "viewpoints": "--viewpoint", "out": "--out", "frame": "--frame", "paper": "--paper",
    "cloud": "",  # the space file: the message names it already
    "units": "--units", "wall_height": "--wall-height", "ceiling_height": "--ceiling-height", "scale": "--scale",
    "ref": "--ref", "storey": "--storey", "wall_layers": "--wall-layers", "wall_classes": "--wall-classes",
    "furniture_heights": "--layer-height",
    "doors": "--doors", "glass": "--glass", "threshold": "--threshold", "max_opening": "--max-opening",
    "min_room_area": "--min-room-area", "ocr": "--no-ocr", "page": "--page",
    **CROWD_FLAGS,
}


# library wording of a boolean parameter -> the flag that sets it
BOOL_FLAGS = {("level_floor", "False"): "--no-level-floor", ("require_feasible", "True"): "--require-feasible"}
_PARAM_VALUE = re.compile(r"(?<![\w-])([a-z][a-z_]*)=('[^']*'|[^\s,;)]*)")


def _flag_for(match: re.Match) -> str:
    """'up=' -> '--up', "up='+y'" -> '--up +y', 'level_floor=False' -> '--no-level-floor'."""
    name, value = match.group(1), match.group(2)
    if (name, value) in BOOL_FLAGS:
        return BOOL_FLAGS[(name, value)]
    flag = FLAGS.get(name)
    if not flag:
        return match.group(0)
    return f"{flag} {value.strip(chr(39))}" if value else flag


def word_error(err: CamplaceError) -> str:
    """The error's line for the command line. With ``err.option`` set, the library's
    leading 'param:' (or '(param)') becomes the flag, else the flag is put in front
    (an option of "" - the command's argument - only drops 'param: '); 'param=value'
    advice and the quoted 'param' in the message are worded as flags too; a message that
    names its fix as '(param=value)' keeps no prefix (the user may not have given it)."""
    msg = str(err)
    opt = getattr(err, "option", None)
    if opt is None or opt not in FLAGS:
        return f"--option {msg}" if opt and msg.startswith(f"{opt}:") and _solver_option(opt, msg) else msg
    flag = FLAGS[opt]
    msg = _TAKES.sub(_flags_taken, _PARAM_VALUE.sub(_flag_for, msg))
    if flag:
        msg = msg.replace(f"'{opt}'", f"'{flag}'")  # "takes no option 'coverage_gap'"
    if msg.startswith(f"{opt}:"):
        return flag + msg[len(opt):] if flag else msg[len(opt) + 1:].lstrip()
    if f"({opt})" in msg:
        return msg.replace(f"({opt})", f"({flag})") if flag else msg
    if flag and re.search(rf"\({re.escape(flag)} [^)\s]+\)", msg):  # ends in the fix, '(--units m)': no prefix
        return msg
    return f"{flag}: {msg}" if flag else msg


_TAKES = re.compile(r"\(it takes ([a-z][a-z_]*(?:, [a-z][a-z_]*)*)\)")


def _flags_taken(match: re.Match) -> str:
    """'(it takes name, units, heights)' -> '(it takes --units, --heights)': the parameters
    listed as the flags that give them (one without a flag cannot be given on the command line)."""
    flags = [FLAGS[x] for x in match.group(1).split(", ") if FLAGS.get(x)]
    return f"(it takes {', '.join(flags)})" if flags else "(it takes none of the command's options)"


_PAREN_OPTION = re.compile(r"\(([a-z][a-z_]*)\)")


def word_options(text: str) -> str:
    """A library line (a note, an import summary item) for the command line: the options
    it names in parentheses, '(units)', become the flags, '(--units)'."""
    return _PAREN_OPTION.sub(lambda m: f"({FLAGS[m.group(1)]})" if FLAGS.get(m.group(1)) else m.group(0), text)


REPORT_AFTER_STOP_S = 6.0  # after the first Ctrl-C the report set may run until this many seconds after it
PREPARE_STAGES = ("scene", "targets", "candidates")  # before visibility: nothing to keep, Ctrl-C ends them at once


def _solver_option(name: str, msg: str) -> bool:
    """True when ``name`` is some solver's option (given with --option) or the message
    refuses it as one."""
    from camplace.solvers.registry import SOLVERS

    return f"option '{name}'" in msg or any(name in s.option_names for s in SOLVERS.values())


class StopFlag:
    """Ctrl-C handling, by phase (``phase``, set from the progress stages and by the writer):

    - ``prepare`` (scene, targets, candidates): nothing to keep, Ctrl-C aborts at once;
    - ``visibility``: the first Ctrl-C stops after the current chunk (finished chunks stay
      cached), the second aborts;
    - ``keep`` (solve, beyond the grid, metrics, the contract files): the first Ctrl-C
      only sets the flag (the solver returns its best placement, the contract files are
      written); the second (``hurry()``) stops waiting for a solver and skips the report set;
    - ``report`` (after the contract files): the report set runs while it fits
      REPORT_AFTER_STOP_S after the first Ctrl-C (``report_deadline()``); a second Ctrl-C
      ends it at once.

    REPORT_AFTER_STOP_S after the first Ctrl-C a second one is simulated, so that a command
    always leaves soon after an interrupt."""

    def __init__(self) -> None:
        self.count = 0
        self.first_at: float | None = None  # time.perf_counter() of the first Ctrl-C
        self.phase = "keep"
        self._timer = None

    def __call__(self) -> bool:
        return self.count > 0

    def hurry(self) -> bool:
        """True after a second Ctrl-C: leave as soon as the contract files are written."""
        return self.count > 1

    def report_deadline(self) -> float | None:
        """The perf_counter() time the report set must end by after an interrupt (None: not interrupted)."""
        return None if self.first_at is None else self.first_at + REPORT_AFTER_STOP_S

    def stage(self, name: str) -> None:
        """Follow the pipeline's progress stages (RichProgress): sets ``phase``."""
        if self.phase in ("report", "done"):
            return
        self.phase = "prepare" if name in PREPARE_STAGES else "visibility" if name == "visibility" else "keep"
        if self.phase == "prepare" and self.count:
            raise KeyboardInterrupt

    def contract_written(self) -> None:
        """The contract files are in place: from now on a second Ctrl-C ends the command at once."""
        self.phase = "report"
        if self.count > 1:
            raise KeyboardInterrupt

    def finished(self) -> None:
        """Every output is written: a Ctrl-C from now on changes nothing."""
        self.phase = "done"
        if self._timer is not None:
            self._timer.cancel()

    def _handler(self, signum, frame) -> None:  # noqa: ARG002 - signal handler signature
        self.count += 1
        if self.phase == "done":
            return
        if self.first_at is None:
            import threading

            self.first_at = time.perf_counter()
            self._timer = threading.Timer(REPORT_AFTER_STOP_S, self._late)
            self._timer.daemon = True
            self._timer.start()
        if self.phase == "prepare" or (self.count > 1 and self.phase in ("visibility", "report")):
            raise KeyboardInterrupt

    def _late(self) -> None:
        """REPORT_AFTER_STOP_S after the first Ctrl-C: act as a second one."""
        import _thread

        _thread.interrupt_main(signal.SIGINT)

    def _unraisable(self, args) -> None:
        """sys.unraisablehook while installed: a Ctrl-C that landed in a finalizer or a weakref
        callback (where Python can only print it, with a traceback, and go on) is delivered
        again a moment later, outside it; anything else goes to the previous hook."""
        if issubclass(args.exc_type, KeyboardInterrupt) and self.phase != "done":
            import threading

            again = threading.Timer(0.05, self._late)
            again.daemon = True
            again.start()
            return
        self._prev_unraisable(args)

    @contextmanager
    def installed(self):
        try:
            prev = signal.signal(signal.SIGINT, self._handler)
        except ValueError:  # not the main thread: leave Ctrl-C alone
            yield self
            return
        self._prev_unraisable, sys.unraisablehook = sys.unraisablehook, self._unraisable
        try:
            yield self
        finally:
            if self._timer is not None:
                self._timer.cancel()
            signal.signal(signal.SIGINT, prev)
            sys.unraisablehook = self._prev_unraisable


class RichProgress:
    """Renders pipeline progress callbacks as rich progress bars (one plain line per
    stage when stderr is not a terminal, e.g. a log file)."""

    def __init__(self, progress: Progress, stop: StopFlag | None = None) -> None:
        self.progress = progress
        self.tasks: dict[str, int] = {}
        self.stop = stop
        self.told_stop = False

    def incumbent(self, objective: float, bound: float | None = None) -> None:
        """on_incumbent callback of the solvers: show the best cost, bound and gap so far."""
        text = f"best {objective:.6g}"
        if bound is not None and abs(bound) != float("inf") and bound == bound:
            gap = 0.0 if objective <= 0 else max(0.0, (objective - bound) / objective)
            text += f"  bound {bound:.6g}  gap {100 * gap:.2f} %"
        if "solve" in self.tasks:
            self.progress.update(self.tasks["solve"], description=f"solve  {text}")
        if state["verbose"]:
            console.print(f"[dim]incumbent: {text}[/dim]", highlight=False)

    def __call__(self, stage: str, done: int, total: int) -> None:
        if self.stop is not None:
            self.stop.stage(stage)
        if self.stop is not None and self.stop() and not self.told_stop:
            self.told_stop = True
            what = ("after the current visibility chunk (finished chunks stay cached)" if stage == "visibility"
                    else "the solver; the best placement so far will be written")
            again = ("Ctrl-C again to abort" if stage == "visibility"
                     else "Ctrl-C again to write only placement.json / metrics.json and leave")
            console.print(f"[yellow]interrupt: stopping {what} ({again})[/yellow]")
        if stage not in self.tasks:
            if not console.is_terminal and not state["quiet"]:
                console.print(f"stage: {stage}", highlight=False)
            # 'solve' runs until the solver returns: an open bar (incumbents update its text)
            self.tasks[stage] = self.progress.add_task(stage, total=None if stage == "solve" else total)
        if stage == "solve":
            return
        self.progress.update(self.tasks[stage], completed=done, total=total)
        if done == 0 and total == 1:
            self.progress.update(self.tasks[stage], completed=1)


def progress_bars() -> Progress:
    """Rich progress bars on stderr (stage, bar, done/total, elapsed, ETA); off with --quiet."""
    return Progress(TextColumn("[bold]{task.description:<11}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                    TimeElapsedColumn(), TimeRemainingColumn(), console=console, transient=True,
                    disable=state["quiet"])


# ------------------------------------------------------------------ shared options

WORKERS_OPT = typer.Option(1, "--workers", min=1, help="Local worker processes for visibility (1 = in-process).")
SCHEDULER_OPT = typer.Option(None, "--scheduler", envvar="CAMPLACE_SCHEDULER",
                             help="Dask scheduler address (tcp://host:port) to run visibility on a cluster.")
CACHE_OPT = typer.Option(None, "--cache", help="Visibility cache folder (default $CAMPLACE_CACHE or ~/.cache/camplace).")
NO_CACHE_OPT = typer.Option(False, "--no-cache", help="Neither reuse nor store visibility blocks.")
TIME_LIMIT_OPT = typer.Option(None, "--time-limit", help="Solver time limit in seconds (default: the scene's "
                              "placement.time_limit_s); the best placement found is written.")
MAX_MEMORY_OPT = typer.Option(None, "--max-memory-gb", help="Refuse scenes whose grids would need more memory "
                              "(default: CAMPLACE_MAX_MEMORY_GB or 80 % of RAM).")
REPEATABLE_OPT = typer.Option(False, "--repeatable", help="Write timings as 0 so that identical runs give "
                              "byte-identical metrics.json (also CAMPLACE_REPEATABLE=1).")
THREADS_OPT = typer.Option(None, "--threads", min=1, help="Solver threads.")
NO_PLAN_OPT = typer.Option(False, "--no-plan", help="Skip the hand-over plan set (plan.pdf, plan.svg, plan.dxf, "
                           "scene.glb) and report.html's plan view.")
PAPER_OPT = typer.Option("A3", "--paper", help="Paper of plan.pdf (landscape): A4, A3 or letter.")
FRAME_OPT = typer.Option("scene", "--frame", help="Frame of the written poses (placement.json/.csv, OpenCV, COLMAP): "
                         "scene (levelled, z up) or input (the scanned / meshed file's own frame; placement.json "
                         "input_from_scene maps one to the other).")

OPTION_OPT = typer.Option(None, "--option", "-o", metavar="KEY=VALUE",
                          help="A solver option (repeatable), e.g. --option restarts=50; camplace solvers lists "
                               "each solver's options, types and defaults. Named flags win over it.")


NOT_OPTIONS = {"budget": "use --budget", "solver": "use --solver", "should_stop": "a callback",
               "progress": "a callback", "on_incumbent": "a callback"}
SEED_OPT = typer.Option(None, "--seed", help="Seed of randomized solvers (default: the scene's placement.options, "
                        "else 0).")


def solver_option_values(pairs: Optional[list[str]], seed: Optional[int] = None) -> dict:
    """--option KEY=VALUE pairs (and --seed) -> {key: 'value'} (dashes in KEY read as
    underscores; the value is converted to the option's declared type by the solver's options)."""
    out: dict = {}
    for pair in pairs or []:
        key, sep, value = pair.partition("=")
        key = key.strip().replace("-", "_")
        if not sep or not key.isidentifier():
            raise InputError(f"--option: expected KEY=VALUE (e.g. restarts=50), got '{pair}'")
        if key in NOT_OPTIONS:
            raise InputError(f"--option: '{key}' is not a solver option ({NOT_OPTIONS[key]})")
        out[key] = value.strip()
    if seed is not None:
        out["seed"] = seed
    return out


def scale_options(workers: int, scheduler: Optional[str], cache: Optional[Path], no_cache: bool) -> dict:
    """run() keyword arguments of the scale-out options."""
    from camplace.visibility.cache import default_cache_dir

    return {"workers": workers, "scheduler": scheduler or None,
            "cache_dir": None if no_cache else (cache or default_cache_dir())}


def memory_bytes(max_memory_gb: Optional[float]) -> int | None:
    """--max-memory-gb (GiB) -> bytes (None: the default limit)."""
    return None if max_memory_gb is None else int(max_memory_gb * 1024**3)


def repeatable_requested(flag: bool) -> bool:
    """--repeatable, or CAMPLACE_REPEATABLE set to anything but '' / '0'."""
    return flag or os.environ.get("CAMPLACE_REPEATABLE", "") not in ("", "0")


def check_options(budget: Optional[int], time_limit: Optional[float], max_memory_gb: Optional[float],
                  out: Optional[Path]) -> None:
    """CLI options, checked before any work (InputError naming the option)."""
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


def certify_solver(certify: Optional[float], solver: Optional[str], time_limit: Optional[float]
                   ) -> tuple[Optional[str], Optional[float]]:
    """--certify SECONDS -> (solver 'certify', time limit SECONDS); else unchanged."""
    if certify is None:
        return solver, time_limit
    if certify <= 0:
        raise InputError(f"--certify: expected seconds > 0, got {certify}")
    return "certify", certify


def floats(text: str, option: str, n: int | None = None) -> list[float]:
    """'1,2,3' (or ';'-separated) -> [1.0, 2.0, 3.0]; InputError naming ``option``."""
    try:
        vals = [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise InputError(f"{option}: expected comma-separated numbers, got '{text}'") from None
    if n is not None and len(vals) != n:
        raise InputError(f"{option}: expected {n} comma-separated numbers, got '{text}'")
    return vals


# ------------------------------------------------------------------ the entry point


def run_main(app: Callable) -> None:
    """Run the typer app, turning CamplaceError into one line + exit code."""
    try:
        rc = app(standalone_mode=False)  # typer.Exit(code) comes back as the return value here
        if isinstance(rc, int) and not isinstance(rc, bool) and rc != 0:
            sys.exit(rc)
    except CamplaceError as err:
        if state["debug"]:
            raise
        label = "interrupted" if err.exit_code == 130 else "error"
        console.print(f"[bold red]{label}:[/bold red] {escape(word_error(err))}", highlight=False, soft_wrap=True)
        sys.exit(err.exit_code)
    except KeyboardInterrupt:
        if state["debug"]:
            raise
        console.print("[bold red]interrupted:[/bold red] stopped (Ctrl-C); no new outputs written")
        sys.exit(130)
    except Exception as err:  # click usage errors and the like
        _exit_on_other(err)


def _exit_on_other(err: Exception) -> None:
    """Exit for an exception that is not a CamplaceError: usage errors (2), exits, aborts
    (130), OS errors (1, one line), anything else an internal error (1)."""
    kind = _click_kind(err)
    if kind == "usage":
        err.show()  # type: ignore[attr-defined] - one usage line + the problem
        sys.exit(2)
    if kind == "exit":
        sys.exit(err.exit_code)  # type: ignore[attr-defined]
    if kind == "abort":
        sys.exit(130)
    if state["debug"]:
        raise err
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
