"""See before you run (issue 25): a picture of what a plan importer understood.

``preview.png`` / ``preview.svg`` (``scene import``: ``<out>.preview.png`` beside the YAML):
the footprint, the rooms (zones) with their names and areas, the walls and other prism
obstacles cut at CUT_M as an architect's plan (camplace.outputs.walls: filled where the
cut crosses them, outlined below it, dashed above it; one colour per provenance label,
the IFC class or DXF layer), the doors and windows the importer found, and the mount
grid: the mount positions that survive (inside the footprint, outside walls, keeping
``mount_rules.clearance``; camplace.cameras.candidates.mount_points, the rule the run
uses). A side column holds the legend, what the importer used and skipped, its notes,
the storeys of an IFC file and the key of the rooms too small to hold their label.

The plan is drawn at a fixed scale (PX_PER_M, within PLAN_PX on its longer side) so
labels keep their size from a 10 m house to a 100 m office floor; a room label goes
inside its room at its pole of inaccessibility (shapely polylabel) at the largest font
that fits without touching another label, else the room gets a key number.
"""

from __future__ import annotations

import io
import math
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import Polygon
from shapely.ops import polylabel

from camplace.core.files import atomic_write_bytes
from camplace.outputs.walls import label_colours, mpl_path, plan_cut, scene_walls

DPI = 150
PX_PER_M = 50.0  # plan scale, unless the plan's longer side leaves PLAN_PX
PLAN_PX = (1200, 4000)  # min, max pixels of the plan's longer side
MARGIN_M = 0.6  # drawn around the footprint
CUT_M = 1.5  # the plan cut (m above the floor)
FONT_PT = 6.5  # side column text
LINE_PT = 9.0  # side column line pitch
SIDE_IN = 3.4  # one side column (inches)
LABEL_PT = (9.0, 8.0, 7.0, 6.0)  # room label sizes tried, largest first
KEY_PT = 6.0  # a room's key number
CHAR_EM = 0.62  # mean character width (em) of the label font, for fitting
MAX_LABELS = 14  # wall labels listed in the legend
WRAP = 58  # side column characters per line
FOOTPRINT_FILL, OUTSIDE_FILL = "#ffffff", "#e9e9e9"
OPENING_FILL, OPENING_EDGE = "#fbb4d9", "#c51b7d"
MOUNT_COLOUR = "#08519c"
ROOM_FILLS = ("#fbe3c1", "#d5ecd4", "#d6e4f2", "#f3d9e8", "#fff3b0", "#dcd3ec", "#cdebe6", "#f6d5c8")
PREVIEW_GRID_BYTES = 64 * 1024**2  # a larger occupancy grid is built coarser for the picture
RC = {"svg.fonttype": "none", "svg.hashsalt": "camplace", "font.size": FONT_PT}


@dataclass(frozen=True)
class RoomLabel:
    """Where a room's label goes: anchor (x, y) m, text, font size (pt); ``key``: the
    room's number in the side key when its name and area did not fit (text = the number)."""

    name: str
    area_m2: float
    anchor: tuple[float, float]
    text: str
    size: float
    key: int | None = None


@dataclass(frozen=True)
class Preview:
    """The rendered picture (PNG and SVG bytes) and the summary it shows (plan_summary)."""

    png: bytes
    svg: bytes
    summary: dict = field(default_factory=dict)


# ----------------------------------------------------------------------------- what to draw


def mount_grid(scene) -> tuple[np.ndarray, dict[str, int]]:
    """The distinct mount positions (M, 3) m of a scene that survive the run's rules, and
    the positions removed: {'inside': in walls or obstacles, 'clearance': closer than
    mount_rules.clearance, 'ruled_out': outside the mount rules' areas}."""
    from camplace.cameras.candidates import mount_points
    from camplace.cameras.mount_rules import explicit_points

    points = explicit_points(scene)
    found, counts = [], {"inside": 0, "clearance": 0, "ruled_out": 0}
    for mount in scene.spec.mounts:
        p, _, c = mount_points(scene, mount, points)
        found.append(p)
        for k in counts:
            counts[k] += c[k]
    pos = np.concatenate(found) if found else np.zeros((0, 3))
    return (np.unique(np.round(pos, 6), axis=0) if len(pos) else pos), counts


def room_areas(scene_data: dict) -> list[tuple[str, float, Polygon]]:
    """(name, area m², polygon) of each volume zone (room) of a scene mapping, in file order."""
    out = []
    for z in scene_data.get("zones") or []:
        if z.get("polygon") and not z.get("privacy"):
            poly = shapely.make_valid(Polygon(z["polygon"]))
            out.append((str(z.get("name", "")), float(poly.area), poly))
    return out


