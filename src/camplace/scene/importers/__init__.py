"""Plans people have -> an editable scene mapping (issue 18): CAD floor plans (DXF),
plan images (PNG/JPG/TIFF, PDF) and BIM models (IFC), and any format a plugin adds.

Plan formats are plugins (issue 35): entry points of the group ``camplace.importers``,
read through ``IMPORTERS`` (a camplace.core.plugins.Registry). An entry point loads an
importer: an object with ``suffixes`` (lowercase, with the dot: ``(".geojson",)``) and
``read(path, **options)`` returning a :class:`PlanImport` or a plain scene-file mapping
(``room``, ``obstacles``, ``zones``, ...: validated like a scene file; the keys it leaves
out - targets, cameras, mounts, placement - get the defaults of every plan import,
:func:`scene_defaults`). Optional: ``options`` (the option names ``read`` takes beyond the
common ones; default: its keyword parameters), ``label`` (for help and docs),
``read_storeys(path, **options)`` and ``storey_elevations(path, units=None)`` (storey
'all'). camplace's own (``ifc``, ``dxf``, ``image``) are :class:`PlanFormat` objects
declared in its pyproject.toml the same way; their modules load at the first read. The
suffix map, the CLI's format lists and its help are derived from the registry
(:func:`plan_suffixes`, :func:`formats_text`). The helpers below build a scene's parts the
same way for every format.
"""

from __future__ import annotations

import inspect
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

from camplace.core.errors import InputError
from camplace.scene.formats import (DXF, IFC, IMAGE, IMPORTERS, NATIVE_FORMATS, PlanFormat,  # noqa: F401 - re-exported
                                    check_importer, formats_text, plan_kind, plan_suffixes)
from camplace.scene.from_scan import DEFAULT_CAMERA

UNITS_M = {"mm": 0.001, "cm": 0.01, "m": 1.0, "in": 0.0254, "ft": 0.3048}  # metres per unit
COMMON_OPTIONS = ("name", "units", "wall_height", "ceiling_height", "heights", "coverage", "budget")
FILLED_OPTIONS = ("name", "heights", "coverage", "budget")  # what camplace applies to a plugin's scene mapping
DEFAULT_CEILING_M = 3.0
MIN_PRISM_AREA_M2 = 1e-4  # wall pieces smaller than this (1 cm²) are dropped
MIN_ZONE_PIECE_M2 = 0.5  # a room's further pieces smaller than this are specks, no zones
GRID_M = 1e-4  # every imported polygon is snapped to this grid (the 4 decimals the YAML keeps) and made valid on it
SLIVER_M = 0.002  # a piece thinner than this (2 mm: area / half its perimeter) is a sliver, dropped


@dataclass
class PlanImport:
    """What an importer understood of a plan, beside the scene mapping it made.

    ``scene``: the scene-file mapping (room, obstacles, zones, ...; lengths in m).
    ``kind``: the importer's name ('ifc', 'dxf', 'image' or a plugin's). ``used``: what
    the importer took and how, one short line per item for the summary table (e.g. {"wall layers": "Walls (60 LINE)",
    "units": "cm ($INSUNITS 5)", "scale": "0.0313 m/px (scale bar)"}). ``skipped``:
    reason -> count of what it left out (never a failed import for one bad element).
    ``openings``: plan polygons (m, [[x, y], ...]) of the doors and windows it found,
    for the preview. ``storeys``: IFC, every storey of the file as {"name",
    "elevation_m", "rooms": [[name, area m²], ...], "chosen": bool}. ``notes``: lines
    the user should read (a guessed scale, the default storey and why).
    ``floor_openings``: plan polygons (m, [[x, y], ...]) where this storey's floor is
    open to the storey below (slab openings, stair voids, atria, shafts, the upper part
    of a space below that is taller than its storey); a building carves them out of the
    slab between the two storeys (camplace.scene.building)."""

    scene: dict
    kind: str
    used: dict[str, str] = field(default_factory=dict)
    skipped: Counter = field(default_factory=Counter)
    openings: list[list[list[float]]] = field(default_factory=list)
    storeys: list[dict] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    floor_openings: list[list[list[float]]] = field(default_factory=list)


def unit_scale(units: str) -> float:
    """Metres per unit of ``units`` (mm, cm, m, in, ft); InputError otherwise."""
    if units not in UNITS_M:
        raise InputError(f"units: unknown unit '{units}'; expected one of {', '.join(UNITS_M)}", option="units")
    return UNITS_M[units]


