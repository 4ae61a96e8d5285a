"""plan.pdf and plan.svg: the printed plan set (matplotlib, vector; no pyplot, no global state).

Pages: 1 the floor plan at a stated scale (1:N, chosen from the usual architectural scales
so the room fits the paper) with scale bar and north arrow (north = +y of the scene
frame): walls, labelled obstacles, each camera as a numbered symbol pointing along its
yaw with its viewshed at the working height, filled by DORI band; 2 the coverage map
(achieved coverage class per target height in the paper's Fig. 2 colours, and the share
of targets meeting Γ) with the per-region table; 3 the camera schedule (more pages when
it is long); 4 the camera views (camplace.outputs.report_html.camera_views cards). Every
page carries the title block (PlanData.title_pairs). plan.svg is page 1 as SVG, with one
``<g id="camera-C1">`` group per camera symbol.
"""

from __future__ import annotations

import base64
import io
import math
from pathlib import Path

import numpy as np

from camplace.core.files import atomic_write_bytes
from camplace.outputs.figures import AREA_STYLES, COVERAGE_CLASSES, SceneView, coverage_slices
from camplace.outputs.pdf_text import pdf_layout_cache
from camplace.outputs.plan_data import DORI_COLOURS, PAPERS_MM, PlanData
from camplace.outputs.walls import label_colours, mpl_path, plan_cut, scene_walls
from camplace.visibility.viewshed import DORI_LEVELS

MM = 1.0 / 25.4  # inches per millimetre
REGION_HEAD = ("region", "targets", "\u0393", "gap", "non-tri %", "unseen")
SCALES = (20, 25, 50, 75, 100, 125, 150, 200, 250, 300, 400, 500, 750, 1000, 1250, 1500, 2000, 2500, 5000, 10000,
          20000, 50000, 100000)
SIDE_MM = 100.0  # right-hand column of page 1: title block and legend
MARGIN_MM = 12.0
OUTLINE = "#1f4fd1"  # viewshed outlines and new cameras
EXISTING = "#7b3294"  # existing cameras
# zones (outline + name), privacy zones (hatched), forbidden / allowed mount areas (dashed / dash-dot)
PLAN_AREAS = {"zone": {"edgecolor": "#1b7837", "linewidth": 1.0}, **AREA_STYLES,
              "allow": {"edgecolor": "#1b7837", "linestyle": "-.", "linewidth": 1.2},
              "opening": {"edgecolor": "#444444", "linestyle": "--", "linewidth": 0.9}}
AREA_LABELS = {"zone": "zone (name)", "privacy": "privacy zone (never seen)", "forbid": "no camera mounted here",
               "allow": "cameras mounted only here", "opening": "floor open to the storey below"}
# text stays text; fixed SVG ids (hash salt) so repeatable runs give identical files
RC = {"pdf.fonttype": 3, "svg.fonttype": "none", "svg.hashsalt": "camplace", "font.size": 7.0, "hatch.linewidth": 0.4}


def page_size_mm(paper: str) -> tuple[float, float]:
    """(width, height) mm of the landscape page."""
    return PAPERS_MM[paper]


def plan_scale(extent_m: tuple[float, float], area_mm: tuple[float, float]) -> int:
    """The smallest of SCALES (1:N) at which extent_m (m) fits area_mm (mm)."""
    need = max(extent_m[0] * 1000.0 / area_mm[0], extent_m[1] * 1000.0 / area_mm[1])
    return next((s for s in SCALES if s >= need), int(math.ceil(need)))


def geom_path(geom):
    """A matplotlib Path of a shapely (Multi)Polygon, holes kept (exteriors counter-clockwise)."""
    return mpl_path(geom)


def _figure(paper: str):
    from matplotlib.figure import Figure

    w, h = page_size_mm(paper)
    return Figure(figsize=(w * MM, h * MM))


