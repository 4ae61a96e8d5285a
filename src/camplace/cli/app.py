"""The ``camplace`` command line: a thin layer over camplace.workflows.run (no logic here)."""

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

from camplace.spec.builtin import BUILTIN_SCENES, builtin_yaml
from camplace.core.errors import CamplaceError

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="camplace: choose where to mount cameras so every place gets the coverage it needs.")
console = Console(stderr=True)
_state = {"debug": False, "quiet": False, "verbose": False, "json": False}


@app.callback()
def _main(debug: bool = typer.Option(False, "--debug", help="Show Python tracebacks on errors."),
          quiet: bool = typer.Option(False, "--quiet", "-q", help="Only errors and the output paths."),
          verbose: bool = typer.Option(False, "--verbose", "-v", help="Also show stage details, solver "
                                       "information and every file written."),
          json_out: bool = typer.Option(False, "--json", help="Print a JSON summary on stdout (for scripts); "
                                        "progress and messages stay on stderr.")) -> None:
    _state["debug"] = debug
    _state["quiet"] = quiet
    _state["verbose"] = verbose and not quiet
    _state["json"] = json_out


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

    def incumbent(self, objective: float, bound: float | None = None) -> None:
        """on_incumbent callback of the solvers: show the best cost, bound and gap so far."""
        text = f"best {objective:.6g}"
        if bound is not None and abs(bound) != float("inf") and bound == bound:
            gap = 0.0 if objective <= 0 else max(0.0, (objective - bound) / objective)
            text += f"  bound {bound:.6g}  gap {100 * gap:.2f} %"
        if "solve" in self.tasks:
            self.progress.update(self.tasks["solve"], description=f"solve  {text}")
        if _state["verbose"]:
            console.print(f"[dim]incumbent: {text}[/dim]", highlight=False)

    def __call__(self, stage: str, done: int, total: int) -> None:
        if self.stop is not None and self.stop() and not self.told_stop:
            self.told_stop = True
            what = ("after the current visibility chunk (finished chunks stay cached)" if stage == "visibility"
                    else "the solver; the best placement so far will be written")
            console.print(f"[yellow]interrupt: stopping {what} (Ctrl-C again to abort)[/yellow]")
        if stage not in self.tasks:
            if not console.is_terminal and not _state["quiet"]:
                console.print(f"stage: {stage}", highlight=False)
            # 'solve' runs until the solver returns: an open bar (incumbents update its text)
            self.tasks[stage] = self.progress.add_task(stage, total=None if stage == "solve" else total)
        if stage == "solve":
            return
        self.progress.update(self.tasks[stage], completed=done, total=total)
        if done == 0 and total == 1:
            self.progress.update(self.tasks[stage], completed=1)