def read_plan(path: str | Path, **options: Any) -> PlanImport:
    """What the importer understood of a plan file: the scene mapping and the summary
    (``options``: None values are left to the importer's defaults; an option the format
    does not take is an InputError). A plugin's plain mapping is completed (scene_defaults)
    and checked by the scene schema here."""
    kind, importer, p, given, filled = _importer(path, options)
    return as_plan_import(_call(kind, importer.read, p, given), kind, p, filled)


def import_plan(path: str | Path, **options: Any) -> dict:
    """The scene mapping of a plan file (options as read_plan)."""
    return read_plan(path, **options).scene


def read_storey_plans(path: str | Path, **options: Any) -> list[tuple[str, PlanImport, float]]:
    """(storey name, what was understood, floor elevation m) of every storey of a file whose
    importer reads storeys (IFC; the plans drawn side by side on a plan image or a DXF sheet;
    a plugin with ``read_storeys``), storey 'all'; options as read_plan. Each scene has its floor at z = 0."""
    kind = plan_kind(path)
    if kind is not None and not callable(getattr(IMPORTERS[kind], "read_storeys", None)):
        storeyed = [getattr(IMPORTERS[n], "label", None) or n for n in IMPORTERS
                    if callable(getattr(IMPORTERS[n], "read_storeys", None))]
        raise InputError(f"storey: 'all' belongs to formats with several storeys ({'; '.join(storeyed)}); "
                         f"{Path(path).name} is a {kind} plan with one storey", option="storey")
    own = kind is not None and isinstance(IMPORTERS[kind], PlanFormat)  # a plugin's read_storeys reads them all
    kind, importer, p, given, filled = _importer(path, dict(options, storey="all") if own else options)
    elevations = getattr(importer, "storey_elevations", None)
    levels = elevations(p, units=given.get("units")) if callable(elevations) else {}
    return [(name, as_plan_import(got, kind, p, filled), levels.get(name, 0.0))
            for name, got in _call(kind, importer.read_storeys, p, given)]


def import_storey_plans(path: str | Path, **options: Any) -> list[tuple[str, dict, float]]:
    """(storey name, scene mapping, floor elevation m) of every storey (storey 'all';
    options as import_plan). Each scene has its floor at z = 0."""
    return [(name, got.scene, elev) for name, got, elev in read_storey_plans(path, **options)]


def importer_options(importer) -> tuple[tuple[str, ...], bool]:
    """(the option names ``importer.read`` takes beyond the path, whether it takes any
    keyword): its ``options`` when it has them, else from read's signature."""
    declared = getattr(importer, "options", None)
    if declared is not None:
        return tuple(declared), False
    params = list(inspect.signature(importer.read).parameters.values())[1:]
    names = tuple(q.name for q in params if q.kind in (q.KEYWORD_ONLY, q.POSITIONAL_OR_KEYWORD))
    return names, any(q.kind == q.VAR_KEYWORD for q in params)


def _importer(path: str | Path, options: dict):
    """(name, importer, path, the options for read, the options camplace fills in) after
    the checks of read_plan."""
    p = Path(path)
    kind = plan_kind(p)
    if kind is None:
        raise InputError(f"{p}: not a plan; expected {formats_text()}")
    if not p.is_file():
        raise InputError(f"{p}: file not found" if not p.exists() else f"{p}: is a folder, expected a file")
    importer = IMPORTERS[kind]
    given = {k: v for k, v in options.items() if v is not None}
    own, anything = importer_options(importer)
    takes = COMMON_OPTIONS + own if isinstance(importer, PlanFormat) else own
    filled = {} if isinstance(importer, PlanFormat) else {k: given[k] for k in FILLED_OPTIONS
                                                          if k in given and k not in takes}
    for key in given:
        if key not in takes and key not in filled and not anything:
            known = tuple(dict.fromkeys(takes + (() if isinstance(importer, PlanFormat) else FILLED_OPTIONS)))
            raise InputError(f"{key}: not an option of {kind} plans (it takes {', '.join(known)})", option=key)
    return kind, importer, p, {k: v for k, v in given.items() if k not in filled}, filled


def _call(kind: str, read, path: Path, options: dict):
    """``read(path, **options)``; a plugin importer's failure other than an InputError is one
    line naming the importer and its distribution (camplace's own raise as they are)."""
    try:
        return read(path, **options)
    except InputError:
        raise
    except Exception as err:  # noqa: BLE001 - a plugin's bug is reported as one line naming it
        if isinstance(IMPORTERS[kind], PlanFormat):
            raise
        raise InputError(f"{path}: the {kind} importer (from {IMPORTERS.distribution(kind)}) failed: "
                         f"{type(err).__name__}: {err}") from err