def _title_block(fig, data: PlanData, page: str) -> None:
    """The framed title block, bottom right: figure-level artists in mm, no axes (faster; issue 37)."""
    from matplotlib.patches import Rectangle
    from matplotlib.transforms import Affine2D

    w, h = page_size_mm(data.paper)
    bw, bh = SIDE_MM - 6.0, 6.0 + 4.2 * (len(data.title_pairs) + 2)
    mm = Affine2D().translate(w - MARGIN_MM - bw, MARGIN_MM).scale(1.0 / w, 1.0 / h) + fig.transFigure  # block mm
    fig.patches.append(Rectangle((0, 0), bw, bh, transform=mm, facecolor="white", edgecolor="black", linewidth=0.8))
    fig.text(3, bh - 4, "camplace \u2013 camera plan", fontsize=9, weight="bold", va="top", transform=mm)
    for y, (lab, val) in zip(bh - 10 - 4.2 * np.arange(len(data.title_pairs)), data.title_pairs):
        fig.text(3, y, lab, fontsize=6.5, color="#555555", va="top", transform=mm)
        fig.text(30, y, val, fontsize=6.5, va="top", transform=mm)
    fig.text(3, 2.5, page, fontsize=6.5, weight="bold", va="bottom", transform=mm)


def _plan_axes(fig, data: PlanData):
    """Axes placed so that 1 m of the scene is 1000 / N mm on paper; returns (ax, N, extent)."""
    fp = np.asarray(data.scene.footprint, float)
    pad = 0.4
    lo, hi = fp.min(0) - pad, fp.max(0) + pad
    ext = hi - lo
    w, h = page_size_mm(data.paper)
    area = (w - 2 * MARGIN_MM - SIDE_MM, h - 2 * MARGIN_MM - 14.0)
    n = plan_scale((float(ext[0]), float(ext[1])), area)
    aw, ah = ext[0] * 1000.0 / n, ext[1] * 1000.0 / n
    bottom = MARGIN_MM + 14.0 + (area[1] - ah) / 2
    ax = fig.add_axes((MARGIN_MM / w, bottom / h, aw / w, ah / h))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_axis_off()
    return ax, n, (lo, hi)


def _scale_bar(ax, n: int, lo: np.ndarray) -> None:
    from matplotlib.patches import Rectangle

    full = (ax.get_xlim()[1] - ax.get_xlim()[0])
    length = next((s for s in (10.0, 5.0, 2.0, 1.0, 0.5) if s * 4 <= full * 0.6), 0.5)
    y = lo[1] - 0.0
    bar_h = 1.5 * n / 1000.0  # 1.5 mm on paper
    for k in range(4):
        ax.add_patch(Rectangle((lo[0] + k * length, y - 3 * bar_h), length, bar_h, facecolor="black" if k % 2 == 0
                               else "white", edgecolor="black", linewidth=0.5, clip_on=False))
        ax.text(lo[0] + k * length, y - 3.5 * bar_h, f"{k * length:g}", fontsize=5.5, ha="center", va="top",
                clip_on=False)
    ax.text(lo[0] + 4 * length, y - 3.5 * bar_h, f"{4 * length:g} m", fontsize=5.5, ha="center", va="top",
            clip_on=False)
    ax.text(lo[0] + 4 * length + 0.6 * length, y - 2.5 * bar_h, f"scale 1:{n} (on {ax.figure._camplace_paper})",
            fontsize=6.5, va="center", clip_on=False)


def _north_arrow(fig, data: PlanData) -> None:
    w, h = page_size_mm(data.paper)
    x, y = (w - MARGIN_MM - 12.0) / w, (h - MARGIN_MM - 22.0) / h
    fig.patches.append(_arrow_patch(fig, x, y, 16.0 / h))
    fig.text(x, y + 18.0 / h, "N", ha="center", va="bottom", fontsize=10, weight="bold")
    fig.text(x, y - 2.0 / h, "+y", ha="center", va="top", fontsize=5.5, color="#555555")


def _arrow_patch(fig, x: float, y: float, length: float):
    from matplotlib.patches import FancyArrow

    return FancyArrow(x, y, 0, length, width=0.004, head_width=0.018, head_length=length * 0.35,
                      transform=fig.transFigure, color="black", length_includes_head=True)


def _draw_walls(ax, data: PlanData) -> dict[str, str]:
    """The prism obstacles (imported walls, ...) cut at the working height: crossing it
    filled by label, wholly below it in outline; returns label -> colour (legend)."""
    from matplotlib.patches import PathPatch

    cut, below = plan_cut(scene_walls(data.scene), data.height)
    colours = label_colours([*cut, *below])
    for label, geom in below.items():
        path = mpl_path(geom)
        if path is not None:
            ax.add_patch(PathPatch(path, facecolor="none", edgecolor=colours[label], linewidth=0.6, zorder=3.6))
    for label, geom in cut.items():
        path = mpl_path(geom)
        if path is not None:
            ax.add_patch(PathPatch(path, facecolor=colours[label], edgecolor="black", linewidth=0.4, zorder=4.5))
    return {k: colours[k] for k in [*cut, *below]}


