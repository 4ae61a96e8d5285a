"""BIM models (IFC, read by ifcopenshell) -> an editable scene mapping of one storey.

The storey's floor level is z = 0 (its placement; a file without storeys: the level its
doors and walls stand on); its ceiling is the lowest slab, roof or ceiling covering above
it (else the next storey's elevation, else its spaces' tops, else its walls'). Every
element body (ifcopenshell.geom, world coordinates, metres whatever the file's units) is
cut to that z range and written as stacked ``prism:`` obstacles, one per distinct
cross-section between the element's vertex heights (exact for walls with door and window
holes, columns, slabs, extruded furniture); an element with more than MAX_BANDS levels
(a stair, a curved chair) becomes one prism of its plan outline over its height. Doors are
open unless ``doors='closed'``; windows occlude unless ``glass='transparent'``. Each
IfcSpace becomes a zone named by its LongName (or Name); the footprint is the building's
outline at the outer faces of its outer walls: the storey's spaces with the walls that bound
them (else its floor slabs with them, else the outline of its walls); separate blocks are
joined by thin seams filled by ``outside`` obstacles.
Elements outside the footprint (trees, site objects) are left out. See docs/plans.md (IFC).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
import shapely

from camplace.core.errors import InputError
from camplace.scene.importers import (UNITS_M, PlanImport, clean_polygons, plan_scene, prism_obstacles, room_zones,
                                      validated)
from camplace.scene.importers.ifc_checks import check_footprint, check_free_floor, nothing_found
from camplace.scene.importers.ifc_geometry import (Element, element_shapes, footprint_shapes, plan_hull, plan_shape,
                                                   z_bands)
from camplace.scene.importers.ifc_model import (Storey, Structure, length_scale, occupiable, open_model, room_labels,
                                                structure, unit_words)
from camplace.scene.importers.ifc_storey import (CEILINGS, FLOOR_MAKERS, FLOOR_TOL_M, WALLS, StoreyRooms,
                                                 ceiling_of, choose_storeys, floor_level, storey_footprint)
from camplace.scene.importers.ifc_openings import STAIRS, VOID, floor_openings
from camplace.scene.importers.ifc_walls import NEVER_WALLS, storey_walls, wall_class_names

OPTIONS = ("storey", "doors", "glass", "max_wall_gap", "wall_classes")
OCCLUDERS = ("IfcElement",)  # walls, slabs, columns, stairs, furniture, proxies, equipment... (IFC2X3 to IFC4X3)
NOT_ELEMENTS = ("IfcFeatureElement", "IfcVirtualElement", "IfcElementComponent")  # openings, virtual, fasteners
NOT_FLOORS = ("ROOF", "LANDING")  # slab types that are never a storey's floor
CEILING_COVERINGS = ("CEILING", "NOTDEFINED", "USERDEFINED", "", "ROOFING")  # coverings that may be a ceiling or roof
STAY_DOWN = ("IfcFurnishingElement", "IfcDoor", "IfcWindow", "IfcCovering", "IfcDistributionElement")  # never reach up


def _entities(model, classes) -> list:
    out = []
    for cls in classes:
        try:
            out += model.by_type(cls)
        except RuntimeError:  # the class is not in this schema version
            continue
    return out


def _occluder_entities(model) -> list:
    """Every element that may block a sight line or be a floor or ceiling (not openings, not
    the terrain)."""
    skip = {e.id() for e in _entities(model, NOT_ELEMENTS)}
    skip |= {e.id() for e in _entities(model, ("IfcGeographicElement",)) if e.PredefinedType == "TERRAIN"}
    return [e for e in _entities(model, OCCLUDERS) if e.id() not in skip]


def _space_storey(s: Structure, el: Element) -> int:
    """The storey key of a space: its relations, else (assigned to the building) the highest
    storey whose floor lies at most FLOOR_TOL_M above the space's bottom."""
    key = s.storey_key(el.eid)
    if key or s.synthetic:
        return key or (s.storeys[0].key if len(s.storeys) == 1 else 0)
    under = [st for st in s.storeys if st.elevation <= el.z_range[0] + FLOOR_TOL_M]
    return max(under, key=lambda st: st.elevation).key if under else s.storeys[0].key


