"""``camplace solvers``: every solver and visibility engine, built-in or from a plugin, with
its options (types, defaults) and tags."""

from __future__ import annotations

import json

import typer

from camplace.cli.common import state


def _value(v) -> str:
    return "none" if v is None else str(v).lower() if isinstance(v, bool) else repr(v) if isinstance(v, str) else str(v)


def _params(items: list[dict], skip: tuple[str, ...] = ()) -> str:
    return ", ".join(f"{p['name']}: {p['type']} = {_value(p['default'])}" for p in items if p["name"] not in skip)


def solvers() -> None:
    """List the solvers (camplace run --solver NAME --option KEY=VALUE) with their options,
    types, defaults and tags, and the visibility engines (--visibility NAME) with their
    parameters. Plugins (entry points camplace.solvers / camplace.engines) are marked."""
    import warnings

    from camplace.core.plugins import PluginWarning
    from camplace.solvers.contract import COMMON_FIELDS
    from camplace.solvers.registry import SOLVERS, catalogue as solver_catalogue
    from camplace.visibility.registry import ENGINES, catalogue as engine_catalogue

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PluginWarning)  # listed below, once
        sol, eng = solver_catalogue(), engine_catalogue()
    skipped = [{"group": r.group, "name": n, "distribution": d, "reason": why}
               for r in (SOLVERS, ENGINES) for n, d, why in r.problems]
    if state["json"]:
        typer.echo(json.dumps({"solvers": sol, "engines": eng, "skipped": skipped}, indent=2, default=repr))
        return
    typer.echo(f"solvers (camplace run --solver NAME --option KEY=VALUE; every solver also takes "
               f"{', '.join(COMMON_FIELDS)}):")
    for s in sol:
        plugin = "" if s["distribution"] == "camplace" else f"  [plugin: {s['distribution']}]"
        typer.echo(f"  {s['name']}: {s['summary']}{plugin}")
        typer.echo(f"      tags: {', '.join(s['tags']) or '-'}")
        typer.echo(f"      options: {_params(s['options'], COMMON_FIELDS) or '-'}")
    typer.echo("engines (camplace run --visibility NAME):")
    for e in eng:
        plugin = "" if e["distribution"] == "camplace" else f"  [plugin: {e['distribution']}]"
        typer.echo(f"  {e['name']}: {e['summary']}{plugin}")
        typer.echo(f"      parameters: {_params(e['parameters']) or '-'}")
    for k in skipped:
        typer.echo(f"skipped: {k['group']} plugin '{k['name']}' from {k['distribution']}: {k['reason']}")
