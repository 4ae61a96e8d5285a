"""See before you run (issue 25): the import summary of a plan printed as tables (rooms,
what the importer used and skipped, its notes, an IFC file's storeys) and the preview
picture (camplace.outputs.plan_preview) rendered, for ``scene import`` and ``run``."""

from __future__ import annotations

from pathlib import Path

from rich.markup import escape
from rich.table import Table

from camplace.cli.common import console, state, word_options

ROOM_COLUMNS_FROM = 16  # more rooms than this: the rooms table in three column pairs


def rooms_table(rooms: list[dict]) -> Table:
    """Rooms (name, area m²), in one column pair or three when there are many."""
    pairs = 3 if len(rooms) > ROOM_COLUMNS_FROM else 1
    t = Table(caption=f"{len(rooms)} rooms, {sum(r['area_m2'] for r in rooms):.1f} m\u00b2", caption_justify="left")
    for _ in range(pairs):
        t.add_column("room")
        t.add_column("m\u00b2", justify="right")
    rows = -(-len(rooms) // pairs)
    for r in range(rows):
        cells: list[str] = []
        for k in range(pairs):
            i = k * rows + r
            cells += [escape(rooms[i]["name"]), f"{rooms[i]['area_m2']:.1f}"] if i < len(rooms) else ["", ""]
        t.add_row(*cells)
    return t


def storeys_table(storeys: list[dict]) -> Table:
    """An IFC file's storeys: name, elevation, rooms, which one this scene is."""
    t = Table(caption="choose with --storey NAME, or --storey all", caption_justify="left")
    for col, just in (("storey", "left"), ("elevation m", "right"), ("rooms", "right"), ("room names", "left"),
                      ("", "left")):
        t.add_column(col, justify=just)  # type: ignore[arg-type]
    for s in storeys:
        rooms = s.get("rooms") or []
        names = ", ".join(str(r[0]) for r in rooms[:6]) + (f", ... {len(rooms) - 6} more" if len(rooms) > 6 else "")
        t.add_row(escape(str(s.get("name"))), f"{float(s.get('elevation_m') or 0):.2f}", str(len(rooms)),
                  escape(names), "chosen" if s.get("chosen") else "")
    return t


def show_summary(summary: dict, title: str) -> None:
    """Print the import summary (rich, on stderr) unless --quiet or --json (then it is
    part of the JSON document)."""
    if state["quiet"] or state["json"]:
        return
    s = summary
    head = (f"[bold]{escape(title)}[/bold]: {s['kind']} plan, footprint {s['footprint_m2']} m\u00b2, ceiling "
            f"{s['ceiling_m']} m, {s['walls']} wall prisms, {s['openings']} doors / windows")
    if "mount_positions" in s:
        d = s["mount_positions_dropped"]
        head += (f", {s['mount_positions']} mount positions ({d.get('inside', 0)} in walls, {d.get('clearance', 0)} "
                 f"closer than the {s['clearance_m']:g} m clearance)")
    console.print(head)
    if s["rooms"]:
        console.print(rooms_table(s["rooms"]))
    else:
        console.print("[yellow]no rooms found: the whole footprint is one zone of the default targets[/yellow]")
    for what, items in (("used", s["used"]), ("skipped", s["skipped"])):
        if items:
            grid = Table.grid(padding=(0, 2))
            grid.add_column(style="dim", no_wrap=True)
            grid.add_column()
            for k, v in items.items():
                grid.add_row(f"  {escape(str(k))}", escape(word_options(str(v))))
            console.print(f"{what}:")
            console.print(grid)
    if s["storeys"]:
        console.print(storeys_table(s["storeys"]))
    for note in s["notes"]:
        console.print(f"[yellow]note: {escape(word_options(note))}[/yellow]", soft_wrap=True)


def write_files(preview, base: Path) -> list[Path]:
    """Write the preview as ``base``.png and ``base``.svg; their paths."""
    from camplace.outputs.plan_preview import write_preview

    return list(write_preview(preview, base))


def json_part(preview, paths: list[Path]) -> dict:
    """The --json form of a preview: {'plan': summary, 'preview': [png, svg]}."""
    return {"plan": preview.summary, "preview": [str(p) for p in paths]}


def preview_of(rep: dict, title: str, show: bool = True):
    """The preview of a space file's import report (camplace.cli.space.scene_data_from_file)
    when it is a plan, its summary printed (``show``); None for scans, meshes, OctoMaps."""
    from camplace.outputs.plan_preview import render_preview

    plan = rep.get("plan")
    if plan is None:
        return None
    preview = render_preview(plan, title)
    if show:
        show_summary(preview.summary, title)
    return preview


def run_extra(preview, out_dir: Path) -> dict | None:
    """Write a run's preview.png / preview.svg into ``out_dir``: the files and the --json
    part for camplace.cli.summary.write_and_summarise (None without a preview)."""
    if preview is None:
        return None
    png, svg = write_files(preview, out_dir / "preview")
    return {"files": {"preview.png": png, "preview.svg": svg}, "plan": preview.summary}