def _storey_rooms(model, s: Structure, spaces: list[Element], named: tuple[str, ...] = ()) -> tuple[dict, dict, dict]:
    """(storey key -> StoreyRooms, space id -> storey key, space id -> zone name); ``named``:
    the classes a user named walls (wall_classes)."""
    where = {e.eid: _space_storey(s, e) for e in spaces}
    ents = {e.eid: model.by_id(e.eid) for e in spaces}
    labels: dict[int, str] = {}
    for key in set(where.values()):
        labels.update(room_labels([ents[i] for i, k in where.items() if k == key]))
    occluders = _occluder_entities(model)
    counts = Counter(s.storey_key(e.id()) for e in occluders)
    makers = Counter(s.storey_key(e.id()) for e in occluders if any(e.is_a(c) for c in WALLS + named) or (
        e.is_a("IfcSlab") and str(getattr(e, "PredefinedType", "") or "") not in NOT_FLOORS))
    rooms = {st.key: StoreyRooms([(labels[e.eid], plan_shape(e).area, occupiable(ents[e.eid], labels[e.eid]))
                                  for e in spaces if where[e.eid] == st.key], counts.get(st.key, 0),
                                 makers.get(st.key, 0))
             for st in s.storeys}
    return rooms, where, labels


def _element_prisms(el: Element, floor: float, top: float, source: str, name: str,
                    skipped: Counter) -> list[dict]:
    """The prisms of one element cut to floor..top (world z), z relative to the floor."""
    src = {"file": source, "class": el.ifc_class, "GlobalId": el.guid}
    bands = z_bands(el, floor, top) or []
    out = []
    for k, (z0, z1, shape) in enumerate(bands):
        prefix = name if len(bands) == 1 else f"{name}-z{k + 1}"
        out += prism_obstacles(shape, z0 - floor, z1 - floor, prefix, src, skipped=skipped)
    return out


def _obstacles(elements: list[Element], floor: float, top: float, footprint, source: str,
               skipped: Counter) -> tuple[list[dict], Counter]:
    """The prisms of the elements that reach into floor..top and touch the footprint, and the
    count of elements per class that gave some."""
    obstacles, names, used = [], Counter(), Counter()
    box = footprint.buffer(0.05)
    for el in elements:
        lo, hi = el.z_range
        if min(hi, top) - max(lo, floor) < 0.01:
            continue
        hull = plan_hull(el, floor, top)  # cheap first; the exact plan only for what straddles the footprint
        if not hull.intersects(box) or not hull.within(box) and not plan_shape(el, floor, top).intersects(box):
            skipped[f"outside the footprint: {el.ifc_class}"] += 1
            continue
        cls = el.ifc_class.removeprefix("Ifc")
        base = el.name if el.name.startswith(cls) else f"{cls} {el.name or el.guid}"
        names[base] += 1
        got = _element_prisms(el, floor, top, source, base if names[base] == 1 else f"{base} ({names[base]})", skipped)
        if got:
            used[el.ifc_class] += 1
        else:
            skipped[f"no prism: {el.ifc_class}"] += 1
        obstacles += got
    return obstacles, used


def _openings(elements: list[Element], floor: float, top: float) -> list[list[list[float]]]:
    """Plan rings (m, the storey's frame) of the doors and windows reaching into floor..top."""
    out = []
    for el in elements:
        if el.ifc_class in ("IfcDoor", "IfcWindow") and min(el.z_range[1], top) - max(el.z_range[0], floor) > 0.01:
            for poly in clean_polygons(plan_shape(el), tolerance=0.005, holes=False):
                out.append([[round(float(x), 3), round(float(y), 3)] for x, y in list(poly.exterior.coords)[:-1]])
    return out


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


def _class_list(wall_classes) -> tuple[str, ...]:
    """The class names of the wall_classes option: a list, or one text 'A,B'."""
    items = wall_classes.split(",") if isinstance(wall_classes, str) else list(wall_classes or ())
    return tuple(str(c).strip() for c in items if str(c).strip())