def as_plan_import(got, kind: str, path: Path, filled: dict) -> PlanImport:
    """An importer's result as a PlanImport: a plain mapping completed with the defaults of
    every plan import (scene_defaults; ``filled``: name, heights, coverage, budget given to
    camplace, not to the importer) and checked by the scene schema (InputError naming the
    file and the key)."""
    if isinstance(got, PlanImport):
        return got
    if not isinstance(got, dict):
        raise InputError(f"{path}: the {kind} importer returned {type(got).__name__}; expected a PlanImport "
                         f"or a scene mapping")
    room = got.get("room") if isinstance(got.get("room"), dict) else {}
    height = float(room.get("height", DEFAULT_CEILING_M))
    d = scene_defaults(height, **{k: v for k, v in filled.items() if k != "name"})
    scene = {"name": path.stem, "voxel_size": d.pop("voxel_size"), "occupancy_resolution": d.pop("occupancy_resolution"),
             "room": None, "obstacles": [], **d, "zones": []}  # the key order of every plan import (plan_scene)
    scene.update(got)
    if isinstance(got.get("room"), dict) and "height" not in room:  # a footprint alone: the default ceiling
        scene["room"] = dict(room, height=height)
    if filled.get("name"):
        scene["name"] = filled["name"]
    if "budget" in filled and isinstance(scene.get("placement"), dict):
        scene["placement"] = dict(scene["placement"], budget=int(filled["budget"]))
    cov = int(filled.get("coverage", 2))
    scene["zones"] = [z if not isinstance(z, dict) or "coverage" in z else dict(z, coverage=cov)
                      for z in scene.get("zones") or []]
    return PlanImport(validated(scene, str(path)), kind, used={"format": f"{kind} (plugin importer)"})


def polygons_of(geom) -> list[Polygon]:
    """The non-empty polygons of a shapely geometry (Polygon, MultiPolygon, collection)."""
    if geom is None or geom.is_empty:
        return []
    if isinstance(geom, Polygon):
        return [geom]
    if isinstance(geom, MultiPolygon) or hasattr(geom, "geoms"):
        return [q for g in geom.geoms for q in polygons_of(g)]
    return []


def _ring(coords: Iterable, digits: int = 4) -> list[list[float]]:
    pts = np.round(np.asarray(coords, float)[:-1], digits)
    return [[float(x), float(y)] for x, y in pts]


def _is_sliver(poly: Polygon, min_area: float) -> bool:
    """True for a piece too small or too thin (mean width 2·area/perimeter < SLIVER_M) to keep."""
    return poly.area < min_area or 2 * poly.area < SLIVER_M * poly.length


def clean_polygons(geom, *, tolerance: float = 0.0, min_area: float = MIN_PRISM_AREA_M2, holes: bool = True,
                   skipped: Counter | None = None) -> list[Polygon]:
    """The valid polygons (m) of any shapely geometry, ready for the scene schema: simplified
    by ``tolerance`` m, snapped to GRID_M and made valid on that grid (shapely make_valid,
    multipolygons split), slivers and specks under ``min_area`` m² dropped (counted in
    ``skipped['slivers']``), oriented counter-clockwise. Each polygon's rings rounded to 4
    decimals still form a valid polygon (the importers never write a prism the schema
    would refuse); ``holes=False`` keeps the outer rings only."""
    if geom is None or geom.is_empty:
        return []
    g = shapely.make_valid(geom)
    if tolerance:
        g = shapely.make_valid(g.simplify(tolerance))
    out = []
    for poly in polygons_of(shapely.make_valid(shapely.set_precision(g, GRID_M))):
        if not holes:
            poly = Polygon(poly.exterior)
        poly = shapely.geometry.polygon.orient(poly)
        if _is_sliver(poly, min_area):
            if skipped is not None and poly.area > 0:
                skipped["slivers"] += 1
            continue
        rings = [Polygon(h) for h in poly.interiors]
        kept = [h for h in poly.interiors if Polygon(h).area >= min_area] if rings else []
        fixed = Polygon(_ring(poly.exterior.coords), [_ring(h.coords) for h in kept])
        if not fixed.is_valid:  # rounding made it touch itself: one more pass on the grid
            pieces = polygons_of(shapely.make_valid(shapely.set_precision(fixed.buffer(0), GRID_M)))
            pieces = [q for q in pieces if not _is_sliver(q, min_area)
                      and Polygon(_ring(q.exterior.coords), [_ring(h.coords) for h in q.interiors]).is_valid]
            if not pieces and skipped is not None:
                skipped["invalid polygons"] += 1
            out += [shapely.geometry.polygon.orient(q) for q in pieces]
            continue
        out.append(shapely.geometry.polygon.orient(fixed))
    return out


