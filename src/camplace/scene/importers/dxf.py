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

from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon

from camplace.core.errors import InputError
from camplace.scene.importers import (DEFAULT_CEILING_M, UNITS_M, PlanImport, plan_scene, polygons_of,
                                      prism_obstacles, room_zones, rooms_footprint, walls_outline)
from camplace.scene.importers.dxf_checks import check_floor, close_outlines, room_printed_areas, unit_from_areas
from camplace.scene.importers.dxf_layers import block_role
from camplace.scene.importers.dxf_objects import chain, furniture, part_sizes
from camplace.scene.importers.dxf_plans import Plan, choose, find_plans
from camplace.scene.importers.dxf_read import Drawing, Shape, filled_polygons, read_drawing, read_dxf
from camplace.scene.importers.dxf_rooms import enclosed_rooms, room_names, room_polygons
from camplace.scene.importers.dxf_units import check_span, read_in_units
from camplace.scene.importers.dxf_wall_layers import (STRAIGHT, layer_roles, layers_of, lines_fills, listing,
                                                      wall_linework)
from camplace.scene.importers.dxf_walls import closing_solid, column_solid, components, fill_gap, span

OPTIONS = ("storey", "wall_layers", "door_layers", "window_layers", "column_layers", "furniture_layers",
           "furniture_heights", "room_layers", "doors", "wall_thickness", "max_wall_thickness")
GLASS_M = 0.05  # width of a glass pane drawn as one line, m
DOOR_MAX_M = 3.5  # a door's plan rectangle is at most this long; larger door-layer groups cut nothing
DOOR_M = (0.6, 1.6)  # the typical (median) door rectangle's length that makes sense, m (a leaf and its swing)
BLOCK_MAX_M = 5.0  # a block named like a door, window or furniture is one when at most this large
COLUMN_MAX_M2 = 10.0  # larger closed shapes on column layers are no column
ROOM_BRIDGE_M = 1.05  # doorways up to this wide (a 1 m opening) are closed when rooms are found from the walls
MAX_HANDLES = 30  # handles named in one obstacle's provenance


@dataclass
class _Sheet:
    """What every plan of a sheet shares: the drawing, its layers' roles, the shapes per
    role, the wall, glass and column solids (m) with the pieces they fall into, the plans,
    the summary so far and the options of the walls and doors."""

    path: Path
    d: Drawing
    role: dict
    how: dict
    parts: dict
    base: PlanImport
    pieces: list
    plans: list[Plan]
    doors: str
    max_wall: float
    furniture_heights: dict


def read(path: Path, *, storey: str | None = None, name: str | None = None, wall_height: float | None = None,
         ceiling_height: float | None = None, heights=None, coverage: int | None = None, budget: int | None = None,
         **options) -> PlanImport:
    """What was understood of a DXF floor plan, with its scene mapping (lengths in m;
    ``*_layers``: fnmatch patterns, case-insensitive, replacing the conventions for that
    role); of one plan where the sheet draws several (``storey``: 'plan-N' or its level
    name; default the plan with most walls)."""
    sheet = _sheet(path, **options)
    index, why = choose(sheet.plans, storey, path)
    scene = {"name": name, "wall_height": wall_height, "ceiling_height": ceiling_height, "heights": heights,
             "coverage": coverage, "budget": budget}
    try:
        return _plan(sheet, index, why, **scene)
    except InputError:
        if storey is not None or len(sheet.plans) == 1:
            raise
        for k in sorted(range(len(sheet.plans)), key=lambda k: -sheet.plans[k].walls_m2)[1:]:  # the next that imports
            try:
                return _plan(sheet, k, f"most walls of the plans with a floor; {sheet.plans[index].name} has none",
                             **scene)
            except InputError:
                continue
        raise