def _progress() -> Progress:
    """Rich progress bars on stderr (stage, bar, done/total, elapsed, ETA); off with --quiet."""
    return Progress(TextColumn("[bold]{task.description:<11}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                    TimeElapsedColumn(), TimeRemainingColumn(), console=console, transient=True,
                    disable=_state["quiet"])


def _json_summary(result, out_dir: Path, paths: dict) -> dict:
    """The --json summary: the placement's headline figures, every metrics.json figure as
    written, and where the files are."""
    p = result.placement
    metrics = json.loads(Path(paths["metrics.json"]).read_text())
    return {"scene": result.scene.name, "solver": p.solver, "status": p.status, "budget": int(result.problem.budget),
            "n_cameras": int(len(p.selected)), "objective": float(p.objective),
            "bound": None if p.bound is None else float(p.bound), "gap": p.gap, **metrics,
            "out_dir": str(out_dir), "files": {k: str(v) for k, v in sorted(paths.items())}}


def _summary(result, out_dir: Path, repeatable: bool = False) -> None:
    from camplace.outputs.write import write_outputs

    import time

    p, m = result.placement, result.metrics
    t0 = time.perf_counter()
    paths = write_outputs(out_dir, result.scene.name, result.visibility, p, result.problem.budget, m,
                          result.timings_s, repeatable=repeatable, scene=result.scene)
    result.timings_s["report"] = time.perf_counter() - t0
    for line in result.log:
        if line.startswith("warning:"):
            console.print(f"[yellow]{escape(line)}[/yellow]", soft_wrap=True)
        elif not _state["quiet"]:
            console.print(f"[dim]{escape(line)}[/dim]")
    if _state["verbose"]:
        for k, v in p.info.items():
            if isinstance(v, (int, float, str, bool)) or v is None:
                console.print(f"[dim]solver {escape(str(k))}: {escape(str(v))}[/dim]")
        groups: dict[str, list[str]] = {}
        for name in sorted(paths):
            groups.setdefault(name.split("/")[0] + "/" if "/" in name else name, []).append(name)
        for key, names in groups.items():
            where = out_dir / key if key.endswith("/") else paths[key]
            more = f" ({len(names)} files)" if key.endswith("/") else ""
            console.print(f"[dim]wrote {escape(str(where))}{more}[/dim]")
    if _state["json"]:
        typer.echo(json.dumps(_json_summary(result, out_dir, paths), indent=2))
        return
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
    if m.well_triangulated_pct is not None:
        t.add_row("well triangulated", f"{m.well_triangulated_pct:.2f} % (rays meet at a usable angle)")
    for name, r in m.regions.items():
        t.add_row(f"  region {name}", f"{r['targets']} targets, gap {r['coverage_gap']:.4f}, "
                                     f"non-tri {r['non_triangulatable_pct']:.1f} %")
    t.add_row("timings (s)", ", ".join(f"{k} {v:.2f}" for k, v in result.timings_s.items()))
    t.add_row("outputs", str(out_dir))
    if "report.html" in paths:
        t.add_row("report", str(paths["report.html"]))
    Console().print(t)


_WORKERS_OPT = typer.Option(1, "--workers", min=1, help="Local worker processes for visibility (1 = in-process).")
_SCHEDULER_OPT = typer.Option(None, "--scheduler", envvar="CAMPLACE_SCHEDULER",
                              help="Dask scheduler address (tcp://host:port) to run visibility on a cluster.")
_CACHE_OPT = typer.Option(None, "--cache", help="Visibility cache folder (default $CAMPLACE_CACHE or ~/.cache/camplace).")
_NO_CACHE_OPT = typer.Option(False, "--no-cache", help="Neither reuse nor store visibility blocks.")


def _scale_options(workers: int, scheduler: Optional[str], cache: Optional[Path], no_cache: bool) -> dict:
    from camplace.visibility.cache import default_cache_dir

    return {"workers": workers, "scheduler": scheduler or None,
            "cache_dir": None if no_cache else (cache or default_cache_dir())}


def _check_options(budget: Optional[int], time_limit: Optional[float], max_memory_gb: Optional[float],
                   out: Optional[Path]) -> None:
    """CLI options, checked before any work (InputError naming the option)."""
    import math

    from camplace.core.errors import InputError

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
    from camplace.workflows.run import run

    _check_options(budget, time_limit, max_memory_gb, out)
    repeatable = repeatable or os.environ.get("CAMPLACE_REPEATABLE", "") not in ("", "0")
    stop = _StopFlag()
    with stop.installed():  # first Ctrl-C: finish with the best placement so far; second: abort
        with _progress() as prog:
            bars = _RichProgress(prog, stop)
            result = run(scene, budget=budget, solver=solver, progress=bars, on_incumbent=bars.incumbent,
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
    """A solver thread that ignored the interrupt (camplace.workflows.run.solve_stoppable) may
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


_CLOUD_OPT = typer.Option(None, "--cloud", help="Build the scene from this scan alone (PLY, PCD, XYZ/CSV, LAS/LAZ).")
_SAVE_SCENE_OPT = typer.Option(None, "--save-scene", help="With --cloud: also write the scene built from the scan (YAML).")
_UP_OPT = typer.Option("+z", "--up", help="With --cloud: the scan's up axis (+z; phone scans are often +y).")
_NO_LEVEL_OPT = typer.Option(False, "--no-level-floor", help="With --cloud: keep the scan's frame (no RANSAC floor levelling).")
_CROP_OPT = typer.Option(None, "--crop", help="With --cloud: keep points in the box 'xmin,ymin,zmin,xmax,ymax,zmax' (m, levelled frame).")
_DOWNSAMPLE_OPT = typer.Option(0.02, "--downsample", help="With --cloud: voxel downsampling edge (m, 0 = off).")
_HEIGHTS_OPT = typer.Option("0.5,1.0,1.5", "--heights", help="With --cloud: walkable target heights (m, comma-separated).")
_COVERAGE_OPT = typer.Option(2, "--coverage", min=0, help="With --cloud: cameras required per walkable target.")
_WALL_MOUNTS_OPT = typer.Option(None, "--wall-mounts", help="With --cloud: also mount on the walls at this height (m).")
_VIEWPOINT_OPT = typer.Option(None, "--viewpoint", help="With --cloud: a scanner position 'x,y,z' (file frame) for "
                              "free-space carving; repeat for several (default: those the file records).")


@app.command("run")
def run_cmd(scene: Optional[str] = typer.Argument(None, help="Scene YAML file or built-in name (demo, standard-store, store-a, warehouse[:AREA_M2]); or give --cloud."),
            cloud: Optional[Path] = _CLOUD_OPT, save_scene: Optional[Path] = _SAVE_SCENE_OPT, up: str = _UP_OPT,
            no_level_floor: bool = _NO_LEVEL_OPT, crop: Optional[str] = _CROP_OPT,
            downsample: float = _DOWNSAMPLE_OPT, heights: str = _HEIGHTS_OPT, coverage: int = _COVERAGE_OPT,
            wall_mounts: Optional[float] = _WALL_MOUNTS_OPT, viewpoint: Optional[list[str]] = _VIEWPOINT_OPT,
            budget: Optional[int] = typer.Option(None, "--budget", help="Number of cameras N_s (default: the scene's)."),
            solver: Optional[str] = typer.Option(None, "--solver", help="Solver (default: the scene's)."),
            out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default camplace-out/<scene>)."),
            workers: int = _WORKERS_OPT, scheduler: Optional[str] = _SCHEDULER_OPT,
            cache: Optional[Path] = _CACHE_OPT, no_cache: bool = _NO_CACHE_OPT,
            time_limit: Optional[float] = _TIME_LIMIT_OPT, require_feasible: bool = _REQUIRE_FEASIBLE_OPT,
            max_memory_gb: Optional[float] = _MAX_MEMORY_OPT, repeatable: bool = _REPEATABLE_OPT,
            visibility: str = typer.Option("voxel", "--visibility",
                                           help="Visibility mode: voxel (fast, centre test) or pixel (per-pixel rays)."),
            stride: Optional[int] = typer.Option(None, "--stride", help="Pixel mode: one ray per STRIDE x STRIDE pixels."),
            probe: Optional[float] = typer.Option(None, "--probe", help="Pixel mode: part of the voxel a ray must cross "
                                                                         "(1 = any part, the paper's rule; 0 = centre)."),
            local_search: bool = typer.Option(False, "--local-search", help="Greedy: 1-swap local search afterwards."),
            threads: Optional[int] = typer.Option(None, "--threads", min=1, help="Solver threads (MIP solvers)."),
            coverage_gap: Optional[float] = typer.Option(None, "--coverage-gap", min=0.0,
                                                         help="min-cameras: allowed coverage gap ε (paper eq. 8; "
                                                              "default 0 = every Γ met)."),
            refine: bool = typer.Option(False, "--refine", help="Move each camera off the grid (continuous pose search)."),
            refine_time: float = typer.Option(60.0, "--refine-time", help="Seconds for --refine."),
            adaptive: int = typer.Option(0, "--adaptive", help="Rounds of finer candidates around the placement."),
            robust: int = typer.Option(0, "--robust", help="1: best worst case over any single camera failure."),
            money_budget: Optional[float] = typer.Option(None, "--money-budget",
                                                         help="Total camera price limit (default: the scene's)."),
            tri_angle: str = typer.Option("20,160", "--tri-angle",
                                          help="MIN,MAX degrees at which two rays triangulate well."),
            well_triangulated: bool = typer.Option(False, "--well-triangulated",
                                                   help="Greedy that counts a camera toward Γ only where it pairs "
                                                        "with another at a --tri-angle angle."),
            certify: Optional[float] = typer.Option(None, "--certify", help="Spend SECONDS on both sides: tabu search "
                                                    "for the placement, Lagrangian/LP/exact bounds for a proven gap "
                                                    "(solver 'certify').")) -> None:
    """Run the whole pipeline on a scene and write placement.json, metrics.json, visibility.npz.

    Ctrl-C during the solve writes the best placement found so far (status 'interrupted',
    exit code 130); a second Ctrl-C aborts without writing.

    With --cloud SCAN (PLY/PCD/XYZ/CSV/LAS/LAZ) the scene is built from the scan alone:
    floor levelled to z = 0, ceiling and footprint detected, walkable volume targets at
    --heights, a 1 m ceiling grid (and wall mounts with --wall-mounts), the default camera
    (docs/scan-to-mount-list.md); --save-scene writes that scene as YAML to edit."""
    if cloud is not None:
        scene = _scene_from_cloud(scene, cloud, save_scene, up, no_level_floor, crop, downsample, heights,
                                  coverage, wall_mounts, budget, viewpoint)
    elif scene is None:
        raise CamplaceInputErrorProxy("run: give a scene (YAML file or built-in name) or --cloud SCAN")
    if certify is not None:
        if certify <= 0:
            raise CamplaceInputErrorProxy(f"--certify: expected seconds > 0, got {certify}")
        solver, time_limit = "certify", certify
    _run(scene, budget, solver, out, time_limit, require_feasible, max_memory_gb, repeatable,
         **_scale_options(workers, scheduler, cache, no_cache), visibility_mode=visibility, stride=stride, probe=probe,
         **({"local_search": True} if local_search else {}), **({"threads": threads} if threads else {}),
         **({"coverage_gap": coverage_gap} if coverage_gap is not None else {}),
         **_beyond_grid_options(refine, refine_time, adaptive, robust, money_budget, tri_angle),
         **({"well_triangulated": True} if well_triangulated else {}))


def _beyond_grid_options(refine: bool, refine_time: float, adaptive: int, robust: int,
                         money_budget: Optional[float], tri_angle: str) -> dict:
    """run() keyword arguments of the issue-10 options (only those given)."""
    try:
        lo, hi = (float(v) for v in tri_angle.split(","))
    except ValueError:
        raise CamplaceInputErrorProxy(f"--tri-angle: expected MIN,MAX degrees, got '{tri_angle}'") from None
    out: dict = {"triangulation_deg": (lo, hi)}
    if refine:
        out.update(refine=True, refine_time_s=refine_time)
    if adaptive:
        out["adaptive"] = adaptive
    if robust:
        out["robust"] = robust
    if money_budget is not None:
        out["money_budget"] = money_budget
    return out


@app.command()
def bench(scene: str = typer.Argument(..., help="Scene YAML file or built-in name."),
          budgets: str = typer.Option("20,30,40,50,60,80", "--budgets", help="Comma-separated camera budgets N_s."),
          methods: str = typer.Option(",".join(("greedy", "mip", "paper-mip", "zhao", "horster")), "--methods",
                                      help="Comma-separated solvers (greedy+ls = greedy with 1-swap)."),
          time_limit: float = typer.Option(60.0, "--time-limit", help="Time limit per solver run, seconds."),
          threads: Optional[int] = typer.Option(None, "--threads", min=1, help="Solver threads."),
          targets: str = typer.Option("volume", "--targets", help="volume (the paper's walkable grid) or all."),
          certify: Optional[float] = typer.Option(None, "--certify", help="Also run solver 'certify' for SECONDS per "
                                                  "budget: best placement, proven bound and gap."),
          out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default camplace-out/bench-<scene>).")) -> None:
    """The paper's experiments: every method at every budget on the same V; writes bench.csv,
    bench.md (beside the paper's Tables I/II) and bench.png (gap and % non-triangulatable)."""
    from camplace.workflows.bench import parse_budgets, run_bench, write_bench

    _check_options(None, time_limit, None, out)
    budget_list = parse_budgets(budgets)
    method_list = [m.strip() for m in methods.split(",") if m.strip()]
    out_dir = out or Path("camplace-out") / f"bench-{Path(scene).stem}"
    stop = _StopFlag()
    with stop.installed(), _progress() as prog:
        name, info, rows = run_bench(scene, budget_list, method_list, time_limit_s=time_limit, threads=threads,
                                     targets=targets, progress=_RichProgress(prog, stop), should_stop=stop,
                                     on_row=lambda rows: write_bench(out_dir, Path(scene).stem, {}, rows),
                                     certify_s=certify)
    paths = write_bench(out_dir, name, info, rows)
    if _state["json"]:
        from dataclasses import asdict

        typer.echo(json.dumps({"scene": name, "rows": [asdict(r) for r in rows], "out_dir": str(out_dir),
                               "files": {k: str(v) for k, v in paths.items()}}, indent=2, default=str))
    elif not _state["quiet"]:
        typer.echo((out_dir / "bench.md").read_text())
    for p in paths.values():
        console.print(f"wrote {escape(str(p))}", highlight=False)


@app.command("solve")
def solve_cmd(visibility: Path = typer.Argument(..., help="A saved instance: visibility.npz (CSR arrays, gamma, "
                                               "location_ids; weights and geometry optional)."),
              budget: int = typer.Option(..., "--budget", help="Number of cameras N_s."),
              solver: str = typer.Option("greedy", "--solver", help="Solver name."),
              certify: Optional[float] = typer.Option(None, "--certify", help="Solver 'certify' for SECONDS: "
                                                      "placement and proven bound."),
              time_limit: Optional[float] = typer.Option(None, "--time-limit", help="Solver time limit, seconds."),
              threads: Optional[int] = typer.Option(None, "--threads", min=1, help="Solver threads."),
              seed: int = typer.Option(0, "--seed", help="Seed of randomized solvers."),
              out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default "
                                                 "camplace-out/<instance>-solved).")) -> None:
    """Re-solve a saved instance with no geometry; writes placement.json and metrics.json."""
    from camplace.problem.instance import instance_name, solve_instance, write_instance_outputs

    _check_options(budget, time_limit, None, out)
    if certify is not None:
        if certify <= 0:
            raise CamplaceInputErrorProxy(f"--certify: expected seconds > 0, got {certify}")
        solver, time_limit = "certify", certify
    opts = {k: v for k, v in {"time_limit_s": time_limit, "threads": threads}.items() if v is not None}
    stop = _StopFlag()
    with stop.installed(), _progress() as prog:
        bars = _RichProgress(prog, stop)
        problem, placement, metrics, arrays, timings = solve_instance(
            visibility, budget, solver, progress=bars, on_incumbent=bars.incumbent, should_stop=stop, seed=seed,
            **opts)
    name = instance_name(visibility)
    out_dir = out or Path("camplace-out") / f"{name}-solved"
    paths = write_instance_outputs(out_dir, name, problem, placement, metrics, arrays, timings)
    p = placement
    if _state["json"]:
        typer.echo(json.dumps({"instance": str(visibility), "solver": p.solver, "status": p.status,
                               "budget": budget, "cost": p.objective, "bound": p.bound, "gap": p.gap,
                               **{k: p.info[k] for k in ("incumbent_method", "bound_method") if k in p.info},
                               "files": {k: str(v) for k, v in paths.items()}}, indent=2))
    elif _state["quiet"]:
        typer.echo(str(out_dir))
    else:
        t = Table(title=f"camplace solve - {name}", show_header=False)
        t.add_row("solver / status", f"{p.solver} / {p.status}")
        t.add_row("cameras (budget)", f"{len(p.selected)} ({budget})")
        t.add_row("cost", f"{p.objective:.6g}" + (f"  ({p.info['incumbent_method']})" if "incumbent_method" in p.info
                                                 else ""))
        t.add_row("bound", "-" if p.bound is None else f"{p.bound:.6g} (gap {100 * (p.gap or 0):.2f} %)"
                  + (f"  ({p.info['bound_method']})" if "bound_method" in p.info else ""))
        t.add_row("coverage gap (eq. 8)", f"{metrics.coverage_gap:.4f}")
        t.add_row("outputs", str(out_dir))
        Console().print(t)
    if stop():
        raise typer.Exit(130)


@app.command("evaluate")
def evaluate_cmd(scene: str = typer.Argument(..., help="Scene YAML file or built-in name."),
                 placement: Path = typer.Argument(..., help="placement.json, or a mount-list CSV with header "
                                                  "id,x,y,z,yaw,pitch,roll,lens (by camplace, by hand or another tool)."),
                 out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default "
                                                    "camplace-out/<scene>-evaluated)."),
                 workers: int = _WORKERS_OPT, scheduler: Optional[str] = _SCHEDULER_OPT,
                 max_memory_gb: Optional[float] = _MAX_MEMORY_OPT, repeatable: bool = _REPEATABLE_OPT) -> None:
    """Score a given placement on a scene with the same metrics as a run.

    The poses are raycast afresh (they need not be grid candidates) and written as a run
    with solver 'file': placement.json, metrics.json, visibility.npz (row i = pose i),
    placement.csv, report.html, figures and exports."""
    from camplace.workflows.evaluate import evaluate

    _check_options(None, None, max_memory_gb, out)
    repeatable = repeatable or os.environ.get("CAMPLACE_REPEATABLE", "") not in ("", "0")
    with _progress() as prog:
        result = evaluate(scene, placement, progress=_RichProgress(prog), workers=workers, scheduler=scheduler or None,
                          max_memory_bytes=None if max_memory_gb is None else int(max_memory_gb * 1024**3))
    _summary(result, out or Path("camplace-out") / f"{result.scene.name}-evaluated", repeatable)


@app.command("compare-visibility")
def compare_visibility_cmd(
        scene: str = typer.Argument(..., help="Scene YAML file or built-in name."),
        stride: Optional[int] = typer.Option(None, "--stride", help="Pixel mode: one ray per STRIDE x STRIDE pixels "
                                                                    "(default: camplace.visibility.pixel.DEFAULT_STRIDE)."),
        probe: float = typer.Option(0.0, "--probe", help="Pixel mode probe: 0 = target centre in a ray's footprint "
                                                         "(like voxel mode), 1 = any part of the voxel (the paper)."),
        budget: Optional[int] = typer.Option(None, "--budget", help="N_s for the coverage-gap comparison (default: the scene's)."),
        json_out: Optional[Path] = typer.Option(None, "--json", help="Also write the figures to this JSON file.")) -> None:
    """Agreement of voxel and pixel visibility: shared V entries and the effect on the coverage gap."""
    from camplace.workflows.compare import compare_visibility
    from camplace.core.files import atomic_write_json

    with _progress() as prog:
        a = compare_visibility(scene, stride=stride, probe=probe, budget=budget, progress=_RichProgress(prog))
    if json_out is not None:
        atomic_write_json(json_out, a.to_dict())
    t = Table(title=f"voxel vs pixel visibility - {a.scene} (stride {a.stride}, probe {a.probe:g})", show_header=False)
    t.add_row("V entries", f"voxel {a.nnz_voxel}, pixel {a.nnz_pixel}, shared {a.shared}")
    t.add_row("agreement", f"Jaccard {100 * a.jaccard:.2f} %, voxel in pixel {100 * a.voxel_in_pixel:.2f} %, "
                           f"pixel in voxel {100 * a.pixel_in_voxel:.2f} %")
    for name, r in a.regions.items():
        t.add_row(f"  region {name}", f"Jaccard {100 * r['jaccard']:.2f} % ({r['nnz_voxel']} / {r['nnz_pixel']})")
    for solved, row in a.gap.items():
        t.add_row(f"gap, {a.solver} on {solved} V", ", ".join(f"scored on {k}: {v:.4f}" for k, v in row.items()))
    t.add_row("time (s)", f"voxel {a.seconds['voxel']:.2f}, pixel {a.seconds['pixel']:.2f} "
                          f"({a.rays} rays, {a.rays_per_s / 1e6:.2f} M rays/s)")
    Console().print(t)


@app.command()
def render(scene: str = typer.Argument(..., help="Scene YAML file or built-in name."),
           camera: int = typer.Option(..., "--camera", help="Candidate id (row of V), or with --placement the "
                                                            "index of the camera in that file."),
           placement: Optional[Path] = typer.Option(None, "--placement", help="placement.json or mount-list CSV."),
           out: Optional[Path] = typer.Option(None, "--out", help="PNG to write (default camplace-out/<scene>/view-<ID>.png)."),
           width: int = typer.Option(480, "--width", help="Rendered image width in pixels (same field of view).")) -> None:
    """Draw the synthetic image a camera sees (depth-shaded, obstacles coloured, covered targets) and its footprint."""
    from camplace.outputs.render import render_camera

    if width < 2:
        raise CamplaceInputErrorProxy(f"--width: expected at least 2 pixels, got {width}")
    if out is None:
        from camplace.spec.builtin import resolve_scene

        out = Path("camplace-out") / resolve_scene(scene)[0].name / f"view-{camera}.png"
    path, _, info = render_camera(scene, camera, placement, out, width)
    if not _state["quiet"]:
        console.print(f"[dim]{info['camera']} at {info['position']}, covers {info['covered']} targets[/dim]")
    typer.echo(str(path))


def _floats(text: str, option: str, n: int | None = None) -> list[float]:
    try:
        vals = [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise CamplaceInputErrorProxy(f"{option}: expected comma-separated numbers, got '{text}'") from None
    if n is not None and len(vals) != n:
        raise CamplaceInputErrorProxy(f"{option}: expected {n} comma-separated numbers, got '{text}'")
    return vals


def _scene_from_cloud(scene, cloud, save_scene, up, no_level_floor, crop, downsample, heights, coverage,
                      wall_mounts, budget, viewpoint=None):
    from camplace.spec.loading import parse_scene
    from camplace.scene.from_scan import scene_from_cloud

    if scene is not None:
        raise CamplaceInputErrorProxy("run: give either a scene or --cloud, not both")
    if up not in ("+x", "-x", "+y", "-y", "+z", "-z"):
        raise CamplaceInputErrorProxy(f"--up: expected one of +x -x +y -y +z -z, got '{up}'")
    box = _floats(crop, "--crop", 6) if crop else None
    data, rep = scene_from_cloud(
        str(cloud), level_floor=not no_level_floor, up=up, crop=(box[:3], box[3:]) if box else None,
        downsample=downsample or None, heights=_floats(heights, "--heights"), coverage=coverage,
        budget=budget if budget is not None else 20, wall_mount_height=wall_mounts,
        viewpoints=[_floats(v, "--viewpoint", 3) for v in viewpoint or []] or None)
    if not _state["quiet"]:
        console.print(f"[dim]scan: {rep['points']:,} points after clean-up; floor levelled, ceiling "
                      f"{rep['height_m']} m above it, footprint {rep['floor_area_m2']} m² "
                      f"({rep['footprint_vertices']} corners), {rep['viewpoints']} scanner viewpoint(s)[/dim]")
    if save_scene is not None:
        import yaml

        from camplace.core.files import atomic_write_text

        atomic_write_text(save_scene, "# camplace scene built from a scan (camplace run --cloud); edit and rerun\n"
                          + yaml.safe_dump(data, sort_keys=False, default_flow_style=None))
        console.print(f"[dim]wrote {escape(str(save_scene))}[/dim]")
    return parse_scene(data, f"--cloud {cloud}")


@app.command()
def scan(scene: str = typer.Argument(..., help="Built-in scene name or YAML file with box obstacles."),
         out: Path = typer.Option(..., "--out", help="Output: .ply, .pcd, .xyz, .csv, .las or .laz (point cloud); "
                                                     ".obj, .stl, .glb, .off (mesh of the boxes); .bt or .ot (OctoMap)."),
         noise: float = typer.Option(0.01, "--noise", min=0.0, help="Range noise (standard deviation, m)."),
         step: float = typer.Option(0.4, "--step", min=0.05, help="Angular step of the scanner (degrees)."),
         viewpoints: Optional[int] = typer.Option(None, "--viewpoints", min=1,
                                                  help="Scanner positions (default: enough to see 99 % of the floor)."),
         height: float = typer.Option(1.6, "--height", help="Scanner height above the floor (m)."),
         seed: int = typer.Option(0, "--seed", help="Noise seed.")) -> None:
    """Write a synthetic scan of a box scene (rays from a few viewpoints, range noise,
    occlusion), or export the scene as a mesh / OctoMap - test data with no outside files."""
    from camplace.spec.builtin import resolve_scene
    from camplace.scene.loaders.pointcloud import write_point_cloud
    from camplace.scene.build import build_scene
    from camplace.workflows.scan import export_mesh, export_octomap, scan_cli_summary, scan_scene

    spec, base, src = resolve_scene(scene)
    sc = build_scene(spec, base, src)
    suf = out.suffix.lower()
    if suf in (".obj", ".stl", ".glb", ".off"):
        export_mesh(sc, out)
        what = "mesh of the occluding boxes"
    elif suf in (".bt", ".ot"):
        export_octomap(sc, out)
        what = f"OctoMap of the occupancy grid ({sc.occupancy.resolution} m)"
    else:
        cloud = scan_scene(sc, n_viewpoints=viewpoints, height=height, step_deg=step, noise=noise, seed=seed)
        write_point_cloud(out, cloud.points, cloud.viewpoints)
        what = scan_cli_summary(cloud)
    if _state["quiet"]:
        typer.echo(str(out))
    else:
        console.print(f"wrote {escape(str(out))}: {what}")


@app.command()
def essential(folder: Path = typer.Argument(..., help="Output folder of camplace run / evaluate."),
              top: Optional[int] = typer.Option(None, "--top", min=1, help="Show only the TOP most essential cameras.")) -> None:
    """Rank a placement's cameras by the cost added if each one fails (most essential first)."""
    from camplace.solvers.robust import essential_from_folder

    ranking, summary = essential_from_folder(folder)
    shown = ranking[:top] if top else ranking
    if _state["json"]:
        typer.echo(json.dumps({"summary": summary, "cameras": shown}, indent=2))
        return
    t = Table(title=f"essential cameras - cost {summary['cost']:.6g}, worst single failure "
                    f"{summary['worst_case_cost']:.6g}")
    for col in ("rank", "candidate", "camera", "position (m)", "yaw / pitch (deg)", "added cost", "cost if it fails"):
        t.add_column(col)
    for r in shown:
        pos = ", ".join(f"{v:.2f}" for v in r["position"] or [])
        t.add_row(str(r["rank"]), str(r["candidate_id"]), str(r["camera"]), pos,
                  f"{r['yaw_deg']:.1f} / {r['pitch_deg']:.1f}", f"{r['added_cost']:.6g}", f"{r['cost_if_fails']:.6g}")
    Console().print(t)


@app.command()
def scenes(show: Optional[str] = typer.Option(None, "--show", help="Print the YAML of this built-in scene.")) -> None:
    """List the built-in scenes (or print one as a scene-file example)."""
    if show:
        typer.echo(builtin_yaml(show))
        return
    for name in BUILTIN_SCENES:
        typer.echo(name)


def CamplaceInputErrorProxy(msg: str) -> CamplaceError:  # noqa: N802 - reads like a class at call sites
    from camplace.core.errors import InputError

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
        console.print("[bold red]interrupted:[/bold red] stopped (Ctrl-C); no new outputs written")
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
