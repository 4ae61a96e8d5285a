"""``camplace evaluate``: score a given placement on a scene with the metrics of a run."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from camplace.cli import crowd
from camplace.cli.common import (MAX_MEMORY_OPT, NO_PLAN_OPT, PAPER_OPT, REPEATABLE_OPT, SCHEDULER_OPT,
                                 WORKERS_OPT, RichProgress, check_options, memory_bytes, progress_bars, repeatable_requested)
from camplace.cli.space import ImportOptions, scene_data_from_file, space_kind
from camplace.cli.summary import write_and_summarise


def evaluate_cmd(scene: str = typer.Argument(..., help="Scene YAML file, built-in name or a space file (scan, "
                                             "mesh, OctoMap or plan, read with the defaults of camplace run)."),
                 placement: Path = typer.Argument(..., help="placement.json, or a mount-list CSV with header "
                                                  "id,x,y,z,yaw,pitch,roll,lens (by camplace, by hand or another tool)."),
                 out: Optional[Path] = typer.Option(None, "--out", help="Output folder (default "
                                                    "camplace-out/<scene>-evaluated)."),
                 workers: int = WORKERS_OPT, scheduler: Optional[str] = SCHEDULER_OPT,
                 max_memory_gb: Optional[float] = MAX_MEMORY_OPT, repeatable: bool = REPEATABLE_OPT,
                 frame: str = typer.Option("scene", "--frame", help="Frame of the placement's poses and of the "
                                           "written ones: scene (levelled, z up) or input (the scene's scanned / "
                                           "meshed file's own frame)."),
                 no_plan: bool = NO_PLAN_OPT, paper: str = PAPER_OPT,
                 crowd_density: Optional[float] = crowd.DENSITY_OPT,
                 crowd_score_samples: Optional[int] = crowd.SCORE_SAMPLES_OPT,
                 crowd_seed: Optional[int] = crowd.SEED_OPT,
                 strict: bool = typer.Option(False, "--strict", help="Exit 1 when a camera sees a privacy zone "
                                             "(the outputs are written and the cameras named either way).")) -> None:
    """Score a given placement on a scene with the same metrics as a run.

    The poses are raycast afresh (they need not be grid candidates) and written as a run
    with solver 'file': placement.json, metrics.json, visibility.npz (row i = pose i),
    placement.csv, report.html, figures and exports. With --frame input the placement's
    poses are in the input file's frame (mapped into the scene before raycasting) and the
    written poses are too. Cameras that see a privacy zone of the scene are named
    (metrics.json ``privacy``); with --strict they make the exit code 1. A scene with a
    crowd (or --crowd-density) adds the placement's metrics in held-out crowds."""
    from camplace.workflows.evaluate import evaluate

    from camplace.outputs.plan_data import check_paper

    check_options(None, None, max_memory_gb, out)
    paper = check_paper(paper)
    repeatable = repeatable_requested(repeatable)
    if space_kind(scene) is not None:  # a scan, mesh, OctoMap or plan: the scene camplace run FILE makes of it
        from camplace.spec.loading import parse_scene

        scene = parse_scene(scene_data_from_file(Path(scene), ImportOptions(), None)[0], scene)
    with progress_bars() as prog:
        result = evaluate(scene, placement, progress=RichProgress(prog), workers=workers, scheduler=scheduler or None,
                          max_memory_bytes=memory_bytes(max_memory_gb), frame=frame,
                          crowd=crowd.crowd_overrides(crowd_density, score_samples=crowd_score_samples, seed=crowd_seed))
    write_and_summarise(result, out or Path("camplace-out") / f"{result.scene.name}-evaluated", repeatable, frame,
                        not no_plan, paper)
    privacy = result.metrics.privacy or {}
    if strict and privacy.get("violations"):
        from camplace.cli.common import console

        console.print(f"[red]privacy: {privacy['violations']} camera(s) see a privacy zone "
                      f"({', '.join(privacy['camera_ids'])}); --strict[/red]")
        raise typer.Exit(1)