def _roles(model, s: Structure, ents: list, named: tuple[str, ...]) -> tuple[dict, set, set]:
    """(entity id -> (class, predefined type, the ``named`` classes it is an instance of),
    ids of roofs (IfcRoof, ROOF slabs, a roof's parts), ids of elements that may be walls by
    their shape (not WALLS, not NEVER_WALLS, not a part of one: a stair's stringers))."""
    kinds = {e.id(): (e.is_a(), str(getattr(e, "PredefinedType", "") or ""), tuple(c for c in named if e.is_a(c)))
             for e in ents}
    roofs = {e.id() for e in ents if e.is_a("IfcRoof") or kinds[e.id()][:2] in (("IfcSlab", "ROOF"),
                                                                              ("IfcCovering", "ROOFING"))
             or s.parent.get(e.id()) and model.by_id(s.parent[e.id()]).is_a("IfcRoof")}
    never = WALLS + NEVER_WALLS
    may_be = {e.id() for e in ents if not any(e.is_a(c) for c in never)
              and not (s.parent.get(e.id()) and any(model.by_id(s.parent[e.id()]).is_a(c) for c in never))}
    return kinds, roofs, may_be


class _Model:
    """An opened IFC file: its structure, unit factor and the bodies tessellated so far."""

    def __init__(self, path: Path, units: str | None):
        self.path, self.model = path, open_model(path)
        scale = length_scale(self.model)
        self.factor = UNITS_M[units] / scale if units is not None else 1.0
        self.metres_per_unit = scale * self.factor
        self.units = (f"{units} (units option; the file says {unit_words(self.model, scale)})" if units is not None
                      else unit_words(self.model, scale))
        self.s = structure(self.model, scale * self.factor)

    def shapes(self, entities: list, skipped: Counter) -> list[Element]:
        """The bodies of ``entities`` (units applied); those without one are counted in
        ``skipped`` (an aggregate whose parts have bodies is not)."""
        got = element_shapes(self.model, entities)
        have = {e.eid for e in got}
        flat = footprint_shapes(self.model, [e for e in entities if e.id() not in have and e.is_a("IfcSpace")])
        got = [e.moved(0.0, self.factor) if self.factor != 1.0 else e for e in got + flat]
        have |= {e.eid for e in flat}
        wholes = set(self.s.parent.values())
        for e in entities:
            if e.id() not in have and e.id() not in wholes:
                skipped[f"no body: {e.is_a()}"] += 1
        return got

    def with_floors(self, elements: list[Element], spaces: bool = False) -> None:
        """The floors the file does not say (a storey without placement or Elevation, a building
        standing in for a storey): the lowest point of its spaces (``spaces``), else the level
        its doors and walls stand on (floor_level); 0 when it has neither."""
        s = self.s

        def floor(st: Storey) -> Storey:
            if st.elevation == st.elevation:
                return st
            own = [e for e in elements if s.storey_key(e.eid) in (st.key, 0 if s.synthetic else -1)]
            if own and spaces:
                return replace(st, elevation=min(e.z_range[0] for e in own), level="lowest space")
            if own:
                return replace(st, elevation=floor_level(own), level="doors and walls")
            return st if spaces else replace(st, elevation=0.0, level="nothing: 0")

        s.storeys = sorted([floor(st) for st in s.storeys], key=lambda st: (st.elevation != st.elevation, st.elevation))


def import_storeys(path: str | Path, **options) -> list[tuple[str, dict]]:
    """(storey name, scene mapping) of each storey imported (options as read_storeys)."""
    return [(name, got.scene) for name, got in read_storeys(path, **options)]


