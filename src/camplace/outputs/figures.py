"""PNG figures of a placement (matplotlib, Agg canvas; no pyplot, no global state).

- ``coverage_slice_z<h>m.png``: one per volume-target height, the achieved coverage of
  each target voxel at that height (the paper's Fig. 1 middle), coloured by class
  0 / 1 / 2 / >= 3 (Fig. 2 colours: 1 = blue, 2 = cyan; 0 = red, >= 3 = green), with
  the obstacles that cross the height and the selected cameras (position, heading, id).
- ``coverage_histogram.png``: targets per achieved coverage count, stacked by region.

The slice grids (``coverage_slices``) are shared with the HTML report.
"""

from __future__ import annotations

import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from camplace.core.files import atomic_write_bytes
from camplace.outputs.walls import label_colours, mpl_path, plan_cut, scene_walls

COVERAGE_CLASSES: tuple[tuple[str, str], ...] = (
    ("0 (not seen)", "#d62728"), ("1", "#1f4fd1"), ("2", "#17becf"), ("\u2265 3", "#2ca02c"))
PNG_DPI = 110  # pixels per inch of the PNG figures
PNG_COMPRESS = 2  # zlib level of the PNGs (fast; level 6 is ~10 % smaller and several times slower)
REGION_COLOURS = ("#4c78a8", "#f58518", "#54a24b", "#b279a2", "#e45756", "#72b7b2", "#eeca3b", "#9d755d")


def coverage_class(coverage: np.ndarray) -> np.ndarray:
    """(N,) int achieved coverage -> (N,) int class 0, 1, 2, 3 (3 = three or more)."""
    return np.minimum(np.asarray(coverage, np.int64), 3)


AREA_STYLES = {"privacy": {"edgecolor": "#7b1fa2", "hatch": "xx", "linewidth": 1.2},
               "forbid": {"edgecolor": "#d32f2f", "linestyle": "--", "linewidth": 1.2}}


@dataclass(frozen=True)
class SceneView:
    """What the pictures need of a scene. footprint: (K, 2) m; height: m; boxes: name ->
    (min (3,), max (3,)) m; voxel_size: target grid step (m)."""

    name: str
    footprint: np.ndarray
    height: float
    voxel_size: float
    boxes: dict = field(default_factory=dict)
    areas: tuple = ()  # (kind, (K, 2) corners m): 'privacy' zones and 'forbid' mount areas (issue 17)
    walls: tuple = ()  # camplace.outputs.walls.Wall: prism obstacles (imported walls, issue 18)
    zones: tuple = ()  # (name, (K, 2) corners m): the volume zones (rooms of an imported plan)

    @classmethod
    def from_scene(cls, scene) -> "SceneView":
        """From a camplace.scene.build.Scene (privacy zones and forbidden mount areas, the
        prism obstacles and the named zones included)."""
        areas = tuple(("privacy", np.asarray(z.polygon, float)) for z in scene.spec.zones if z.privacy) + tuple(
            ("forbid", np.asarray(f, float)) for f in scene.spec.mount_rules.forbid)
        zones = tuple((z.name, np.asarray(z.polygon, float)) for z in scene.spec.zones
                      if z.polygon is not None and not z.privacy)
        return cls(scene.name, np.asarray(scene.footprint, float), float(scene.height),
                   float(scene.spec.voxel_size), dict(scene.boxes), areas, scene_walls(scene), zones)

    @classmethod
    def from_targets(cls, name: str, positions: np.ndarray, cameras: list[dict] = ()) -> "SceneView":
        """A stand-in when no scene is at hand: the bounding rectangle of the targets."""
        p = np.asarray(positions, float).reshape(-1, 3)
        cams = np.array([c["position"] for c in cameras], float).reshape(-1, 3)
        allp = np.vstack([p, cams]) if len(cams) else p
        lo, hi = allp.min(0), allp.max(0)
        xs = np.unique(np.round(p[:, 0], 6))
        step = float(np.min(np.diff(xs))) if len(xs) > 1 else 0.25
        fp = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
        return cls(name, fp, float(max(hi[2], 1e-3)), step, {})


@dataclass(frozen=True)
class CoverageSlice:
    """Coverage of the volume targets at one height. x: (nx,), y: (ny,) voxel centres
    (m); coverage: (ny, nx) float, NaN where there is no target; boxes: (name, xmin,
    ymin, xmax, ymax) of the obstacles that cross this height; walls: label -> union of
    the prism obstacles that cross it (shapely, camplace.outputs.walls.plan_cut)."""

    height: float
    x: np.ndarray
    y: np.ndarray
    coverage: np.ndarray
    boxes: list
    walls: dict = field(default_factory=dict)


