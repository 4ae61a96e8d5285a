"""Plan images: door and window gaps bridged, rooms as the enclosed free regions, and
both turned into polygons in metres (pixel masks in, shapely out).

Pixels are (row, col), row 0 at the top; ``s`` is the scale in m per pixel. A pixel
(r, c) is centred at x = (c + 0.5) s, y = (H - r - 0.5) s (H: the image's rows).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage
from shapely.geometry import Polygon

from camplace.scene.importers.image_walls import square_morphology


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


def colour_keys(rgb: np.ndarray) -> np.ndarray:
    """(h, w) int colour class of each pixel: the 3x3 mean colour in 8 levels a channel
    (a flat fill is one class; scan noise and JPEG ringing are averaged out)."""
    smooth = ndimage.uniform_filter(rgb.astype(np.float32), size=(3, 3, 1), mode="nearest")
    q = np.clip(smooth, 0, 255).astype(np.int32) >> 5
    return (q[..., 0] << 6) | (q[..., 1] << 3) | q[..., 2]


def colour_rooms(rgb: np.ndarray, ink: np.ndarray, walls: np.ndarray, labels: np.ndarray, rooms: list[int],
                 s: float, min_room_area: float) -> tuple[np.ndarray, list[int], int]:
    """Rooms of a coloured plan (each room a flat fill): (labels, room labels, rooms added).
    A fill is a colour's piece between walls (text and dimension lines crossing it do not
    part it). A region enclosed by walls that holds two or more fills of at least
    ``min_room_area`` is split between them (each pixel to the nearest fill: a hall and
    a kitchen drawn without a wall between them); a fill outside every region beside the
    ``walls`` (a porch drawn without walls) is a room of its own. ``rgb`` (h, w, 3),
    ``ink``, ``walls`` and ``labels`` cover the plan's box; the fills are told apart from
    the paper (the commonest colour)."""
    keys = colour_keys(rgb)
    paper = np.bincount(keys[~ink].ravel()).argmax() if (~ink).any() else -1
    px_min = min_room_area / (s * s)
    counts = np.bincount(keys[(labels > 0) & ~ink & (keys != paper)].ravel(), minlength=512)
    fill = np.zeros(labels.shape, np.int32)  # one number per fill (a colour's piece between walls), 0: none
    for key in np.flatnonzero(counts >= px_min):
        solid = square_morphology((keys == key) & (labels > 0), 0.25 / s, "open")  # lines in a colour: not fills
        pieces, n = ndimage.label(square_morphology(solid, 0.3 / s, "close") & (labels > 0) & ~walls)
        fill[solid] = np.where(pieces[solid] > 0, pieces[solid] + fill.max(), 0)  # across dimension lines, not walls
    if not fill.any():
        return labels, rooms, 0
    out = np.where(np.isin(labels, rooms), labels, 0)
    top, added = int(labels.max()), 0
    boxes = ndimage.find_objects(out)
    for r in list(rooms):
        box = boxes[r - 1]
        region = out[box] == r
        share = np.bincount(fill[box][region].ravel())
        own = [f for f in range(1, len(share)) if share[f] >= px_min]
        if len(own) < 2:
            continue
        markers = np.where(region & np.isin(fill[box], own), fill[box], 0)
        _, (ri, ci) = ndimage.distance_transform_edt(markers == 0, return_indices=True)
        nearest = markers[ri, ci]
        for f in own[1:]:
            top += 1
            out[box][region & (nearest == f)] = top
            rooms.append(top)
            added += 1
    near_walls = ndimage.maximum_filter(walls.astype(np.uint8), size=5) > 0
    lone, n = ndimage.label((fill > 0) & (out == 0))
    border = set(np.unique(np.r_[lone[0], lone[-1], lone[:, 0], lone[:, -1]]))
    area = np.bincount(lone.ravel(), minlength=n + 1)
    for f in range(1, n + 1):
        if f in border or area[f] < px_min or not (near_walls & (lone == f)).any():
            continue
        top += 1
        out[lone == f] = top
        rooms.append(top)
        added += 1
    return out, rooms, added
