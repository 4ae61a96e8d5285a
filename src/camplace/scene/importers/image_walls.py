"""Plan images: the ink, the walls and the separate plans of a sheet (pixel masks).

Pixels are (row, col) with row 0 at the top; every length given in metres is turned into
pixels by the scale ``s`` (m per pixel). All steps are vectorised scipy.ndimage filters
and labellings, so an A3 sheet at 150 dpi takes about a second.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

EIGHT = np.ones((3, 3), bool)  # 8-connectivity
COLOUR_SPREAD = 100  # a pen this far from grey (brightest minus dimmest channel, 0..255) is a coloured line
DOOR_M = 1.0  # the widest door beside a corner
MIN_JAMB_M = 0.12  # a wall beside a door runs at least this far in line with it
REACH_M = 1.0  # a small wall piece this close to a plan belongs to it (to the nearest plan)
LONG_STROKE_M = 0.6  # ink pieces at least this long across are strokes (wall outlines, dimension lines)
HOLLOW_WALL_M = 0.5  # a closed strip of paper up to this wide between two lines is the inside of a wall
LINE_RUN_M = 1.0  # a wall drawn as a single line runs straight this far somewhere along its piece of ink
LINE_PIECE_M = 0.4  # ... or is a straight piece this long in line with such walls
LINE_WALL_M = 0.1  # the thickness given to walls drawn as single lines (m)
POCHE_MAX_M = 1.0  # the widest wall whose inside, filled with marks of any kind (poché), is wall
POCHE_SPREAD_M = 0.12  # the marks of a poché lie at most this far from every point of it ...
POCHE_COVER = 0.9  # ... over this share of it


def brightness(rgb: np.ndarray) -> np.ndarray:
    """(H, W) uint8: the brightest channel of each pixel (HSV value), so a flat colour
    fill (magenta, green: one bright channel) is light and only grey-to-black ink is dark."""
    return rgb.max(axis=2)


def colour_lines(rgb: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels of a saturated pen (a CAD plot's red, cyan, blue lines): at
    least COLOUR_SPREAD between their brightest and dimmest channel. brightness() takes
    them for paper; the importer tries them as ink only when no room is found without."""
    a = rgb.astype(np.int16)
    return (a.max(axis=2) - a.min(axis=2)) >= COLOUR_SPREAD


def label_sum(values: np.ndarray, labels: np.ndarray, n: int) -> np.ndarray:
    """(n + 1,) sum of ``values`` over each label 0..n (bincount over the labelled pixels)."""
    m = labels > 0
    return np.bincount(labels[m], weights=values[m].astype(np.float64), minlength=n + 1)


def label_mean(values: np.ndarray, labels: np.ndarray, n: int) -> np.ndarray:
    """(n + 1,) mean of ``values`` over each label 0..n (0 for an empty label)."""
    count = np.bincount(labels[labels > 0], minlength=n + 1)
    return label_sum(values, labels, n) / np.maximum(count, 1)


def label_max(values: np.ndarray, labels: np.ndarray, n: int) -> np.ndarray:
    """(n + 1,) maximum of ``values`` (≥ 0) over each label 0..n (0 for an empty label)."""
    m = labels > 0
    out = np.zeros(n + 1, np.float64)
    np.maximum.at(out, labels[m], values[m])
    return out


def otsu_threshold(values: np.ndarray) -> float:
    """The level (0..255) that best splits ``values`` into two classes (Otsu)."""
    hist = np.bincount(np.clip(values, 0, 255).astype(np.int64).ravel(), minlength=256).astype(float)
    w0 = np.cumsum(hist)
    m0 = np.cumsum(hist * np.arange(256))
    total, mean = w0[-1], m0[-1]
    w1 = total - w0
    with np.errstate(divide="ignore", invalid="ignore"):
        between = (mean * w0 - total * m0) ** 2 / (w0 * w1)
    between[~np.isfinite(between)] = -1
    return float(np.argmax(between)) + 0.5


def odd(px: float, least: int = 1) -> int:
    """The odd window size (pixels) nearest ``px``, at least ``least``."""
    return max(least, 2 * int(round(px / 2)) + 1)