def label_point(corners: np.ndarray) -> tuple[float, float]:
    """A point inside a polygon (K, 2) m where its name goes (shapely's representative point)."""
    from shapely.geometry import Polygon as SPolygon

    p = SPolygon(np.asarray(corners, float)).representative_point()
    return float(p.x), float(p.y)


def coverage_slices(view: SceneView, positions: np.ndarray, is_surface: np.ndarray,
                    coverage: np.ndarray) -> list[CoverageSlice]:
    """One CoverageSlice per distinct height of the volume targets (ascending)."""
    pos = np.asarray(positions, float)
    vol = ~np.asarray(is_surface, bool)
    if not vol.any():
        return []
    p, c = pos[vol], np.asarray(coverage, float)[vol]
    v = float(view.voxel_size)
    x0, y0 = p[:, 0].min(), p[:, 1].min()
    ix = np.rint((p[:, 0] - x0) / v).astype(np.int64)
    iy = np.rint((p[:, 1] - y0) / v).astype(np.int64)
    nx, ny = int(ix.max()) + 1, int(iy.max()) + 1
    xs, ys = x0 + v * np.arange(nx), y0 + v * np.arange(ny)
    zr = np.round(p[:, 2], 6)
    out = []
    for h in np.unique(zr):
        m = zr == h
        grid = np.full((ny, nx), np.nan)
        grid[iy[m], ix[m]] = c[m]
        boxes = [(name, float(b[0][0]), float(b[0][1]), float(b[1][0]), float(b[1][1]))
                 for name, b in view.boxes.items() if b[0][2] <= h <= b[1][2]]
        out.append(CoverageSlice(float(h), xs, ys, grid, boxes, plan_cut(view.walls, float(h))[0]))
    return out


def _png(fig) -> bytes:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=PNG_DPI, pil_kwargs={"compress_level": PNG_COMPRESS})
    return buf.getvalue()


def _slice_figure(view: SceneView, overlay: bool):
    """(figure, axes) of a coverage-slice picture at PNG_DPI on a transparent background:
    the footprint's extent, equal aspect, room for the legend on the right. ``overlay``:
    with the axes frame, ticks and labels; else the axes drawn bare (the overlay brings them)."""
    from matplotlib.figure import Figure

    fp = np.asarray(view.footprint, float)
    w, h = np.ptp(fp[:, 0]), np.ptp(fp[:, 1])
    fig = Figure(figsize=(min(12.0, 2.0 + 7.5 * w / max(w, h)) + 1.8, min(10.0, 1.2 + 7.5 * h / max(w, h))),
                 dpi=PNG_DPI)
    ax = fig.add_subplot(1, 1, 1)
    ax.set_xlim(fp[:, 0].min() - 0.2, fp[:, 0].max() + 0.2)
    ax.set_ylim(fp[:, 1].min() - 0.2, fp[:, 1].max() + 0.2)
    ax.set_aspect("equal")
    fig.subplots_adjust(left=0.07, right=0.80, bottom=0.08, top=0.93)
    fig.patch.set_alpha(0.0)
    ax.patch.set_alpha(0.0)
    if overlay:
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    else:
        ax.set_axis_off()
    return fig, ax