def read_storeys(path: Path, *, storey: str | None = None, name: str | None = None, wall_height=None,
                 ceiling_height=None, heights=None, coverage=None, budget=None,
                 **options) -> list[tuple[str, PlanImport]]:
    """(storey name, what was understood) of every plan drawn on the sheet, in reading
    order (dxf_plans), each in the sheet's coordinates; a plan that cannot be a storey
    (no floor) is left out and named in the others' notes (its error raised when no plan
    can)."""
    sheet = _sheet(path, **options)
    out, failed = [], []
    for i, p in enumerate(sheet.plans):
        try:
            out.append((p.name, _plan(sheet, i, "storey 'all'", name=name and f"{name} {p.name}",
                                      wall_height=wall_height, ceiling_height=ceiling_height, heights=heights,
                                      coverage=coverage, budget=budget)))
        except InputError as err:
            failed.append((p.name, err))
    if not out:
        raise failed[0][1]
    for _, got in out:
        got.notes += [f"left out {n}: {str(err).split(': ', 1)[-1]}" for n, err in failed]
    return out


def storey_elevations(path: Path, units=None) -> dict[str, float]:
    """A DXF sheet says no floor levels: every plan at 0 m."""
    return {}


def _sheet(path: Path, *, units: str | None = None, wall_layers=None, door_layers=None, window_layers=None,
           column_layers=None, furniture_layers=None, furniture_heights: dict | None = None, room_layers=None,
           doors: str = "open", wall_thickness: float = 0.2, max_wall_thickness: float = 0.6) -> _Sheet:
    """The drawing read in metres (the unit its area texts prove, when the file says
    another), its layers' roles, the wall, glass and column solids and the plans."""
    if doors not in ("open", "closed"):
        raise InputError(f"doors: expected open or closed, got '{doors}'", option="doors")
    doc, damaged = read_dxf(path)
    d = _unit_checked(doc, read_in_units(doc, path, units), units)
    d.notes += [damaged] if damaged else []
    given = {"wall": wall_layers, "door": door_layers, "window": window_layers, "column": column_layers,
             "room": room_layers, "furniture": furniture_layers}
    out = PlanImport({}, "dxf", used={"units": d.units}, skipped=d.skipped, notes=d.notes)
    role, how = layer_roles(d, given, max_wall_thickness / 2, wall_thickness)
    parts = _by_role(d, role)
    walls, wall_how = wall_linework(path, d, parts, role, how, given["wall"], max_wall_thickness / 2,
                                     wall_thickness)
    out.used["wall layers"] = listing(d, wall_how)
    r = max_wall_thickness / 2
    wall_solid = closing_solid(walls[0], walls[1], r, wall_thickness)
    glass = closing_solid(*lines_fills(parts["window"]), r, GLASS_M)
    columns = shapely.union_all([q for q in polygons_of(column_solid(*lines_fills(parts["column"])))
                                 if q.area <= COLUMN_MAX_M2] or [Polygon()])
    kinds = [(wall_solid, 1.0), (glass, 0.0), (columns, 0.0)]
    pieces = [(q, w, k) for k, (g, w) in enumerate(kinds) for q in polygons_of(g)]
    plans = find_plans([p[0] for p in pieces], [p[0].area * p[1] for p in pieces], d.labels)
    if not plans:  # walls too small to close into anything: the unit, most likely
        check_floor(path, Polygon(), None, d.units, span(shapely.union_all([*walls[0], *walls[1]])) / d.scale)
    return _Sheet(path, d, role, how, parts, out, pieces, plans, doors, max_wall_thickness, furniture_heights or {})


def _unit_checked(doc, d: Drawing, units: str | None) -> Drawing:
    """``d``, or the drawing read again in the unit its area texts and closed outlines
    agree in (dxf_checks.unit_from_areas) where that is not the unit it was read in
    (never against a unit the user gave: a note then)."""
    ev = unit_from_areas(d.labels, lambda: filled_polygons([sh for sh in d.shapes
                                                            if sh.closed or not isinstance(sh.geom, LineString)]),
                         d.scale)
    if ev.unit is None or abs(UNITS_M[ev.unit] / d.scale - 1) < 1e-9:
        return d
    if units is not None:
        d.notes.append(f"{ev.texts} area texts agree with the room outlines in {ev.unit}, not in {units} "
                       f"({ev.example}); is the unit right? (units)")
        return d
    said = d.units
    again = read_drawing(doc, UNITS_M[ev.unit], f"{ev.unit} (from its area texts; the file says {said})")
    again.notes.append(f"read in {ev.unit}, not in the file's unit ({said}): {ev.texts} area texts agree with the "
                       f"room outlines in {ev.unit} only ({ev.example}); if that is wrong, give the unit (units)")
    return again


