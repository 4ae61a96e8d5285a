"""``camplace render``: the synthetic image a camera sees, and its footprint."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from camplace.cli.common import console, state
from camplace.core.errors import InputError


def render(scene: str = typer.Argument(..., help="Scene YAML file or built-in name."),
           camera: int = typer.Option(..., "--camera", help="Candidate id (row of V), or with --placement the "
                                                            "index of the camera in that file."),
           placement: Optional[Path] = typer.Option(None, "--placement", help="placement.json or mount-list CSV."),
           out: Optional[Path] = typer.Option(None, "--out", help="PNG to write (default camplace-out/<scene>/view-<ID>.png)."),
           width: int = typer.Option(480, "--width", help="Rendered image width in pixels (same field of view).")) -> None:
    """Draw the synthetic image a camera sees (depth-shaded, obstacles coloured, covered targets) and its footprint."""
    from camplace.workflows.render import render_camera

    if width < 2:
        raise InputError(f"--width: expected at least 2 pixels, got {width}")
    if out is None:
        from camplace.spec.builtin import resolve_scene

        out = Path("camplace-out") / resolve_scene(scene)[0].name / f"view-{camera}.png"
    path, _, info = render_camera(scene, camera, placement, out, width)
    if not state["quiet"]:
        console.print(f"[dim]{info['camera']} at {info['position']}, covers {info['covered']} targets[/dim]")
    typer.echo(str(path))