def square_morphology(mask: np.ndarray, px: float, op: str) -> np.ndarray:
    """Binary ``op`` ('open' or 'close') of ``mask`` by a square of about ``px`` pixels
    (odd, centred; separable min / max filters, so fast for large squares)."""
    k = odd(px)
    m = mask.astype(np.uint8)
    first, second = (ndimage.minimum_filter, ndimage.maximum_filter) if op == "open" else \
        (ndimage.maximum_filter, ndimage.minimum_filter)
    return second(first(m, size=k, mode="nearest"), size=k, mode="nearest").astype(bool)


def ink_threshold(dark: np.ndarray, s: float, max_wall_m: float) -> tuple[float, str]:
    """(level, how) splitting ink from paper: Otsu on the brightness; when the dark class
    holds broad flat areas (room fills darker than the split: a square wider than any wall
    fits in more than a quarter of it), Otsu again within the dark class."""
    t = otsu_threshold(dark)
    ink = dark < t
    if ink.any():
        broad = square_morphology(ink, max_wall_m / s, "open")
        if broad.sum() > 0.25 * ink.sum() and np.count_nonzero(dark < t) > 0:
            t2 = otsu_threshold(dark[ink])
            if t2 < t - 10:
                return t2, "Otsu below the dark room fills"
    return t, "Otsu"


