"""Plans people have -> an editable scene mapping (issue 18): CAD floor plans (DXF),
plan images (PNG/JPG/TIFF) and BIM models (IFC).

One registry: suffix -> importer module; each module offers
``import_plan(path, **options) -> dict``, a complete scene-file mapping (name, room
footprint and height, obstacles with ``source`` provenance, zones named after the
rooms, the default targets, camera and ceiling mounts of a scene from a scan). The
helpers below build those parts the same way for every format.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any, Iterable

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

from camplace.core.errors import InputError
from camplace.scene.from_scan import DEFAULT_CAMERA

PLAN_SUFFIXES = {".dxf": "dxf", ".png": "image", ".jpg": "image", ".jpeg": "image", ".tif": "image",
                 ".tiff": "image", ".ifc": "ifc"}
UNITS_M = {"mm": 0.001, "cm": 0.01, "m": 1.0, "in": 0.0254, "ft": 0.3048}  # metres per unit
COMMON_OPTIONS = ("name", "units", "wall_height", "ceiling_height", "heights", "coverage", "budget")
DEFAULT_CEILING_M = 3.0
MIN_PRISM_AREA_M2 = 1e-4  # wall pieces smaller than this (1 cm²) are dropped


def plan_kind(path: str | Path) -> str | None:
    """'dxf', 'image' or 'ifc' by the file's suffix; None for anything else."""
    return PLAN_SUFFIXES.get(Path(path).suffix.lower())


def unit_scale(units: str) -> float:
    """Metres per unit of ``units`` (mm, cm, m, in, ft); InputError otherwise."""
    if units not in UNITS_M:
        raise InputError(f"units: unknown unit '{units}'; expected one of {', '.join(UNITS_M)}", option="units")
    return UNITS_M[units]


def import_plan(path: str | Path, **options: Any) -> dict:
    """The scene mapping of a plan file (``options``: None values are left to the
    importer's defaults; an option the format does not take is an InputError)."""
    module, p, given = _importer(path, options)
    return module.import_plan(p, **given)


def import_storey_plans(path: str | Path, **options: Any) -> list[tuple[str, dict, float]]:
    """(storey name, scene mapping, floor elevation m) of every storey of an IFC file
    (storey 'all'; options as import_plan). Each scene has its floor at z = 0."""
    if plan_kind(path) not in (None, "ifc"):
        raise InputError(f"storey: 'all' belongs to IFC files; {Path(path).name} is a {plan_kind(path)} plan "
                         "with one storey", option="storey")
    module, p, given = _importer(path, dict(options, storey="all"))
    levels = module.storey_elevations(p, units=given.get("units"))
    return [(name, data, levels.get(name, 0.0)) for name, data in module.import_storeys(p, **given)]


def _importer(path: str | Path, options: dict):
    """(importer module, path, the options given) after the checks of import_plan."""
    p = Path(path)
    kind = plan_kind(p)
    if kind is None:
        raise InputError(f"{p}: not a plan; expected {', '.join(sorted(set(PLAN_SUFFIXES)))}")
    if not p.is_file():
        raise InputError(f"{p}: file not found" if not p.exists() else f"{p}: is a folder, expected a file")
    module = importlib.import_module(f"camplace.scene.importers.{kind}")
    given = {k: v for k, v in options.items() if v is not None}
    for key in given:
        if key not in COMMON_OPTIONS and key not in module.OPTIONS:
            raise InputError(f"{key}: not an option of {kind} plans (it takes "
                             f"{', '.join(COMMON_OPTIONS + tuple(module.OPTIONS))})", option=key)
    return module, p, given


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