def _cell_pixels(ax, sl: CoverageSlice, v: float, hw: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """(flat pixel indices, flat grid indices (iy * nx + ix)) of the pixels of an (H, W)
    figure whose centre lies inside the axes and in a voxel of the slice grid (the cells of
    ``sl``, edge ``v`` m): the coverage image drawn by hand, as imshow's nearest neighbour."""
    h, w = hw
    ax.apply_aspect()
    bb = ax.bbox
    inv = ax.transData.inverted()
    cx, cy = np.arange(w) + 0.5, h - (np.arange(h) + 0.5)  # pixel centres in display coordinates (y up)
    xd = inv.transform(np.c_[cx, np.full(w, bb.y0)])[:, 0]
    yd = inv.transform(np.c_[np.full(h, bb.x0), cy])[:, 1]
    ix = np.floor((xd - (sl.x[0] - v / 2)) / v).astype(np.int64)
    iy = np.floor((yd - (sl.y[0] - v / 2)) / v).astype(np.int64)
    okx = (ix >= 0) & (ix < len(sl.x)) & (cx >= bb.x0) & (cx <= bb.x1)
    oky = (iy >= 0) & (iy < len(sl.y)) & (cy >= bb.y0) & (cy <= bb.y1)
    rows, cols = np.nonzero(oky)[0], np.nonzero(okx)[0]
    return (rows[:, None] * w + cols[None, :]).ravel(), (iy[rows][:, None] * len(sl.x) + ix[cols][None, :]).ravel()


def _static_overlay(view: SceneView, cameras: list[dict]):
    """The parts of every slice picture that do not change with the height, on a
    transparent figure: forbidden/privacy areas, rooms and their names, the cameras (arrows,
    ids) and the axes. Returns (figure, the areas' legend handles)."""
    from matplotlib.patches import Patch, Polygon

    fig, ax = _slice_figure(view, overlay=True)
    fp = np.asarray(view.footprint, float)
    w, h = np.ptp(fp[:, 0]), np.ptp(fp[:, 1])
    area_handles = []
    for kind, corners in view.areas:  # privacy zones (purple, hatched) and forbidden mount areas (red, dashed)
        style = AREA_STYLES[kind]
        ax.add_patch(Polygon(corners, closed=True, fill=False, zorder=2.5, **style))
        if kind not in [h.get_label() for h in area_handles]:
            area_handles.append(Patch(fill=False, label=kind, **style))
    for name, corners in view.zones:  # rooms: thin green outline, name in italics
        ax.add_patch(Polygon(corners, closed=True, fill=False, edgecolor="#1b7837", linewidth=0.7, zorder=2.4))
        ax.text(*label_point(corners), name, fontsize=7, color="#1b7837", style="italic", ha="center", va="center",
                zorder=3.5, bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.6, "pad": 0.4})
    if cameras:
        pos = np.array([c["position"] for c in cameras], float)
        fwd = np.array([np.asarray(c["rotation"], float)[:2, 2] for c in cameras])
        fwd /= np.maximum(np.linalg.norm(fwd, axis=1, keepdims=True), 1e-9)
        ax.quiver(pos[:, 0], pos[:, 1], fwd[:, 0], fwd[:, 1], angles="xy", scale_units="xy",
                  scale=1.0 / (0.06 * max(w, h)), width=0.003, color="black", zorder=3)
        ax.plot(pos[:, 0], pos[:, 1], "o", color="black", markersize=3, zorder=3)
        for cam, (x, y) in zip(cameras, pos[:, :2]):
            ax.text(x, y, f" {cam.get('candidate_id', '')}", fontsize=6, color="black", va="bottom", clip_on=False)
    return fig, area_handles


def _rgba(fig) -> np.ndarray:
    """(H, W, 4) uint8 straight-alpha pixels of ``fig`` drawn on an Agg canvas."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    canvas.draw()
    return np.array(canvas.buffer_rgba())


def over(top: np.ndarray, base: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8: straight-alpha RGBA ``top`` (H, W, 4) composited over the opaque
    ``base`` (H, W, 3 or 4); only the pixels ``top`` covers are computed."""
    out = np.ascontiguousarray(base[..., :3])
    m = np.flatnonzero(top[..., 3])
    t, o = top.reshape(-1, 4)[m], out.reshape(-1, 3)
    a = t[:, 3:4].astype(np.float32) * (1.0 / 255.0)
    o[m] = (t[:, :3] * a + o[m] * (1.0 - a) + 0.5).astype(np.uint8)
    return out


def _slice_pixels(top: np.ndarray, layer: np.ndarray, pix: np.ndarray, rgb: np.ndarray) -> bytes:
    """PNG of one slice: white, the coverage colours ``rgb`` at flat pixels ``pix``, then the
    slice's ``layer`` (obstacles, legend, title) and the cameras' ``top`` (RGBA) over them."""
    h, w = top.shape[:2]
    img = np.full((h * w, 3), 255, np.uint8)
    img[pix] = rgb
    return png_bytes(over(top, over(layer, img.reshape(h, w, 3))))