def plan_summary(plan, mounts: int | None = None, dropped: dict | None = None, clearance: float | None = None) -> dict:
    """The import summary of a camplace.scene.importers.PlanImport as plain data (the
    --json form; the CLI prints it as tables): kind, footprint m², ceiling m, rooms
    [{name, area_m2}], walls / openings counts, used, skipped, notes, storeys and the
    surviving mount positions (when known)."""
    data = plan.scene or {}
    room = data.get("room") or {}
    fp = room.get("footprint")
    out = {"kind": plan.kind,
           "footprint_m2": round(float(Polygon(fp).area), 2) if fp and len(fp) >= 3 else None,
           "ceiling_m": room.get("height"),
           "rooms": [{"name": n, "area_m2": round(a, 2)} for n, a, _ in room_areas(data)],
           "walls": sum("prism" in o for o in data.get("obstacles") or []),
           "openings": len(plan.openings or []),
           "used": {str(k): str(v) for k, v in (plan.used or {}).items()},
           "skipped": {str(k): int(v) for k, v in (plan.skipped or {}).items()},
           "notes": [str(n) for n in plan.notes or []],
           "storeys": [dict(s) for s in plan.storeys or []]}
    if mounts is not None:
        out["mount_positions"] = int(mounts)
        out["mount_positions_dropped"] = dict(dropped or {})
        out["clearance_m"] = clearance
    return out


def _two_lines(name: str) -> list[str]:
    """``name`` broken at the space nearest its middle ([] when it has no space)."""
    cuts = [k for k, ch in enumerate(name) if ch == " "]
    if not cuts:
        return []
    k = min(cuts, key=lambda c: abs(2 * c - len(name)))
    return [f"{name[:k]}\n{name[k + 1:]}"]


def room_labels(rooms: list[tuple[str, float, Polygon]], m_per_pt: float) -> list[RoomLabel]:
    """The labels of the rooms (room_areas) at ``m_per_pt`` metres per point: name and
    area inside the room, at its centre (else its pole of inaccessibility), at the largest
    LABEL_PT size that fits the room and touches no label placed before (larger rooms
    first); else a key number (1, 2, ... in file order) at the pole."""
    placed: list = []
    chosen: dict[int, RoomLabel] = {}
    order = sorted(range(len(rooms)), key=lambda k: -rooms[k][1])
    for k in order:
        name, area, poly = rooms[k]
        if poly.is_empty or area <= 0:
            continue
        part = max(getattr(poly, "geoms", [poly]), key=lambda g: g.area)
        if part.geom_type != "Polygon":
            continue
        pole = polylabel(part, tolerance=max(0.01, math.sqrt(part.area) / 60))
        spots = [part.centroid, pole] if part.contains(part.centroid) else [pole]  # the centre when it is inside
        texts = [f"{name}\n{area:.1f} m\u00b2"] + [f"{n}\n{area:.1f} m\u00b2" for n in _two_lines(name)]
        fit = None
        for size in LABEL_PT:
            for text in texts:
                lines = text.split("\n")
                w = (max(len(s) for s in lines) * CHAR_EM + 0.5) * size * m_per_pt  # with the label's padding
                h = (len(lines) * 1.2 + 0.4) * size * m_per_pt
                for c in spots:
                    box = shapely.box(c.x - w / 2, c.y - h / 2, c.x + w / 2, c.y + h / 2)
                    if part.contains(box) and not any(box.intersects(b) for b in placed):
                        fit = (box, c, size, text)
                        break
                if fit:
                    break
            if fit:
                break
        if fit:
            placed.append(fit[0])
            chosen[k] = RoomLabel(name, area, (fit[1].x, fit[1].y), fit[3], fit[2])
        else:
            chosen[k] = RoomLabel(name, area, (pole.x, pole.y), "", KEY_PT, key=0)
    out, n = [], 0
    for k in range(len(rooms)):  # key numbers in file order
        lab = chosen.get(k)
        if lab is None:
            continue
        if lab.key is not None:
            n += 1
            lab = RoomLabel(lab.name, lab.area_m2, lab.anchor, str(n), KEY_PT, n)
        out.append(lab)
    return out


