"""DXF floor plans -> what was understood (PlanImport) and the scene mapping
(camplace.scene.importers.read_plan / import_plan).

The modelspace is read with its block references exploded (dxf_read). Each layer's role
comes from its name in the common conventions and languages (dxf_layers; the
``*_layers`` options replace them); wall layers that no name reveals are found by their
geometry, parallel line pairs a wall's thickness apart or single lines that enclose rooms
(dxf_walls). Walls are the
linework closed into solids, hatches as they are; glass (window layers) and columns are
solids too. The main building is the largest cluster of them: what lies apart (title
block, legend, a second drawing) is left out and counted. Doors are open (their plan
rectangle cuts the walls) or closed (fills the gap); windows and glass occlude.
Furniture blocks become prisms of their plan hull. Rooms are the closed outlines on
room layers, else the free pieces the walls enclose, named by the texts and block
attributes inside (dxf_rooms). The footprint is the building's outline at the outer
faces of its outer walls: the rooms with the walls that bound them (rooms_footprint),
else the walls' outline (walls_outline).
"""

from __future__ import annotations

import re
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon

from camplace.core.errors import InputError
from camplace.scene.importers import (DEFAULT_CEILING_M, PlanImport, plan_scene, polygons_of, prism_obstacles,
                                      room_zones, rooms_footprint, walls_outline)
from camplace.scene.importers.dxf_layers import ROLES, block_role, layer_role, matches
from camplace.scene.importers.dxf_read import FILLED, LINEWORK, Drawing, Shape, filled_polygons, read_dxf
from camplace.scene.importers.dxf_rooms import enclosed_rooms, room_names, room_polygons
from camplace.scene.importers.dxf_units import check_span, read_in_units
from camplace.scene.importers.dxf_walls import (MIN_SEGMENT_M, closing_solid, column_solid, components,
                                                door_leaves, encloses_room, fill_gap, is_wall_fill, layer_pairs, main_building,
                                                single_line_rooms, span, wall_layers_by_geometry)

OPTIONS = ("wall_layers", "door_layers", "window_layers", "column_layers", "furniture_layers", "furniture_heights",
           "room_layers", "doors", "wall_thickness", "max_wall_thickness")
DEFAULT_FURNITURE_M = 0.9
GLASS_M = 0.05  # width of a glass pane drawn as one line, m
DOOR_MAX_M = 3.5  # a door's plan rectangle is at most this long; larger door-layer groups cut nothing
DOOR_M = (0.6, 1.6)  # the typical (median) door rectangle's length that makes sense, m (a leaf and its swing)
BLOCK_MAX_M = 5.0  # a block named like a door, window or furniture is one when at most this large
FURNITURE_MAX_M = 6.0
MIN_FURNITURE_M2 = 0.05  # a closed outline on a furniture layer smaller than this is a detail, no piece
COLUMN_MAX_M2 = 10.0  # larger closed shapes on column layers are no column
ROOM_BRIDGE_M = 1.05  # doorways up to this wide (a 1 m opening) are closed when rooms are found from the walls
MAX_HANDLES = 30  # handles named in one obstacle's provenance
STRAIGHT = {"LINE", "LWPOLYLINE", "POLYLINE"}  # single-line walls: these, not arcs (door swings) or splines
MIN_NAMED_WALLS_M = 8.0  # less linework than this on the wall layers (a legend's stub): ask the geometry too
ALSO_WALLS_SHARE = 0.2  # wall-like pairs elsewhere, this share of the named walls' linework or more, get a note