def _plan(sheet: _Sheet, index: int, why: str, *, name=None, wall_height=None, ceiling_height=None, heights=None,
          coverage=None, budget=None) -> PlanImport:
    """What was understood of plan ``index`` of the sheet (its scene in the sheet's coordinates)."""
    path, d, role, how, parts = sheet.path, sheet.d, sheet.role, sheet.how, sheet.parts
    base = sheet.base
    out = PlanImport({}, "dxf", used=dict(base.used), skipped=Counter(base.skipped), notes=list(base.notes))
    region, wall_solid, glass, columns = _one_plan(out, sheet, index, why)
    scale, unit_text, src = d.scale, d.units, path.name
    ceiling = float(ceiling_height or DEFAULT_CEILING_M)
    wall_z = min(float(wall_height or ceiling), ceiling)
    out.notes += check_span(span(wall_solid), scale, unit_text)
    door_rects = _doors(out, parts["door"], region, scale, unit_text)
    uncut = wall_solid
    if sheet.doors == "open" and door_rects:
        wall_solid = wall_solid.difference(shapely.union_all(door_rects))
    glass = glass.difference(wall_solid)
    sources = _sources(parts, role)
    obstacles = _obstacles(wall_solid, sources["wall"], 0.0, wall_z, "wall", src, out.skipped)
    obstacles += _obstacles(glass, sources["window"], 0.0, wall_z, "window", src, out.skipped)
    jambs = shapely.union_all([uncut, glass])
    gaps = shapely.union_all([fill_gap(jambs, q, sheet.max_wall) for q in door_rects] or [Polygon()])
    if sheet.doors == "closed":
        obstacles += _obstacles(gaps.difference(jambs), sources["door"], 0.0, wall_z, "door", src, out.skipped)
    obstacles += _obstacles(columns, sources["column"], 0.0, ceiling, "column", src, out.skipped)
    obstacles += furniture(d, role, region, sheet.furniture_heights, ceiling, src, out)
    out.openings = [_ring(q) for q in door_rects + polygons_of(glass)]
    for what, rects in (("door", door_rects), ("window", polygons_of(glass))):
        if rects:
            out.used[f"{what}s"] = f"{len(rects)} on {listing(d, layers_of(parts[what], how), counts=False)}"
    if not columns.is_empty:
        out.used["columns"] = f"{len(polygons_of(columns))} on {listing(d, layers_of(parts['column'], how), False)}"
    try:
        rooms, footprint = _rooms_and_footprint(out, d, parts["room"], role, how, region, uncut, glass,
                                                columns.union(gaps), sheet.max_wall, str(path))
    except InputError:  # no walls to make a footprint of: say why (a wrong unit, most likely) and the fix
        rooms, footprint = [], Polygon()
    check_floor(path, footprint, shapely.union_all([uncut, glass, columns]), unit_text, span(uncut) / scale)
    zones = room_zones(rooms, coverage or 2, skipped=out.skipped)
    title = name or (path.stem if len(sheet.plans) == 1 else f"{path.stem} {sheet.plans[index].name}")
    out.scene = plan_scene(title, footprint, ceiling, obstacles, zones, heights=heights,
                           coverage=coverage, budget=budget)
    return out


def import_plan(path: Path, **options) -> dict:
    """The scene mapping of a DXF floor plan (options as read)."""
    return read(path, **options).scene


# ------------------------------------------------------------------ layers and their roles
def _by_role(d: Drawing, role: dict) -> dict[str, list[Shape]]:
    """Shapes per role: the role of the innermost block reference around them that is
    named like a door, window or furniture and at most BLOCK_MAX_M large, else their
    layer's; a straight line longer than any door (DOOR_MAX_M) on a door layer is no door
    piece but linework no name explains (walls drawn on the door layer: measured like
    the layers no name explains)."""
    size = part_sizes(d)
    named: dict[int, str | None] = {}
    out: dict[str, list[Shape]] = defaultdict(list)
    for sh in d.shapes:
        if sh.part not in named:
            named[sh.part] = next((r for p in chain(d, sh.part) if size[p] <= BLOCK_MAX_M
                                   for r in [block_role(d.parts[p][1])] if r), None)
        mine = named[sh.part] or role.get(sh.layer) or "none"
        if not named[sh.part] and mine == "door" and sh.kind in STRAIGHT and sh.geom.length > DOOR_MAX_M:
            mine = "none"
        out[mine].append(sh)
    return out