def _side_lines(plan, summary: dict, walls_by_label: dict, colours: dict, labels: list[RoomLabel],
                title: str) -> list[tuple[str, str, object]]:
    """The side column as (style, text, swatch) lines: style 'title', 'head', 'text',
    'swatch' (swatch: a fill colour, ('outline', colour) or ('marker', colour)) or 'scale'
    (swatch: the bar's length in inches; added by draw_preview)."""
    s = summary
    L: list[tuple[str, str, object]] = [("title", title, None)]
    L.append(("text", f"{plan.kind.upper()} plan: footprint {s['footprint_m2']} m\u00b2, ceiling {s['ceiling_m']} m",
              None))
    L += [("text", "", None), ("head", "legend", None),
          ("swatch", "footprint (outside it grey)", ("outline", "#000000")),
          ("swatch", f"rooms ({len(s['rooms'])}): name, area", ROOM_FILLS[0])]
    for k, (lab, n) in enumerate(walls_by_label.items()):
        if k == MAX_LABELS:
            L.append(("text", f"   ... {len(walls_by_label) - MAX_LABELS} more labels", None))
            break
        L.append(("swatch", f"{lab} ({n})", colours[lab]))
    L.append(("swatch", f"doors and windows found ({s['openings']})", OPENING_FILL))
    if "mount_positions" in s:
        L.append(("swatch", f"mount positions ({s['mount_positions']}), {s['clearance_m']:g} m clearance",
                  ("marker", MOUNT_COLOUR)))
        d = s["mount_positions_dropped"]
        if d.get("inside") or d.get("clearance"):
            L.append(("text", f"   not drawn: {d.get('inside', 0)} in walls, {d.get('clearance', 0)} closer than the "
                              "clearance", None))
    L.append(("text", f"walls cut at {CUT_M:g} m: filled = cut, outline = lower, dashed = higher", None))
    for head, items in (("used", [f"{k}: {v}" for k, v in s["used"].items()]),
                        ("skipped", [f"{k}: {v}" for k, v in s["skipped"].items()]), ("notes", s["notes"]),
                        ("storeys", [f"{'>' if st.get('chosen') else ' '} {st.get('name')}  "
                                     f"{float(st.get('elevation_m') or 0):.2f} m  {len(st.get('rooms') or [])} rooms"
                                     for st in s["storeys"]])):
        if items:
            L += [("text", "", None), ("head", head, None)]
            for item in items:
                L += [("text", line, None) for line in textwrap.wrap(item, WRAP, subsequent_indent="   ") or [""]]
    keyed = [lab for lab in labels if lab.key is not None]
    if keyed:
        L += [("text", "", None), ("head", "rooms by number", None)]
        L += [("text", f"{lab.key:>3}  {lab.name}  {lab.area_m2:.1f} m\u00b2", None) for lab in keyed]
    return L


# ----------------------------------------------------------------------------- drawing


def plan_bounds(footprint: np.ndarray, shapes: list, openings: list) -> tuple[np.ndarray, np.ndarray]:
    """(lo (2,), hi (2,)) m: the box around everything drawn (footprint, walls, rooms,
    openings; what lies outside the footprint too), MARGIN_M wider."""
    pts = [np.asarray(footprint, float).reshape(-1, 2)]
    pts += [np.asarray(g.bounds, float).reshape(2, 2) for g in shapes if not g.is_empty]
    pts += [np.asarray(r, float).reshape(-1, 2) for r in openings if len(r)]
    allp = np.concatenate(pts)
    return allp.min(0) - MARGIN_M, allp.max(0) + MARGIN_M


def scale_bar_m(px_per_m: float, max_in: float = 1.8) -> float:
    """The longest round length (m) whose bar at the plan's scale fits ``max_in`` inches."""
    fits = [v for v in (0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500) if v * px_per_m / DPI <= max_in]
    return float(fits[-1] if fits else 0.5)