def read(path: Path, *, name: str | None = None, units: str | None = None, wall_height: float | None = None,
         ceiling_height: float | None = None, heights=None, coverage: int | None = None, budget: int | None = None,
         wall_layers=None, door_layers=None, window_layers=None, column_layers=None, furniture_layers=None,
         furniture_heights: dict | None = None, room_layers=None, doors: str = "open", wall_thickness: float = 0.2,
         max_wall_thickness: float = 0.6) -> PlanImport:
    """What was understood of a DXF floor plan, with its scene mapping (lengths in m;
    ``*_layers``: fnmatch patterns, case-insensitive, replacing the conventions for that
    role)."""
    if doors not in ("open", "closed"):
        raise InputError(f"doors: expected open or closed, got '{doors}'", option="doors")
    doc, damaged = read_dxf(path)
    d = read_in_units(doc, path, units)
    scale, unit_text = d.scale, d.units
    d.notes += [damaged] if damaged else []
    given = {"wall": wall_layers, "door": door_layers, "window": window_layers, "column": column_layers,
             "room": room_layers, "furniture": furniture_layers}
    out = PlanImport({}, "dxf", used={"units": unit_text}, skipped=d.skipped, notes=d.notes)
    role, how = _layer_roles(d, given)
    parts = _by_role(d, role)
    walls, wall_how = _wall_linework(path, d, parts, role, how, given["wall"], max_wall_thickness / 2,
                                     wall_thickness)
    out.used["wall layers"] = _listing(d, wall_how)
    r = max_wall_thickness / 2
    wall_solid = closing_solid(walls[0], walls[1], r, wall_thickness)
    glass = closing_solid(*_lines_fills(parts["window"]), r, GLASS_M)
    columns = shapely.union_all([q for q in polygons_of(column_solid(*_lines_fills(parts["column"])))
                                 if q.area <= COLUMN_MAX_M2] or [Polygon()])
    region, wall_solid, glass, columns = _main_building(out, wall_solid, glass, columns)
    src = path.name
    ceiling = float(ceiling_height or DEFAULT_CEILING_M)
    wall_z = min(float(wall_height or ceiling), ceiling)
    out.notes += check_span(span(wall_solid), scale, unit_text)
    door_rects = _doors(out, parts["door"], region, scale, unit_text)
    uncut = wall_solid
    if doors == "open" and door_rects:
        wall_solid = wall_solid.difference(shapely.union_all(door_rects))
    glass = glass.difference(wall_solid)
    sources = _sources(parts, role)
    obstacles = _obstacles(wall_solid, sources["wall"], 0.0, wall_z, "wall", src, out.skipped)
    obstacles += _obstacles(glass, sources["window"], 0.0, wall_z, "window", src, out.skipped)
    jambs = shapely.union_all([uncut, glass])
    gaps = shapely.union_all([fill_gap(jambs, q, max_wall_thickness) for q in door_rects] or [Polygon()])
    if doors == "closed":
        obstacles += _obstacles(gaps.difference(jambs), sources["door"], 0.0, wall_z, "door", src, out.skipped)
    obstacles += _obstacles(columns, sources["column"], 0.0, ceiling, "column", src, out.skipped)
    obstacles += _furniture(d, role, region, furniture_heights or {}, ceiling, src, out)
    out.openings = [_ring(q) for q in door_rects + polygons_of(glass)]
    for what, rects in (("door", door_rects), ("window", polygons_of(glass))):
        if rects:
            out.used[f"{what}s"] = f"{len(rects)} on {_listing(d, _layers_of(parts[what], how), counts=False)}"
    if not columns.is_empty:
        out.used["columns"] = f"{len(polygons_of(columns))} on {_listing(d, _layers_of(parts['column'], how), False)}"
    rooms, footprint = _rooms_and_footprint(out, d, parts["room"], role, how, region, uncut, glass, columns.union(gaps),
                                            max_wall_thickness, str(path))
    zones = room_zones(rooms, coverage or 2, skipped=out.skipped)
    out.scene = plan_scene(name or path.stem, footprint, ceiling, obstacles, zones, heights=heights,
                           coverage=coverage, budget=budget)
    return out


def import_plan(path: Path, **options) -> dict:
    """The scene mapping of a DXF floor plan (options as read)."""
    return read(path, **options).scene


# ------------------------------------------------------------------ layers and their roles
def _layer_roles(d: Drawing, given: dict) -> tuple[dict[str, str | None], dict[str, str]]:
    """(layer -> role or None, layer -> how the role was found: 'given' or 'by name')."""
    role, how = {}, {}
    for layer in {sh.layer for sh in d.shapes}:
        mine = next((r for r in ROLES if given[r] and matches(layer, given[r])), None)
        if mine is not None:
            role[layer], how[layer] = mine, "given"
            continue
        named = layer_role(layer)
        role[layer] = None if named in ROLES and given[named] else named
        how[layer] = "by name"
    return role, how