def _draw_room(ax, data: PlanData, n: int) -> None:
    from matplotlib.patches import Polygon as MPolygon, Rectangle

    fp = np.asarray(data.scene.footprint, float)
    ax.add_patch(MPolygon(fp, closed=True, facecolor="#fbfbf8", edgecolor="none", zorder=0))
    ax.add_patch(MPolygon(fp, closed=True, fill=False, edgecolor="black", linewidth=2.2, zorder=5, joinstyle="miter"))
    for name, (bmin, bmax) in data.scene.boxes.items():
        ax.add_artist(Rectangle((bmin[0], bmin[1]), bmax[0] - bmin[0], bmax[1] - bmin[1], facecolor="#c8c8c8",
                                edgecolor="#444444", linewidth=0.6, hatch="///", zorder=4))  # limits set: no search
        vertical = (bmax[1] - bmin[1]) > 1.5 * (bmax[0] - bmin[0])
        ax.text((bmin[0] + bmax[0]) / 2, (bmin[1] + bmax[1]) / 2, f"{name}\n{bmax[2]:.2f} m", fontsize=5,
                ha="center", va="center", rotation=90 if vertical else 0, zorder=6,
                bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.75, "pad": 0.6})


def dori_union(data: PlanData) -> list[tuple[str, object]]:
    """(level, geometry) of the plan's fill, coarsest first: 'seen' = the union of every
    viewshed, then each DORI level = the union of the cameras' bands of that level (where
    at least one camera reaches it)."""
    import shapely

    out = [("seen", shapely.union_all([v.polygon for v in data.shed]))]
    for name, _ in DORI_LEVELS:
        out.append((name, shapely.union_all([v.bands[name] for v in data.shed if name in v.bands])))
    return out


def _draw_viewsheds(ax, data: PlanData) -> None:
    """The best DORI level reached at each point (filled), and each camera's viewshed outline."""
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import PathPatch

    fills = {"seen": "#e3e3e3", **DORI_COLOURS}
    patches, colours = [], []
    for name, geom in dori_union(data):
        path = geom_path(geom)
        if path is not None:
            patches.append(PathPatch(path))
            colours.append(fills[name])
    ax.add_collection(PatchCollection(patches, facecolors=colours, edgecolors="none", alpha=0.75, zorder=1),
                      autolim=False)
    outlines = [PathPatch(p) for p in (geom_path(v.polygon) for v in data.shed) if p is not None]
    ax.add_collection(PatchCollection(outlines, facecolors="none", edgecolors=OUTLINE, linewidths=0.4, alpha=0.7,
                                      zorder=2), autolim=False)


def _draw_cameras(ax, data: PlanData, n: int) -> None:
    from matplotlib.patches import Circle, Polygon as MPolygon

    r = 2.2 * n / 1000.0  # symbol radius: 2.2 mm on paper
    for c, mark in zip(data.cameras, data.marks):
        x, y = c["position"][:2]
        a = math.radians(c["yaw_deg"])
        d, s = np.array([math.cos(a), math.sin(a)]), np.array([-math.sin(a), math.cos(a)])
        tip = np.array([x, y]) + 2.4 * r * d
        wedge = np.array([np.array([x, y]) + 0.6 * r * s, tip, np.array([x, y]) - 0.6 * r * s])
        colour = EXISTING if c.get("existing") else OUTLINE
        for part, art in (("wedge", MPolygon(wedge, closed=True, facecolor=colour, edgecolor="white", linewidth=0.3,
                                              zorder=7)),
                          ("symbol", Circle((x, y), r, facecolor="white", edgecolor=colour, linewidth=0.9, zorder=8))):
            art.set_gid(f"camera-{mark}-{part}")  # plan.svg: <g id="camera-C1-symbol"> (report.html's hover rows)
            ax.add_artist(art)  # not add_patch: the limits are set, no Bezier extrema per symbol (issue 37)
        # the mark once, inside the circle (as the schedule spells it)
        t = ax.text(x, y, mark, fontsize=4.2 if len(mark) < 4 else 3.4, ha="center", va="center", weight="bold",
                    color=colour, zorder=9)
        t.set_gid(f"camera-{mark}-label")