def read_storeys(path: str | Path, *, storey: str | None = None, doors: str = "open", glass: str = "opaque",
                 max_wall_gap: float = 0.6, name: str | None = None, units: str | None = None,
                 wall_height: float | None = None, ceiling_height: float | None = None, heights=None,
                 coverage: int | None = None, budget: int | None = None,
                 wall_classes=None) -> list[tuple[str, PlanImport]]:
    """(storey name, what was understood) of each storey imported: the one named ``storey``,
    every storey with rooms for 'all', else the one a user plans (choose_storeys).
    ``units`` overrides the file's length unit; ``max_wall_gap`` (m): the thickest wall
    between two spaces that the footprint closes over; ``wall_classes``: IFC classes
    (names, or one text 'A,B') whose elements are walls, beside IfcWall and the elements
    shaped like walls (ifc_walls)."""
    p = Path(path)
    _check(doors, glass, max_wall_gap, units, wall_height)
    m = _Model(p, units)
    named = wall_class_names(m.model, _class_list(wall_classes)) if wall_classes else ()
    s, skipped = m.s, Counter()
    spaces = m.shapes(list(m.model.by_type("IfcSpace")), skipped)
    m.with_floors(spaces, spaces=True)
    rooms, where, labels = _storey_rooms(m.model, s, spaces, named)
    chosen, why = choose_storeys(s, rooms, storey, p)
    own = {st.key for st in chosen} | {0}
    below = {s.below(st).key for st in chosen if s.below(st) is not None} - own
    above = {s.above(st).key for st in chosen if s.above(st) is not None} - own

    def wanted(e) -> bool:  # its own storey's; what may reach up from the one below; the ceilings above
        key = s.storey_key(e.id())
        return (s.synthetic or key in own or key in below and not any(e.is_a(c) for c in STAY_DOWN)
                or key in above and e.is_a() in CEILINGS)

    ents = [e for e in _occluder_entities(m.model) if wanted(e)]
    elements = m.shapes(ents, skipped)
    m.with_floors(elements)
    chosen = [next(x for x in s.storeys if x.key == st.key) for st in chosen]
    kinds, roofs, may_be = _roles(m.model, s, ents, named)
    levels = {x.key: x.elevation for x in s.storeys}
    opts = dict(doors=doors, glass=glass, gap=max_wall_gap, name=name, heights=heights, coverage=coverage,
                budget=budget, ceiling=ceiling_height, several=len(chosen) > 1, why=why, named=named, roofs=roofs,
                may_be=may_be, given=storey not in (None, "all"),
                others=[x.name for x in s.storeys if rooms.get(x.key, StoreyRooms([], 0)).elements],
                spaces=[(e, levels.get(where[e.eid], float("nan"))) for e in spaces],
                model_m2=_plan_extent(elements + spaces))
    out = []
    for st in chosen:
        own = [e for e in spaces if where[e.eid] == st.key]
        got = _storey(m, st, own, elements, kinds, labels, Counter(skipped), opts)
        got.storeys = [{"name": x.name, "elevation_m": round(x.elevation, 4), "chosen": x.key == st.key,
                        "rooms": [[n, round(a, 2)] for n, a, _ in rooms.get(x.key, StoreyRooms([], 0)).rooms]}
                       for x in s.storeys]
        out.append((st.name, got))
    return out