def prism_obstacles(geom, zmin: float, zmax: float, prefix: str, source: dict[str, str],
                    tolerance: float = 0.005, skipped: Counter | None = None) -> list[dict]:
    """Scene obstacles (``prism:``) of the polygons of ``geom`` (m), named prefix-1..n,
    each with ``source`` provenance; simplified by ``tolerance`` m and made valid
    (clean_polygons), slivers counted in ``skipped``. An empty z range gives none."""
    if not float(zmax) - float(zmin) >= 1e-4:
        if skipped is not None and geom is not None and not geom.is_empty:
            skipped["flat elements"] += 1
        return []
    out = []
    for poly in clean_polygons(geom, tolerance=tolerance, skipped=skipped):
        prism: dict = {"polygon": _ring(poly.exterior.coords), "z": [round(float(zmin), 4), round(float(zmax), 4)]}
        if poly.interiors:
            prism["holes"] = [_ring(h.coords) for h in poly.interiors]
        out.append({"name": f"{prefix}-{len(out) + 1}", "prism": prism, "source": dict(source)})
    return out


def room_zones(rooms: list[tuple[str, Polygon]], coverage: int, skipped: Counter | None = None) -> list[dict]:
    """Volume zones (``zones:``) of named room polygons (m; outer rings, made valid);
    a room in several pieces gives name, name-2, ... (its pieces but the largest only from
    MIN_ZONE_PIECE_M2 up: smaller ones are specks a pinch left, counted as slivers);
    duplicate names get -2, -3..."""
    out, seen = [], {}
    for name, poly in rooms:
        pieces = sorted(clean_polygons(poly, tolerance=0.005, min_area=0.01, holes=False, skipped=skipped),
                        key=lambda q: -q.area)
        specks = [q for q in pieces[1:] if q.area < MIN_ZONE_PIECE_M2]
        if specks:
            pieces = [q for q in pieces if not any(q is x for x in specks)]
            if skipped is not None:
                skipped["slivers"] += len(specks)
        for k, piece in enumerate(pieces):
            base = name if k == 0 else f"{name}-{k + 1}"
            seen[base] = seen.get(base, 0) + 1
            label = base if seen[base] == 1 else f"{base}-{seen[base]}"
            out.append({"name": label, "polygon": _ring(piece.exterior.coords), "coverage": int(coverage)})
    return out


def footprint_of(parts: list, source: str) -> Polygon:
    """The outline (no holes) of the largest piece of the union of ``parts`` (m)."""
    polys = polygons_of(shapely.unary_union([p.buffer(1e-6) for p in parts]) if parts else None)
    if not polys:
        raise InputError(f"{source}: no walls or rooms found to make a footprint of")
    big = max(polys, key=lambda q: q.area)
    outline = shapely.make_valid(shapely.set_precision(Polygon(big.exterior).simplify(0.005), 1e-3))
    return shapely.geometry.polygon.orient(Polygon(max(polygons_of(outline), key=lambda q: q.area).exterior))


def walls_outline(walls, gap: float = 1.5, min_share: float = 0.5, how: list | None = None) -> Polygon:
    """The building's outline (m, no holes) from its walls alone, when no closed rooms
    say it (open plans, pavilions): the area enclosed by the outer walls (the walls
    closed over openings up to ``gap`` m, holes filled, largest piece) when it covers at
    least ``min_share`` of the walls' convex hull; else that convex hull. The same rule
    for every format, so a DXF and an IFC of one building agree. ``how`` (a list) gets
    which it was: 'enclosed by the outer walls' or 'convex hull of the walls'."""
    hull = walls.convex_hull if walls is not None and not walls.is_empty else Polygon()
    if not isinstance(hull, Polygon) or hull.area <= 0:
        raise InputError("no walls to make a footprint of")
    d = gap / 2
    closed = shapely.make_valid(walls.buffer(d, join_style="mitre").buffer(-d, join_style="mitre"))
    filled = [Polygon(q.exterior) for q in polygons_of(closed)]
    best = max(filled, key=lambda q: q.area) if filled else Polygon()
    shape = best if best.area >= min_share * hull.area else hull
    if how is not None:
        how.append("enclosed by the outer walls" if shape is best else "convex hull of the walls")
    return footprint_of([shape], "walls")