def prism_obstacles(geom, zmin: float, zmax: float, prefix: str, source: dict[str, str],
                    tolerance: float = 0.005) -> list[dict]:
    """Scene obstacles (``prism:``) of the polygons of ``geom`` (m), named prefix-1..n,
    each with ``source`` provenance; simplified by ``tolerance`` m, specks dropped."""
    out = []
    for poly in polygons_of(shapely.make_valid(geom.simplify(tolerance)) if tolerance else geom):
        poly = shapely.geometry.polygon.orient(poly)
        if poly.area < MIN_PRISM_AREA_M2 or len(poly.exterior.coords) < 4:
            continue
        holes = [_ring(h.coords) for h in poly.interiors if Polygon(h).area >= MIN_PRISM_AREA_M2]
        prism: dict = {"polygon": _ring(poly.exterior.coords), "z": [round(float(zmin), 4), round(float(zmax), 4)]}
        if holes:
            prism["holes"] = holes
        out.append({"name": f"{prefix}-{len(out) + 1}", "prism": prism, "source": dict(source)})
    return out


def room_zones(rooms: list[tuple[str, Polygon]], coverage: int) -> list[dict]:
    """Volume zones (``zones:``) of named room polygons (m); duplicate names get -2, -3..."""
    out, seen = [], {}
    for name, poly in rooms:
        for k, piece in enumerate(polygons_of(poly)):
            base = name if k == 0 else f"{name}-{k + 1}"
            seen[base] = seen.get(base, 0) + 1
            label = base if seen[base] == 1 else f"{base}-{seen[base]}"
            ext = shapely.geometry.polygon.orient(piece.simplify(0.005))
            out.append({"name": label, "polygon": _ring(ext.exterior.coords), "coverage": int(coverage)})
    return out


def footprint_of(parts: list, source: str) -> Polygon:
    """The outline (no holes) of the largest piece of the union of ``parts`` (m)."""
    polys = polygons_of(shapely.unary_union([p.buffer(1e-6) for p in parts]) if parts else None)
    if not polys:
        raise InputError(f"{source}: no walls or rooms found to make a footprint of")
    big = max(polys, key=lambda q: q.area)
    return shapely.geometry.polygon.orient(Polygon(big.exterior).simplify(0.005))


def rooms_footprint(rooms: list, walls, gap: float, source: str) -> Polygon:
    """The footprint of a plan: the room polygons (m) merged across the walls between them
    (a closing by ``gap`` m, the thickest wall), outline of the largest piece; the walls'
    outline when there are no rooms. The outer walls lie outside it (occupied anyway)."""
    d = gap / 2
    if not rooms:
        return footprint_of([walls], source)
    merged = shapely.unary_union(rooms).buffer(d, join_style="mitre").buffer(-d, join_style="mitre")
    return footprint_of([shapely.make_valid(merged)], source)


def plan_scene(name: str, footprint: Polygon, height: float, obstacles: list[dict], zones: list[dict], *,
               heights: Iterable[float] | None = None, coverage: int | None = None,
               budget: int | None = None) -> dict:
    """A complete scene mapping: the footprint (m) and ceiling ``height`` (m), the given
    obstacles and zones, walkable volume targets, the default camera on a 1 m ceiling grid."""
    hs = [float(h) for h in (heights if heights is not None else (0.5, 1.0, 1.5)) if 0 < float(h) < height - 0.1]
    if not hs:
        raise InputError(f"heights: no target height below the ceiling ({height} m)", option="heights")
    data = {
        "name": name,
        "voxel_size": 0.25,
        "occupancy_resolution": 0.05,
        "room": {"footprint": _ring(footprint.exterior.coords, 3), "height": round(float(height), 3)},
        "obstacles": obstacles,
        "targets": [{"name": "walkable", "kind": "volume", "heights": hs,
                     "coverage": int(coverage if coverage is not None else 2)}],
        "cameras": [dict(DEFAULT_CAMERA)],
        "mounts": [{"kind": "ceiling_grid", "camera": "wide", "spacing": 1.0, "offset_below_ceiling": 0.1,
                    "yaw_deg": {"start": 0, "stop": 330, "step": 30}, "pitch_deg": [30, 45, 60]}],
        "placement": {"budget": int(budget if budget is not None else 20), "solver": "greedy"},
        "zones": zones,
    }
    return data


def validated(data: dict, source: str) -> dict:
    """``data`` after the scene schema accepted it (InputError naming the file otherwise)."""
    from camplace.spec.loading import parse_scene

    parse_scene(data, source)
    return data
