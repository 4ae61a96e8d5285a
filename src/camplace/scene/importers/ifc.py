"""BIM models (IFC, read by ifcopenshell) -> an editable scene mapping of one storey.

The storey's floor level (its Elevation) is z = 0; its ceiling is the lowest slab,
roof or ceiling covering above it (else the next storey's elevation, else its spaces'
tops). Every element body (ifcopenshell.geom, world coordinates, metres whatever the
file's units) is cut to that z range and written as stacked ``prism:`` obstacles, one
per distinct cross-section between the element's vertex heights (exact for walls with
door and window holes, columns, slabs, extruded furniture); an element with more than
MAX_BANDS levels (a stair, a curved chair) becomes one prism of its plan outline over
its height. Doors are open unless ``doors='closed'``; windows occlude unless
``glass='transparent'``. Each IfcSpace becomes a zone named by its LongName (or Name);
the footprint is the union of the storey's spaces with the walls between them closed
(else the storey's slab outline). See docs/plans.md (IFC).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import Polygon

from camplace.core.errors import InputError
from camplace.scene.importers import (UNITS_M, PlanImport, footprint_of, plan_scene, polygons_of, prism_obstacles, room_zones,
                                      validated)
from camplace.scene.importers.ifc_geometry import Element, clip_z, element_shapes, plan_shape, z_bands

OPTIONS = ("storey", "doors", "glass", "max_wall_gap")
OCCLUDERS = ("IfcBuildingElement", "IfcBuiltElement", "IfcFurnishingElement")  # IFC2X3/IFC4, IFC4X3, furniture
NOT_OCCLUDING = ("IfcDoor", "IfcWindow")  # unless doors='closed' / glass='opaque'
CEILINGS = ("IfcSlab", "IfcRoof", "IfcCovering")
MIN_CEILING_M = 1.5  # a slab lower than this above the floor is a step or a landing, not the ceiling


@dataclass(frozen=True)
class Storey:
    """An IfcBuildingStorey: its name, elevation (m) and the entity."""

    name: str
    elevation: float
    entity: object


def open_model(path: Path):
    """The ifcopenshell model of ``path``; InputError naming the file when it is not IFC."""
    import ifcopenshell

    with open(path, "rb") as f:
        head = f.read(64)
    if not head.lstrip().startswith(b"ISO-10303-21"):
        raise InputError(f"{path}: not an IFC file (an IFC STEP file starts with 'ISO-10303-21;')")
    try:
        return ifcopenshell.open(str(path))
    except Exception as err:  # ifcopenshell raises its own kinds for broken files
        msg = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise InputError(f"{path}: not a readable IFC file ({msg[:120]})") from None


def length_scale(model) -> float:
    """Metres per length unit of the file (IfcUnitAssignment: mm 0.001, m 1, ft 0.3048)."""
    import ifcopenshell.util.unit

    return float(ifcopenshell.util.unit.calculate_unit_scale(model))


def storeys(model, scale: float) -> list[Storey]:
    """The file's storeys, lowest first (elevation in m: Elevation, else the placement's z)."""
    import ifcopenshell.util.placement

    out = []
    for st in model.by_type("IfcBuildingStorey"):
        elev = st.Elevation
        if elev is None and st.ObjectPlacement is not None:
            elev = ifcopenshell.util.placement.get_local_placement(st.ObjectPlacement)[2, 3]
        out.append(Storey(st.Name or f"#{st.id()}", float(elev or 0.0) * scale, st))
    return sorted(out, key=lambda s: s.elevation)


def storey_of(element):
    """The IfcBuildingStorey an element is contained in or part of (None when none is)."""
    import ifcopenshell.util.element as ue

    x, seen = element, 0
    while x is not None and seen < 32:
        if x.is_a("IfcBuildingStorey"):
            return x
        x = ue.get_container(x) or ue.get_aggregate(x)
        seen += 1
    return None


def _by_storey(model, elements: list[Element]) -> dict[int, list[Element]]:
    """Element shapes grouped by their storey's entity id (0: in no storey)."""
    out: dict[int, list[Element]] = {}
    for e in elements:
        st = storey_of(model.by_guid(e.guid))
        out.setdefault(st.id() if st is not None else 0, []).append(e)
    return out


def _union(elements: list[Element]):
    return shapely.union_all([plan_shape(e) for e in elements]) if elements else Polygon()


def choose_storeys(path: Path, all_storeys: list[Storey], spaces: dict, slabs: dict, storey: str | None
                   ) -> list[Storey]:
    """The storeys to import: the one named ``storey``, every one with spaces ('all'), or the one
    with the largest floor area (its spaces' area, else its slabs')."""
    if not all_storeys:
        raise InputError(f"{path}: the file has no IfcBuildingStorey")
    if storey == "all":  # every storey with rooms (a roof or a site level without IfcSpace is no floor to plan)
        return [s for s in all_storeys if spaces.get(s.entity.id())] or all_storeys
    if storey is not None:
        hit = [s for s in all_storeys if s.name == storey]
        if not hit:
            raise InputError(f"{path}: no storey named '{storey}'; its storeys are "
                             f"{', '.join(repr(s.name) for s in all_storeys)}", option="storey")
        return hit[:1]

    def area(s: Storey) -> tuple[float, float]:
        return _union(spaces.get(s.entity.id(), [])).area, _union(slabs.get(s.entity.id(), [])).area

    return [max(all_storeys, key=area)]


