"""Rendered camera views (the paper's Fig. 3b) and top-down view footprints.

``render_view`` raycasts one ray per pixel of a reduced-resolution copy of the camera
(same lens model, intrinsics scaled) through the occupancy grid with the compiled
ray walking of camplace.visibility.raywalk, and colours each pixel by what it hits:
floor, walls and ceiling in neutral greys, each obstacle in its own colour, shaded by
depth (and dimmed beyond the camera's max range). ``view_figure_png`` draws that image
with the targets the camera covers overlaid (projected target centres) next to a
top-down map of its footprint (where its rays end). Everything here draws what it is
given (scene, camera model, pose, targets, covered ids); rebuilding those from a scene
name or an output folder is camplace.workflows.render. Nothing here prints.
"""

from __future__ import annotations

import functools
import io
from dataclasses import dataclass

import numpy as np

from camplace.cameras.models import CameraModel
from camplace.scene.build import Scene
from camplace.targets.build import Targets
from camplace.visibility.raywalk import BOUNDARY, cast_rays, free_distance

FREE, WALL, FLOOR, CEILING, OTHER = 0, 1, 2, 3, 4  # labels; obstacle k (scene.boxes order) = 5 + k
NEUTRAL = {WALL: (0.80, 0.80, 0.78), FLOOR: (0.62, 0.62, 0.60), CEILING: (0.92, 0.92, 0.90),
           OTHER: (0.55, 0.50, 0.45), FREE: (0.0, 0.0, 0.0)}
FACE_LIGHT = (0.80, 0.90, 1.0)  # brightness of faces hit across x, y, z


@dataclass(frozen=True)
class RenderedView:
    """A synthetic camera image. rgb: (h, w, 3) float in [0, 1]; depth: (h, w) metres
    along the ray (inf = nothing hit); labels: (h, w) int16 (FREE/WALL/FLOOR/CEILING/
    OTHER or 5 + obstacle index); hits: (h, w, 3) world points where rays end; scale:
    render pixels per camera pixel; names: label -> name."""

    rgb: np.ndarray
    depth: np.ndarray
    labels: np.ndarray
    hits: np.ndarray
    scale: float
    names: dict


def label_grid(scene: Scene) -> tuple[np.ndarray, dict]:
    """(nx, ny, nz) int16 label of every occupancy cell and label -> name."""
    occ = scene.occupancy
    lab = np.where(occ.occupied, WALL, FREE).astype(np.int16)
    zs = occ.cell_centres(2)
    lab[:, :, zs < 0] = np.where(occ.occupied[:, :, zs < 0], FLOOR, FREE)
    lab[:, :, zs > scene.height] = np.where(occ.occupied[:, :, zs > scene.height], CEILING, FREE)
    names = {WALL: "wall", FLOOR: "floor", CEILING: "ceiling", OTHER: "other"}
    inside_room = lab == WALL
    xs, ys = occ.cell_centres(0), occ.cell_centres(1)
    from shapely import contains_xy

    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    in_fp = contains_xy(scene.polygon, gx, gy)
    lab[inside_room & in_fp[:, :, None]] = OTHER  # occupied inside the room: an obstacle (scan, mesh, ...)
    for k, (name, (bmin, bmax)) in enumerate(scene.boxes.items()):
        sl = []
        for a in range(3):
            c = occ.cell_centres(a)
            idx = np.nonzero((c >= bmin[a]) & (c <= bmax[a]))[0]
            sl.append(slice(idx[0], idx[-1] + 1) if len(idx) else slice(0, 0))
        block = lab[sl[0], sl[1], sl[2]]
        block[block == OTHER] = 5 + k
        names[5 + k] = name
    return lab, names


def obstacle_colours(n: int) -> np.ndarray:
    """(n, 3) distinct colours (matplotlib tab10/tab20 cycle)."""
    from matplotlib import colormaps

    cmap = colormaps["tab20"] if n > 10 else colormaps["tab10"]
    return np.array([cmap(k % cmap.N)[:3] for k in range(n)])


def scene_grids(scene: Scene) -> tuple[tuple[np.ndarray, dict], np.ndarray]:
    """What ``render_view`` reads of a scene, computed once for many views: (``label_grid(scene)``,
    the occupancy's free distance (nx, ny, nz) uint8, camplace.visibility.raywalk.free_distance)."""
    return label_grid(scene), free_distance(scene.occupancy)