def _draw_plan(ax, plan, footprint: np.ndarray, rooms: list, walls, colours: dict, mounts: np.ndarray,
               labels: list[RoomLabel], m_per_pt: float) -> None:
    """The plan itself on ``ax`` (data in metres): outside grey, footprint, rooms, walls cut
    at CUT_M, openings, mount positions, room labels."""
    from matplotlib.patches import PathPatch

    ax.set_facecolor(OUTSIDE_FILL)
    ax.tick_params(labelsize=FONT_PT, length=2, color="#888888", labelcolor="#555555")
    ax.set_xlabel("x (m)", fontsize=FONT_PT, color="#555555")
    ax.set_ylabel("y (m)", fontsize=FONT_PT, color="#555555")
    outline = mpl_path(Polygon(footprint))
    ax.add_patch(PathPatch(outline, fc=FOOTPRINT_FILL, ec="none", zorder=1))
    ax.add_patch(PathPatch(outline, fc="none", ec="#000000", lw=1.3, zorder=4.5))  # over rooms and walls
    for k, (_, _, poly) in enumerate(rooms):
        path = mpl_path(poly)
        if path is not None:
            ax.add_patch(PathPatch(path, fc=ROOM_FILLS[k % len(ROOM_FILLS)], ec="#8c8c8c", lw=0.4, zorder=2))
    cut, below = plan_cut(walls, CUT_M)
    above: dict[str, list] = {}
    for w in walls:
        if w.zmin > CUT_M:
            above.setdefault(w.label, []).append(w.shape)
    for lab, geom in cut.items():
        ax.add_patch(PathPatch(mpl_path(geom), fc=colours[lab], ec=colours[lab], lw=0.3, zorder=3))
    for lab, geom in below.items():
        ax.add_patch(PathPatch(mpl_path(geom), fc="none", ec=colours[lab], lw=0.7, zorder=3))
    for lab, shapes in above.items():
        ax.add_patch(PathPatch(mpl_path(shapely.union_all(shapes)), fc="none", ec=colours[lab], lw=0.5, ls="--",
                               zorder=3))
    for ring in plan.openings or []:
        poly = shapely.make_valid(Polygon(ring)) if len(ring) >= 3 else Polygon()
        path = mpl_path(poly) if not poly.is_empty else None
        if path is not None:
            ax.add_patch(PathPatch(path, fc=OPENING_FILL, ec=OPENING_EDGE, lw=0.6, zorder=4))
    if len(mounts):
        size = float(np.clip(0.18 / m_per_pt, 2.5, 6.0))
        ax.scatter(mounts[:, 0], mounts[:, 1], s=size**2, marker="+", c=MOUNT_COLOUR, linewidths=0.6, zorder=5,
                   rasterized=len(mounts) > 3000)
    for lab in labels:
        ax.text(*lab.anchor, lab.text, fontsize=lab.size, ha="center", va="center", zorder=6, linespacing=1.1,
                color="#1a1a1a", weight="bold" if lab.key is not None else "normal",
                bbox={"boxstyle": "round,pad=0.12", "fc": "white", "ec": "none", "alpha": 0.75})


def _draw_side(fig, side: list, x0_in: float, top_in: float, cols: int) -> None:
    """The side column lines (_side_lines) on ``fig`` from ``x0_in`` inches, in ``cols`` columns."""
    from matplotlib.patches import Rectangle

    fig_w, fig_h = fig.get_size_inches()
    line_in = LINE_PT / 72.0
    per_col = max(1, math.ceil(len(side) / cols))
    for n, (style, text, swatch) in enumerate(side):
        col, row = divmod(n, per_col)
        x = (x0_in + col * SIDE_IN) / fig_w
        y = (fig_h - top_in - (row + 0.8) * line_in) / fig_h
        tx = x
        if style == "scale":  # a bar as long as `text` metres on the plan
            fig.add_artist(Rectangle((x, y - 0.025 / fig_h), swatch / fig_w, 0.05 / fig_h, transform=fig.transFigure,
                                     fc="#000000", ec="none"))
            tx = x + (swatch + 0.08) / fig_w
        elif style == "swatch":
            sw, sh = 0.22 / fig_w, 0.09 / fig_h
            if isinstance(swatch, tuple) and swatch[0] == "marker":
                fig.text(x + sw / 2, y, "+", color=swatch[1], fontsize=FONT_PT + 2, ha="center", va="center")
            else:
                outline_only = isinstance(swatch, tuple)
                fig.add_artist(Rectangle((x, y - sh / 2), sw, sh, transform=fig.transFigure,
                                         fc="none" if outline_only else swatch,
                                         ec=swatch[1] if outline_only else "#555555", lw=0.5))
            tx = x + sw + 0.06 / fig_w
        fig.text(tx, y, text, fontsize=FONT_PT + (1.5 if style == "title" else 0), va="center", ha="left",
                 weight="bold" if style in ("title", "head") else "normal", family="DejaVu Sans")