def _draw_areas(ax, data: PlanData) -> list[str]:
    """The scene's zones, privacy zones and mount-rule areas (PlanData.areas) with their
    names; returns the kinds drawn (for the legend)."""
    from matplotlib.patches import Polygon as MPolygon
    from shapely.geometry import Polygon

    kinds = []
    for kind, name, corners in data.areas:
        style = PLAN_AREAS[kind]
        ax.add_patch(MPolygon(corners, closed=True, fill=False, zorder=3, **style))
        x, y = Polygon(corners).representative_point().coords[0]
        ax.text(x, y, name, fontsize=7, ha="center", va="center", color=style["edgecolor"], style="italic",
                zorder=6, bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.7, "pad": 0.5})
        kinds += [kind] if kind not in kinds else []
    return kinds


def _draw_openings(ax, data: PlanData) -> list[str]:
    """A storey's floor openings (open to the storey below): dashed, crossed, labelled."""
    from matplotlib.patches import PathPatch

    for geom in data.openings:
        ax.add_patch(PathPatch(mpl_path(geom), fill=False, zorder=3, **PLAN_AREAS["opening"]))
        (x0, y0, x1, y1), (cx, cy) = geom.bounds, geom.representative_point().coords[0]
        ax.plot([x0, x1], [y0, y1], [x0, x1], [y1, y0], color=PLAN_AREAS["opening"]["edgecolor"], linewidth=0.5,
                zorder=3)
        ax.text(cx, cy, "open to below", fontsize=5.5, ha="center", va="center", zorder=6,
                bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.7, "pad": 0.4})
    return ["opening"] if data.openings else []


def _legend(fig, data: PlanData, kinds: list[str], walls: dict[str, str] | None = None) -> None:
    from matplotlib.patches import Patch

    w, h = page_size_mm(data.paper)
    handles = [Patch(facecolor="#e3e3e3", label="seen, below detect"),
               *[Patch(facecolor=DORI_COLOURS[nm], alpha=0.75, label=f"{nm} \u2265 {v:g} px/m") for nm, v in DORI_LEVELS],
               Patch(facecolor="none", edgecolor=OUTLINE, label="one camera's viewshed (outline)"),
               *([Patch(facecolor="#c8c8c8", hatch="///", edgecolor="#444444", label="obstacle (top height)")]
                 if data.scene.boxes or not walls else []),
               *[Patch(facecolor=c, edgecolor="black", label=f"{k} (cut at {data.height:.2f} m)")
                 for k, c in (walls or {}).items()],
               Patch(facecolor="white", edgecolor=OUTLINE, label="new camera (mark, facing yaw)"),
               *([Patch(facecolor="white", edgecolor=EXISTING, label="existing camera")]
                 if any(c.get("existing") for c in data.cameras) else []),
               *[Patch(fill=False, label=AREA_LABELS[k], **PLAN_AREAS[k]) for k in kinds]]
    fig.legend(handles=handles, loc="upper left", bbox_to_anchor=((w - MARGIN_MM - SIDE_MM + 6) / w,
                                                                  (h - MARGIN_MM - 40.0) / h),
               fontsize=6.5, frameon=False, title=f"viewsheds at {data.height:.2f} m: best DORI level\nof any camera (EN/IEC 62676-4)",
               title_fontsize=7)


def plan_figure(data: PlanData):
    """Page 1: the floor plan (a matplotlib Figure of the paper's size)."""
    from matplotlib import rc_context

    with rc_context(RC):
        return _plan_figure(data)


