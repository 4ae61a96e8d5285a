"""Plan images: door and window gaps bridged, rooms as the enclosed free regions, and
both turned into polygons in metres (pixel masks in, shapely out).

Pixels are (row, col), row 0 at the top; ``s`` is the scale in m per pixel. A pixel
(r, c) is centred at x = (c + 0.5) s, y = (H - r - 0.5) s (H: the image's rows).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage
from shapely.geometry import Polygon

from camplace.scene.importers.image_walls import EIGHT, odd


def _line(mask: np.ndarray, length: int, axis: int, op: str) -> np.ndarray:
    """Binary ``op`` ('open' / 'close') of ``mask`` by a line of ``length`` pixels along ``axis``."""
    size = (length, 1) if axis == 0 else (1, length)
    m = mask.astype(np.uint8)
    first, second = (ndimage.minimum_filter, ndimage.maximum_filter) if op == "open" else \
        (ndimage.maximum_filter, ndimage.minimum_filter)
    return second(first(m, size=size, mode="nearest"), size=size, mode="nearest").astype(bool)


def bridge_openings(walls: np.ndarray, s: float, max_opening_m: float, max_wall_m: float) -> np.ndarray:
    """Pixels that close the door and window gaps of ``walls`` (H, W) bool. Along each
    axis, a run of free pixels up to ``max_opening_m`` long between two wall pixels is a
    gap when a wall running along that axis (no thicker across than ``max_wall_m``) ends
    at one of its two ends: a door beside a corner is a gap, a room or corridor between
    two wall faces is not. Gaps thicker across than a wall are not bridged either."""
    gap, thick = odd(max_opening_m / s, 3), int(round(max_wall_m / s)) + 1
    out = np.zeros_like(walls)
    for along in (1, 0):
        across = 1 - along
        pieces = walls & ~_line(walls, thick, across, "open")  # thin across: walls running along this axis
        added = _line(walls, gap, along, "close") & ~walls
        row = np.zeros((3, 3), bool)
        row[1, :] = True
        runs, n = ndimage.label(added, row if along == 1 else row.T)
        if n == 0:
            continue
        touch = added & (np.roll(pieces, 1, axis=along) | np.roll(pieces, -1, axis=along))
        ends = np.r_[False, ndimage.maximum(touch, runs, np.arange(1, n + 1)) > 0][runs]
        out |= _between_rooms(ends & ~_line(ends, thick, across, "open"), walls, across)
    return out


def _between_rooms(bridges: np.ndarray, walls: np.ndarray, across: int) -> np.ndarray:
    """The bridges with free space on both sides across (a gap through a wall), not those
    lying along a wall's face (a run between two bumps of one wall): at most a quarter
    of the pixels bordering a bridge across are wall."""
    lab, n = ndimage.label(bridges, EIGHT)
    if n == 0:
        return bridges
    border = np.zeros(lab.shape, np.int64)
    wall = np.zeros(lab.shape, np.int64)
    for step in (1, -1):
        edge = bridges & ~np.roll(bridges, step, axis=across)
        border += edge
        wall += edge & np.roll(walls, step, axis=across)
    idx = np.arange(1, n + 1)
    ok = ndimage.sum(wall, lab, idx) <= 0.25 * np.maximum(ndimage.sum(border, lab, idx), 1)
    return np.r_[False, ok][lab]


def free_regions(barrier: np.ndarray) -> tuple[np.ndarray, int, np.ndarray]:
    """(labels, n, outside): the 4-connected free regions of ``~barrier`` and a bool per
    label 0..n, True for regions that touch the image border (outside every plan)."""
    labels, n = ndimage.label(~barrier)
    outside = np.zeros(n + 1, bool)
    outside[np.unique(np.r_[labels[0], labels[-1], labels[:, 0], labels[:, -1]])] = True
    outside[0] = True
    return labels, n, outside


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


def region_polygon(labels: np.ndarray, k: int, box: tuple[slice, slice], s: float):
    """The polygon (m, simplified by half a pixel) of region ``k`` of ``labels`` in its box."""
    return mask_polygons(labels[box] == k, s, (box[0].start, box[1].start), len(labels)).simplify(s / 2)