def _storey(m: _Model, st: Storey, spaces: list[Element], elements: list[Element], kinds: dict, labels: dict,
            skipped: Counter, opts: dict) -> PlanImport:
    """What was understood of one storey (its scene with the floor at z = 0)."""
    s, p = m.s, m.path
    below, up = s.below(st), s.above(st)
    keys = {st.key, 0} | ({below.key} if below else set())
    mine = [e for e in elements if s.synthetic or s.storey_key(e.eid) in keys]
    floor = st.elevation
    ceilings = [e for e in elements if e.ifc_class in CEILINGS and (e.ifc_class != "IfcCovering" or kinds[e.eid][1]
                                                                   in CEILING_COVERINGS)
                and (s.synthetic or s.storey_key(e.eid) in keys | ({up.key} if up else set()))]
    walls, by_hand, by_shape = storey_walls(mine, kinds, floor, opts["gap"], opts["named"], spaces, opts["may_be"])
    height, h_from = ((opts["ceiling"], "ceiling_height option") if opts["ceiling"] is not None else
                      ceiling_of(floor, up.elevation if up else None, ceilings, spaces, walls, opts["roofs"]))
    top = floor + height
    floors = [e for e in mine if (e.ifc_class == "IfcSlab" and kinds[e.eid][1] not in NOT_FLOORS
                                  or kinds[e.eid][:2] == ("IfcCovering", "FLOORING"))
              and abs(e.z_range[1] - floor) <= FLOOR_TOL_M]
    where = f"{p}: storey '{st.name}'" if not s.synthetic else f"{p}: the building '{st.name}'"
    others = [n for n in opts["others"] if n != st.name]
    own = [e for e in mine if s.synthetic or s.storey_key(e.eid) in (st.key, 0)]
    if own or spaces:  # a wrong unit shrinks walls below a wall's height, rooms below a room's area: say it first
        extent = shapely.box(*shapely.union_all([plan_hull(e) for e in own + spaces]).bounds)
        check_footprint(extent, "elements' extent", where, m.units, m.metres_per_unit, opts["model_m2"], others)
    own = [e for e in own if e.z_range[1] > floor + 0.05 and e.z_range[0] < top]
    hint, fix = nothing_found(own, opts["may_be"], others, opts["given"])
    fp = storey_footprint(spaces, floors, walls, floor, height, opts["gap"], where, hint, fix)
    check_footprint(fp.polygon, f"footprint (from {fp.how})", where, m.units, m.metres_per_unit, opts["model_m2"],
                    others)
    skip = {"IfcDoor"} if opts["doors"] == "open" else set()
    skip |= {"IfcWindow"} if opts["glass"] == "transparent" else set()
    lying = {e.eid for e in floors}  # floor slabs and finishes: the floor itself, not obstacles
    blockers = [e for e in mine if e.ifc_class not in skip and e.eid not in lying and not (
        e.ifc_class == "IfcCovering" and kinds[e.eid][1] in ("CEILING", "FLOORING"))]
    obstacles, used = _obstacles(blockers, floor, top, fp.polygon, p.name, skipped)
    obstacles += prism_obstacles(fp.seams, 0.0, height, "outside", {"file": p.name, "class": "outside"},
                                 skipped=skipped)
    check_free_floor(fp.polygon, obstacles, where, others)
    inside = [e for e in spaces if plan_shape(e).intersection(fp.polygon).area > 0.5 * plan_shape(e).area]
    skipped["IfcSpace outside the footprint"] += len(spaces) - len(inside)
    coverage = opts["coverage"] if opts["coverage"] is not None else 2
    zones = room_zones([(labels[e.eid], plan_shape(e)) for e in inside] or [(st.name, fp.polygon)], coverage,
                       skipped=skipped)
    name = opts["name"] or (f"{p.stem} {st.name}" if opts["several"] else p.stem)
    data = plan_scene(name, fp.polygon, height, obstacles, zones, heights=opts["heights"], coverage=opts["coverage"],
                      budget=opts["budget"])
    got = PlanImport(validated(data, f"{p} (storey '{st.name}')"), "ifc")
    got.skipped = Counter({k: v for k, v in skipped.items() if v})
    got.openings = _openings(mine, floor, top)
    if below is not None:
        lower = [e for e, z in opts["spaces"] if z < floor - FLOOR_TOL_M]
        stairs = [e for e in mine if e.ifc_class in STAIRS]
        voids = [e for e in spaces if VOID.search(labels[e.eid])]
        got.floor_openings, found = floor_openings(fp.polygon, floor, floors, walls, stairs, lower, voids)
    else:
        found = {}
    said = {"lowest space": "the lowest point of its spaces", "doors and walls": "where most of its doors and walls "
            "stand", "nothing: 0": "it has no spaces, doors or walls to say it"}
    got.notes = [opts["why"]] + ([f"the file gives '{st.name}' no floor level: taken at z = {floor:.2f} m "
                                  f"({said[st.level]}); elements below it (footings) are left out"]
                                 if st.level in said else [])
    if fp.pieces > 1:
        got.notes.append(f"the rooms form {fp.pieces} separate pieces (blocks, or rooms parted by walls thicker than "
                         f"{opts['gap']:g} m): joined by {fp.pieces - 1} thin seam(s) filled by 'outside' obstacles "
                         "(no target or camera there)")
    n_doors = sum(e.ifc_class == "IfcDoor" for e in mine if min(e.z_range[1], top) - max(e.z_range[0], floor) > 0.01)
    n_glass = sum(e.ifc_class == "IfcWindow" for e in mine if min(e.z_range[1], top) - max(e.z_range[0], floor) > 0.01)
    got.used = {
        "units": m.units,
        "storey": f"{st.name} (floor at {floor:+.2f} m, from its {st.level}; "
                  f"{len(inside)} room{'s' * (len(inside) != 1)})",
        "ceiling": f"{height:.2f} m ({h_from})",
        "footprint": f"{fp.polygon.area:.1f} m² from {fp.how}",
        "rooms": (f"{len(inside)} IfcSpace, zones named by LongName (else Name)" if inside else
                  f"no IfcSpace: one zone '{zones[0]['name']}' over the footprint"),
        "elements": ", ".join(f"{c} {n}" for c, n in sorted(used.items(), key=lambda t: (-t[1], t[0]))),
        "walls": _wall_words([e for e in walls if e.z_range[1] > floor + 0.05 and e.z_range[0] < top], by_hand,
                             by_shape),
        "floor openings": (f"{len(got.floor_openings)} open to the storey below"
                           + (f" ({', '.join(f'{k} {n}' for k, n in found.items() if n)})" if got.floor_openings
                              else "") if below is not None else "none: the lowest storey"),
        "doors": f"{opts['doors']}: {n_doors} IfcDoor " + ("left out (open)" if opts["doors"] == "open" else "block"),
        "glass": f"{opts['glass']}: {n_glass} IfcWindow " + ("occlude" if opts["glass"] == "opaque" else "left out"),
    }
    return got