def _plan_figure(data: PlanData):
    fig = _figure(data.paper)
    fig._camplace_paper = data.paper
    ax, n, (lo, hi) = _plan_axes(fig, data)
    _draw_room(ax, data, n)
    walls = _draw_walls(ax, data)
    _draw_viewsheds(ax, data)
    kinds = _draw_areas(ax, data)
    kinds += _draw_openings(ax, data)
    _draw_cameras(ax, data, n)
    _scale_bar(ax, n, lo)
    _north_arrow(fig, data)
    _legend(fig, data, kinds, walls)
    w, h = page_size_mm(data.paper)
    if data.skipped:
        fig.text((w - MARGIN_MM - SIDE_MM + 6) / w, (MARGIN_MM + 80.0) / h, f"{data.skipped} viewsheds not computed "
                 "within the time budget\n(their cameras are drawn without one).", fontsize=7, color="#b2182b")
    fig.text(MARGIN_MM / page_size_mm(data.paper)[0], 1 - 8.0 / page_size_mm(data.paper)[1],
             f"{data.placement.get('scene', data.scene.name)}{_storey_words(data)}: floor plan, {len(data.cameras)} cameras",
             fontsize=11, weight="bold", va="top")
    _title_block(fig, data, data.sheet(1, "floor plan"))
    return fig


def _storey_words(data: PlanData) -> str:
    """', storey NAME' in a storey sheet's heading; '' otherwise."""
    return f", storey {data.storey}" if data.storey else ""