def ceiling_of(st: Storey, nxt: Storey | None, ceilings: list[Element], spaces: list[Element]) -> float:
    """The storey's clear height (m above its floor): the lowest slab / roof / ceiling
    covering bottom over its spaces at least MIN_CEILING_M up, else the next storey's
    elevation, else the top of its spaces."""
    area = _union(spaces)
    tops = []
    for e in ceilings:
        z = e.z_range[0] - st.elevation
        if z >= MIN_CEILING_M and (nxt is None or e.z_range[0] <= nxt.elevation + 1e-6):
            if area.is_empty or plan_shape(e).intersection(area).area > 0.25 * area.area:
                tops.append(z)
    if tops:
        return min(tops)
    if nxt is not None:
        return nxt.elevation - st.elevation
    if spaces:
        return max(e.z_range[1] for e in spaces) - st.elevation
    return 3.0


def closed_footprint(parts, gap: float) -> Polygon | None:
    """The union of ``parts`` (shapely, m) with gaps up to ``gap`` m (walls) closed, as one
    polygon without holes; None when it stays in pieces."""
    d = gap / 2
    union = shapely.union_all([p for p in parts if not p.is_empty]) if parts else Polygon()
    closed = union.buffer(d, join_style="mitre").buffer(-d, join_style="mitre")
    polys = polygons_of(shapely.make_valid(closed))
    if len(polys) != 1:
        return None
    return footprint_of(polys, "footprint")


def _occluders(model, doors: str, glass: str) -> list:
    """The element entities that block sight lines, by the door and glass options."""
    skip = set()
    if doors == "open":
        skip.add("IfcDoor")
    if glass == "transparent":
        skip.add("IfcWindow")
    out = []
    for cls in OCCLUDERS:
        try:
            found = model.by_type(cls)
        except RuntimeError:  # the class is not in this schema version
            continue
        out += [e for e in found if e.is_a() not in skip and not (e.is_a("IfcCovering") and e.PredefinedType in
                                                                   ("CEILING", "FLOORING"))]
    return list({e.id(): e for e in out}.values())


def element_prisms(el: Element, source: str, name: str) -> list[dict]:
    """The prisms of one element cut to the storey (z relative to the floor level)."""
    src = {"file": source, "class": el.ifc_class, "GlobalId": el.guid}
    bands = z_bands(el)
    if bands is None:
        lo, hi = el.z_range
        bands = [(lo, hi, plan_shape(el))]
    out = []
    for k, (z0, z1, shape) in enumerate(bands):
        prefix = name if len(bands) == 1 else f"{name}-z{k + 1}"
        out += prism_obstacles(shape, z0, z1, prefix, src)
    return out


def _storey_scene(path: Path, st: Storey, height: float, spaces: list[Element], slabs: list[Element],
                  occluders: list[Element], opts: dict) -> dict:
    """The scene mapping of one storey (element z already relative to its floor)."""
    footprint = closed_footprint([plan_shape(e) for e in spaces], opts["max_wall_gap"])
    if footprint is None:
        footprint = closed_footprint([plan_shape(e) for e in slabs], opts["max_wall_gap"])
    if footprint is None:
        raise InputError(f"{path}: storey '{st.name}' has no spaces or floor slab to make a footprint of",
                         option="storey")
    obstacles, names = [], {}
    for el in occluders:
        cls = el.ifc_class.removeprefix("Ifc")
        base = el.name if el.name.startswith(cls) else f"{cls} {el.name or el.guid}"
        names[base] = names.get(base, 0) + 1
        obstacles += element_prisms(el, path.name, base if names[base] == 1 else f"{base} ({names[base]})")
    rooms = [(opts["labels"].get(e.guid) or e.name or e.guid, plan_shape(e)) for e in spaces]
    zones = room_zones(rooms, opts["coverage"] if opts["coverage"] is not None else 2)
    name = opts["name"] or (f"{path.stem} {st.name}" if opts["several"] else path.stem)
    return plan_scene(name, footprint, height, obstacles, zones, heights=opts["heights"], coverage=opts["coverage"],
                      budget=opts["budget"])


def _relative(elements: list[Element], dz: float, factor: float) -> list[Element]:
    """Elements scaled by ``factor`` (a units override) and moved down by dz (m)."""
    return [Element(e.guid, e.ifc_class, e.name, e.vertices * factor - np.array([0.0, 0.0, dz]), e.faces)
            for e in elements]


