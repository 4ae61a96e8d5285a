"""``camplace essential``: rank a placement's cameras by the cost their failure adds."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer
from rich.console import Console
from rich.table import Table

from camplace.cli.common import state


def _table(shown: list[dict], summary: dict) -> Table:
    t = Table(title=f"essential cameras - cost {summary['cost']:.6g}, worst single failure "
                    f"{summary['worst_case_cost']:.6g}")
    for col in ("rank", "candidate", "camera", "position (m)", "yaw / pitch (deg)", "added cost", "cost if it fails"):
        t.add_column(col)
    for r in shown:
        pos = ", ".join(f"{v:.2f}" for v in r["position"] or [])
        t.add_row(str(r["rank"]), str(r["candidate_id"]), str(r["camera"]), pos,
                  f"{r['yaw_deg']:.1f} / {r['pitch_deg']:.1f}", f"{r['added_cost']:.6g}", f"{r['cost_if_fails']:.6g}")
    return t


def essential(folder: Path = typer.Argument(..., help="Output folder of camplace run / evaluate."),
              top: Optional[int] = typer.Option(None, "--top", min=1, help="Show only the TOP most essential cameras.")) -> None:
    """Rank a placement's cameras by the cost added if each one fails (most essential first)."""
    from camplace.workflows.essential import essential_from_folder

    ranking, summary = essential_from_folder(folder)
    shown = ranking[:top] if top else ranking
    if state["json"]:
        typer.echo(json.dumps({"summary": summary, "cameras": shown}, indent=2))
        return
    Console().print(_table(shown, summary))
