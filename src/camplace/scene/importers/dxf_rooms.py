"""Rooms of a DXF plan (m): closed polylines and hatches on room-area layers, or the free
pieces the walls enclose, named by the texts and block attributes inside them (a room
stamp's name before its number or area).
"""

from __future__ import annotations

import re
from collections import Counter

import numpy as np
import shapely
from shapely.geometry import Polygon

from camplace.scene.importers import polygons_of
from camplace.scene.importers.dxf_layers import normalise

MIN_ROOM_M2 = 0.5  # smaller closed outlines on room layers are symbols, not rooms
MIN_ROOM_WIDTH_M = 0.5  # a free piece narrower than this everywhere is no room (the gap beside a counter, a shaft)
MAX_NAME_CHARS = 40  # longer texts are notes, not room names
_NAME_TAG = re.compile(r"NAM|BEZ|NOM|DESC|USE|NUTZ|FUNC|TITLE|LABEL|BENENN|DENOM|LONG")
_NUMBER_TAG = re.compile(r"NUM|NR|NO\b|^NO|ID|CODE|KEY|NUMMER|NUMERO")
_AREA_TAG = re.compile(r"AREA|FLAECH|FL\b|SURF|M2|QM|NGF|NRF|SIZE|SUPERF|GROESSE")
_AREA_TEXT = re.compile(r"^(?:[A-Z]{1,4}\s*[:=]\s*)?\d+(?:[.,']\d+)*\s*(?:M2|QM|SQ\.?\s*FT|SF|FT2)$|"
                        r"^[A-Z]{1,4}\s*[:=]\s*\d+(?:[.,']\d+)*$")
_LEVEL_TEXT = re.compile(r"^(?:[A-Z]{0,4}\s*)?[+±]\s*\d")


def room_polygons(polys: list[Polygon], skipped: Counter) -> list[Polygon]:
    """The rooms among closed outlines on room layers (m): at least MIN_ROOM_M2, each
    once (outlines drawn twice kept once), and none that holds two or more of the others
    (a storey outline around its rooms, a gross-area polygon)."""
    polys = sorted((q for p in polys for q in polygons_of(shapely.make_valid(p)) if q.area >= MIN_ROOM_M2),
                   key=lambda q: q.area)
    kept: list[Polygon] = []
    if polys:
        arr = np.asarray(polys, dtype=object)
        a, b = shapely.STRtree(arr).query(arr, predicate="intersects")
        a, b = a[a > b], b[a > b]  # each pair once: b the smaller (sorted by area), kept first
        same = shapely.area(shapely.intersection(arr[a], arr[b])) > 0.9 * shapely.area(arr[a])
        twice = set(a[same].tolist())
        kept = [q for k, q in enumerate(polys) if k not in twice]
        if twice:
            skipped["room outlines drawn twice"] += len(twice)
    if len(kept) < 3:
        return reading_order(kept)
    arr = np.asarray(kept, dtype=object)
    tree = shapely.STRtree(arr)
    a, b = tree.query(shapely.point_on_surface(arr), predicate="within")
    holds = np.bincount(b[a != b], minlength=len(kept))
    out = [q for q, n in zip(kept, holds) if n < 2]
    if len(kept) > len(out):
        skipped["outlines around other rooms (storey or gross-area outlines)"] += len(kept) - len(out)
    return reading_order(out)


def reading_order(polys: list[Polygon]) -> list[Polygon]:
    """Polygons top to bottom, then left to right (by their centroids, 0.1 m rows)."""
    return sorted(polys, key=lambda q: (-round(q.centroid.y, 1), q.centroid.x))


def label_kind(text: str, tag: str) -> int:
    """How much a label says a room's name: 3 an attribute tagged as a name, 2 a text
    that reads like a name, 1 a number or code (A101, E.012), 0 an area or level
    ('24.5 m²', '+0.00'), -1 not a label (empty, too long)."""
    t = text.strip()
    if not t or len(t) > MAX_NAME_CHARS:
        return -1
    tag = normalise(tag)
    if tag and _AREA_TAG.search(tag):
        return 0
    if tag and _NUMBER_TAG.search(tag) and not _NAME_TAG.search(tag):
        return 1
    up = normalise(t)
    if _AREA_TEXT.match(up) or _LEVEL_TEXT.search(up):
        return 0
    letters = sum(c.isalpha() for c in t)
    digits = sum(c.isdigit() for c in t)
    named = letters >= 3 or (letters >= 2 and digits == 0)
    if tag and _NAME_TAG.search(tag) and named:
        return 3
    return 2 if named else 1


