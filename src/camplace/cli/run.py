"""``camplace run``: the whole pipeline on a scene file, a
built-in name or a space file (scan, mesh, OctoMap), then the outputs and a summary."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Optional

import typer
from rich.markup import escape

from camplace.cli import crowd
from camplace.cli.building import ELEVATIONS_OPT, STOREY_BUDGET_OPT, is_building, storey_budgets
from camplace.cli.common import (CACHE_OPT, FRAME_OPT, MAX_MEMORY_OPT, NO_CACHE_OPT, NO_PLAN_OPT, OPTION_OPT,
                                 PAPER_OPT, REPEATABLE_OPT, SCHEDULER_OPT, SEED_OPT, solver_option_values,
                                 TIME_LIMIT_OPT, WORKERS_OPT, RichProgress, StopFlag, certify_solver, check_options,
                                 console, memory_bytes, progress_bars, repeatable_requested, scale_options, state)
from camplace.cli.space import (PLAN_FORMATS, CEILING_OPT, REF_OPT, SCALE_OPT, STOREY_OPT, UNITS_OPT, WALL_HEIGHT_OPT,
                                 DOORS_OPT, GLASS_OPT, LAYER_HEIGHT_OPT, MAX_OPENING_OPT, MIN_ROOM_OPT, NO_OCR_OPT,
                                 PAGE_OPT,
                                 THRESHOLD_OPT, WALL_CLASSES_OPT, WALL_LAYERS_OPT,
                                 ImportOptions, describe_import, plan_import_options, scene_data_from_file, scene_yaml,
                                 space_kind)
from camplace.cli.plan_preview import preview_of, run_extra
from camplace.cli.summary import write_and_summarise
from camplace.core.errors import InputError


def run_pipeline(scene, budget: Optional[int], solver: Optional[str], out: Optional[Path],
                 time_limit: Optional[float] = None, require_feasible: bool = False,
                 max_memory_gb: Optional[float] = None, repeatable: bool = False, frame: str = "scene",
                 plan: bool = True, paper: str = "A3", preview=None, leave: bool = True, source: dict | None = None,
                 **options) -> None:
    """camplace.workflows.run.run with progress bars and Ctrl-C handling; writes the outputs
    into ``out`` (default camplace-out/<scene>, poses in ``frame``; a plan's ``preview``
    as preview.png / preview.svg) and prints the summary. Interrupted: exit 130 at once
    (``leave``; else typer.Exit(130))."""
    from camplace.workflows import warm

    check_options(budget, time_limit, max_memory_gb, out)
    warming = warm.start(solver)  # a fresh install: the later stages' kernels compile beside visibility's
    try:  # started before the heavy imports below: it compiles the visibility kernel's callees first
        from camplace.outputs.plan_data import check_paper
        from camplace.outputs.write import check_frame
        from camplace.workflows.run import run

        check_frame(frame)
        paper = check_paper(paper)
        repeatable = repeatable_requested(repeatable)
    except BaseException:
        warm.stop(warming)
        raise
    stop = StopFlag()
    with stop.installed():  # first Ctrl-C: finish with the best placement so far; second: abort
        try:
            with progress_bars() as prog:
                bars = RichProgress(prog, stop)
                result = run(scene, budget=budget, solver=solver, progress=bars, on_incumbent=bars.incumbent,
                             time_limit_s=time_limit, should_stop=stop, require_feasible=require_feasible,
                             max_memory_bytes=memory_bytes(max_memory_gb), **options)
        finally:
            warm.stop(warming)
        out_dir = out or Path("camplace-out") / result.scene.name
        if source:  # an IFC input: cameras.ifc is a copy of it with the cameras (camplace.outputs.cameras_ifc)
            result.scene.info["source"] = {k: v for k, v in source.items() if k != "building"}
        if source and source.get("building"):  # the building as a scene file: edit it, run it, reopen the run
            from camplace.core.files import atomic_write_text

            out_dir.mkdir(parents=True, exist_ok=True)
            atomic_write_text(out_dir / "building.yaml", scene_yaml(source["building"], "camplace run: the building "
                                                                                       "this run planned"))
        write_and_summarise(result, out_dir, repeatable, frame, plan, paper, extra=run_extra(preview, out_dir),
                            stop=stop)
    if stop():
        took = "" if stop.first_at is None else f" {time.perf_counter() - stop.first_at:.1f} s after the Ctrl-C"
        console.print(f"[yellow]interrupted: wrote the best placement found so far (status "
                      f"'{result.placement.status}') to {escape(str(out_dir))}{took}[/yellow]")
        if leave:
            _leave(130)
        raise typer.Exit(130)


def _leave(code: int) -> None:
    """Exit with ``code`` at once after an interrupt: the outputs are written (atomically,
    fsynced), and a solver thread that ignored the interrupt (camplace.workflows.run.solve_stoppable)
    may still run native code, under which interpreter shutdown can abort the process; a
    normal shutdown would also spend seconds tearing down what the run built."""
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def scene_from_space_file(path: Path, budget: Optional[int], save_scene: Optional[Path] = None,
                          opts: ImportOptions = ImportOptions()):
    """(parsed scene, plan preview or None) from a space file with the import defaults
    (``save_scene``: also write it as YAML, for the deprecated ``run --cloud FILE --save-scene``)."""
    from camplace.core.files import atomic_write_text
    from camplace.spec.loading import parse_scene

    data, rep, _ = scene_data_from_file(path, opts, budget)
    preview = preview_of(rep, path.name)  # a plan: the import summary printed, the picture for the run folder
    if preview is None and not state["quiet"]:
        console.print(f"[dim]{escape(describe_import(rep))}[/dim]")
    if save_scene is not None:
        atomic_write_text(save_scene, scene_yaml(data, "camplace run --cloud"))
        console.print(f"[dim]wrote {escape(str(save_scene))}[/dim]")
    return parse_scene(data, str(path)), preview


REFINE_OPT = typer.Option(None, "--refine/--grid-only",
                          help="Refine the grid solution off the grid, within the mount rules (default; not with "
                               "--robust, --certify or --well-triangulated), or --grid-only: the paper's pure grid "
                               "method.")


def refine_default(refine: Optional[bool], *, robust: int = 0, certify: Optional[float] = None,
                   well_triangulated: bool = False) -> bool | str:
    """--refine/--grid-only as given, else "auto" (refine below site scale: run()'s
    ``refine``) unless the run optimises something the refinement does not keep (robust
    worst case, a certified grid bound, triangulation)."""
    if refine is not None:
        return refine
    return False if (robust or certify is not None or well_triangulated) else "auto"


def beyond_grid_options(refine: bool | str, refine_time: float, adaptive: int, robust: int,
                        money_budget: Optional[float], tri_angle: str) -> dict:
    """run() keyword arguments of the options beyond the candidate grid (only those given)."""
    try:
        lo, hi = (float(v) for v in tri_angle.split(","))
    except ValueError:
        raise InputError(f"--tri-angle: expected MIN,MAX degrees, got '{tri_angle}'") from None
    if robust and (refine is True or adaptive):
        raise InputError("--robust 1 cannot be combined with --refine / --adaptive (they optimise the nominal cost)")
    out: dict = {"triangulation_deg": (lo, hi)}
    if refine:
        out.update(refine=refine, refine_time_s=refine_time)
    if adaptive:
        out["adaptive"] = adaptive
    if robust:
        out["robust"] = robust
    if money_budget is not None:
        out["money_budget"] = money_budget
    return out


def run_cmd(scene: Optional[list[str]] = typer.Argument(None, help="Scene YAML file, built-in name (demo, standard-store, "
                                                  "store-a, warehouse[:AREA_M2]) or a space file: a scan (PLY, PCD, "
                                                  "XYZ/CSV, LAS/LAZ), a mesh (OBJ, PLY with faces, STL, GLB), an "
                                                  "OctoMap (.bt/.ot) or a plan: " + PLAN_FORMATS + "; several plan files "
                                                  "with --elevations: one building."),
            budget: Optional[int] = typer.Option(None, "--budget", help="Number of cameras N_s (default: the scene's)."),
            solver: Optional[str] = typer.Option(None, "--solver", help="Solver (default: the scene's); "
                                                 "camplace solvers lists them with their options."),
            out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default camplace-out/<scene>)."),
            workers: int = WORKERS_OPT, scheduler: Optional[str] = SCHEDULER_OPT,
            cache: Optional[Path] = CACHE_OPT, no_cache: bool = NO_CACHE_OPT,
            time_limit: Optional[float] = TIME_LIMIT_OPT,
            require_feasible: bool = typer.Option(False, "--require-feasible", help="Fail (exit 2) when some targets "
                                                  "cannot reach their coverage (default: a warning that names them)."),
            max_memory_gb: Optional[float] = MAX_MEMORY_OPT, repeatable: bool = REPEATABLE_OPT,
            frame: str = FRAME_OPT, no_plan: bool = NO_PLAN_OPT, paper: str = PAPER_OPT,
            visibility: str = typer.Option("voxel", "--visibility",
                                           help="Visibility mode: voxel (fast, sight lines to targets) or pixel "
                                                "(per-pixel rays)."),
            stride: Optional[int] = typer.Option(None, "--stride", help="Pixel mode: one ray per STRIDE x STRIDE pixels."),
            probe: Optional[float] = typer.Option(None, "--probe", help="Part of a target's voxel a sight line must "
                                                  "reach, 0..1 (1 = any part, the paper's rule; 0 = centre); default 0 "
                                                  "in voxel mode, 1 in pixel mode."),
            local_search: bool = typer.Option(False, "--local-search", help="Greedy: 1-swap local search afterwards."),
            threads: Optional[int] = typer.Option(None, "--threads", min=1, help="Solver threads (MIP solvers)."),
            coverage_gap: Optional[float] = typer.Option(None, "--coverage-gap", min=0.0,
                                                         help="min-cameras: allowed coverage gap ε (paper eq. 8; "
                                                              "default 0 = every Γ met)."),
            refine: Optional[bool] = REFINE_OPT,
            refine_time: float = typer.Option(60.0, "--refine-time", help="Seconds for the refinement."),
            adaptive: int = typer.Option(0, "--adaptive", help="Rounds of finer candidates around the placement."),
            robust: int = typer.Option(0, "--robust", help="1: best worst case over any single camera failure."),
            quality: Optional[str] = typer.Option(None, "--quality",
                                                  help="high: the best placement the whole run reaches in "
                                                       "--quality-time seconds (a 2x denser grid, refinement and "
                                                       "relocation chained; docs/beyond-the-grid.md); default: the scene's "
                                                       "placement.quality, else default."),
            quality_time: Optional[float] = typer.Option(None, "--quality-time",
                                                         help="--quality high: seconds for the whole run "
                                                              "(default 30)."),
            money_budget: Optional[float] = typer.Option(None, "--money-budget",
                                                         help="Total camera price limit (default: the scene's)."),
            tri_angle: str = typer.Option("20,160", "--tri-angle",
                                          help="MIN,MAX degrees at which two rays triangulate well."),
            well_triangulated: bool = typer.Option(False, "--well-triangulated",
                                                   help="Greedy that counts a camera toward Γ only where it pairs "
                                                        "with another at a --tri-angle angle."),
            keep: Optional[Path] = typer.Option(None, "--keep", help="A previous run's placement.json or .csv: its "
                                                "cameras stay (fixed, counted toward coverage, not budget) and "
                                                "--budget more are added (extend a plan in phases)."),
            certify: Optional[float] = typer.Option(None, "--certify", help="Spend SECONDS on both sides: tabu search "
                                                    "for the placement, Lagrangian/LP/exact bounds for a proven gap "
                                                    "(solver 'certify')."),
            option: Optional[list[str]] = OPTION_OPT, seed: Optional[int] = SEED_OPT,
            units: Optional[str] = UNITS_OPT, wall_height: Optional[float] = WALL_HEIGHT_OPT,
            ceiling_height: Optional[float] = CEILING_OPT, scale: Optional[str] = SCALE_OPT,
            ref: Optional[str] = REF_OPT, storey: Optional[str] = STOREY_OPT,
            wall_layers: Optional[str] = WALL_LAYERS_OPT, wall_classes: Optional[str] = WALL_CLASSES_OPT,
            layer_height: Optional[list[str]] = LAYER_HEIGHT_OPT,
            doors: Optional[str] = DOORS_OPT, glass: Optional[str] = GLASS_OPT,
            threshold: Optional[float] = THRESHOLD_OPT, max_opening: Optional[float] = MAX_OPENING_OPT,
            min_room_area: Optional[float] = MIN_ROOM_OPT, no_ocr: bool = NO_OCR_OPT,
            page: Optional[int] = PAGE_OPT, elevations: Optional[str] = ELEVATIONS_OPT,
            storey_budget: Optional[list[str]] = STOREY_BUDGET_OPT,
            crowd_density: Optional[float] = crowd.DENSITY_OPT, crowd_samples: Optional[int] = crowd.SAMPLES_OPT,
            crowd_score_samples: Optional[int] = crowd.SCORE_SAMPLES_OPT, crowd_seed: Optional[int] = crowd.SEED_OPT,
            crowd_aware: bool = crowd.AWARE_OPT,
            cloud: Optional[Path] = typer.Option(None, "--cloud", hidden=True,
                                                 help="Deprecated: give the scan as SCENE (camplace run SCAN)."),
            save_scene: Optional[Path] = typer.Option(None, "--save-scene", hidden=True,
                                                      help="Deprecated: use camplace scene import SCAN --out FILE.")
            ) -> None:
    """Run the whole pipeline on a scene and write placement.json, metrics.json, visibility.npz.

    Ctrl-C during the solve writes the best placement found so far (status 'interrupted',
    exit code 130); a second Ctrl-C aborts without writing.

    A space file (scan, mesh or OctoMap) is turned into a scene with the defaults of
    camplace scene import: floor levelled to z = 0, ceiling and footprint detected,
    walkable volume targets, a 1 m ceiling grid, the default camera
    (docs/scan-to-mount-list.md). To adjust those, write the scene with
    camplace scene import FILE --out scene.yaml, edit it and run that. A plan (IFC,
    DXF, plan image or a plugin's format) gives walls as obstacles and rooms as zones (docs/plans.md)."""
    files = list(scene or [])
    building = is_building(files, storey)
    if len(files) > 1 and not building:
        raise InputError(f"run: {len(files)} scenes given; several plan files make one building with --elevations")
    scene = files[0] if len(files) == 1 else None
    if cloud is not None:
        if scene is not None:
            raise InputError("run: give either a scene or --cloud, not both")
        console.print("[yellow]warning: --cloud is deprecated; give the scan as the scene (camplace run SCAN) and "
                      "write the scene with camplace scene import[/yellow]")
        scene, _ = scene_from_space_file(cloud, budget, save_scene)
    elif scene is None and not building:
        raise InputError("run: give a scene (YAML file, built-in name or space file)")
    elif save_scene is not None:
        raise InputError("--save-scene: use camplace scene import FILE --out SCENE.yaml")
    plan = plan_import_options("plan" if building else space_kind(scene) if isinstance(scene, str) else None,
                               units=units,
                               wall_height=wall_height, ceiling_height=ceiling_height, scale=scale, ref=ref,
                               storey=storey, wall_layers=wall_layers, wall_classes=wall_classes,
                               layer_height=layer_height, doors=doors,
                               glass=glass, threshold=threshold, max_opening=max_opening, min_room_area=min_room_area,
                               no_ocr=no_ocr, page=page)
    preview = source = None
    budgets = storey_budgets(storey_budget)
    if building:  # every storey (or those named) of a plan, or one storey per file: one building scene
        from camplace.cli.building import building_spec

        scene, imports, building_data = building_spec(files, plan, budget, elevations, budgets)
        for name, got in imports:
            preview_of({"plan": got}, f"{Path(files[0]).name if len(files) == 1 else name}, storey '{name}'")
        source = dict(_ifc_source(files) or {}, building=building_data)
    else:
        if budgets or elevations is not None:
            raise InputError(f"{'--storey-budget' if budgets else '--elevations'}: belongs to buildings "
                             f"(--storey all, --storey A,B or several plan files)")
        if isinstance(scene, str) and space_kind(scene) is not None:
            scene, preview = scene_from_space_file(Path(scene), budget, opts=plan)
            source = _ifc_source(files, preview)
    refine = refine_default(refine, robust=robust, certify=certify, well_triangulated=well_triangulated)
    solver, time_limit = certify_solver(certify, solver, time_limit)
    run_pipeline(scene, budget, solver, out, time_limit, require_feasible, max_memory_gb, repeatable, frame,
                 not no_plan, paper, **scale_options(workers, scheduler, cache, no_cache), visibility_mode=visibility,
                 stride=stride,
                 probe=probe, **({"local_search": True} if local_search else {}),
                 **({"threads": threads} if threads else {}),
                 **({"coverage_gap": coverage_gap} if coverage_gap is not None else {}),
                 **beyond_grid_options(refine, refine_time, adaptive, robust, money_budget, tri_angle),
                 **({"quality": quality} if quality is not None else {}),
                 **({"quality_time_s": quality_time} if quality_time is not None else {}),
                 **({"well_triangulated": True} if well_triangulated else {}),
                 **({"keep": keep} if keep is not None else {}), preview=preview,
                 **({"crowd": c} if (c := crowd.crowd_overrides(crowd_density, crowd_samples, crowd_score_samples,
                                                                crowd_seed, crowd_aware)) else {}),
                 options=solver_option_values(option, seed), source=source)


def _ifc_source(files: list[str], preview=None) -> dict | None:
    """What cameras.ifc needs of an IFC input: {"file": path, "storey": {name, elevation_m}
    of a single-storey run} (None for other inputs)."""
    if len(files) != 1 or Path(files[0]).suffix.lower() not in (".ifc", ".ifczip"):
        return None
    out: dict = {"file": str(Path(files[0]).resolve())}
    for st in (getattr(preview, "summary", None) or {}).get("storeys") or []:
        if st.get("chosen"):
            out["storey"] = {"name": st["name"], "elevation_m": float(st.get("elevation_m") or 0.0)}
    return out