def png_bytes(rgb: np.ndarray) -> bytes:
    """PNG bytes of (H, W, 3 or 4) uint8 pixels (Pillow, zlib level PNG_COMPRESS; releases the GIL)."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, format="PNG", compress_level=PNG_COMPRESS)
    return buf.getvalue()


def slice_figures_png(slices: list[CoverageSlice], view: SceneView, cameras: list[dict] = ()) -> list[bytes]:
    """PNG bytes of each coverage slice (obstacles hatched, cameras as arrows with ids).

    Drawn once, reused: the parts that do not change with the height (cameras and their ids,
    rooms, areas, axes: most of the text) are drawn once on a transparent overlay; each slice
    draws only its obstacles, legend and title on one reused transparent figure; the coverage
    colours are set pixel by pixel (``_cell_pixels``, no image resampling) and the layers laid
    over them on a second thread, which also encodes the PNG, while the next slice draws."""
    from concurrent.futures import ThreadPoolExecutor

    from matplotlib.patches import Patch, PathPatch, Polygon, Rectangle

    if not slices:
        return []
    v = view.voxel_size
    overlay_fig, area_handles = _static_overlay(view, list(cameras))
    top = _rgba(overlay_fig)
    fig, ax = _slice_figure(view, overlay=False)
    pix, cell = _cell_pixels(ax, slices[0], v, top.shape[:2])
    colours = np.array([[int(c[1:3], 16), int(c[3:5], 16), int(c[5:7], 16)] for _, c in COVERAGE_CLASSES], np.uint8)
    ax.add_patch(Polygon(np.asarray(view.footprint, float), closed=True, fill=False, edgecolor="black", linewidth=1.2))
    wall_colours = label_colours([k for sl in slices for k in sl.walls])
    pending = []
    with ThreadPoolExecutor(1, thread_name_prefix="camplace-png") as pool:
        for sl in slices:
            cls = np.where(np.isnan(sl.coverage), np.nan, np.minimum(sl.coverage, 3))
            boxes = [ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor="#bdbdbd", edgecolor="#555555",
                                            hatch="//", linewidth=0.8, zorder=2)) for _, x0, y0, x1, y1 in sl.boxes]
            paths = [(k, mpl_path(g)) for k, g in sl.walls.items()]
            boxes += [ax.add_patch(PathPatch(p, facecolor=wall_colours[k], edgecolor="black", linewidth=0.3,
                                             zorder=2.2)) for k, p in paths if p is not None]
            counts = np.bincount(cls[~np.isnan(cls)].astype(np.int64), minlength=4)
            ax.legend(handles=[Patch(color=c, label=f"{lab}: {n}") for (lab, c), n in zip(COVERAGE_CLASSES, counts)]
                      + area_handles + [Patch(facecolor=wall_colours[k], edgecolor="black", label=k) for k in sl.walls],
                      title="cameras seeing", loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8,
                      title_fontsize=8)
            ax.set_title(f"{view.name}: coverage at z = {sl.height:.2f} m", y=1.0)  # y: no search for tick labels
            layer = _rgba(fig)
            k = np.nan_to_num(cls, nan=-1.0).astype(np.int64).ravel()[cell]
            pending.append(pool.submit(_slice_pixels, top, layer, pix[k >= 0], colours[k[k >= 0]]))
            for b in boxes:
                b.remove()
        return [f.result() for f in pending]


def slice_figure_png(sl: CoverageSlice, view: SceneView, cameras: list[dict] = ()) -> bytes:
    """PNG bytes of one coverage slice."""
    return slice_figures_png([sl], view, cameras)[0]


def histogram_figure_png(histograms: dict[str, dict[str, int]], gammas: dict[str, int] | None = None,
                         title: str = "") -> bytes:
    """PNG bytes of the coverage histogram: histograms = region -> {"k": targets seen by k
    cameras}; bars stacked by region; a dashed line at each region's required Γ."""
    from matplotlib.figure import Figure

    kmax = max([int(k) for h in histograms.values() for k in h] + [0])
    ks = np.arange(kmax + 1)
    fig = Figure(figsize=(7.5, 4.0))
    ax = fig.add_subplot(1, 1, 1)
    bottom = np.zeros(len(ks))
    for n, (name, hist) in enumerate(histograms.items()):
        vals = np.array([hist.get(str(k), 0) for k in ks], float)
        ax.bar(ks, vals, bottom=bottom, color=REGION_COLOURS[n % len(REGION_COLOURS)], label=name, width=0.8)
        bottom += vals
        if gammas and name in gammas:
            ax.axvline(gammas[name] - 0.5, color=REGION_COLOURS[n % len(REGION_COLOURS)], linestyle="--", linewidth=1)
    ax.set_xticks(ks)
    ax.set_xlabel("cameras seeing the target (achieved coverage)")
    ax.set_ylabel("targets")
    ax.set_title(title or "coverage histogram (dashed: required \u0393 per region)")
    ax.legend(fontsize=8)
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.12, top=0.92)  # tight_layout's margins, without its search
    return _png(fig)


def slice_png_name(height: float) -> str:
    return f"coverage_slice_z{height:.2f}m.png"


def write_figures(out_dir: str | Path, view: SceneView, positions: np.ndarray, is_surface: np.ndarray,
                  coverage: np.ndarray, cameras: list[dict], histograms: dict[str, dict[str, int]],
                  gammas: dict[str, int] | None = None,
                  slices: list[CoverageSlice] | None = None) -> dict[str, Path]:
    """Write the slice PNGs and coverage_histogram.png into out_dir; name -> path."""
    out = Path(out_dir)
    if slices is None:
        slices = coverage_slices(view, positions, is_surface, coverage)
    paths = {}
    names = {slice_png_name(s.height) for s in slices}
    for stale in out.glob("coverage_slice_z*m.png"):  # heights of an earlier run into the same folder
        if stale.name not in names:
            stale.unlink()
    for s, png in zip(slices, slice_figures_png(slices, view, cameras)):
        paths[slice_png_name(s.height)] = atomic_write_bytes(out / slice_png_name(s.height), png)
    paths["coverage_histogram.png"] = atomic_write_bytes(
        out / "coverage_histogram.png", histogram_figure_png(histograms, gammas, f"{view.name}: coverage histogram"))
    return paths
