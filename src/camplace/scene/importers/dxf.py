"""DXF floor plans -> a scene mapping (camplace.scene.importers.import_plan).

Walls: LINE, LWPOLYLINE/POLYLINE, ARC and HATCH entities on wall layers. Double-line
walls are closed into solids by a morphological closing of the linework (buffer by half
the thickest wall, union, buffer back), single lines get ``wall_thickness``; HATCH
boundaries are solid already. Doors (door layers, or blocks named ``*DOOR*``) cut the
walls (``doors: open``, the default) or fill their gap (``closed``); windows fill it.
Furniture blocks become prisms of their plan hull, ``furniture_heights`` per layer
pattern. Closed polylines on room layers become zones named by the TEXT/MTEXT inside.
"""

from __future__ import annotations

from fnmatch import fnmatch
from pathlib import Path

import shapely
from shapely.geometry import LineString, MultiPoint, Point, Polygon, box

from camplace.core.errors import InputError
from camplace.scene.importers import (PlanImport, DEFAULT_CEILING_M, footprint_of, plan_scene, polygons_of, prism_obstacles,
                                      room_zones, rooms_footprint, unit_scale)

OPTIONS = ("wall_layers", "door_layers", "window_layers", "furniture_layers", "furniture_heights", "room_layers",
           "doors", "wall_thickness", "max_wall_thickness")
WALL_LAYERS = ("A-WALL*", "WALL*", "WAND*")
DOOR_LAYERS = ("A-DOOR*", "DOOR*", "TUER*")
WINDOW_LAYERS = ("A-GLAZ*", "WINDOW*", "FENSTER*")
FURNITURE_LAYERS = ("A-FURN*", "A-EQPM*", "FURN*", "MOEBEL*")
ROOM_LAYERS = ("A-AREA*", "ROOM*", "A-SPACE*", "RAUM*")
INSUNITS = {1: "in", 2: "ft", 4: "mm", 5: "cm", 6: "m"}
FLATTEN = 0.01  # chord error of arcs and bulges, drawing units x this / metre-scale (see _paths)
DEFAULT_FURNITURE_M = 0.9


def _matches(layer: str, patterns) -> bool:
    name = layer.upper()
    return any(fnmatch(name, p.upper()) for p in patterns)


def _read(path: Path):
    import ezdxf

    try:
        return ezdxf.readfile(str(path))
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"{path}: cannot read the file ({err})") from None
    except ezdxf.DXFError as err:
        raise InputError(f"{path}: not a DXF file ({str(err).splitlines()[0] if str(err) else type(err).__name__})"
                         ) from None


def _units(doc, path: Path, units: str | None) -> float:
    """Metres per drawing unit: ``units`` if given, else the header's $INSUNITS."""
    if units is not None:
        return unit_scale(units)
    code = int(doc.header.get("$INSUNITS", 0))
    if code not in INSUNITS:
        raise InputError(f"{path}: the drawing units are unknown ($INSUNITS {code}); expected mm, cm, m, in or ft "
                         "(units)", option="units")
    return unit_scale(INSUNITS[code])


def _points(entity, s: float) -> list[list[tuple[float, float]]]:
    """Plan vertex lists (m) of the entity's paths (arcs and bulges flattened)."""
    from ezdxf import path as dxfpath

    paths = dxfpath.from_hatch(entity) if entity.dxftype() == "HATCH" else [dxfpath.make_path(entity)]
    out = []
    for p in paths:
        pts = [(v.x * s, v.y * s) for v in p.flattening(FLATTEN / s)]
        if len(pts) >= 2:
            out.append(pts)
    return out


def _walls(msp, s: float, layers, thickness: float, max_thickness: float) -> tuple[object, list[tuple]]:
    """(wall solid (m), [(geometry, layer, handle)] of the wall entities): closing of the
    linework, HATCH solids."""
    lines, solids, found = [], [], []
    for e in msp.query("LINE LWPOLYLINE POLYLINE ARC HATCH"):
        if not _matches(e.dxf.layer, layers):
            continue
        for pts in _points(e, s):
            if e.dxftype() == "HATCH" and len(pts) >= 3:
                solids.append(shapely.make_valid(Polygon(pts)))
            else:
                lines.append(LineString(pts))
            found.append(((solids if e.dxftype() == "HATCH" else lines)[-1], e.dxf.layer, e.dxf.handle))
    if not lines and not solids:
        return None, found
    r = max_thickness / 2
    net = shapely.unary_union(lines)
    closed = net.buffer(r, join_style="mitre").buffer(-r, join_style="mitre") if lines else Polygon()
    single = [ln for ln in lines if ln.difference(closed.buffer(thickness)).length > thickness]
    parts = [closed, *solids, *(ln.buffer(thickness / 2, cap_style="flat") for ln in single)]
    return shapely.unary_union(parts), found