def _plan_extent(elements: list[Element]) -> float:
    """The area (m²) of the plan bounding box of ``elements`` (0 for none)."""
    if not elements:
        return 0.0
    lo = np.min([e.vertices[:, :2].min(axis=0) for e in elements], axis=0)
    hi = np.max([e.vertices[:, :2].max(axis=0) for e in elements], axis=0)
    return float(np.prod(hi - lo))


def _wall_words(walls: list[Element], by_hand: Counter, by_shape: Counter) -> str:
    """The summary's walls line: classes with counts, and which came by hand or by shape."""
    plain = Counter(e.ifc_class for e in walls) - by_hand - by_shape
    words = [f"{c} {n}" for c, n in plain.most_common()]
    words += [f"{c} {n} (wall_classes)" for c, n in by_hand.most_common()]
    words += [f"{c} {n} (shaped like walls)" for c, n in by_shape.most_common()]
    return ", ".join(words) or "none"


def storey_elevations(path: str | Path, units: str | None = None) -> dict[str, float]:
    """Storey name -> floor elevation (m; ``units`` overrides the file's length unit)."""
    m = _Model(Path(path), units)
    if any(st.elevation != st.elevation for st in m.s.storeys):
        m.with_floors(m.shapes(list(m.model.by_type("IfcSpace")), Counter()), spaces=True)
        m.with_floors(m.shapes(list({e.id(): e for e in _entities(m.model, [c for cs in FLOOR_MAKERS for c in cs])
                                     }.values()), Counter()))
    return {st.name: st.elevation for st in m.s.storeys}


def import_plan(path: str | Path, **options) -> dict:
    """The scene mapping of one storey of an IFC file (options: see read_storeys; storey
    'all' belongs to import_storeys, which gives one scene per storey)."""
    return read(path, **options).scene


def read(path: str | Path, **options) -> PlanImport:
    """What was understood of one storey of an IFC file (options as read_storeys)."""
    if options.get("storey") == "all":
        raise InputError(f"{path}: storey 'all' gives one scene per storey; import them with import_storeys",
                         option="storey")
    return read_storeys(path, **options)[0][1]
