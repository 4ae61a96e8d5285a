"""Plan images (PNG/JPG/TIFF, e.g. a scan of a paper plan) -> a scene mapping
(camplace.scene.importers.import_plan).

Scale from ``scale`` (m per pixel) or ``ref`` (two pixel points and their distance in
m). Wall pixels are the dark ones (Otsu threshold unless ``threshold`` 0..255 is
given), thinner strokes than ``min_wall_thickness`` m (text, door swings, dimension
lines) removed by a morphological opening; the wall mask is polygonised (contourpy,
simplified) and extruded to the wall height. Rooms are the enclosed free regions:
connected free pixels not touching the image border, separated at door gaps up to
``door_width`` m wide; they become zones room-1..n (top to bottom, left to right).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy import ndimage
from shapely.geometry import Polygon

from camplace.core.errors import InputError
from camplace.scene.importers import (DEFAULT_CEILING_M, PlanImport, plan_scene, prism_obstacles, room_zones,
                                      rooms_footprint)

OPTIONS = ("scale", "ref", "threshold", "min_wall_thickness", "door_width", "min_room_area")
MAX_PIXELS = 100_000_000


def read_gray(path: Path) -> np.ndarray:
    """(H, W) float64 grey levels 0..255 of an image file."""
    from PIL import Image, UnidentifiedImageError

    Image.MAX_IMAGE_PIXELS = MAX_PIXELS
    try:
        with Image.open(path) as im:
            return np.asarray(im.convert("L"), np.float64)
    except (UnidentifiedImageError, OSError, Image.DecompressionBombError) as err:
        raise InputError(f"{path}: not a readable image ({str(err).splitlines()[0]})") from None


def otsu_threshold(gray: np.ndarray) -> float:
    """The grey level (0..255) that best splits ``gray`` into two classes (Otsu)."""
    hist = np.bincount(np.clip(gray, 0, 255).astype(np.int64).ravel(), minlength=256).astype(float)
    w0 = np.cumsum(hist)
    m0 = np.cumsum(hist * np.arange(256))
    total, mean = w0[-1], m0[-1]
    w1 = total - w0
    with np.errstate(divide="ignore", invalid="ignore"):
        between = (mean * w0 - total * m0) ** 2 / (w0 * w1)
    between[~np.isfinite(between)] = -1
    return float(np.argmax(between)) + 0.5


def metres_per_pixel(path: Path, scale: float | None, ref) -> float:
    if scale is not None:
        if not scale > 0:
            raise InputError(f"scale: expected metres per pixel > 0, got {scale}", option="scale")
        return float(scale)
    if ref is not None:
        x1, y1, x2, y2, dist = (float(v) for v in ref)
        px = math.hypot(x2 - x1, y2 - y1)
        if px <= 0 or not dist > 0:
            raise InputError(f"ref: expected two distinct points and a distance > 0 m, got {list(ref)}", option="ref")
        return dist / px
    raise InputError(f"{path}: the plan's scale is unknown; give metres per pixel (scale) or two reference points "
                     "and their distance (ref)", option="scale")


def mask_polygons(mask: np.ndarray, s: float, at: tuple[int, int] = (0, 0), image_rows: int | None = None):
    """Shapely (multi)polygon (m) of the True pixels of ``mask`` (h, w), a window at
    pixel ``at`` (row, col) of an image of ``image_rows`` rows (default: the mask is the
    image): row 0 at the top, pixel (r, c) centred at x = (c + 0.5) s, y = (H - r - 0.5) s."""
    import contourpy
    import shapely

    h, w = mask.shape
    z = np.pad(mask.astype(np.float64), 1)[::-1]  # row 0 = bottom (y up)
    x = (at[1] + np.arange(w + 2) - 0.5) * s
    y = ((image_rows or h) - at[0] - h + np.arange(h + 2) - 0.5) * s
    gen = contourpy.contour_generator(x, y, z, fill_type=contourpy.FillType.OuterOffset, corner_mask=False)
    points, offsets = gen.filled(0.5, 1.5)
    polys = []
    for pts, off in zip(points, offsets):
        rings = [pts[a:b] for a, b in zip(off[:-1], off[1:]) if b - a >= 4]
        if rings:
            polys.append(shapely.make_valid(Polygon(rings[0], rings[1:])))
    return shapely.unary_union(polys) if polys else Polygon()


def square_morphology(mask: np.ndarray, px: float, op: str) -> np.ndarray:
    """Binary ``op`` ('open' or 'close') of ``mask`` by a square of about ``px`` pixels
    (odd, centred; separable min / max filters, so fast for large squares)."""
    k = 2 * int(round(px / 2)) + 1
    m = mask.astype(np.uint8)
    first, second = (ndimage.minimum_filter, ndimage.maximum_filter) if op == "open" else \
        (ndimage.maximum_filter, ndimage.minimum_filter)
    return second(first(m, size=k, mode="nearest"), size=k, mode="nearest").astype(bool)


def import_plan(path: Path, *, name: str | None = None, units: str | None = None, wall_height: float | None = None,
                ceiling_height: float | None = None, heights=None, coverage: int | None = None,
                budget: int | None = None, scale: float | None = None, ref=None, threshold: float | None = None,
                min_wall_thickness: float = 0.05, door_width: float = 1.0, min_room_area: float = 1.0) -> dict:
    """The scene mapping of a plan image (lengths in m; ``units`` is refused: the scale says it)."""
    if units is not None:
        raise InputError("units: a plan image has no units; give its scale (scale or ref)", option="units")
    gray = read_gray(path)
    s = metres_per_pixel(path, scale, ref)
    t = otsu_threshold(gray) if threshold is None else float(threshold)
    walls = square_morphology(gray < t, min_wall_thickness / s, "open")
    if walls.sum() == 0:
        raise InputError(f"{path}: no walls found (no dark strokes at least {min_wall_thickness} m thick)")
    shut = square_morphology(walls, door_width / s, "close") | walls
    labels, n = ndimage.label(~shut)
    border = np.unique(np.r_[labels[0], labels[-1], labels[:, 0], labels[:, -1]])
    sizes = ndimage.sum_labels(np.ones_like(labels), labels, index=np.arange(1, n + 1)) * s * s
    keep = [k for k in range(1, n + 1) if k not in border and sizes[k - 1] >= min_room_area]
    if not keep:
        raise InputError(f"{path}: no closed room found (no free region of at least {min_room_area} m² "
                         "enclosed by walls)")
    ceiling = float(ceiling_height or DEFAULT_CEILING_M)
    wall_geom = mask_polygons(walls, s).simplify(s / 2)
    boxes = ndimage.find_objects(labels)
    rooms = [(f"room-{i + 1}", mask_polygons(labels[boxes[k - 1]] == k, s, (boxes[k - 1][0].start,
                                                                             boxes[k - 1][1].start),
                                             len(labels)).simplify(s / 2)) for i, k in enumerate(keep)]
    src = {"file": path.name, "entity": "wall pixels", "threshold": f"{t:g}", "m_per_px": f"{s:g}"}
    obstacles = prism_obstacles(wall_geom, 0.0, min(float(wall_height or ceiling), ceiling), "wall", src,
                                tolerance=0)
    footprint = rooms_footprint([p for _, p in rooms], wall_geom, door_width, str(path))
    return plan_scene(name or path.stem, footprint, ceiling, obstacles, room_zones(rooms, coverage or 2),
                      heights=heights, coverage=coverage, budget=budget)


def read(path: Path, **options) -> PlanImport:
    """What was understood of the plan (options as import_plan)."""
    return PlanImport(import_plan(path, **options), "image")
