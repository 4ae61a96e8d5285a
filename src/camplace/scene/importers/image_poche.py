"""Plan images: wall fill of every kind, lines that are not walls, furniture (issue 34).

- **Poché of every kind is wall fill**: a strip between two strokes no wider than a wall
  (POCHE_MAX_M) whose marks cover it evenly (a stipple of dots, a hatch, a solid fill) is
  the inside of a wall; so is a closed, door-less strip of paper that narrow and long
  between two thin lines (a wall drawn as an empty outline) where the plan draws its
  walls as outlines.
- **Lines that run past the building** (column grid lines, dimension and extension lines)
  are never walls: a thin straight line with POCHE_PAST_M or more of its length outside the
  building is dropped from the walls where it is thin.
- **Furniture and counters** (a closed thin outline in a room, against a wall or free) in
  a plan whose walls are solid are obstacles FURNITURE_M high, never room dividers.

Masks are (H, W) bool in pixels, ``s`` m per pixel, as in image_walls.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from collections import Counter

from camplace.scene.importers.image_rooms import free_regions
from camplace.scene.importers.image_walls import (EIGHT, POCHE_MAX_M, _line, bridge_openings, label_max, odd,
                                                  square_morphology)

POCHE_LONG = 2.5  # a wall's inside is at least this many times as long as it is wide
LINE_THIN_M = 0.16  # a line (grid, dimension, furniture outline) is at most this thick
PAST_M = 0.5  # a line is past the building when this much of it lies outside
PAST_TOLERANCE_M = 0.3  # ... beyond the building's outline grown by this (overshooting corners)
BUILDING_OPEN_M = 1.5  # strips narrower than this along the outline (wall to dimension line) are outside
SOLID_SHARE = 0.5  # a plan draws its walls solid when this share of its wall pixels lie in thick strokes
FURNITURE_M = 0.9  # the height of a counter or piece of furniture read from a plan image (as DXF's default)


def thin(walls: np.ndarray, s: float) -> np.ndarray:
    """The pixels of ``walls`` in strokes at most LINE_THIN_M thick (lines, not solid walls)."""
    return walls & ~square_morphology(walls, LINE_THIN_M / s + 1, "open")


def solid_plan(walls: np.ndarray, s: float) -> bool:
    """True when the plan draws its walls solid: SOLID_SHARE of its wall pixels or more lie
    in strokes thicker than LINE_THIN_M."""
    n = np.count_nonzero(walls)
    return n > 0 and np.count_nonzero(walls & ~thin(walls, s)) >= SOLID_SHARE * n


def building(walls: np.ndarray, bridges: np.ndarray, s: float) -> np.ndarray:
    """The building's area: the walls (of a solid plan, solid_plan, its solid walls: not the
    lines drawn from them), bridged openings and what they enclose, without the strips
    narrower than BUILDING_OPEN_M that stick out of it."""
    lines = thin(walls, s)
    solid = walls & ~lines if solid_plan(walls, s) else walls  # a solid plan's outline: its solid walls
    filled = ndimage.binary_fill_holes(solid | bridges)
    return square_morphology(filled, BUILDING_OPEN_M / s, "open")


def wall_thickness(walls: np.ndarray, s: float) -> float:
    """The thickest wall of ``walls`` (m): twice its largest inner distance."""
    return 2 * s * float(ndimage.distance_transform_edt(walls).max()) if walls.any() else 0.0


def settle(walls: np.ndarray, s: float, max_opening: float, max_wall: float, skipped: Counter,
           context: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(walls, bridges, objects, thickest wall m) of a plan's wall mask: the lines running
    past the building dropped (lines_past), each closed door-less strip (closed_strips)
    made wall, or, in a plan whose walls are solid (solid_plan), an object (a counter, a
    piece of furniture: its inside and its outline, ``objects``) when taking its outline
    away joins it to no more than the one room around it. Openings are bridged through
    walls up to the thickest one found (at most POCHE_MAX_M) or ``max_wall``. ``context``:
    the sheet's walls around the plan (as ``walls``), for lines_past."""
    def thickest(w: np.ndarray) -> float:  # bridges pass through walls this thick
        return max(max_wall, min(wall_thickness(w, s), POCHE_MAX_M))

    reach = thickest(walls)
    bridges = bridge_openings(walls, s, max_opening, reach)
    past = lines_past(walls, bridges, s, context)
    if past.any():  # thin lines: the thickest wall stays
        walls = walls & ~past
        skipped["lines running past the building (grid, dimension lines)"] += ndimage.label(past, EIGHT)[1]
        bridges = bridge_openings(walls, s, max_opening, reach)
    labels, n, outside = free_regions(walls | bridges)
    strips = closed_strips(labels, [k for k in range(1, n + 1) if not outside[k]], bridges, s)
    objects = np.zeros_like(walls)
    if strips:
        solid = solid_plan(walls, s)
        for k in strips:
            region = labels == k
            outline = _object_outline(walls, bridges, labels, outside, region, s, strips) if solid else None
            if outline is None:
                walls = walls | region
                skipped["insides of walls drawn as outlines or poché (not rooms)"] += 1
            else:
                walls = walls & ~outline
                objects |= region | outline
                skipped["counters and furniture drawn as outlines (obstacles, not walls)"] += 1
        reach = thickest(walls)
        bridges = bridge_openings(walls, s, max_opening, reach)
    return walls, bridges, objects, reach


