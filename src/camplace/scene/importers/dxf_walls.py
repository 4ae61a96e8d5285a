"""Walls of a DXF plan from its linework (m): which layers hold walls when their names do
not say it (parallel line pairs a wall's thickness apart, or single lines that enclose
rooms on their own: walls drawn as one line each), the wall solids (double lines
closed into solids, single lines given a thickness, hatches as they are), and the main
building (the largest cluster of walls; a title block, a legend or a second drawing on
the sheet is left out).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon

from camplace.scene.importers import polygons_of

PAIR_M = (0.05, 0.6)  # the gap between the two faces of a wall, m
MIN_SEGMENT_M = 0.25  # shorter straight pieces say nothing about walls
PARALLEL_SIN = 0.05  # |sin| of the angle below which two segments are parallel (about 3 degrees)
MIN_PAIRED_M = 4.0  # a wall layer holds at least this much paired linework, m
MIN_PAIRED_SHARE = 0.3  # ... and at least this share of its linework is paired
MAX_LADDER_SHARE = 0.6  # ... and at most this share of the paired lines has partners on both sides (stairs, hatching)
MIN_LAYER_SHARE = 0.15  # a layer joins the walls with at least this share of the best layer's paired length
MIN_SOLID_M2 = 1e-4  # a closed piece of linework smaller than this is numerical dust, no solid
MAX_WALL_WIDTH_M = 1.5  # a filled area wider than this (mean width 2 A / P) is no wall
BUILDING_GAP_M = 5.0  # walls, glass and columns closer than this belong to one building
MIN_ROOM_FACE_M2 = 1.0  # a face of a layer's lines this large and wider on average than a wall is a room
MIN_SINGLE_ROOMS_M2 = 8.0  # single-line walls enclose at least this much room area ...
MIN_SINGLE_SHARE = 0.5  # ... with at least this share of the layer's straight linework on the rooms' edges
SWING_RADIUS_M = (0.3, 1.6)  # an arc this wide (a cupboard's to a double door's leaf) may be a door's swing
LEAF_LENGTH = (0.9, 1.15)  # a door leaf drawn as a line: its length over its swing's radius
LEAF_HINGE = 0.1  # ... starting this share of the radius from the swing's centre
LEAF_ANGLE_DEG = 10.0  # ... pointing into the swing's sweep, give or take this


@dataclass
class LayerPairs:
    """Parallel-pair statistics of one layer's straight linework (m): ``total`` length,
    ``paired`` length (segments with a parallel partner PAIR_M apart on one side at
    least), ``ladder`` length (partners on both sides), ``gaps`` the pair gaps (m),
    ``thin`` filled area of wall-thin hatches (m²), ``lines`` the segments paired on one
    side only (a wall's faces; the inner rungs of a ladder left out)."""

    total: float
    paired: float
    ladder: float
    gaps: np.ndarray
    thin: float
    lines: list


def segments(lines: list) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(P0 (n, 2), P1 (n, 2), owner (n,)) straight pieces of LineStrings, owner = index into ``lines``."""
    if not lines:
        return np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, int)
    coords, idx = shapely.get_coordinates(np.asarray(lines, dtype=object), return_index=True)
    same = idx[1:] == idx[:-1]
    return coords[:-1][same], coords[1:][same], idx[:-1][same]


def pair_sides(p0: np.ndarray, p1: np.ndarray, group: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(left, right, gap) per segment (m): whether a parallel segment of the same
    ``group`` lies PAIR_M apart on its left / right side, overlapping at least half the
    shorter one (or 1 m); ``gap`` the nearest such distance (nan without one)."""
    n = len(p0)
    left, right, gap = np.zeros(n, bool), np.zeros(n, bool), np.full(n, np.nan)
    if n < 2:
        return left, right, gap
    d = p1 - p0
    length = np.hypot(d[:, 0], d[:, 1])
    u = d / np.maximum(length, 1e-12)[:, None]
    tree = shapely.STRtree(shapely.linestrings(np.stack([p0, p1], axis=1)))
    i, j = tree.query(tree.geometries, predicate="dwithin", distance=PAIR_M[1])
    keep = (i != j) & (group[i] == group[j])
    i, j = i[keep], j[keep]
    ui = u[i]
    par = np.abs(ui[:, 0] * u[j, 1] - ui[:, 1] * u[j, 0]) < PARALLEL_SIN
    rel = 0.5 * (p0[j] + p1[j]) - p0[i]
    side = ui[:, 0] * rel[:, 1] - ui[:, 1] * rel[:, 0]
    dist = np.abs(side)
    t0 = ((p0[j] - p0[i]) * ui).sum(1)
    t1 = ((p1[j] - p0[i]) * ui).sum(1)
    over = np.minimum(length[i], np.maximum(t0, t1)) - np.maximum(0.0, np.minimum(t0, t1))
    ok = par & (dist >= PAIR_M[0]) & (dist <= PAIR_M[1]) & (over > 0.1) & (
        (over >= 0.5 * np.minimum(length[i], length[j])) | (over >= 1.0))
    np.logical_or.at(left, i[ok & (side > 0)], True)
    np.logical_or.at(right, i[ok & (side < 0)], True)
    np.fmin.at(gap, i[ok], dist[ok])
    return left, right, gap


def layer_pairs(lines_by_layer: dict[str, list], fills_by_layer: dict[str, list]) -> dict[str, LayerPairs]:
    """LayerPairs of every layer (straight pieces MIN_SEGMENT_M or longer; pairs within a layer only)."""
    names = sorted(set(lines_by_layer) | set(fills_by_layer))
    lines, layer_of = [], []
    for k, name in enumerate(names):
        lines += lines_by_layer.get(name, [])
        layer_of += [k] * len(lines_by_layer.get(name, []))
    p0, p1, owner = segments(lines)
    length = np.hypot(*(p1 - p0).T) if len(p0) else np.zeros(0)
    long = length >= MIN_SEGMENT_M
    p0, p1, owner, length = p0[long], p1[long], owner[long], length[long]
    seg_layer = np.asarray(layer_of, int)[owner] if len(owner) else np.zeros(0, int)
    left, right, gap = pair_sides(p0, p1, seg_layer)
    paired = left | right
    out = {}
    for k, name in enumerate(names):
        m = seg_layer == k
        pm = m & paired
        thin = sum(q.area for q in fills_by_layer.get(name, []) if PAIR_M[0] * q.length <= 2 * q.area
                   <= PAIR_M[1] * q.length)
        face = m & (left ^ right)  # a wall's face: a partner on one side (ladders' inner rungs are left out)
        out[name] = LayerPairs(float(length[m].sum()), float(length[pm].sum()), float(length[m & left & right].sum()),
                               gap[pm], float(thin), list(shapely.linestrings(np.stack([p0[face], p1[face]], axis=1)))
                               if face.any() else [])
    return out


def single_line_rooms(lines: list) -> tuple[float, float]:
    """(area m², edge m) of the rooms a layer's straight ``lines`` enclose on their own:
    the faces of the noded lines at least MIN_ROOM_FACE_M2 and wider on average (2 A / P)
    than the widest wall (a wall's two faces enclose a thin strip, no room); ``edge`` the
    length of their boundaries, shared ones once."""
    if not lines:
        return 0.0, 0.0
    noded = shapely.union_all(np.asarray(lines, dtype=object))
    faces = np.asarray(polygons_of(shapely.polygonize(shapely.get_parts(noded))), dtype=object)
    if not len(faces):
        return 0.0, 0.0
    area, perimeter = shapely.area(faces), shapely.length(faces)
    rooms = faces[(area >= MIN_ROOM_FACE_M2) & (2 * area > PAIR_M[1] * perimeter)]
    if not len(rooms):
        return 0.0, 0.0
    return float(shapely.area(rooms).sum()), float(shapely.union_all(shapely.boundary(rooms)).length)


def _swing(arc: LineString) -> tuple[np.ndarray, float, float, float] | None:
    """(centre (2,), radius m, start angle, sweep) of a flattened arc (its first, middle and
    last points on the circle); None when they lie on a line."""
    c = np.asarray(arc.coords)[:, :2]
    a, b, e = c[0], c[len(c) // 2], c[-1]
    d = 2 * (a[0] * (b[1] - e[1]) + b[0] * (e[1] - a[1]) + e[0] * (a[1] - b[1]))
    if len(c) < 3 or abs(d) < 1e-12:
        return None
    sq = (a * a).sum(), (b * b).sum(), (e * e).sum()
    centre = np.array([sq[0] * (b[1] - e[1]) + sq[1] * (e[1] - a[1]) + sq[2] * (a[1] - b[1]),
                       sq[0] * (e[0] - b[0]) + sq[1] * (a[0] - e[0]) + sq[2] * (b[0] - a[0])]) / d
    ang = np.unwrap(np.arctan2(c[:, 1] - centre[1], c[:, 0] - centre[0]))
    lo, hi = float(ang.min()), float(ang.max())
    return centre, float(np.linalg.norm(a - centre)), lo, hi - lo


def door_leaves(lines: list, arcs: list) -> np.ndarray:
    """Which of the straight ``lines`` (m) are door leaves drawn as a line: from the centre
    of a door swing among ``arcs`` (radius SWING_RADIUS_M) out to about its radius, within
    its sweep (a door drawn open on a wall layer, no wall)."""
    out = np.zeros(len(lines), bool)
    swings = [w for w in (_swing(a) for a in arcs) if w and SWING_RADIUS_M[0] <= w[1] <= SWING_RADIUS_M[1]]
    if not swings or not lines:
        return out
    tol = np.radians(LEAF_ANGLE_DEG)
    for i, ln in enumerate(lines):
        c = np.asarray(ln.coords)[:, :2]
        if len(c) != 2:
            continue
        for centre, r, lo, sweep in swings:
            for p, q in ((c[0], c[1]), (c[1], c[0])):
                v = q - p
                if (np.linalg.norm(p - centre) <= LEAF_HINGE * r
                        and LEAF_LENGTH[0] * r <= np.linalg.norm(v) <= LEAF_LENGTH[1] * r
                        and (np.arctan2(v[1], v[0]) - lo + tol) % (2 * np.pi) <= sweep + 2 * tol):
                    out[i] = True
    return out


def encloses_room(solid) -> bool:
    """True when wall solids (m) enclose a free area of at least MIN_ROOM_FACE_M2 that is
    wider on average than a wall (a room, not the strip between two faces)."""
    return rooms_closed(solid) > 0


def rooms_closed(solid, bridge: float = 0.0) -> int:
    """How many free areas wall solids (m) enclose, each at least MIN_ROOM_FACE_M2 and
    wider on average than a wall, once gaps up to ``bridge`` m (doorways) are closed."""
    if bridge > 0 and not solid.is_empty:
        d = bridge / 2
        solid = shapely.union_all([solid, solid.buffer(d, join_style="mitre").buffer(-d, join_style="mitre")])
    filled = shapely.union_all([Polygon(q.exterior) for q in polygons_of(solid)] or [Polygon()])
    return sum(1 for q in polygons_of(filled.difference(solid))
               if q.area >= MIN_ROOM_FACE_M2 and 2 * q.area > PAIR_M[1] * q.length)


def wall_layers_by_geometry(stats: dict[str, LayerPairs],
                            rooms: dict[str, tuple[float, float]] | None = None) -> dict[str, str]:
    """The layers whose linework looks like walls -> how ('pairs' or 'single'): enough
    parallel pairs a wall's thickness apart with few ladders (stairs, hatching), or
    wall-thin filled areas ('pairs': the wall faces are taken); else, where pairs are
    few, single lines that enclose rooms on their own (``rooms``: layer -> (area, edge)
    of single_line_rooms of its straight lines; 'single': every straight line is a
    wall). Each at least MIN_LAYER_SHARE of the best layer's score (paired or room-edge
    length, m), best first."""
    score, mode = {}, {}
    for name, st in stats.items():
        lines_ok = (st.paired >= MIN_PAIRED_M and st.paired >= MIN_PAIRED_SHARE * st.total
                    and st.ladder <= MAX_LADDER_SHARE * st.paired)
        area, edge = (rooms or {}).get(name, (0.0, 0.0))
        single_ok = (not lines_ok and area >= MIN_SINGLE_ROOMS_M2 and edge >= MIN_SINGLE_SHARE * st.total
                     and st.paired < MIN_PAIRED_SHARE * st.total)
        fills_ok = st.thin >= 1.0
        if lines_ok or single_ok or fills_ok:
            score[name] = (st.paired if lines_ok else edge if single_ok else 0.0) + (st.thin / 0.2 if fills_ok else 0.0)
            mode[name] = "single" if single_ok else "pairs"
    best = max(score.values(), default=0.0)
    return {n: mode[n] for n in sorted(score, key=lambda n: -score[n]) if score[n] >= MIN_LAYER_SHARE * best}


def closing_solid(lines: list, fills: list, radius: float, single: float):
    """The solid (m) of linework and filled areas: lines closed into solids by a
    morphological closing of ``radius`` (so the two faces of a wall up to 2 ``radius``
    thick fill the strip between them), lines that no pair closes given the width
    ``single``, filled areas as they are."""
    parts = [q for q in fills if not q.is_empty]
    if lines:
        arr = np.asarray(lines, dtype=object)
        grown = shapely.union_all(shapely.buffer(arr, radius, join_style="mitre")).simplify(1e-6)  # (no spikes)
        closed = shapely.union_all([q for q in polygons_of(shapely.make_valid(grown.buffer(-radius, join_style="mitre")))
                                    if q.area > MIN_SOLID_M2] or [Polygon()])  # (a lone line's closing: no area)
        parts.append(closed)
        near = closed.buffer(single)
        shapely.prepare(near)
        loose = arr[~shapely.covered_by(arr, near)]
        left = [ln for ln in loose if ln.difference(near).length > single]
        parts += [ln.buffer(single / 2, cap_style="flat", join_style="mitre") for ln in left]
    return shapely.make_valid(shapely.union_all(np.asarray(parts, dtype=object))) if parts else Polygon()


def column_solid(lines: list, fills: list):
    """Columns (m): the faces their outlines enclose, filled areas, other lines 5 cm wide."""
    parts = [q for q in fills if not q.is_empty]
    if lines:
        noded = shapely.union_all(np.asarray(lines, dtype=object))
        faces = polygons_of(shapely.polygonize(shapely.get_parts(noded)))
        parts += faces
        cover = shapely.union_all(np.asarray(faces, dtype=object)) if faces else Polygon()
        rest = noded.difference(cover.buffer(1e-6))
        if rest.length > 0:
            parts.append(rest.buffer(0.025, cap_style="flat"))
    return shapely.make_valid(shapely.union_all(np.asarray(parts, dtype=object))) if parts else Polygon()


def is_wall_fill(poly: Polygon) -> bool:
    """True for a filled area thin enough to be a wall (mean width 2 A / P at most MAX_WALL_WIDTH_M)."""
    return poly.area > 0 and 2 * poly.area <= MAX_WALL_WIDTH_M * poly.length


def building_clusters(pieces: list, weights: list[float], gap: float = BUILDING_GAP_M
                      ) -> tuple[list[Polygon], np.ndarray, np.ndarray]:
    """(clusters, cluster of each piece, each cluster's total weight): pieces (m; walls,
    glass, columns) closer than ``gap`` join one cluster, its pieces grown by gap / 2."""
    if not pieces:
        return [], np.zeros(0, int), np.zeros(0)
    arr = np.asarray(pieces, dtype=object)
    blobs = polygons_of(shapely.union_all(shapely.buffer(arr, gap / 2)))
    tree = shapely.STRtree(np.asarray(blobs, dtype=object))
    inside = tree.query(shapely.point_on_surface(arr), predicate="within")
    blob_of = np.zeros(len(pieces), int)
    blob_of[inside[0]] = inside[1]
    return blobs, blob_of, np.bincount(blob_of, weights=np.asarray(weights, float), minlength=len(blobs))


def fill_gap(walls, opening, reach: float, touch: float = 0.1):
    """The wall gap beside an ``opening`` (a door's plan rectangle, m): the hull of the
    jambs (the pieces of the walls within ``reach`` of it that come within ``touch`` of
    it), less the walls. Where that is larger than a gap can be (the door's length times
    ``reach``: in a room narrower than the band, a WC or closet, the jambs join the walls
    across it), only the jambs' ends within ``touch`` of the door: a thin fill across the
    doorway, never the room behind it."""
    band = opening.buffer(reach, join_style="mitre")
    local = shapely.make_valid(shapely.clip_by_rect(walls, *band.bounds))
    jambs = [q for q in polygons_of(local.intersection(band)) if q.distance(opening) <= touch]
    if not jambs:
        return Polygon()
    gap = shapely.union_all(jambs).convex_hull.difference(local)
    if gap.area <= span(opening) * reach:
        return gap
    ends = local.intersection(opening.buffer(touch, join_style="mitre"))
    return ends.convex_hull.difference(local).difference(opening) if not ends.is_empty else Polygon()


def components(geoms: list, join: float = 0.05) -> list[Polygon]:
    """The outlines (minimum rotated rectangles, m) of the connected groups of
    ``geoms`` (pieces closer than ``join`` m join): one per door or window drawn as loose
    lines, arcs and blocks."""
    if not geoms:
        return []
    arr = np.asarray(geoms, dtype=object)
    blobs = polygons_of(shapely.union_all(shapely.buffer(arr, join / 2, quad_segs=2)))
    a, b = shapely.STRtree(np.asarray(blobs, dtype=object)).query(shapely.point_on_surface(arr), predicate="within")
    out = []
    for k in range(len(blobs)):
        rect = shapely.union_all(arr[a[b == k]]).minimum_rotated_rectangle
        out.append(rect if isinstance(rect, Polygon) and rect.area > 0 else rect.buffer(join / 2))
    return out


def span(geom) -> float:
    """The larger side (m) of a geometry's bounding box."""
    if geom is None or geom.is_empty:
        return 0.0
    x0, y0, x1, y1 = geom.bounds
    return max(x1 - x0, y1 - y0)


def as_lines(geom) -> list[LineString]:
    """The LineStrings of a (multi)line geometry."""
    return [g for g in shapely.get_parts(geom) if isinstance(g, LineString)]