def outline_pieces(rooms: list, walls, reach: float, min_area: float = 0.0) -> list[Polygon]:
    """The building outline of a plan (m, no holes) in pieces, largest first: the ``rooms``
    (polygons: rooms, spaces, floor slabs) merged with the walls that bound them, closed over
    gaps up to ``reach`` m (the thickest wall), holes filled; pieces under ``min_area`` m²
    dropped. The walls that bound them: the connected pieces of ``walls`` that come within
    ``reach`` of a room, cut to the rooms' convex hull grown by ``reach`` (a closet or shaft
    without a room between them is filled; a garden wall running off is left out). Its
    edge is the outer face of the outer walls: the building's footprint, the rule of
    every importer."""
    union = shapely.union_all([q for q in rooms if q is not None and not q.is_empty] or [Polygon()])
    if union.is_empty:
        return []
    if walls is not None and not walls.is_empty:
        pieces = np.asarray(polygons_of(shapely.make_valid(walls)), dtype=object)
        near = union.buffer(reach, join_style="mitre")
        bounding = pieces[shapely.intersects(pieces, near)] if len(pieces) else pieces
        if len(bounding):
            hull = union.convex_hull.buffer(reach, join_style="mitre")
            union = shapely.union_all([union, shapely.union_all(bounding).intersection(hull)])
    d = reach / 2
    closed = shapely.make_valid(union.buffer(d, join_style="mitre").buffer(-d, join_style="mitre"))
    out = [Polygon(q.exterior) for q in polygons_of(closed)]
    return sorted([q for q in out if q.area > 0 and q.area >= min_area], key=lambda q: -q.area)


def rooms_footprint(rooms: list, walls, gap: float, source: str) -> Polygon:
    """The footprint of a plan (m, no holes): the largest piece of the rooms merged with the
    walls that bound them (outline_pieces; ``gap`` m the thickest wall), so its edge is the
    outer face of the outer walls; the walls' outline (walls_outline) when there are no rooms."""
    if not rooms:
        return walls_outline(walls)
    return footprint_of(outline_pieces(rooms, walls, gap)[:1], source)


def scene_defaults(height: float, *, heights: Iterable[float] | None = None, coverage: int | None = None,
                   budget: int | None = None) -> dict:
    """The keys every plan import gets besides room, obstacles and zones (a room of
    ``height`` m): voxel and occupancy sizes, walkable volume targets at ``heights`` (those
    below the ceiling), the default camera on a 1 m ceiling grid, the placement's budget."""
    hs = [float(h) for h in (heights if heights is not None else (0.5, 1.0, 1.5)) if 0 < float(h) < height - 0.1]
    if not hs:
        raise InputError(f"heights: no target height below the ceiling ({height} m)", option="heights")
    return {
        "voxel_size": 0.25,
        "occupancy_resolution": 0.05,
        "targets": [{"name": "walkable", "kind": "volume", "heights": hs,
                     "coverage": int(coverage if coverage is not None else 2)}],
        "cameras": [dict(DEFAULT_CAMERA)],
        "mounts": [{"kind": "ceiling_grid", "camera": "wide", "spacing": 1.0, "offset_below_ceiling": 0.1,
                    "yaw_deg": {"start": 0, "stop": 330, "step": 30}, "pitch_deg": [30, 45, 60]}],
        "placement": {"budget": int(budget if budget is not None else 20), "solver": "greedy"},
    }


def plan_scene(name: str, footprint: Polygon, height: float, obstacles: list[dict], zones: list[dict], *,
               heights: Iterable[float] | None = None, coverage: int | None = None,
               budget: int | None = None) -> dict:
    """A complete scene mapping: the footprint (m) and ceiling ``height`` (m), the given
    obstacles and zones, and the defaults of every plan import (scene_defaults)."""
    d = scene_defaults(height, heights=heights, coverage=coverage, budget=budget)
    room = {"footprint": _ring(footprint.exterior.coords, 3), "height": round(float(height), 3)}
    return {"name": name, "voxel_size": d.pop("voxel_size"), "occupancy_resolution": d.pop("occupancy_resolution"),
            "room": room, "obstacles": obstacles, **d, "zones": zones}


def validated(data: dict, source: str) -> dict:
    """``data`` after the scene schema accepted it (InputError naming the file otherwise)."""
    from camplace.spec.loading import parse_scene

    parse_scene(data, source)
    return data