def _check(doors: str, glass: str, max_wall_gap: float, units: str | None, wall_height) -> None:
    if doors not in ("open", "closed"):
        raise InputError(f"doors: expected 'open' or 'closed', got '{doors}'", option="doors")
    if glass not in ("opaque", "transparent"):
        raise InputError(f"glass: expected 'opaque' or 'transparent', got '{glass}'", option="glass")
    if not max_wall_gap >= 0:
        raise InputError(f"max_wall_gap: expected a length >= 0 m, got {max_wall_gap}", option="max_wall_gap")
    if units is not None and units not in UNITS_M:
        raise InputError(f"units: unknown unit '{units}'; expected one of {', '.join(UNITS_M)}", option="units")
    if wall_height is not None:
        raise InputError("wall_height: IFC walls have their own heights; give ceiling_height to cut them",
                         option="wall_height")


def import_storeys(path: str | Path, *, storey: str | None = None, doors: str = "open", glass: str = "opaque",
                   max_wall_gap: float = 0.6, name: str | None = None, units: str | None = None,
                   wall_height: float | None = None, ceiling_height: float | None = None, heights=None,
                   coverage: int | None = None, budget: int | None = None) -> list[tuple[str, dict]]:
    """(storey name, scene mapping) of each storey imported: the one named ``storey``,
    every storey for 'all', else the one with the largest floor area. ``units``
    overrides the file's length unit; ``max_wall_gap`` (m): the thickest wall between
    two spaces that the footprint closes over."""
    p = Path(path)
    _check(doors, glass, max_wall_gap, units, wall_height)
    model = open_model(p)
    scale = length_scale(model)
    factor = UNITS_M[units] / scale if units is not None else 1.0
    all_storeys = storeys(model, scale * factor)
    space_ents = list(model.by_type("IfcSpace"))
    labels = {e.GlobalId: e.LongName for e in space_ents if getattr(e, "LongName", None)}
    firsts = _relative(element_shapes(model, space_ents + [e for c in CEILINGS for e in model.by_type(c)]), 0.0,
                       factor)
    spaces = _by_storey(model, [e for e in firsts if e.ifc_class == "IfcSpace"])
    ceilings = [e for e in firsts if e.ifc_class != "IfcSpace" and not (
        e.ifc_class == "IfcCovering" and model.by_guid(e.guid).PredefinedType == "FLOORING")]
    slabs = _by_storey(model, [e for e in ceilings if e.ifc_class == "IfcSlab"])
    chosen = choose_storeys(p, all_storeys, spaces, slabs, storey)
    occluders = _by_storey(model, _relative(element_shapes(model, _occluders(model, doors, glass)), 0.0, factor))
    opts = dict(max_wall_gap=max_wall_gap, labels=labels, name=name, heights=heights, coverage=coverage,
                budget=budget, several=len(chosen) > 1)
    out = []
    for st in chosen:
        k = all_storeys.index(st)
        nxt = all_storeys[k + 1] if k + 1 < len(all_storeys) else None
        below = all_storeys[k - 1] if k > 0 else None
        own = spaces.get(st.entity.id(), [])
        h = ceiling_height if ceiling_height is not None else ceiling_of(st, nxt, ceilings, own)
        near = [e for sid, els in occluders.items() if sid in (0, st.entity.id(), below and below.entity.id())
                for e in els]
        cut = [c for c in (clip_z(e, st.elevation, st.elevation + h) for e in near) if c is not None]
        data = _storey_scene(p, st, h, _relative(own, st.elevation, 1.0),
                             _relative(slabs.get(st.entity.id(), []), st.elevation, 1.0),
                             _relative(cut, st.elevation, 1.0), opts)
        out.append((st.name, validated(data, f"{p} (storey '{st.name}')")))
    return out


def storey_elevations(path: str | Path, units: str | None = None) -> dict[str, float]:
    """Storey name -> floor elevation (m; ``units`` overrides the file's length unit)."""
    model = open_model(Path(path))
    scale = length_scale(model)
    factor = UNITS_M[units] / scale if units is not None else 1.0
    return {s.name: s.elevation for s in storeys(model, scale * factor)}


def import_plan(path: str | Path, **options) -> dict:
    """The scene mapping of one storey of an IFC file (options: see import_storeys;
    storey 'all' belongs to import_storeys, which gives one scene per storey)."""
    if options.get("storey") == "all":
        raise InputError(f"{path}: storey 'all' gives one scene per storey; import them with import_storeys",
                         option="storey")
    return import_storeys(path, **options)[0][1]


def read_storeys(path: str | Path, **options) -> list[tuple[str, PlanImport]]:
    """(storey name, what was understood) of each storey imported (options as import_storeys)."""
    return [(name, PlanImport(data, "ifc")) for name, data in import_storeys(path, **options)]


def read(path: str | Path, **options) -> PlanImport:
    """What was understood of one storey of an IFC file (options as import_plan)."""
    return PlanImport(import_plan(path, **options), "ifc")