def _by_role(d: Drawing, role: dict) -> dict[str, list[Shape]]:
    """Shapes per role: the role of the innermost block reference around them that is
    named like a door, window or furniture and at most BLOCK_MAX_M large, else their
    layer's; a straight line longer than any door (DOOR_MAX_M) on a door layer is no door
    piece but linework no name explains (walls drawn on the door layer: measured like
    the layers no name explains)."""
    size = _part_sizes(d)
    named: dict[int, str | None] = {}
    out: dict[str, list[Shape]] = defaultdict(list)
    for sh in d.shapes:
        if sh.part not in named:
            named[sh.part] = next((r for p in _chain(d, sh.part) if size[p] <= BLOCK_MAX_M
                                   for r in [block_role(d.parts[p][1])] if r), None)
        mine = named[sh.part] or role.get(sh.layer) or "none"
        if not named[sh.part] and mine == "door" and sh.kind in STRAIGHT and sh.geom.length > DOOR_MAX_M:
            mine = "none"
        out[mine].append(sh)
    return out


def _chain(d: Drawing, part: int):
    """The block references around a shape's ``part``, innermost first."""
    while part >= 0:
        yield part
        part = d.parts[part][3]


def _part_sizes(d: Drawing) -> np.ndarray:
    """The larger side (m) of each block reference's content, nested ones included."""
    lo, hi = np.full((len(d.parts), 2), np.inf), np.full((len(d.parts), 2), -np.inf)
    if d.shapes and d.parts:
        b = shapely.bounds(np.asarray([sh.geom for sh in d.shapes], dtype=object))
        for sh, (x0, y0, x1, y1) in zip(d.shapes, b):
            for p in _chain(d, sh.part):
                lo[p] = np.minimum(lo[p], (x0, y0))
                hi[p] = np.maximum(hi[p], (x1, y1))
    return np.nan_to_num((hi - lo).max(axis=1) if len(d.parts) else np.zeros(0), nan=np.inf, neginf=np.inf)


def _extent(geoms: list) -> float:
    """The larger side (m) of the box around ``geoms``."""
    b = shapely.bounds(np.asarray(geoms, dtype=object))
    return float(max(b[:, 2].max() - b[:, 0].min(), b[:, 3].max() - b[:, 1].min()))


def _lines_fills(shapes: list[Shape]) -> tuple[list, list]:
    """(LineStrings, filled Polygons) of shapes, m."""
    lines = [sh.geom for sh in shapes if isinstance(sh.geom, LineString)]
    fills = [q for sh in shapes if not isinstance(sh.geom, LineString) for q in polygons_of(sh.geom)]
    return lines, fills


def _wall_linework(path: Path, d: Drawing, parts: dict, role: dict, how: dict, given, radius: float,
                   single: float) -> tuple[tuple, dict]:
    """((wall lines, wall fills), layer -> how found) by name or given patterns, else by
    geometry; where the named walls (closed into solids: closing_solid with ``radius``,
    ``single``) close no room, the single-line wall layers around them too (a renovation
    plan's new walls named, the building's walls on a layer no name explains); InputError
    listing the layers with linework when there are none."""
    lines, fills = _lines_fills(parts["wall"])
    thin = [q for q in fills if is_wall_fill(q)]
    if len(fills) > len(thin):
        d.skipped["filled areas on wall layers too wide to be walls"] += len(fills) - len(thin)
    named = sum(ln.length for ln in lines) + sum(q.length / 2 for q in thin)
    found = _layers_of(parts["wall"], how)
    if given is None and named < MIN_NAMED_WALLS_M:  # nothing, or a legend's stub: what does the geometry say?
        geo = _walls_by_geometry(d, parts, role)
        if geo is not None and sum(ln.length for ln in geo[0]) > 2 * named:
            d.notes.append(f"{'no layer is named like walls' if not named else 'little on the wall layers'}; took "
                           f"{', '.join(geo[2])} by their geometry ({geo[3]}); if that is wrong, name "
                           "the wall layers (wall_layers)")
            for n in geo[2]:
                role[n] = "wall"
            return (lines + geo[0], thin + geo[1]), {**found, **{n: f"by geometry: {geo[3]}"
                                                               for n in geo[2]}}
    if lines or thin:
        if given is None:  # walls on a layer no name explains besides the named ones? say so, take nothing
            geo = _walls_by_geometry(d, parts, role)
            around = _enclosing(geo[4], closing_solid(lines, thin, radius, single)) if geo else []
            if around:
                d.notes.append(f"the named wall layers close no room; took {', '.join(around)} too: single lines "
                               "enclosing rooms around them; if that is wrong, name the wall layers (wall_layers)")
                for n in around:
                    role[n] = "wall"
                return (lines + [ln for n in around for ln in geo[4][n]], thin), {
                    **found, **{n: "by geometry: single lines enclosing rooms around the named walls" for n in around}}
            extra = sum(ln.length for ln in geo[0]) if geo else 0.0
            if extra >= ALSO_WALLS_SHARE * named:
                d.notes.append(f"{', '.join(geo[2])} also hold{'s' if len(geo[2]) == 1 else ''} {geo[3]} like walls "
                               f"({extra:.0f} m); if they are walls, name every wall layer "
                               "(wall_layers)")
        return (lines, thin), found
    raise InputError(_no_walls_message(path, d, given), option="wall_layers")


