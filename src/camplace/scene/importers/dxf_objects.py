"""Objects in a DXF plan (m): furniture blocks and outlines as prisms of their plan hull
with their height, the block references around a shape (chain, part_sizes), and the
layers that hold objects though their name or their line pairs look like walls
(object_layers: small closed shapes and repeated blocks that close no room, such as a
'Works of Art - sculpture-murals' layer).
"""

from __future__ import annotations

import re
from collections import Counter, defaultdict

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon

from camplace.scene.importers import PlanImport, polygons_of, prism_obstacles
from camplace.scene.importers.dxf_layers import block_role, matches
from camplace.scene.importers.dxf_read import Drawing, Shape
from camplace.scene.importers.dxf_walls import closing_solid, rooms_closed, span

DEFAULT_FURNITURE_M = 0.9
FURNITURE_MAX_M = 6.0
MIN_FURNITURE_M2 = 0.05  # a closed outline on a furniture layer smaller than this is a detail, no piece
OBJECT_SHARE = 0.8  # a layer is objects when at least this share of its linework is small closed shapes or blocks
DOORWAY_M = 1.05  # doorways up to this wide are closed when counting the rooms a layer closes


def object_layers(d: Drawing, shapes: dict[str, list[Shape]], radius: float, single: float,
                  around=None) -> dict[str, str]:
    """The layers (layer -> its shapes) that hold objects, not walls -> what they hold
    ('3 small closed shapes, 2 repeated blocks'): at least OBJECT_SHARE of the layer's
    linework (m) in closed shapes or in blocks inserted twice or more on it, each at most
    FURNITURE_MAX_M large, and the layer closes no room: with the other layers of
    ``shapes`` and the walls ``around`` (a solid, m) it encloses no more rooms
    (rooms_closed, doorways up to DOORWAY_M closed) than they do without it. Linework is
    closed into solids by closing_solid with ``radius``, ``single``."""
    size = part_sizes(d)
    candidates = {}
    for layer, got in shapes.items():
        outer = [next(iter(reversed(list(chain(d, sh.part)))), -1) for sh in got]
        blocks = Counter(d.parts[p][1] for p in set(outer) if p >= 0)
        small_closed, repeated, total, objects = set(), set(), 0.0, 0.0
        for sh, p in zip(got, outer):
            length = sh.geom.length if isinstance(sh.geom, LineString) else sh.geom.length / 2
            total += length
            if p >= 0 and size[p] <= FURNITURE_MAX_M and blocks[d.parts[p][1]] >= 2:
                repeated.add(p)
                objects += length
            elif p < 0 and sh.closed and span(sh.geom) <= FURNITURE_MAX_M:
                small_closed.add(id(sh))
                objects += length
        if total > 0 and objects >= OBJECT_SHARE * total:
            what = [f"{len(small_closed)} small closed shapes"] if small_closed else []
            candidates[layer] = ", ".join(what + ([f"{len(repeated)} repeated blocks"] if repeated else []))
    if not candidates:
        return {}
    solids = {}
    for layer, got in shapes.items():
        lines = [sh.geom for sh in got if isinstance(sh.geom, LineString)]
        fills = [q for sh in got if not isinstance(sh.geom, LineString) for q in polygons_of(sh.geom)]
        solids[layer] = closing_solid(lines, fills, radius, single)
    base = around if around is not None else Polygon()
    out = {}
    for layer, what in candidates.items():
        others = shapely.union_all([base, *(q for la, q in solids.items() if la != layer)])
        if rooms_closed(shapely.union_all([others, solids[layer]]), DOORWAY_M) <= rooms_closed(others, DOORWAY_M):
            out[layer] = what
    return out


def chain(d: Drawing, part: int):
    """The block references around a shape's ``part``, innermost first."""
    while part >= 0:
        yield part
        part = d.parts[part][3]


def part_sizes(d: Drawing) -> np.ndarray:
    """The larger side (m) of each block reference's content, nested ones included."""
    lo, hi = np.full((len(d.parts), 2), np.inf), np.full((len(d.parts), 2), -np.inf)
    if d.shapes and d.parts:
        b = shapely.bounds(np.asarray([sh.geom for sh in d.shapes], dtype=object))
        for sh, (x0, y0, x1, y1) in zip(d.shapes, b):
            for p in chain(d, sh.part):
                lo[p] = np.minimum(lo[p], (x0, y0))
                hi[p] = np.maximum(hi[p], (x1, y1))
    return np.nan_to_num((hi - lo).max(axis=1) if len(d.parts) else np.zeros(0), nan=np.inf, neginf=np.inf)


def furniture(d: Drawing, role: dict, region, heights: dict, ceiling: float, src: str,
               out: PlanImport) -> list[dict]:
    """Prisms of the furniture blocks (block references on furniture layers or named
    like furniture, the outermost such one up to FURNITURE_MAX_M) inside the building:
    their plan hull, floor to the height of the first ``heights`` pattern matching the
    reference's layer (default 0.9 m); and of the closed outlines drawn on furniture
    layers outside such blocks (a table drawn as a rectangle, an exploded block's
    outline), each up to FURNITURE_MAX_M and at least MIN_FURNITURE_M2."""
    size = part_sizes(d)

    def is_furniture(p: int) -> bool:
        return bool(size[p] <= FURNITURE_MAX_M and (role.get(d.parts[p][0]) == "furniture"
                                                    or block_role(d.parts[p][1]) == "furniture"))

    groups: dict[int, list] = defaultdict(list)
    outlines = []
    for sh in d.shapes:
        outer = [p for p in chain(d, sh.part) if is_furniture(p)]
        if outer:
            groups[outer[-1]].append(sh.geom)
        elif sh.closed and role.get(sh.layer) == "furniture":
            outlines.append(sh)
    pieces = [(shapely.union_all(geoms).convex_hull, *d.parts[p][:3]) for p, geoms in groups.items()]
    n_blocks = len(pieces)
    for sh in outlines:
        shape = polygons_of(Polygon(sh.geom.coords) if isinstance(sh.geom, LineString) else sh.geom)
        if shape and span(shape[0]) <= FURNITURE_MAX_M and shape[0].area >= MIN_FURNITURE_M2:
            pieces.append((shape[0], sh.layer, "", sh.handle))
    obstacles = []
    for k, (hull, layer, block, handle) in enumerate(pieces):
        if not hull.intersects(region):
            out.skipped["furniture blocks outside the building" if k < n_blocks else
                        "furniture outlines outside the building"] += 1
            continue
        hull = hull if isinstance(hull, Polygon) else hull.buffer(0.01)
        h = next((float(v) for k, v in heights.items() if matches(layer, [k])), DEFAULT_FURNITURE_M)
        label = re.sub(r"[^a-z0-9_]+", "-", block.lower()).strip("-") or "furniture"
        source = {"file": src, "layer": layer, "handle": handle, **({"block": block} if block else {})}
        for o in prism_obstacles(hull, 0.0, min(h, ceiling - 0.05), label, source, skipped=out.skipped):
            obstacles.append(dict(o, name=f"{o['name'].rsplit('-', 1)[0]}-{len(obstacles) + 1}"))
    if obstacles:
        n_out = sum(1 for o in obstacles if "block" not in o["source"])
        out.used["furniture"] = f"{len(obstacles) - n_out} blocks" + (
            f", {n_out} outline{'s' if n_out > 1 else ''} on furniture layers" if n_out else "")
    return obstacles