def _wall_obstacles(walls, found: list[tuple], z: float, src: str) -> list[dict]:
    """Prism obstacles wall-1..n, each naming the layers and handles of the entities in it."""
    out = []
    for piece in polygons_of(walls):
        near = [(layer, h) for g, layer, h in found if g.distance(piece) < 1e-3]
        source = {"file": src, "layer": ",".join(sorted({layer for layer, _ in near})),
                  "handle": ",".join(h for _, h in near)}
        out += [dict(o, name=f"wall-{len(out) + 1}") for o in prism_obstacles(piece, 0.0, z, "wall", source)]
    return out


def _hull(entity, s: float):
    """Plan polygon (m) of an entity or block reference: the hull of its flattened paths."""
    pts = []
    ents = entity.virtual_entities() if entity.dxftype() == "INSERT" else [entity]
    for ve in ents:
        if ve.dxftype() == "INSERT":
            pts += list(_hull(ve, s).exterior.coords) if not _hull(ve, s).is_empty else []
            continue
        try:
            for ring in _points(ve, s):
                pts += ring
        except (TypeError, ValueError, AttributeError):  # TEXT, ATTRIB, ...: no outline
            continue
    hull = MultiPoint(pts).convex_hull if pts else Polygon()
    return hull if isinstance(hull, Polygon) else hull.buffer(0.01)


def _fill_gap(walls, opening, reach: float):
    """The wall gap next to an ``opening`` (a door's / window's plan box, m): what a
    closing of the walls near it adds within ``reach`` m of the box."""
    x0, y0, x1, y1 = opening.bounds
    R = max(x1 - x0, y1 - y0) / 2 + 0.05
    region = opening.buffer(reach, join_style="mitre")
    local = walls.intersection(region.buffer(R))
    closed = local.buffer(R, join_style="mitre").buffer(-R, join_style="mitre")
    gap = closed.intersection(region).difference(walls).buffer(-1e-4)
    return shapely.unary_union([q.convex_hull for q in polygons_of(gap)]).difference(walls)


def _openings(msp, s: float, door_layers, window_layers) -> tuple[list, list]:
    """([(polygon, entity)] doors, [(polygon, entity)] windows): plan boxes (m)."""
    doors, windows = [], []
    for e in msp:
        layer = e.dxf.get("layer", "0")
        is_door = _matches(layer, door_layers) or (e.dxftype() == "INSERT" and "DOOR" in e.dxf.name.upper())
        is_window = not is_door and _matches(layer, window_layers)
        if not (is_door or is_window):
            continue
        hull = _hull(e, s)
        if hull.is_empty:
            continue
        (doors if is_door else windows).append((box(*hull.bounds), e))
    return doors, windows


def _merge(items: list) -> list:
    """Door / window pieces (polygon, entity) merged where they overlap, first entity kept."""
    out: list = []
    for poly, e in items:
        for k, (q, f) in enumerate(out):
            if q.intersects(poly):
                out[k] = (q.union(poly).envelope, f)
                break
        else:
            out.append((poly, e))
    return out


def _furniture(msp, s: float, layers, heights: dict, ceiling: float, src: str) -> list[dict]:
    out = []
    for e in msp.query("INSERT"):
        if not _matches(e.dxf.layer, layers):
            continue
        h = next((float(v) for k, v in heights.items() if _matches(e.dxf.layer, [k])), DEFAULT_FURNITURE_M)
        hull = _hull(e, s)
        if hull.is_empty:
            continue
        obs = prism_obstacles(hull, 0.0, min(h, ceiling - 0.05), f"{e.dxf.name.lower()}",
                              {"file": src, "layer": e.dxf.layer, "block": e.dxf.name, "handle": e.dxf.handle})
        out += [dict(o, name=f"{o['name'].rsplit('-', 1)[0]}-{len(out) + 1}") for o in obs]
    return out