def _walls_by_geometry(d: Drawing, parts: dict, role: dict) -> tuple | None:
    """(wall lines, wall-thin fills, layers, what they hold: 'parallel line pairs 0.25 m
    apart' / 'single lines enclosing rooms', the single-line layers -> their straight
    lines) of the layers no name explains whose linework looks like walls
    (dxf_walls.wall_layers_by_geometry: of a layer of pairs its wall faces, of a layer of
    single-line walls its straight lines); None when there are none."""
    by_line, by_fill, straight = defaultdict(list), defaultdict(list), defaultdict(list)
    arcs = [sh.geom for got in parts.values() for sh in got if sh.kind == "ARC" and isinstance(sh.geom, LineString)]
    for sh in parts.get("none", []) + parts.get("other", []):
        if not isinstance(sh.geom, LineString):
            by_fill[sh.layer] += polygons_of(sh.geom)
        elif role.get(sh.layer) in (None, "door"):  # a door layer's lines here are longer than a door
            by_line[sh.layer].append(sh.geom)
            if sh.kind in STRAIGHT and sh.geom.length >= MIN_SEGMENT_M:
                straight[sh.layer].append(sh.geom)
    for n, ls in straight.items():  # door leaves drawn as lines are no single-line walls
        leaf = door_leaves(ls, arcs)
        straight[n] = [ln for ln, x in zip(ls, leaf) if not x]
        if leaf.any():
            d.skipped["door leaves drawn as a line from a swing's centre (no wall)"] += int(leaf.sum())
    stats = layer_pairs(by_line, by_fill)
    chosen = wall_layers_by_geometry(stats, {n: single_line_rooms(ls) for n, ls in straight.items()})
    if not chosen:
        return None
    what = []
    paired = [n for n, m in chosen.items() if m == "pairs"]
    gaps = np.concatenate([stats[n].gaps for n in paired] or [np.zeros(0)])
    if len(gaps):
        lo, hi = np.percentile(gaps, [10, 90])
        what.append(f"parallel line pairs {lo:.2f} m apart" if hi - lo < 0.005 else
                    f"parallel line pairs {lo:.2f}-{hi:.2f} m apart")
    if len(paired) < len(chosen):
        what.append("single lines enclosing rooms")
    lines = [ln for n, m in chosen.items() for ln in (stats[n].lines if m == "pairs" else straight[n])]
    return (lines, [q for n in chosen for q in by_fill.get(n, []) if is_wall_fill(q)], list(chosen),
            "; ".join(what) or "wall-thin filled areas", {n: straight[n] for n, m in chosen.items() if m == "single"})


def _enclosing(singles: dict[str, list], named) -> list[str]:
    """The single-line wall layers (layer -> straight lines, m) whose lines span the
    ``named`` wall solid (90 % of it within their hull grown by 0.5 m), where those named
    walls close no room; [] where they do."""
    if not singles or named.is_empty or encloses_room(named):
        return []
    return [n for n, ls in singles.items()
            if shapely.union_all(ls).convex_hull.buffer(0.5).intersection(named).area >= 0.9 * named.area]