def draw_preview(plan, scene, mounts: np.ndarray, summary: dict, title: str):
    """The preview Figure (matplotlib, no pyplot) of a PlanImport, its built Scene and the
    surviving mount positions (M, 3) m; ``summary``: plan_summary. The plan at PX_PER_M
    (within PLAN_PX), the side column beside it in as many columns (at most 3) as it needs."""
    from matplotlib.figure import Figure

    fp = np.asarray(scene.footprint, float)
    walls = scene_walls(scene)
    rooms = room_areas(plan.scene)
    lo, hi = plan_bounds(fp, [w.shape for w in walls] + [r[2] for r in rooms], plan.openings or [])
    ext = hi - lo
    px_per_m = float(np.clip(ext.max() * PX_PER_M, *PLAN_PX)) / ext.max()
    m_per_pt = DPI / 72.0 / px_per_m
    plan_w, plan_h = ext * px_per_m / DPI  # inches
    labels = room_labels(rooms, m_per_pt)
    by_label: dict[str, int] = {}
    for w in walls:
        by_label[w.label] = by_label.get(w.label, 0) + 1
    colours = label_colours(by_label)
    side = _side_lines(plan, summary, by_label, colours, labels, title)
    bar = scale_bar_m(px_per_m)
    side.insert(2, ("scale", f"{bar:g} m on the plan", bar * px_per_m / DPI))
    top, bottom, left, gap = 0.35, 0.45, 0.55, 0.3  # inches around the plan
    avail = max(plan_h, 4.0)
    cols = max(1, math.ceil(len(side) * LINE_PT / 72.0 / avail))
    if cols > 3:
        cols, avail = 3, len(side) * LINE_PT / 72.0 / 3
    fig_w, fig_h = left + plan_w + gap + cols * SIDE_IN, top + bottom + max(plan_h, avail)
    fig = Figure(figsize=(fig_w, fig_h), dpi=DPI)
    ax = fig.add_axes((left / fig_w, (fig_h - top - plan_h) / fig_h, plan_w / fig_w, plan_h / fig_h))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    _draw_plan(ax, plan, fp, rooms, walls, colours, mounts, labels, m_per_pt)
    _draw_side(fig, side, left + plan_w + gap, top, cols)
    return fig


def preview_figure(plan, title: str, scene=None):
    """(Figure, summary) of a PlanImport: its scene mapping built into a Scene (unless
    ``scene`` is given), the surviving mount positions found, the picture drawn."""
    from camplace.scene.build import build_scene, estimate_grid_bytes
    from camplace.spec.loading import parse_scene

    coarse = None
    if scene is None:
        spec = parse_scene(plan.scene, title)
        need = estimate_grid_bytes(spec)
        if need > PREVIEW_GRID_BYTES:  # a huge plan: the picture's mount grid on coarser cells, never a refusal
            coarse = round(spec.occupancy_resolution * (need / PREVIEW_GRID_BYTES) ** (1 / 3) + 5e-4, 3)
            spec = spec.model_copy(update={"occupancy_resolution": coarse})
        scene = build_scene(spec, source=title)
    mounts, dropped = mount_grid(scene)
    summary = plan_summary(plan, len(mounts), {k: v for k, v in dropped.items() if k != "ruled_out" or v},
                           float(scene.spec.mount_rules.clearance))
    if coarse is not None:
        summary["notes"].append(f"preview: mount grid found on {coarse:g} m occupancy cells (a large plan); the run "
                                f"uses occupancy_resolution {plan.scene.get('occupancy_resolution', 0.05):g} m")
    return draw_preview(plan, scene, mounts, summary, title), summary


def render_preview(plan, title: str, scene=None) -> Preview:
    """The preview of a PlanImport (preview_figure): PNG and SVG bytes and the summary."""
    import matplotlib

    with matplotlib.rc_context(RC):
        fig, summary = preview_figure(plan, title, scene)
        buf_png, buf_svg = io.BytesIO(), io.BytesIO()
        fig.savefig(buf_png, format="png", dpi=DPI, metadata={"Software": None}, pil_kwargs={"compress_level": 3})
        fig.savefig(buf_svg, format="svg", metadata={"Date": None})
    return Preview(buf_png.getvalue(), buf_svg.getvalue(), summary)


def preview_paths(base: Path) -> tuple[Path, Path]:
    """(PNG, SVG) paths of a preview named ``base`` (a path without suffix)."""
    return base.with_name(base.name + ".png"), base.with_name(base.name + ".svg")


def write_preview(preview: Preview, base: Path) -> tuple[Path, Path]:
    """Write ``base``.png and ``base``.svg (atomically); returns their paths."""
    png, svg = preview_paths(base)
    atomic_write_bytes(png, preview.png)
    atomic_write_bytes(svg, preview.svg)
    return png, svg
