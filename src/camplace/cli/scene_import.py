"""``camplace scene import FILE --out scene.yaml``: the editable scene of a space file
(scan, mesh or OctoMap), with the options of building it."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer
from rich.markup import escape

from camplace.cli.building import ELEVATIONS_OPT, STOREY_BUDGET_OPT, is_building, storey_budgets
from camplace.cli.common import console, state
from camplace.cli.plan_preview import json_part, preview_of, write_files
from camplace.cli.space import (PLAN_FORMATS, CEILING_OPT, REF_OPT, SCALE_OPT, STOREY_OPT, UNITS_OPT, WALL_HEIGHT_OPT,
                                 DOORS_OPT, GLASS_OPT, LAYER_HEIGHT_OPT, MAX_OPENING_OPT, MIN_ROOM_OPT, NO_OCR_OPT,
                                 PAGE_OPT,
                                 THRESHOLD_OPT, WALL_CLASSES_OPT, WALL_LAYERS_OPT,
                                 ImportOptions, describe_import, scene_data_from_file, scene_yaml)
from camplace.core.errors import InputError

scene_app = typer.Typer(add_completion=False, no_args_is_help=True, help="Scenes from space files.")


@scene_app.command("import")
def import_cmd(files: list[Path] = typer.Argument(..., help="A scan (PLY, PCD, XYZ/CSV, LAS/LAZ), a mesh (OBJ, PLY "
                                                  "with faces, STL, GLB), an OctoMap (.bt/.ot) or a plan: "
                                                  + PLAN_FORMATS + "; several plan files with --elevations: one "
                                                  "building."),
               out: Path = typer.Option(..., "--out", help="Scene YAML to write (atomically)."),
               up: str = typer.Option("+z", "--up", help="The file's up axis (+z; phone scans are often +y)."),
               no_level_floor: bool = typer.Option(False, "--no-level-floor",
                                                   help="Keep the file's frame (no RANSAC floor levelling)."),
               crop: Optional[str] = typer.Option(None, "--crop", help="Keep points in the box "
                                                  "'xmin,ymin,zmin,xmax,ymax,zmax' (m, levelled frame)."),
               downsample: float = typer.Option(0.02, "--downsample", help="Voxel downsampling edge (m, 0 = off)."),
               heights: str = typer.Option("0.5,1.0,1.5", "--heights",
                                           help="Walkable target heights (m, comma-separated)."),
               coverage: int = typer.Option(2, "--coverage", min=0, help="Cameras required per walkable target."),
               wall_mounts: Optional[float] = typer.Option(None, "--wall-mounts",
                                                           help="Also mount on the walls at this height (m)."),
               viewpoint: Optional[list[str]] = typer.Option(None, "--viewpoint", help="A scanner position 'x,y,z' "
                                                             "(file frame) for free-space carving; repeat for "
                                                             "several (PLY/PCD scans may record their own)."),
               budget: Optional[int] = typer.Option(None, "--budget", min=0,
                                                    help="placement.budget of the scene (default 20)."),
               units: Optional[str] = UNITS_OPT, wall_height: Optional[float] = WALL_HEIGHT_OPT,
               ceiling_height: Optional[float] = CEILING_OPT, scale: Optional[str] = SCALE_OPT,
               ref: Optional[str] = REF_OPT, storey: Optional[str] = STOREY_OPT,
               wall_layers: Optional[str] = WALL_LAYERS_OPT, wall_classes: Optional[str] = WALL_CLASSES_OPT,
               layer_height: Optional[list[str]] = LAYER_HEIGHT_OPT,
               doors: Optional[str] = DOORS_OPT, glass: Optional[str] = GLASS_OPT,
               threshold: Optional[float] = THRESHOLD_OPT, max_opening: Optional[float] = MAX_OPENING_OPT,
               min_room_area: Optional[float] = MIN_ROOM_OPT, no_ocr: bool = NO_OCR_OPT,
               page: Optional[int] = PAGE_OPT, elevations: Optional[str] = ELEVATIONS_OPT,
               storey_budget: Optional[list[str]] = STOREY_BUDGET_OPT) -> None:
    """Write the scene built from a space file as YAML to edit, then camplace run it.

    The floor is levelled to z = 0, ceiling and footprint detected, walkable volume
    targets placed at --heights, a 1 m ceiling grid (and wall mounts with --wall-mounts)
    and the default camera added (docs/scan-to-mount-list.md)."""
    from camplace.core.files import atomic_write_text

    if out.exists() and out.is_dir():
        raise InputError(f"--out: '{out}' is a folder; expected a scene file (.yaml)")
    if out.suffix.lower() not in (".yaml", ".yml"):
        raise InputError(f"--out: expected a .yaml scene file, got '{out}'")
    opts = ImportOptions(up=up, level_floor=not no_level_floor, crop=crop, downsample=downsample, heights=heights,
                         coverage=coverage, wall_mounts=wall_mounts, viewpoint=list(viewpoint or []), units=units,
                         wall_height=wall_height, ceiling_height=ceiling_height, scale=scale, ref=ref, storey=storey,
                         wall_layers=wall_layers, wall_classes=wall_classes, layer_height=layer_height, doors=doors,
                         glass=glass, threshold=threshold, max_opening=max_opening, min_room_area=min_room_area,
                         no_ocr=no_ocr, page=page)
    budgets = storey_budgets(storey_budget)
    if is_building([str(f) for f in files], storey):
        _write_building(files, opts, budget, out, elevations, budgets)
        return
    if budgets or elevations is not None:
        raise InputError(f"{'--storey-budget' if budgets else '--elevations'}: belongs to buildings "
                         f"(--storey all, --storey A,B or several plan files)")
    file = files[0]
    data, rep, _ = scene_data_from_file(file, opts, budget)
    preview = preview_of(rep, file.name)  # rendered before anything is written
    if preview is None and not state["quiet"]:
        console.print(f"[dim]{escape(describe_import(rep))}[/dim]")
    atomic_write_text(out, scene_yaml(data, f"camplace scene import {file.name}"))
    pictures = write_files(preview, preview_base(out)) if preview is not None else []
    if state["json"]:
        typer.echo(json.dumps({"scene": str(out), **(json_part(preview, pictures) if preview else {})}, indent=2))
    elif state["quiet"]:
        typer.echo(str(out))
    else:
        console.print(f"wrote {escape(str(out))}: edit it, then camplace run {escape(str(out))}")
        if pictures:
            console.print(f"wrote {escape(str(pictures[0]))} (and .svg): what was understood; look at it first")


def preview_base(out: Path) -> Path:
    """site.yaml -> site.preview (the preview's .png / .svg beside the scene file)."""
    return out.with_name(f"{out.stem}.preview")


def _write_building(files: list[Path], opts: ImportOptions, budget: Optional[int], out: Path,
                    elevations: Optional[str], budgets: dict[str, int]) -> None:
    """scene import of a building (--storey all / A,B, several files): one scene file with
    ``storeys:`` at --out and a preview per storey beside it (OUT.<slug>.preview.png/.svg);
    everything imported and checked before anything is written."""
    from camplace.cli.building import building_spec
    from camplace.core.files import atomic_write_text
    from camplace.workflows.storeys import storey_slugs

    _, imports, data = building_spec([str(f) for f in files], opts, budget, elevations, budgets)
    names = [n for n, _ in imports]
    where = files[0].name if len(files) == 1 else ", ".join(f.name for f in files)
    previews = [preview_of({"plan": got}, f"{where}, storey '{n}'") for n, got in imports]
    atomic_write_text(out, scene_yaml(data, f"camplace scene import {where}: a building of {len(names)} storeys"))
    docs = []
    for (name, _), slug, preview in zip(imports, storey_slugs(names), previews):
        base = out.with_name(f"{out.stem}.{slug}.preview")
        docs.append({"storey": name, "elevation_m": data["storeys"][name]["elevation"],
                     **json_part(preview, write_files(preview, base))})
    if state["json"]:
        typer.echo(json.dumps({"scene": str(out), "storeys": docs}, indent=2))
    elif state["quiet"]:
        typer.echo(str(out))
    else:
        for d in docs:
            console.print(f"storey '{escape(d['storey'])}': floor at {d['elevation_m']:g} m, "
                          f"{len(data['storeys'][d['storey']]['zones'])} rooms")
        console.print(f"wrote {escape(str(out))} (a building: storeys {escape(', '.join(names))}) and a preview per "
                      f"storey beside it: edit it, then camplace run {escape(str(out))}")
