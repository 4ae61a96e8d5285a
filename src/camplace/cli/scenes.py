"""``camplace scenes``: the built-in scenes (or one of them as a scene-file example)."""

from __future__ import annotations

from typing import Optional

import typer

from camplace.spec.builtin import BUILTIN_SCENES, builtin_yaml


def scenes(show: Optional[str] = typer.Option(None, "--show", help="Print the YAML of this built-in scene.")) -> None:
    """List the built-in scenes (or print one as a scene-file example)."""
    if show:
        typer.echo(builtin_yaml(show))
        return
    for name in BUILTIN_SCENES:
        typer.echo(name)