def _no_walls_message(path: Path, d: Drawing, given) -> str:
    per = defaultdict(Counter)
    for (layer, kind), n in d.inventory.items():
        if kind in LINEWORK or kind in FILLED or kind == "MLINE":
            per[layer][kind] += n
    ranked = sorted(per, key=lambda la: -sum(per[la].values()))
    listing = ", ".join(f"{la} ({', '.join(f'{n} {k}' for k, n in per[la].most_common())})" for la in ranked[:12])
    listing += f" and {len(ranked) - 12} more" if len(ranked) > 12 else ""
    where = (f"on the layers {', '.join(given)}" if given else
             "(no layer is named like walls - WALL, WAND, MUR, MURO, PARED, PAREDE, PARETE, A-WALL, ... - and none "
             "holds parallel line pairs 5-60 cm apart or single lines enclosing rooms)")
    have = f"the layers with linework are {listing}" if ranked else "the drawing has no linework"
    return f"{path}: no walls found {where}; {have}; name the wall layers (wall_layers)"


def _layers_of(shapes: list[Shape], how: dict) -> dict[str, str]:
    return {sh.layer: how.get(sh.layer, "by name") for sh in shapes}


def _listing(d: Drawing, layers: dict[str, str], counts: bool = True, most: int = 8) -> str:
    """'E41_AUSSENWAENDE (212 LINE, 4 HATCH), E61_INNENWAENDE (80 LINE) (by name)'."""
    per = defaultdict(Counter)
    for (layer, kind), n in d.inventory.items():
        if layer in layers and (kind in LINEWORK or kind in FILLED):
            per[layer][kind] += n
    names = sorted(layers, key=lambda la: -sum(per[la].values()))
    text = ", ".join(f"{la} ({', '.join(f'{n} {k}' for k, n in per[la].most_common(3))})" if counts and per[la]
                     else la for la in names[:most])
    text += f" and {len(names) - most} more" if len(names) > most else ""
    hows = sorted(set(layers.values()))
    return f"{text} ({'; '.join(hows)})" if hows else text


# ------------------------------------------------------------------ the building and its parts
def _main_building(out: PlanImport, walls, glass, columns):
    """(region, walls, glass, columns) of the main building (the largest cluster)."""
    kinds = [(walls, 1.0), (glass, 0.0), (columns, 0.0)]
    pieces = [(q, w, k) for k, (g, w) in enumerate(kinds) for q in polygons_of(g)]
    region, kept = main_building([p[0] for p in pieces], [p[0].area * p[1] for p in pieces])
    picked = [shapely.union_all([p[0] for p, keep in zip(pieces, kept) if keep and p[2] == k] or [Polygon()])
              for k in range(3)]
    dropped = [p for p, keep in zip(pieces, kept) if not keep]
    if dropped:
        out.skipped["wall, glass and column pieces apart from the main building"] += len(dropped)
        area = sum(p[0].area for p in dropped if p[2] == 0)
        out.notes.append(f"kept the largest building; left out {len(dropped)} pieces apart from it "
                         f"({area:.1f} m² of walls)")
    return region, *picked


def _doors(out: PlanImport, shapes: list[Shape], region, scale: float, units: str) -> list[Polygon]:
    """Plan rectangles (m) of the doors drawn in ``shapes`` inside ``region``: one per
    group of touching pieces (leaf, swing, frame), at most DOOR_MAX_M long (larger groups
    counted); a note when the doors' typical size makes no sense in the drawing's units."""
    rects = components([sh.geom for sh in shapes if sh.geom.intersects(region)])
    keep = [q for q in rects if span(q) <= DOOR_MAX_M]
    if len(rects) > len(keep):
        out.skipped["door outlines too large for one door"] += len(rects) - len(keep)
    if len(rects) >= 3:
        out.notes += check_span(float(np.median([span(q) for q in rects])), scale, units, DOOR_M, "doors")
    return keep


def _sources(parts: dict, role: dict) -> dict[str, tuple]:
    """{'wall', 'window', 'door', 'column'} -> (STRtree of those shapes, the shapes), for provenance."""
    out = {}
    for kind in ("wall", "window", "door", "column"):
        shapes = list(parts.get(kind, []))
        if kind == "wall":  # layers taken by their geometry
            shapes += [sh for sh in parts.get("none", []) + parts.get("other", []) if role.get(sh.layer) == "wall"]
        out[kind] = (shapely.STRtree(np.asarray([sh.geom for sh in shapes], dtype=object)), shapes)
    return out