def room_names(rooms: list[Polygon], labels: list) -> tuple[list[str], Counter]:
    """The name of each room (m polygons): the best label (label_kind, then attribute
    before text, taller text, nearer the room's centre) whose point lies in it, its
    number added where the name repeats; 'room-k' without one. Also what named them
    ({'block attributes': n, 'texts': n})."""
    inside: list[list] = [[] for _ in rooms]
    if rooms and labels:
        arr = np.asarray(rooms, dtype=object)
        pts = np.asarray([lb.point for lb in labels], dtype=object)
        li, ri = shapely.STRtree(arr).query(pts, predicate="within")
        areas = np.array([r.area for r in rooms])
        smallest: dict[int, int] = {}
        for a, b in zip(li.tolist(), ri.tolist()):  # a label names the smallest room it lies in
            if a not in smallest or areas[b] < areas[smallest[a]]:
                smallest[a] = b
        for a, b in smallest.items():
            inside[b].append(labels[a])
    names, numbers, how = [], [], Counter()
    for k, (room, found) in enumerate(zip(rooms, inside)):
        c = room.centroid
        ranked = sorted(((label_kind(lb.text, lb.tag), bool(lb.tag), lb.height, -lb.point.distance(c), lb)
                         for lb in found), key=lambda r: r[:4], reverse=True)
        best = next((r for r in ranked if r[0] >= 2), None) or next((r for r in ranked if r[0] == 1), None)
        number = next((r[4].text for r in ranked if r[0] == 1), None)
        if best is None:
            names.append(f"room-{k + 1}")
        else:
            names.append(best[4].text)
            how["block attributes" if best[1] else "texts"] += 1
        numbers.append(number if best is not None and best[0] >= 2 else None)
    seen = Counter(names)
    return [f"{n} {num}" if seen[n] > 1 and num else n for n, num in zip(names, numbers)], how


def enclosed_rooms(footprint: Polygon, barrier, bridge: float, min_area: float = 1.0) -> list[Polygon]:
    """The free pieces (m) of ``footprint`` the ``barrier`` (walls, glass, columns, door
    gaps) encloses once gaps up to ``bridge`` m are closed, at least ``min_area`` m²
    each, grown back into the corners the closing took (each piece up to ``bridge`` / 2,
    larger rooms first; never into another room); then the free space no room took, less
    its parts narrower than MIN_ROOM_WIDTH_M, in pieces of at least ``min_area`` (a galley
    kitchen, a corridor narrower than ``bridge``: the closing filled them). For finding
    rooms only: the walls keep their openings."""
    d = bridge / 2
    if barrier.is_empty:
        return [footprint]
    closed = shapely.union_all([barrier, barrier.buffer(d, join_style="mitre").buffer(-d, join_style="mitre")])
    seeds = sorted((q for q in polygons_of(footprint.difference(closed)) if q.area >= min_area), key=lambda q: -q.area)
    free = footprint.difference(barrier)
    every = shapely.union_all(seeds) if seeds else Polygon()
    out, taken = [], Polygon()
    for seed in seeds:
        grown = seed.buffer(d, join_style="mitre").intersection(free).difference(every.difference(seed)).difference(
            taken)
        piece = max((q for q in polygons_of(grown) if q.intersects(seed)), key=lambda q: q.area, default=seed)
        out.append(piece)
        taken = taken.union(piece)
    w = MIN_ROOM_WIDTH_M / 2
    rest = free.difference(taken)
    opened = rest.buffer(-w, join_style="mitre").buffer(w, join_style="mitre").intersection(rest)
    return reading_order(out + [q for q in polygons_of(opened) if q.area >= min_area])