def _labels(msp, s: float) -> list[tuple[Point, str]]:
    out = []
    for e in msp.query("TEXT MTEXT"):
        text = e.plain_text() if e.dxftype() == "MTEXT" else e.dxf.text
        text = " ".join(str(text).split())
        if text:
            p = e.dxf.insert
            out.append((Point(p.x * s, p.y * s), text))
    return out


def _rooms(msp, s: float, layers) -> list[tuple[str, Polygon]]:
    polys = []
    for e in msp.query("LWPOLYLINE POLYLINE"):
        if _matches(e.dxf.layer, layers) and e.is_closed:
            for pts in _points(e, s):
                if len(pts) >= 3:
                    polys.append(shapely.make_valid(Polygon(pts)))
    labels = _labels(msp, s)
    out = []
    for k, poly in enumerate(polys):
        inside = [t for p, t in labels if poly.contains(p)]
        out.append((inside[0] if inside else f"room-{k + 1}", poly))
    return out


def import_plan(path: Path, *, name: str | None = None, units: str | None = None, wall_height: float | None = None,
                ceiling_height: float | None = None, heights=None, coverage: int | None = None,
                budget: int | None = None, wall_layers=WALL_LAYERS, door_layers=DOOR_LAYERS,
                window_layers=WINDOW_LAYERS, furniture_layers=FURNITURE_LAYERS, furniture_heights: dict | None = None,
                room_layers=ROOM_LAYERS, doors: str = "open", wall_thickness: float = 0.2,
                max_wall_thickness: float = 0.6) -> dict:
    """The scene mapping of a DXF floor plan (lengths in m; layer patterns fnmatch-style,
    case-insensitive)."""
    if doors not in ("open", "closed"):
        raise InputError(f"doors: expected open or closed, got '{doors}'", option="doors")
    doc = _read(path)
    s = _units(doc, path, units)
    msp = doc.modelspace()
    ceiling = float(ceiling_height or DEFAULT_CEILING_M)
    wall_z = min(float(wall_height or ceiling), ceiling)
    walls, found = _walls(msp, s, wall_layers, wall_thickness, max_wall_thickness)
    if walls is None or walls.area <= 0:
        raise InputError(f"{path}: no walls found (no LINE, LWPOLYLINE, POLYLINE, ARC or HATCH on the layers "
                         f"{', '.join(wall_layers)})")
    src = path.name
    door_boxes, window_boxes = (_merge(x) for x in _openings(msp, s, door_layers, window_layers))
    fills = [("window", _fill_gap(walls, poly, max_wall_thickness), e) for poly, e in window_boxes]
    for poly, e in door_boxes:
        if doors == "open":
            walls = walls.difference(poly)
        else:
            fills.append(("door", _fill_gap(walls, poly, max_wall_thickness), e))
    obstacles = _wall_obstacles(walls, found, wall_z, src)
    for what, gap, e in fills:
        obs = prism_obstacles(gap, 0.0, wall_z, what, {"file": src, "layer": e.dxf.get("layer", "0"),
                                                       "handle": e.dxf.handle})
        n = sum(o["name"].startswith(f"{what}-") for o in obstacles)
        obstacles += [dict(o, name=f"{what}-{n + k + 1}") for k, o in enumerate(obs)]
    obstacles += _furniture(msp, s, furniture_layers, furniture_heights or {}, ceiling, src)
    rooms = _rooms(msp, s, room_layers)
    if not rooms:  # the enclosed free pieces inside the walls' outline
        rooms = [(f"room-{k + 1}", q) for k, q in enumerate(
            q for q in polygons_of(footprint_of([walls], str(path)).difference(walls)) if q.area >= 1.0)]
    footprint = rooms_footprint([p for _, p in rooms], walls, max_wall_thickness, str(path))
    return plan_scene(name or path.stem, footprint, ceiling, obstacles, room_zones(rooms, coverage or 2),
                      heights=heights, coverage=coverage, budget=budget)


def read(path: Path, **options) -> PlanImport:
    """What was understood of the plan (options as import_plan)."""
    return PlanImport(import_plan(path, **options), "dxf")