def _one_plan(out: PlanImport, sheet: _Sheet, index: int, why: str):
    """(region, walls, glass, columns) of plan ``index`` of the sheet; the pieces apart
    from it (a title block's key plan, a legend, the other plans) left out and said."""
    plan, pieces = sheet.plans[index], sheet.pieces
    picked = [shapely.union_all([p[0] for p, keep in zip(pieces, plan.kept) if keep and p[2] == k] or [Polygon()])
              for k in range(3)]
    dropped = [p for p, keep in zip(pieces, plan.kept) if not keep]
    if len(sheet.plans) > 1:
        out.used["plans"] = f"{len(sheet.plans)} on the sheet; {plan.name} ({why})"
    if len(sheet.plans) > 1 and why != "storey 'all'":
        out.notes.append(f"{len(sheet.plans)} plans on the sheet ({', '.join(p.name for p in sheet.plans)}, left "
                         f"to right, then top to bottom): {plan.name} taken ({why}); choose another with storey="
                         "'NAME' (or plan-N), or storey='all' for every plan")
    if dropped:
        out.skipped["wall, glass and column pieces apart from the plan" if len(sheet.plans) > 1 else
                    "wall, glass and column pieces apart from the main building"] += len(dropped)
        area = sum(p[0].area for p in dropped if p[2] == 0)
        out.notes.append(f"kept {'the largest building' if len(sheet.plans) == 1 else plan.name}; left out "
                         f"{len(dropped)} pieces apart from it ({area:.1f} m² of walls)")
    return plan.region, *picked


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


def _rooms_and_footprint(out: PlanImport, d: Drawing, room_shapes: list[Shape], role: dict, how: dict, region,
                         walls, glass, columns, gap: float, source: str) -> tuple[list, Polygon]:
    """([(name, polygon)] rooms, footprint) (m): the closed outlines on room layers in
    the building, named; the footprint those rooms with the walls, glass, columns and door
    gaps that bound them (rooms_footprint: the outer faces of the outer walls). Without
    them (or where they cover less than half the walls' outline) the footprint is the
    walls' outline and the rooms the free pieces the walls enclose."""
    kind: list[str] = []
    outline = walls_outline(walls, how=kind)
    closed, n_closed, left_open = close_outlines([sh for sh in room_shapes if sh.geom.intersects(region)], gap)
    polys = [q for q in filled_polygons(room_shapes) + closed if region.contains(q.representative_point())]
    if n_closed:
        out.notes.append(f"closed {n_closed} open room outline{'s' if n_closed > 1 else ''} (ends at most "
                         f"{gap:g} m apart, a wall's thickness)")
    if left_open:
        out.notes.append(f"left out {len(left_open)} open room outline{'s' if len(left_open) > 1 else ''} whose "
                         f"ends lie {min(left_open):.2f}-{max(left_open):.2f} m apart (more than a wall's "
                         f"{gap:g} m; max_wall_thickness)")
        out.skipped["open room outlines"] += len(left_open)
    rooms = room_polygons(polys, out.skipped)
    labels = [lb for lb in d.labels if region.contains(lb.point)]
    barrier = shapely.union_all([walls, glass, columns])
    footprint = rooms_footprint(rooms, barrier, gap, source) if rooms else None
    if rooms:
        out.used["rooms"] = f"{len(rooms)} outlines on {listing(d, layers_of(room_shapes, how), counts=False)}"
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
    out.notes += room_printed_areas(rooms, names, labels)
    return list(zip(names, rooms)), footprint


def _ring(poly: Polygon) -> list[list[float]]:
    return [[round(float(x), 4), round(float(y), 4)] for x, y in list(poly.exterior.coords)[:-1]]
