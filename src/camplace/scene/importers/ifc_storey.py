"""One storey of an IFC model from its element bodies (world z, metres): the default storey,
the floor level of a building without storeys, the ceiling, and the footprint (the building's
outline at the outer wall faces: spaces, else floor slabs, with the walls that bound them;
else the walls' outline; separate blocks joined into one simple polygon by thin seams that
an ``outside`` obstacle fills).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import shapely
from shapely.geometry import Polygon

from camplace.core.errors import InputError
from camplace.scene.importers import DEFAULT_CEILING_M, footprint_of, outline_pieces, polygons_of, walls_outline
from camplace.scene.importers.ifc_geometry import Element, plan_shape
from camplace.scene.importers.ifc_model import Storey, Structure

MIN_CEILING_M = 1.5  # a slab lower than this above the floor is a step or a landing, not the ceiling
FLOOR_TOL_M = 0.3  # a slab whose top lies this close to the floor level is the floor
MIN_PIECE_M2 = 1.0  # a piece of the footprint smaller than this is dropped
SEAM_M = 0.1  # width of the seam that joins two separate blocks into one footprint
CEILINGS = ("IfcSlab", "IfcRoof", "IfcCovering")
WALLS = ("IfcWall", "IfcWallStandardCase", "IfcWallElementedCase", "IfcCurtainWall")
FLOOR_MAKERS = (("IfcDoor",), WALLS + ("IfcColumn",))  # what stands on the floor, best witness first


@dataclass
class Footprint:
    """A storey's footprint (one simple polygon, m, world xy), the seams that joined its
    pieces (shapely, m²; filled by an obstacle), and how it was found (for the summary)."""

    polygon: Polygon
    seams: object
    pieces: int
    how: str


@dataclass(frozen=True)
class StoreyRooms:
    """What the default choice weighs: a storey's rooms [(name, m², occupiable)], its element
    count and how many of them are walls or floor slabs (what a footprint is made of)."""

    rooms: list[tuple[str, float, bool]]
    elements: int
    makers: int = 0

    @property
    def occupiable(self) -> tuple[int, float]:
        got = [a for _, a, ok in self.rooms if ok]
        return len(got), sum(got)


def _describe(st: Storey, r: StoreyRooms) -> str:
    n, area = r.occupiable
    if n:
        return f"'{st.name}' {n} room{'s' * (n != 1)}, {area:.1f} m²"
    why = (" (a roof or foundation level)" if st.roof_or_foundation else
           " (no walls, no floor slab)" if not r.makers else "")
    return f"'{st.name}' {'no rooms' if not r.rooms else 'no room to plan'}{why}"


def choose_storeys(s: Structure, rooms: dict[int, StoreyRooms], storey: str | None, path) -> tuple[list[Storey], str]:
    """The storeys to import and a note saying why: the one named ``storey``; for 'all' every
    storey with a room to plan (else every storey not named a roof or foundation level that
    has walls or a floor slab: not a level holding only its roof);
    by default the one a user plans: not a roof or foundation level, the most rooms to
    plan (occupiable IfcSpaces: not external, not a roof), then the most floor area, then
    the most elements."""
    if storey not in (None, "all"):
        return [s.by_name(path, storey)], f"storey '{storey}' as asked"
    if s.synthetic:
        return list(s.storeys), ("the file has no IfcBuildingStorey: " + ", ".join(
            f"the building '{st.name}'" for st in s.storeys) + " as one storey")
    empty = StoreyRooms([], 0)
    if storey == "all":
        with_rooms = [st for st in s.storeys if rooms.get(st.key, empty).occupiable[0]]
        plain = [st for st in s.storeys if not st.roof_or_foundation and rooms.get(st.key, empty).makers]
        some = [st for st in s.storeys if not st.roof_or_foundation and rooms.get(st.key, empty).elements]
        picked = with_rooms or plain or some or list(s.storeys)
        left = [st for st in s.storeys if st not in picked]
        why = ("every storey: the storeys with rooms to plan" if with_rooms else
               "every storey: the storeys with walls or a floor slab (none has a room to plan)" if plain else
               "every storey: the storeys with elements (none has a room to plan, walls or a floor slab)")
        return picked, why + (f"; left out: {'; '.join(_describe(x, rooms.get(x.key, empty)) for x in left)}"
                              if left else "")

    def key(st: Storey):
        r = rooms.get(st.key, empty)
        return (not st.roof_or_foundation, *r.occupiable, r.makers > 0, r.elements)

    best = max(s.storeys, key=key)
    others = [x for x in s.storeys if x is not best]
    note = (f"default storey {_describe(best, rooms.get(best.key, empty))}: the most rooms to plan, then floor area"
            + (f"; the others: {'; '.join(_describe(x, rooms.get(x.key, empty)) for x in others)}" if others else "")
            + " (pick another with the storey option)")
    return [best], note


def floor_level(elements: list[Element]) -> float:
    """The floor (m, world z) of a building without storeys: the height most of its doors
    stand on (else its walls and columns; ties: the higher, above the footings)."""
    for classes in FLOOR_MAKERS:
        zs = Counter(round(e.z_range[0], 2) + 0.0 for e in elements if e.ifc_class in classes)
        if zs:
            top = max(zs.values())
            return float(max(z for z, n in zs.items() if n == top))
    return float(min((e.z_range[0] for e in elements), default=0.0))


def _lowest_level(floor: float, nxt: float | None, elements: list[Element], area) -> tuple[float, list] | None:
    """(height above ``floor``, elements) of the lowest level (5 cm) of the undersides of
    ``elements`` at least MIN_CEILING_M up (and not above ``nxt``) that together lie over a
    quarter of ``area`` (the storey's spaces; empty: any); None when there is none."""
    levels: dict[float, list[Element]] = {}
    for e in elements:
        z = e.z_range[0] - floor
        if z >= MIN_CEILING_M and (nxt is None or e.z_range[0] <= nxt + 1e-6):
            levels.setdefault(round(z / 0.05) * 0.05, []).append(e)
    for z in sorted(levels):
        els = levels[z]
        if area.is_empty or shapely.union_all([plan_shape(e) for e in els]).intersection(area).area > 0.25 * area.area:
            return min(e.z_range[0] for e in els) - floor, els
    return None


def ceiling_of(floor: float, nxt: float | None, ceilings: list[Element], spaces: list[Element],
               walls: list[Element], roofs: set[int] = frozenset()) -> tuple[float, str]:
    """The storey's clear height (m above ``floor``) and where it came from, first found of:
    the ceiling coverings (IfcCovering) over the rooms; the slabs above (the lowest level,
    5 cm, of undersides at least MIN_CEILING_M up that together lie over a quarter of its
    spaces), unless its spaces' tops are lower; the top of its spaces; only then the roof
    (``roofs``: entity ids of IfcRoof, ROOF slabs, ROOFING coverings, a roof's parts): a mono-pitch roof's
    eave says nothing where a covering or a space says the height; the next storey's
    elevation ``nxt``; the height most of its walls reach; DEFAULT_CEILING_M."""
    area = shapely.union_all([plan_shape(e) for e in spaces]) if spaces else Polygon()
    tops = [e.z_range[1] - floor for e in spaces]
    top = min(max(tops), nxt - floor) if tops and nxt is not None else max(tops) if tops else 0.0
    space_top = top if top >= MIN_CEILING_M else None
    covers = _lowest_level(floor, nxt, [e for e in ceilings if e.ifc_class == "IfcCovering" and e.eid not in roofs],
                           area)
    if covers:
        return covers[0], f"IfcCovering underside over {'the rooms' if spaces else 'the storey'}"
    slabs = _lowest_level(floor, nxt, [e for e in ceilings if e.ifc_class != "IfcCovering" and e.eid not in roofs],
                          area)
    if slabs and (space_top is None or slabs[0] <= space_top + 1e-6):
        return slabs[0], f"{slabs[1][0].ifc_class} underside"
    if space_top is not None:
        return space_top, "top of the spaces" + (", not the roof: a roof counts only where no covering or space "
                                                 "says the height" if any(e.eid in roofs for e in ceilings) else "")
    roof = _lowest_level(floor, nxt, [e for e in ceilings if e.eid in roofs], area)
    if roof:
        return roof[0], f"{roof[1][0].ifc_class} underside: a roof, as no ceiling covering or space says the height"
    if nxt is not None:
        return nxt - floor, "next storey's elevation"
    tops = Counter(round(e.z_range[1] - floor, 2) for e in walls if e.z_range[1] - floor >= MIN_CEILING_M)
    if tops:
        return float(tops.most_common(1)[0][0]), "height of most walls"
    return DEFAULT_CEILING_M, "default"


def join_pieces(pieces: list[Polygon], width: float = SEAM_M) -> tuple[Polygon, object]:
    """One simple polygon over separate ``pieces`` (largest first) and the seams (shapely)
    added to join them: each piece in turn is joined to the nearest one already joined by
    a strip ``width`` m wide along the shortest line between them (``width`` inside both,
    so that the strip enters them clear of their corners)."""
    joined, seams, rest = pieces[0], [], list(pieces[1:])
    while rest:
        k = min(range(len(rest)), key=lambda i: joined.distance(rest[i]))
        piece = rest.pop(k)
        inner = joined.buffer(-width), piece.buffer(-width)  # from `width` inside both: clear of their corners
        ends = shapely.shortest_line(*(inner if not (inner[0].is_empty or inner[1].is_empty) else (joined, piece)))
        if ends.length > 1e-9:
            seams.append(ends.buffer(width / 2, cap_style="flat"))
        joined = shapely.union_all([joined, piece] + seams[-1:])
        joined = max(polygons_of(shapely.make_valid(joined)), key=lambda q: q.area)
    union = shapely.union_all(pieces)
    outline = footprint_of([joined], "footprint")
    return outline, shapely.union_all(seams).intersection(outline).difference(union) if seams else Polygon()


def storey_footprint(spaces: list[Element], floors: list[Element], walls: list[Element], floor: float,
                     height: float, gap: float, where: str, hint: str = "", option: str | None = None) -> Footprint:
    """The footprint of a storey, the building's outline at the outer faces of its outer
    walls: its spaces merged with the walls that bound them (outline_pieces; walls up to
    ``gap`` m thick); else its floor slabs (top within FLOOR_TOL_M of ``floor``) with those
    walls; else the outline of its walls above the floor (walls_outline). Separate pieces
    are joined by seams. InputError naming ``where`` when the storey has none of these (``hint``:
    what it holds and the fix, ``option`` the option that fixes it)."""
    shapes = [q for q in (plan_shape(e) for e in walls  # the walls reaching above the floor (not the footings)
                          if min(e.z_range[1], floor + height) - max(e.z_range[0], floor + 0.05) > 0)
              if not q.is_empty]
    wall_plan = shapely.union_all(shapes) if shapes else Polygon()
    for found, how in ((spaces, "IfcSpace"), (floors, "floor slab")):
        pieces = outline_pieces([plan_shape(e) for e in found], wall_plan, gap, MIN_PIECE_M2)
        if pieces:
            polygon, seams = join_pieces(pieces)
            n = len(pieces)
            return Footprint(polygon, seams, n, f"{len(found)} {how}{'s' * (len(found) != 1)} with the walls that "
                             f"bound them (outer faces; gaps ≤ {gap:g} m closed)"
                             + (f"; {n} pieces joined by seams" if n > 1 else ""))
    if shapes:
        return Footprint(walls_outline(wall_plan), Polygon(), 1,
                         f"outline of {len(shapes)} walls above the floor (no IfcSpace, no floor slab)")
    raise InputError(f"{where} has no IfcSpace, floor slab or wall to make a footprint of{hint}", option=option)