def solid_walls(ink: np.ndarray, s: float, hatch_m: float, min_wall_m: float, max_wall_m: float,
                skipped: Counter, hollow_skipped: Counter | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    """(walls, hollow walls or None): wall pixels of the ink mask. Long strokes (pieces of
    ink at least LONG_STROKE_M across: wall outlines with their hatch, dimension lines)
    bound the paper; paper is the inside of a wall where it is narrow (at most ``hatch_m``
    wide: a hatch cell, the strip between the two lines of a thin wall) or in a strip no
    wider than ``max_wall_m`` holding marks (a hatch of dashes, ≥ 8 % ink, drawn slanted:
    more diagonal than upright neighbours, unlike text) and long (not the disc inside the
    circle around a room number). Those fill in; rooms, the strips between a wall and a
    dimension line and the text in them do not. The hollow walls (None when they would be
    the same) fill in also every closed strip of paper up to HOLLOW_WALL_M wide (a wall
    drawn as an empty outline; also the strip between a wall and a dimension line drawn
    from wall to wall inside a room, hence a second result, see image.analyse; what it
    skips goes to ``hollow_skipped``). Broad filled areas that were mostly paper (stair
    treads) are given back, then strokes thinner than ``min_wall_m`` (text, dimension
    lines, door swings) are opened away."""
    lab, n = ndimage.label(ink, EIGHT)
    if n == 0:
        return ink, None
    extent = np.r_[0, [max(b[0].stop - b[0].start, b[1].stop - b[1].start) for b in ndimage.find_objects(lab)]]
    strokes = square_morphology(extent[lab] * s >= LONG_STROKE_M, 3, "close")  # small breaks sealed
    free = ~strokes & ~_edge_paper(~strokes)  # the paper between a sheet's frame and its edge is no wall
    cells = free & ~square_morphology(free, hatch_m / s, "open")  # hatch cells, the inside of thin walls
    bands = free & ~square_morphology(free, max(max_wall_m, POCHE_MAX_M) / s, "open")  # strips no wider than a wall
    blab, nb = ndimage.label(bands)
    marked = np.zeros(nb + 1, bool)
    closed = np.zeros(nb + 1, bool)
    if nb:  # a strip along a wall, not a disc (the circle around a room number)
        width = label_max(ndimage.distance_transform_edt(bands), blab, nb)[1:]
        marks = ink & free
        diagonal = (marks & (np.roll(marks, (1, 1), (0, 1)) | np.roll(marks, (1, -1), (0, 1)))).astype(np.int8)
        square = (marks & (np.roll(marks, 1, 0) | np.roll(marks, 1, 1))).astype(np.int8)
        long = np.bincount(blab.ravel(), minlength=nb + 1)[1:] >= 8 * width ** 2
        marked[1:] = ((label_mean(marks, blab, nb)[1:] >= 0.08) & long & (width <= max_wall_m / s / 2)
                      & (label_sum(diagonal, blab, nb)[1:] > label_sum(square, blab, nb)[1:]))
        marked[1:] |= long & (label_mean(marks, blab, nb)[1:] >= 0.03) & evenly_marked(marks, blab, nb, s)
        closed[1:] = long & (width <= HOLLOW_WALL_M / s / 2) & _closed_bands(free, blab, nb) & ~marked[1:]
    solid = ink | strokes | cells | marked[blab]
    poche = marked[blab]
    walls = _finished(solid, ink, s, min_wall_m, max_wall_m, skipped, poche)
    if not closed.any():
        return walls, None
    return walls, _finished(solid | closed[blab], ink, s, min_wall_m, max_wall_m,
                            hollow_skipped if hollow_skipped is not None else Counter(), poche)


def evenly_marked(marks: np.ndarray, blab: np.ndarray, nb: int, s: float) -> np.ndarray:
    """(nb,) bool: the strips 1..nb of ``blab`` whose ``marks`` (ink inside them) cover them
    evenly, poché of any kind: at least POCHE_COVER of each strip lies within
    POCHE_SPREAD_M of a mark (a stipple of dots, a hatch at any angle). The text between
    a wall and its dimension line covers a few places of its strip, not all of it."""
    near = ndimage.maximum_filter(marks, size=odd(2 * POCHE_SPREAD_M / s, 3))
    return label_mean(near, blab, nb)[1:] >= POCHE_COVER


def _finished(solid: np.ndarray, ink: np.ndarray, s: float, min_wall_m: float, max_wall_m: float,
              skipped: Counter, poche: np.ndarray) -> np.ndarray:
    """The filled wall mask ``solid`` with its broad areas that were mostly paper given
    back to ``ink`` (stair treads, text blocks: counted in ``skipped``; not the ``poche``,
    walls filled evenly with marks) and strokes thinner than ``min_wall_m`` opened away."""
    solid = solid.copy()
    broad = square_morphology(solid, max_wall_m / s, "open")
    if broad.any():
        blab, nb = ndimage.label(broad, EIGHT)
        textured = np.r_[False, label_mean(ink, blab, nb)[1:] < 0.5]
        if textured.any():
            skipped["textured areas (stairs, text blocks)"] += int(textured.sum())
            back = textured[blab] & ~ndimage.maximum_filter(poche, size=3)
            solid[back] = ink[back]
    return square_morphology(solid, max(min_wall_m / s, 2), "open")


def _closed_bands(free: np.ndarray, blab: np.ndarray, nb: int) -> np.ndarray:
    """(nb,) bool: the strips 1..nb of ``blab`` that are a whole piece of paper of ``free``
    (closed all round: the inside of a wall drawn as an outline), not the narrow part of a
    larger piece (the strip between a wall and its dimension line, open at its ends)."""
    flab, nf = ndimage.label(free)
    size = np.bincount(flab.ravel(), minlength=nf + 1)
    at = label_max(flab, blab, nb)[1:].astype(np.int64)  # the piece of paper each strip lies in
    return np.bincount(blab.ravel(), minlength=nb + 1)[1:] >= size[at]


def _edge_paper(free: np.ndarray) -> np.ndarray:
    """The pixels of ``free`` (bool) connected to the image's edge."""
    lab, _ = ndimage.label(free)
    edge = np.unique(np.r_[lab[0], lab[-1], lab[:, 0], lab[:, -1]])
    return np.isin(lab, edge[edge > 0])


def line_walls(ink: np.ndarray, s: float, max_opening_m: float) -> np.ndarray:
    """Walls of a plan drawn in single lines (hairlines: a CAD export or a sketch with no
    wall drawn thicker than a pen, which solid_walls opens away): the pieces of ink with a
    straight run of at least LINE_RUN_M along either axis somewhere (text, whose letters
    are separate pieces, symbols and loose door swings have none; a door's leaf and swing
    drawn onto its wall stay with it), and the straight pieces of at least LINE_PIECE_M in
    line with those walls, no more than ``max_opening_m`` from them (between windows,
    beside doors); small breaks sealed, drawn LINE_WALL_M thick (m) so they occlude and
    part rooms."""
    lab, n = ndimage.label(ink, EIGHT)
    keep = np.zeros(n + 1, bool)
    for axis in (0, 1):
        keep[np.unique(lab[_line(ink, odd(LINE_RUN_M / s, 3), axis, "open")])] = True
    keep[0] = False
    walls = keep[lab]
    for axis in (0, 1):  # short pieces in line with the walls: between windows, beside doors
        short = _line(ink & ~walls, odd(LINE_PIECE_M / s, 3), axis, "open")
        along = _line(walls, odd(LINE_PIECE_M / s, 3), axis, "open")
        joined, _ = ndimage.label(_line(along | short, odd(max_opening_m / s, 3), axis, "close"), EIGHT)
        hit = np.unique(joined[along])
        ok = np.isin(joined, hit[hit > 0]) & short
        keep[np.unique(lab[ok])] = True
    keep[0] = False
    sealed = square_morphology(keep[lab], 3, "close")
    return ndimage.maximum_filter(sealed, size=odd(LINE_WALL_M / s, 1)).astype(bool)


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
    gap when walls running along that axis (no thicker across than ``max_wall_m``, at
    least MIN_JAMB_M long) end at both its ends, or at one end for a gap up to DOOR_M (a
    door beside a corner); a room or corridor between two wall faces is not a gap. Gaps thicker across than a wall are not bridged either."""
    gap, thick = odd(max_opening_m / s, 3), int(round(max_wall_m / s)) + 1
    out = np.zeros_like(walls)
    row = np.zeros((3, 3), bool)
    row[1, :] = True
    for along in (1, 0):
        across = 1 - along
        pieces = walls & ~_line(walls, thick, across, "open")  # thin across: walls running along this axis
        added = _line(walls, gap, along, "close") & ~walls
        runs, n = ndimage.label(added, row if along == 1 else row.T)
        if n == 0:
            continue
        plab, npl = ndimage.label(pieces, row if along == 1 else row.T)  # runs of the walls along the axis
        long = np.r_[False, np.bincount(plab.ravel(), minlength=npl + 1)[1:] * s >= MIN_JAMB_M][plab]
        before = label_sum(added & np.roll(long, 1, axis=along), runs, n)[1:] > 0
        after = label_sum(added & np.roll(long, -1, axis=along), runs, n)[1:] > 0
        short = np.bincount(runs.ravel(), minlength=n + 1)[1:] * s <= DOOR_M
        ends = np.r_[False, (before & after) | ((before | after) & short)][runs]
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
    ok = label_sum(wall, lab, n)[1:] <= 0.25 * np.maximum(label_sum(border, lab, n)[1:], 1)
    return np.r_[False, ok][lab]


@dataclass
class Sheet:
    """The plans found on a sheet: ``plans`` (list of (rows, cols) slices, one per plan,
    reading order), ``walls`` the kept wall mask (H, W) and ``plan_of`` (H, W) int32 plan
    number 1..n of each kept wall pixel (0 elsewhere)."""

    walls: np.ndarray
    plan_of: np.ndarray
    plans: list[tuple[slice, slice]] = field(default_factory=list)


def find_plans(raw: np.ndarray, ink: np.ndarray, s: float, max_opening_m: float, max_wall_m: float,
               skipped: Counter, reach_m: float = REACH_M) -> Sheet:
    """The separate plans of a sheet in the wall mask ``raw``. A wall piece (8-connected)
    is drawn (its edge is ink: an outline, a solid stroke, ≥ 60 %, and at least 0.05 m²)
    or a blot of symbols; a thin ring around most of the sheet is its frame. Drawn pieces
    (also the short wall pieces between windows, once only those of a twentieth of the
    largest piece: walls broken by many windows fell apart into several plans) joined
    across the openings between walls in
    line (bridge_openings: ``max_opening_m``, ``max_wall_m``), but not across a gutter no
    room spans (gutter_bridges), are one plan; the other pieces within ``reach_m`` of
    one belong to the nearest. Plans under a quarter of the largest plan's wall area (key
    plans, title blocks, legends, scale bars) and frames around other plans are not the
    building; each plan keeps its drawn pieces and any piece at least a quarter of its
    largest."""
    lab, n = ndimage.label(raw, EIGHT)
    if n == 0:
        return Sheet(raw, np.zeros(raw.shape, np.int32))
    area = np.bincount(lab.ravel(), minlength=n + 1)[1:].astype(float)
    edge = raw & ~ndimage.binary_erosion(raw)
    drawn = (label_mean(ink, np.where(edge, lab, 0), n)[1:] >= 0.6) | (area >= 0.25 * area.max())
    drawn &= area * s * s >= 0.05
    frame = _sheet_frames(ndimage.find_objects(lab), area, drawn, raw.shape)
    if frame.any():
        skipped["sheet frames"] += int(frame.sum())
        drawn &= ~frame
    bones = drawn[lab - 1] & raw  # every drawn piece: the wall pieces between windows bridge too
    bridges = bridge_openings(bones, s, max_opening_m, max_wall_m)
    bones |= bridges & ~gutter_bridges(bones, bridges)  # one plan across its windows and doors, not across gutters
    glab, ng = ndimage.label(ndimage.maximum_filter(bones, size=3), EIGHT)
    group = _nearest_groups(glab, lab, n, reach_m / s)
    group = _inner_groups_joined(group, ndimage.find_objects(glab), np.bincount(group, weights=area * drawn,
                                                                               minlength=ng + 1))
    biggest = np.zeros(ng + 1)
    np.maximum.at(biggest, group, area)
    keep = (drawn | (area >= 0.25 * biggest[group])) & ~frame
    keep &= group > 0
    gsum = np.bincount(group, weights=area * keep, minlength=ng + 1)
    gsum[0] = 0
    plans = [int(g) for g in np.flatnonzero((gsum > 0) & (gsum >= 0.25 * gsum.max()))]  # none: no plan
    on_plan = np.isin(group, plans)
    if np.count_nonzero(on_plan & ~keep):
        skipped["text and symbols on the plans"] += int(np.count_nonzero(on_plan & ~keep))
    if np.count_nonzero(~on_plan):
        skipped["marks off the plans (title block, legend, scale bar, key plan, text)"] += int(
            np.count_nonzero(~on_plan))
    piece_group = np.r_[0, np.where(keep & on_plan, group, 0)]
    boxes = ndimage.find_objects(piece_group[lab])
    order = sorted(plans, key=lambda g: (round(boxes[g - 1][0].start * s / 3.0), boxes[g - 1][1].start))
    piece_plan = np.zeros(n + 1, np.int32)
    for k, g in enumerate(order, 1):
        piece_plan[1:][(group == g) & keep] = k
    plan_of = piece_plan[lab]
    return Sheet(plan_of > 0, plan_of, [boxes[g - 1] for g in order])


def _nearest_groups(glab: np.ndarray, lab: np.ndarray, n: int, reach_px: float) -> np.ndarray:
    """(n + 1,) int64: the group (``glab``) nearest each piece 1..n of ``lab`` (at its
    nearest pixel), 0 where none is within ``reach_px``; a piece of a group is its own."""
    dist, (r, c) = ndimage.distance_transform_edt(glab == 0, return_indices=True)
    m = lab > 0
    least = np.full(n + 1, np.inf)
    np.minimum.at(least, lab[m], dist[m])
    at = m & (dist <= least[lab])
    group = label_max(np.where(at, glab[r, c], 0), lab, n).astype(np.int64)
    group[least > reach_px] = 0
    return group[1:]


def gutters(walls: np.ndarray) -> list[tuple[int, slice, slice]]:
    """The gutters between the wall structures of a sheet (recursive XY cut of ``walls``,
    (H, W) bool): (axis, rows, cols) of each band of columns (axis 1) or rows (axis 0)
    with no wall across its whole block, between walls on both sides. A block is cut at
    all its gutters along one axis, then each part again, till none is left: no size in
    metres, only where the walls are."""
    out = []
    blocks = [(slice(0, walls.shape[0]), slice(0, walls.shape[1]))]
    while blocks:
        box = blocks.pop()
        sub = walls[box]
        for axis in (1, 0):
            used = np.flatnonzero(sub.any(axis=1 - axis))
            if not len(used):
                break
            ends = np.flatnonzero(np.diff(used) > 1)  # a gap after used[e]
            if not len(ends):
                continue
            at = box[axis].start
            starts = np.r_[used[0], used[ends + 1]] + at
            stops = np.r_[used[ends] + 1, used[-1] + 1] + at
            for lo, hi in zip(stops[:-1], starts[1:]):
                band = (box[0], slice(lo, hi)) if axis == 1 else (slice(lo, hi), box[1])
                out.append((axis, *band))
            for lo, hi in zip(starts, stops):
                blocks.append((box[0], slice(lo, hi)) if axis == 1 else (slice(lo, hi), box[1]))
            break
    return out


def gutter_bridges(walls: np.ndarray, bridges: np.ndarray) -> np.ndarray:
    """The ``bridges`` (bool, as ``walls``) that cross a gutter (gutters) where no room
    spans it: no free region enclosed by the walls and all bridges lies in the gutter and
    on both sides of it. The strip between two storeys drawn side by side, with their
    outer walls in line, is a gutter no room spans; a hall whose windows part the walls of
    one building (a U or L whose halves meet only across window gaps) spans its gutter."""
    out = np.zeros_like(bridges)
    cuts = [g for g in gutters(walls) if bridges[g[1], g[2]].any()]
    if not cuts:
        return out
    free, nf = ndimage.label(~(walls | bridges))
    enclosed = np.ones(nf + 1, bool)
    enclosed[np.r_[0, free[0], free[-1], free[:, 0], free[:, -1]]] = False

    def seen(*box) -> np.ndarray:  # (nf + 1,) bool: the free regions with a pixel in the box
        hit = np.zeros(nf + 1, bool)
        hit[free[box]] = True
        return hit

    for axis, rows, cols in cuts:
        before = (rows, slice(0, cols.start)) if axis == 1 else (slice(0, rows.start), cols)
        after = (rows, slice(cols.stop, None)) if axis == 1 else (slice(rows.stop, None), cols)
        if not (enclosed & seen(rows, cols) & seen(*before) & seen(*after)).any():
            out[rows, cols] |= bridges[rows, cols]
    return out


def _inner_groups_joined(group: np.ndarray, boxes: list, weight: np.ndarray) -> np.ndarray:
    """``group`` (per piece) with every group whose box centre lies in the box of a
    heavier group (``weight`` per group) joined to the heaviest such: furniture, a stair
    core, a free-standing wall inside a building belong to its plan."""
    to = np.arange(len(weight))
    for g in np.argsort(-weight):
        if g == 0 or boxes[g - 1] is None:
            continue
        b = boxes[g - 1]
        cy, cx = (b[0].start + b[0].stop) / 2, (b[1].start + b[1].stop) / 2
        for h in np.argsort(-weight):
            if weight[h] <= weight[g]:
                break
            o = boxes[h - 1] if h else None
            if o is not None and o[0].start <= cy < o[0].stop and o[1].start <= cx < o[1].stop:
                to[g] = to[h]
                break
    return to[group]


def _sheet_frames(boxes: list, area: np.ndarray, drawn: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Per piece, True for a sheet frame: a thin ring (a fifth of its box or less) across
    most of the sheet (80 % each way) around drawn pieces of a tenth of its area or more."""
    r0, r1 = np.array([b[0].start for b in boxes]), np.array([b[0].stop for b in boxes])
    c0, c1 = np.array([b[1].start for b in boxes]), np.array([b[1].stop for b in boxes])
    big = ((r1 - r0) >= 0.8 * shape[0]) & ((c1 - c0) >= 0.8 * shape[1]) & (area < 0.2 * (r1 - r0) * (c1 - c0))
    out = np.zeros(len(boxes), bool)
    cy, cx = (r0 + r1) / 2, (c0 + c1) / 2
    for i in np.flatnonzero(big):
        inside = drawn & (cy > r0[i]) & (cy < r1[i]) & (cx > c0[i]) & (cx < c1[i])
        inside[i] = False
        out[i] = area[inside].sum() >= 0.1 * area[i]
    return out