def _object_outline(walls: np.ndarray, bridges: np.ndarray, labels: np.ndarray, outside: np.ndarray,
                    region: np.ndarray, s: float, strips: list[int]) -> np.ndarray | None:
    """The thin strokes outlining ``region`` (within LINE_THIN_M of it) when taking them
    away joins it to at most one region of ``labels`` other than the ``strips`` and none
    outside the building (a counter in its kitchen); None otherwise (a wall's inside
    between two rooms)."""
    near = ndimage.maximum_filter(region, size=odd(2 * LINE_THIN_M / s + 1, 3))
    outline = near & thin(walls, s)
    free, _ = ndimage.label(~((walls & ~outline) | bridges))
    joined = np.isin(free, np.unique(free[region]))
    merged = np.unique(labels[joined & ~region])
    merged = merged[(merged > 0) & ~np.isin(merged, strips)]
    return outline if len(merged) <= 1 and not outside[merged].any() else None


def lines_past(walls: np.ndarray, bridges: np.ndarray, s: float, context: np.ndarray | None = None) -> np.ndarray:
    """The wall pixels to drop: the thin parts of every straight line (along either axis,
    at least PAST_M long, joined across the walls it crosses and the gaps of a dashed
    line) with PAST_M or more of its length outside the building (building) grown by
    PAST_TOLERANCE_M: column grid lines, dimension lines and their extension lines, and
    the thin pieces left of them wholly outside; not where a line across them that runs
    past nothing crosses (a counter's edge). ``context``: the sheet's walls around the
    plan (the dashes of a grid line beyond the plan's own pieces). A wall of the building
    never runs outside it."""
    inside = building(walls, bridges, s)
    rows, cols = np.nonzero(walls)
    if not len(rows) or inside.sum() < 0.25 * (np.ptp(rows) + 1) * (np.ptp(cols) + 1):  # no closed building
        return np.zeros_like(walls)
    outside = ~ndimage.maximum_filter(inside, size=odd(2 * PAST_TOLERANCE_M / s, 3))
    ink = walls if context is None else walls | context
    lines = thin(ink, s)
    run = odd(PAST_M / s, 3)
    alongs, drops = [], []
    for axis in (0, 1):
        straight = lines & ~_line(lines, odd(LINE_THIN_M / s + 1), 1 - axis, "open")  # thin across this axis
        along = _line(straight, run, axis, "open")
        joined = _line(straight | (ink & ~lines), odd(POCHE_MAX_M / s, 3), axis, "close")  # across walls and gaps
        structure = np.zeros((3, 3), bool)
        structure[1, :] = True
        lab, n = ndimage.label(joined, structure if axis == 1 else structure.T)
        out = np.bincount(lab[outside & along], minlength=n + 1) * s
        alongs.append(_line(lines, run, axis, "open"))  # every run this long, crossings included
        drops.append(np.r_[False, out[1:] >= PAST_M][lab] & lines)
    drop = ((drops[0] & ~(alongs[1] & ~drops[1])) | (drops[1] & ~(alongs[0] & ~drops[0]))) & walls
    if drop.any():  # what is left of them outside (the stubs of extension lines past a dimension line) or small
        lab, n = ndimage.label(walls & ~drop, EIGHT)  # (the corners of a blurred crossing)
        size = np.bincount(lab.ravel(), minlength=n + 1)
        touch = np.zeros(n + 1, bool)
        touch[lab[ndimage.maximum_filter(drop, size=3)]] = True
        gone = (np.bincount(lab[outside], minlength=n + 1) == size) | (touch & (size * s * s <= LINE_THIN_M ** 2))
        gone[0] = False
        drop |= gone[lab] & lines & walls
    return drop


def closed_strips(labels: np.ndarray, ids: list[int], bridges: np.ndarray, s: float) -> list[int]:
    """The free regions ``ids`` of ``labels`` that are a wall's inside or an object's, not
    a room: no wider than POCHE_MAX_M (twice their largest inner distance), at least
    POCHE_LONG times as long as wide (area / width²), and with no door (no bridged opening
    touches them)."""
    if not ids:
        return []
    n = int(labels.max())
    half = label_max(ndimage.distance_transform_edt(labels > 0), labels, n)
    area = np.bincount(labels.ravel(), minlength=n + 1)
    door = np.zeros(n + 1, bool)
    door[labels[ndimage.maximum_filter(bridges, size=3)]] = True
    out = []
    for k in ids:
        width = 2 * half[k]
        if 0 < width * s <= POCHE_MAX_M and area[k] >= POCHE_LONG * width ** 2 and not door[k]:
            out.append(k)
    return out