def coverage_figure(data: PlanData):
    """Page 2: coverage class per target height (Fig. 2 colours) and the per-region table."""
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch, Polygon as MPolygon

    fig = _figure(data.paper)
    w, h = page_size_mm(data.paper)
    t = data.targets
    view = SceneView.from_scene(data.scene)
    slices = coverage_slices(view, t.positions, t.is_surface, data.coverage)
    vol = ~np.asarray(t.is_surface, bool)
    cmap = ListedColormap([c for _, c in COVERAGE_CLASSES]).with_extremes(bad=(0, 0, 0, 0))
    ncol = max(1, math.ceil(math.sqrt(len(slices) or 1)))
    nrow = max(1, math.ceil(len(slices) / ncol))
    left, right, top, bottom = MARGIN_MM / w, (w - MARGIN_MM - SIDE_MM) / w, 1 - 16.0 / h, (MARGIN_MM + 6) / h
    gs = fig.add_gridspec(nrow, ncol, left=left, right=right, top=top, bottom=bottom, wspace=0.12, hspace=0.25)
    fp = np.asarray(data.scene.footprint, float)
    v = view.voxel_size
    for k, sl in enumerate(slices):
        ax = fig.add_subplot(gs[k // ncol, k % ncol])
        cls = np.where(np.isnan(sl.coverage), np.nan, np.minimum(sl.coverage, 3))
        ax.imshow(np.ma.masked_invalid(cls), origin="lower", cmap=cmap, norm=BoundaryNorm([-0.5, 0.5, 1.5, 2.5, 3.5], 4),
                  interpolation="none", extent=(sl.x[0] - v / 2, sl.x[-1] + v / 2, sl.y[0] - v / 2, sl.y[-1] + v / 2))
        ax.add_patch(MPolygon(fp, closed=True, fill=False, edgecolor="black", linewidth=0.8))
        at = vol & (np.abs(t.positions[:, 2] - sl.height) < 1e-6)
        met = float(np.mean(data.coverage[at] >= t.gamma[at]) * 100) if at.any() else 0.0
        # title y and axis label places fixed: no search of the tick labels (issue 37)
        ax.set_title(f"z = {sl.height:.2f} m: {met:.1f} % of targets reach \u0393", fontsize=7, y=1.0)
        ax.xaxis.set_label_coords(0.5, -0.1), ax.yaxis.set_label_coords(-0.1, 0.5)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=5)
    fig.legend(handles=[Patch(color=c, label=lab) for lab, c in COVERAGE_CLASSES], title="cameras seeing",
               loc="upper left", bbox_to_anchor=((w - MARGIN_MM - SIDE_MM + 6) / w, 1 - 16.0 / h), fontsize=7,
               frameon=False)
    rows = region_rows(data)
    if rows:
        tall = (len(rows) + 1) * 6.0 * 1.6 * 25.4 / 72.0 / h
        tax = fig.add_axes(((w - MARGIN_MM - SIDE_MM + 4) / w, 0.62 - tall, (SIDE_MM - 6) / w, tall))
        tax.set_axis_off()
        _column_table(tax, REGION_HEAD, rows, (6, 3, 2, 3, 3, 3), 6.0)
    fig.text(left, 1 - 8.0 / h, f"{data.placement.get('scene', data.scene.name)}{_storey_words(data)}: coverage "
             f"against \u0393 per target height", fontsize=11, weight="bold", va="top")
    _title_block(fig, data, data.sheet(2, "coverage"))
    return fig


def region_rows(data: PlanData) -> list[tuple[str, ...]]:
    """(region, targets, Γ, coverage gap, non-triangulatable %, not seen) per region of metrics.json."""
    t, out = data.targets, []
    for r, name in enumerate(t.region_names):
        m = (data.metrics.get("regions") or {}).get(str(name), {})
        g = int(t.gamma[t.region_ids == r].max()) if np.any(t.region_ids == r) else 0
        out.append((str(name), str(m.get("targets", "")), str(g), f"{float(m.get('coverage_gap', 0.0)):.4f}",
                    f"{float(m.get('non_triangulatable_pct', 0.0)):.1f}",
                    str((m.get("coverage_histogram") or {}).get("0", 0))))
    return out


def _column_table(ax, head: tuple[str, ...], rows: list[tuple[str, ...]], widths: tuple[float, ...],
                  fontsize: float) -> None:
    """A table drawn as one text per column (rows joined by newlines; fast in every backend) with
    rules between rows; ax spans the table, (0, 0) bottom left to (1, 1) top right."""
    n = len(rows) + 1
    x = np.r_[0.0, np.cumsum(widths)] / float(sum(widths))
    for k, name in enumerate(head):
        col = "\n".join([name, *[r[k] for r in rows]])
        ax.text(x[k] + 0.003, 1.0, col, fontsize=fontsize, va="top", ha="left", linespacing=1.6,
                family="DejaVu Sans", transform=ax.transAxes)
    ax.hlines(1.0 - np.arange(n + 1) / n, 0, 1, colors="#bbbbbb", linewidth=0.3, transform=ax.transAxes)


def schedule_figures(data: PlanData) -> list:
    """Page(s) 3: the camera schedule, as many rows a page as the paper holds."""
    rows = data.schedule_rows()
    w, h = page_size_mm(data.paper)
    fs = 6.0 if data.paper == "A3" else 4.6
    row_mm = fs * 1.6 * 25.4 / 72.0  # one text line at linespacing 1.6
    per_page = max(5, int((h - 2 * MARGIN_MM - 60.0) / row_mm) - 1)
    figs = []
    chunks = [rows[a:a + per_page] for a in range(0, len(rows), per_page)] or [[]]
    for p, chunk in enumerate(chunks):
        fig = _figure(data.paper)
        top = 1 - 18.0 / h
        tall = (len(chunk) + 1) * row_mm / h
        ax = fig.add_axes((MARGIN_MM / w, top - tall, 1 - 2 * MARGIN_MM / w, tall))
        ax.set_axis_off()
        head = data.schedule_head
        widths = (3, 3, 3.5, 3.5, 4.5, 3.5, 3.5, 3.5, 5, 11, 3, 8, 20, 4)
        if len(head) > len(widths):  # a building: the storey column after the id
            widths = (*widths[:2], 5, *widths[2:-2], 16, 4)
        _column_table(ax, head, chunk, widths, fs)
        more = f" ({p + 1}/{len(chunks)})" if len(chunks) > 1 else ""
        fig.text(MARGIN_MM / w, 1 - 8.0 / h, f"camera schedule{more}: DORI distances along the optical axis "
                 f"(identify / recognise / observe / detect)", fontsize=11, weight="bold", va="top")
        _title_block(fig, data, data.sheet(3, f"camera schedule{more}"))
        figs.append(fig)
    return figs


def views_figure(data: PlanData):
    """Page 4: a grid of the camera views (as report.html renders them)."""
    fig = _figure(data.paper)
    w, h = page_size_mm(data.paper)
    views = data.views
    fig.text(MARGIN_MM / w, 1 - 8.0 / h, "camera views: what each camera sees, dots = the targets it covers "
             "(coloured by coverage class)", fontsize=11, weight="bold", va="top")
    if views:
        _views_mosaic(fig, data, views)
    missing = len(data.cameras) - len(views)
    if missing:
        fig.text(MARGIN_MM / w, (MARGIN_MM + 44.0) / h, f"{missing} views not rendered within the time budget "
                 "(camplace render draws any camera).", fontsize=7)
    _title_block(fig, data, data.sheet(4, "camera views"))
    return fig


def _views_mosaic(fig, data: PlanData, views: list[dict]) -> None:
    """The views pasted into one image (one embedded picture, pixels as rendered: no
    resampling), a grid of ncol columns, each titled with its mark and id."""
    from PIL import Image

    w, h = page_size_mm(data.paper)
    imgs = [Image.open(io.BytesIO(base64.b64decode(v["uri"].split(",", 1)[1]))).convert("RGB") for v in views]
    cw, ch = max(i.width for i in imgs), max(i.height for i in imgs)
    pad, head = max(4, cw // 30), max(12, ch // 9)  # px between cells, px above each for its title
    area = (w - 2 * MARGIN_MM, h - 18.0 - MARGIN_MM - 50.0)
    ncol = min(len(imgs), max(1, round(math.sqrt(len(imgs) * area[0] * (ch + head) / (area[1] * (cw + pad))))))
    nrow = math.ceil(len(imgs) / ncol)
    W, H = ncol * (cw + pad), nrow * (ch + head + pad)
    mosaic = Image.new("RGB", (W, H), "white")
    for k, im in enumerate(imgs):
        mosaic.paste(im, ((k % ncol) * (cw + pad) + (cw - im.width) // 2, (k // ncol) * (ch + head + pad) + head))
    s = min(area[0] / W, area[1] / H)  # mm per pixel
    ax = fig.add_axes((MARGIN_MM / w, 1 - (18.0 + H * s) / h, W * s / w, H * s / h))
    ax.imshow(np.asarray(mosaic), interpolation="none", extent=(0, W, H, 0))  # embedded as is: no resampling
    ax.set_xlim(0, W)
    ax.set_ylim(H, 0)
    ax.set_axis_off()
    marks = {int(c["candidate_id"]): m for c, m in zip(data.cameras, data.marks)}
    for k, v in enumerate(views):
        ax.text((k % ncol) * (cw + pad) + cw / 2, (k // ncol) * (ch + head + pad) + head * 0.85,
                f"{marks.get(int(v['id']), '')} (id {v['id']})", fontsize=6, ha="center", va="bottom")


def write_plan_pdf(path: str | Path, data: PlanData, plan_fig=None, extra_sheets=()) -> Path:
    """Write plan.pdf (plan_pdf_bytes) atomically."""
    return atomic_write_bytes(Path(path), plan_pdf_bytes(data, plan_fig, extra_sheets))


def plan_pdf_bytes(data: PlanData, plan_fig=None, extra_sheets=()) -> bytes:
    """plan.pdf: every page above, then ``extra_sheets`` (e.g. the bill of materials of
    camplace.outputs.plan_bom; figures, or one callable making them); ``plan_fig``: sheet 1
    when already drawn by plan_figure. Repeatable runs (data.dated None) carry no creation date."""
    def pages():
        yield plan_fig or plan_figure(data)
        yield coverage_figure(data)
        yield from schedule_figures(data)
        yield views_figure(data)
        yield from (extra_sheets() if callable(extra_sheets) else extra_sheets)

    return pdf_pages_bytes(data, pages)


def pdf_pages_bytes(data: PlanData, pages) -> bytes:
    """The figures ``pages()`` makes (under the plan set's rc settings, each drawn as it comes)
    as one PDF, with ``data``'s title in its metadata (no creation date when data.dated is None)."""
    from matplotlib import rc_context
    from matplotlib.backends.backend_pdf import PdfPages

    buf = io.BytesIO()
    meta = {"Title": f"camplace plan: {data.placement.get('scene', data.scene.name)}", "Creator": "camplace"}
    if data.dated is None:
        meta["CreationDate"] = None
    with rc_context(RC), pdf_layout_cache(), PdfPages(buf, metadata=meta) as buf_pages:  # each string laid out once
        for fig in pages():
            fig.savefig(buf_pages, format="pdf")
    return buf.getvalue()


def plan_svg(data: PlanData, plan_fig=None) -> str:
    """Page 1 (``plan_fig`` when already drawn) as an SVG document (text kept as text; no date
    in repeatable runs)."""
    from matplotlib import rc_context

    buf = io.StringIO()
    with rc_context(RC):
        (plan_fig or plan_figure(data)).savefig(buf, format="svg", metadata={"Date": None} if data.dated is None else None)
    return buf.getvalue()