def scaled_camera(cam: CameraModel, width: int) -> CameraModel:
    """The same lens at a lower resolution (``width`` pixels wide, same field of view)."""
    s = min(1.0, width / cam.width)
    w, h = max(2, int(round(cam.width * s))), max(2, int(round(cam.height * s)))
    sx, sy = w / cam.width, h / cam.height
    return CameraModel(cam.name, cam.model, w, h, cam.fx * sx, cam.fy * sy, (cam.cx + 0.5) * sx - 0.5,
                       (cam.cy + 0.5) * sy - 0.5, cam.max_range, cam.distortion, cam.cost, cam.max_fov_deg)


@functools.lru_cache(maxsize=16)
def _pixel_rays(camera: CameraModel) -> np.ndarray:
    """``camera.pixel_rays(1)``, read-only, kept for the next view of the same (scaled) camera
    type: a report renders every selected camera, most of one or two types."""
    rays = camera.pixel_rays(1)
    rays.flags.writeable = False
    return rays


def render_view(scene: Scene, camera: CameraModel, position: np.ndarray, rotation: np.ndarray,
                width: int = 480, labels: tuple[np.ndarray, dict] | None = None,
                dist: np.ndarray | None = None) -> RenderedView:
    """Raycast the image of ``camera`` at ``position`` (3,) m with world-from-camera
    ``rotation`` (3, 3) at ``width`` pixels wide. When rendering many views of one scene,
    pass ``labels`` (a cached ``label_grid(scene)``) and ``dist`` (a cached
    ``free_distance(scene.occupancy)``, (nx, ny, nz) uint8) so that they are computed
    once; the image is the same either way."""
    small = scaled_camera(camera, width)
    lab, names = labels if labels is not None else label_grid(scene)
    occ = scene.occupancy
    if dist is None:
        dist = free_distance(occ)
    elif dist.shape != occ.shape:
        raise ValueError(f"dist: expected the occupancy grid's shape {occ.shape}, got {dist.shape}")
    rays_c = _pixel_rays(small)
    R = np.asarray(rotation, float)
    dirs = np.ascontiguousarray(rays_c @ R.T)
    n = len(dirs)
    diag = float(np.linalg.norm(np.array(occ.shape) * occ.resolution)) + 1.0
    p = np.asarray(position, float)
    t, cell, axis = cast_rays(occ.occupied, dist, occ.origin, occ.resolution, p, dirs, diag)
    shape = np.array(occ.shape)
    inside = np.all((cell >= 0) & (cell < shape), axis=1) & np.isfinite(t)
    lbl = np.full(n, FREE, np.int16)
    ci = cell[inside]
    lbl[inside] = lab[ci[:, 0], ci[:, 1], ci[:, 2]]
    lbl[np.isfinite(t) & ~inside] = WALL  # left the grid: the room's outer shell
    lbl[(axis == BOUNDARY) & (t == 0)] = OTHER  # camera inside an obstacle
    box_cols = obstacle_colours(max(1, len(scene.boxes)))
    base = np.zeros((n, 3))
    for k, c in NEUTRAL.items():
        base[lbl == k] = c
    obs = lbl >= 5
    base[obs] = box_cols[(lbl[obs] - 5) % len(box_cols)]
    light = np.where(axis >= 0, np.take(np.array(FACE_LIGHT), np.clip(axis, 0, 2)), 1.0)
    tf = np.where(np.isfinite(t), t, diag)
    shade = light * (1.0 - 0.55 * np.clip(tf / max(diag * 0.6, 1e-9), 0, 1))
    shade = np.where(tf > camera.max_range, shade * 0.55, shade)  # beyond range: dimmed
    rgb = np.clip(base * shade[:, None], 0, 1)
    hits = p + dirs * tf[:, None]
    h, w = small.height, small.width
    return RenderedView(rgb.reshape(h, w, 3), np.where(np.isfinite(t), t, np.inf).reshape(h, w),
                        lbl.reshape(h, w), hits.reshape(h, w, 3), small.width / camera.width, names)