def _obstacles(geom, sources: tuple, z0: float, z1: float, prefix: str, src: str, skipped: Counter) -> list[dict]:
    """Prisms prefix-1..n of the pieces of ``geom`` (m), each naming the layers and
    handles of the entities that made it."""
    tree, shapes = sources
    out = []
    for piece in polygons_of(geom):
        near = [shapes[i] for i in tree.query(piece, predicate="dwithin", distance=1e-3)] if shapes else []
        handles = list(dict.fromkeys(sh.handle for sh in near if sh.handle))
        source = {"file": src, "layer": ",".join(sorted({sh.layer for sh in near})) or prefix,
                  "handle": ",".join(handles[:MAX_HANDLES]) + (f",+{len(handles) - MAX_HANDLES}"
                                                               if len(handles) > MAX_HANDLES else "")}
        for o in prism_obstacles(piece, z0, z1, prefix, source, skipped=skipped):
            out.append(dict(o, name=f"{prefix}-{len(out) + 1}"))
    return out


def _furniture(d: Drawing, role: dict, region, heights: dict, ceiling: float, src: str,
               out: PlanImport) -> list[dict]:
    """Prisms of the furniture blocks (block references on furniture layers or named
    like furniture, the outermost such one up to FURNITURE_MAX_M) inside the building:
    their plan hull, floor to the height of the first ``heights`` pattern matching the
    reference's layer (default 0.9 m); and of the closed outlines drawn on furniture
    layers outside such blocks (a table drawn as a rectangle, an exploded block's
    outline), each up to FURNITURE_MAX_M and at least MIN_FURNITURE_M2."""
    size = _part_sizes(d)

    def furniture(p: int) -> bool:
        return size[p] <= FURNITURE_MAX_M and (role.get(d.parts[p][0]) == "furniture"
                                               or block_role(d.parts[p][1]) == "furniture")

    groups: dict[int, list] = defaultdict(list)
    outlines = []
    for sh in d.shapes:
        outer = [p for p in _chain(d, sh.part) if furniture(p)]
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


def _rooms_and_footprint(out: PlanImport, d: Drawing, room_shapes: list[Shape], role: dict, how: dict, region,
                         walls, glass, columns, gap: float, source: str) -> tuple[list, Polygon]:
    """([(name, polygon)] rooms, footprint) (m): the closed outlines on room layers in
    the building, named; the footprint those rooms with the walls, glass, columns and door
    gaps that bound them (rooms_footprint: the outer faces of the outer walls). Without
    them (or where they cover less than half the walls' outline) the footprint is the
    walls' outline and the rooms the free pieces the walls enclose."""
    kind: list[str] = []
    outline = walls_outline(walls, how=kind)
    polys = [q for q in filled_polygons(room_shapes) if region.contains(q.representative_point())]
    rooms = room_polygons(polys, out.skipped)
    labels = [lb for lb in d.labels if region.contains(lb.point)]
    barrier = shapely.union_all([walls, glass, columns])
    footprint = rooms_footprint(rooms, barrier, gap, source) if rooms else None
    if rooms:
        out.used["rooms"] = f"{len(rooms)} outlines on {_listing(d, _layers_of(room_shapes, how), counts=False)}"
    if footprint is None or footprint.area < 0.5 * outline.area:
        if footprint is not None:
            out.notes.append(f"the room outlines cover {footprint.area:.0f} m² of the walls' {outline.area:.0f} m²: "
                             "the footprint is the walls' outline")
        footprint = outline
        out.used["footprint"] = f"{footprint.area:.1f} m², {kind[0]}"
        if not rooms:
            rooms = enclosed_rooms(footprint, barrier, ROOM_BRIDGE_M)
            out.used["rooms"] = f"{len(rooms)} free areas the walls enclose (no room outlines)"
    else:
        out.used["footprint"] = f"{footprint.area:.1f} m², the rooms with the walls that bound them (outer faces)"
    names, named = room_names(rooms, labels)
    if named:
        out.used["room names"] = ", ".join(f"{k} ({n})" for k, n in named.items())
    return list(zip(names, rooms)), footprint


def _ring(poly: Polygon) -> list[list[float]]:
    return [[round(float(x), 4), round(float(y), 4)] for x, y in list(poly.exterior.coords)[:-1]]