def covered_pixels(camera: CameraModel, position: np.ndarray, rotation: np.ndarray, points: np.ndarray,
                   scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Project world points (N, 3) into the camera: (uv (N, 2) in render pixels, valid (N,))."""
    pc = (np.asarray(points, float) - np.asarray(position, float)) @ np.asarray(rotation, float)
    uv, ok = camera.project(pc)
    return (uv + 0.5) * scale - 0.5, ok


def view_figure_png(scene: Scene, view: RenderedView, camera: CameraModel, position: np.ndarray,
                    rotation: np.ndarray, targets: Targets | None = None, covered: np.ndarray | None = None,
                    title: str = "") -> bytes:
    """PNG bytes: the rendered image with covered targets overlaid (volume: green dots,
    surface: orange squares) and a top-down footprint of the view."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch
    from matplotlib.patches import Polygon as MplPolygon
    from matplotlib.patches import Rectangle

    h, w = view.labels.shape
    fig = Figure(figsize=(12, 4.8))
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.02, 0.08, 0.56, 0.82))
    ax.imshow(view.rgb, interpolation="nearest")
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title(title or f"{camera.name} view ({camera.model}, {camera.width}x{camera.height} px, rendered {w}x{h})",
                 fontsize=9)
    cols = obstacle_colours(max(1, len(scene.boxes)))
    if targets is not None and covered is not None and len(covered):
        pts = targets.positions[covered]
        uv, ok = covered_pixels(camera, position, rotation, pts, view.scale)
        surf = targets.is_surface[covered]
        for sel, style in ((~surf & ok, dict(c="#2ca02c", marker="o", s=6)),
                           (surf & ok, dict(c="#ff7f0e", marker="s", s=8))):
            if sel.any():
                ax.scatter(uv[sel, 0], uv[sel, 1], alpha=0.75, linewidths=0, **style)
    handles = [Patch(color=cols[k % len(cols)], label=name) for k, name in enumerate(scene.boxes)]
    handles += [Patch(color=NEUTRAL[FLOOR], label="floor"), Patch(color=NEUTRAL[WALL], label="wall")]
    if targets is not None and covered is not None:
        handles += [Patch(color="#2ca02c", label="covered volume targets"),
                    Patch(color="#ff7f0e", label="covered surface targets")]
    ax.legend(handles=handles, fontsize=6, loc="lower left", bbox_to_anchor=(0.0, -0.12), ncol=6, frameon=False)

    ax2 = fig.add_axes((0.62, 0.08, 0.36, 0.82))
    ax2.add_patch(MplPolygon(scene.footprint, closed=True, fill=False, ec="k", lw=1.2))
    for k, (name, (bmin, bmax)) in enumerate(scene.boxes.items()):
        ax2.add_patch(Rectangle((bmin[0], bmin[1]), bmax[0] - bmin[0], bmax[1] - bmin[1],
                                color=cols[k % len(cols)], alpha=0.8))
    hit = view.hits.reshape(-1, 3)
    inr = np.isfinite(view.depth.ravel()) & (view.depth.ravel() <= camera.max_range)
    step = max(1, int(inr.sum() // 6000))
    ax2.scatter(hit[inr][::step, 0], hit[inr][::step, 1], s=1, c="#1f77b4", alpha=0.25, linewidths=0)
    if targets is not None and covered is not None and len(covered):
        pts = targets.positions[covered]
        ax2.scatter(pts[:, 0], pts[:, 1], s=4, c="#2ca02c", alpha=0.5, linewidths=0)
    p = np.asarray(position, float)
    fwd = np.asarray(rotation, float)[:, 2]
    ax2.plot([p[0]], [p[1]], marker="o", color="crimson")
    L = 0.6 + 0.1 * camera.max_range
    if np.hypot(fwd[0], fwd[1]) > 1e-9:
        ax2.annotate("", xy=(p[0] + L * fwd[0] / np.hypot(fwd[0], fwd[1]), p[1] + L * fwd[1] / np.hypot(fwd[0], fwd[1])),
                     xytext=(p[0], p[1]), arrowprops=dict(arrowstyle="->", color="crimson"))
    lo, hi = scene.footprint.min(0), scene.footprint.max(0)
    ax2.set_xlim(lo[0] - 0.3, hi[0] + 0.3)
    ax2.set_ylim(lo[1] - 0.3, hi[1] + 0.3)
    ax2.set_aspect("equal")
    ax2.set_title("top-down footprint (ray ends within range)", fontsize=9)
    ax2.set_xlabel("x (m)", fontsize=8)
    ax2.set_ylabel("y (m)", fontsize=8)
    ax2.tick_params(labelsize=7)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()
