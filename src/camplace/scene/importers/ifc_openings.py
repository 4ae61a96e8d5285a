"""Where an IFC storey's floor is open to the storey below (issue 33): the plan polygons
(m, world x, y) a building carves out of the slab between the two storeys.

Four kinds of evidence, each from the model itself:

- slab openings: the IfcOpeningElements that void a floor slab of the storey;
- voids in the slab's own profile (a shaft or stair hole drawn as an inner loop): the holes
  of the floor slabs' union, less the walls standing in them;
- stair voids: the part of an IfcStair / IfcStairFlight / IfcRamp(Flight) of a lower storey
  that rises within HEADROOM_M of this floor and reaches it;
- atria and double-height spaces: an IfcSpace of a lower storey that reaches more than
  ATRIUM_M above this floor, where this storey has no floor slab over it;
- void spaces: an IfcSpace of this storey named as the air over a lower room or a shaft
  (VOID: void, Luftraum, vide, vuoto, vacío, shaft, Schacht, gaine, open to below...).

Each piece is cut to the storey's footprint; pieces under MIN_OPENING_M2 or narrower than
MIN_WIDTH_M (the gaps between a room's finish floors under a wall) are dropped.
"""

from __future__ import annotations

import re

import shapely
from shapely.geometry import Polygon

from camplace.scene.importers import clean_polygons, polygons_of
from camplace.scene.importers.ifc_geometry import Element, plan_shape, section
from camplace.scene.importers.ifc_storey import FLOOR_TOL_M

HEADROOM_M = 2.0  # a stair's void spans where it rises within this of the floor above
ATRIUM_M = 1.0  # a space of a lower storey reaching this far above the floor is open through it
MIN_OPENING_M2 = 0.25
MIN_WIDTH_M = 0.4  # narrower: a gap between slabs or finish floors, not a way through
STAIRS = ("IfcStair", "IfcStairFlight", "IfcRamp", "IfcRampFlight")
VOID = re.compile(r"(?:^|[^a-zäöüéíáó])(void|voids|luftraum|luftr[äa]ume|leerraum|vide|vides|vuoto|vac[ií]o|"
                  r"doble altura|double[- ]height|open to below|shaft|shafts|schacht|gaine|cavedio|patinillo)"
                  r"(?:[^a-zäöüéíáó]|$)", re.I)


def slab_voids(floors: list[Element], walls: list[Element]) -> list:
    """The openings of the floor slabs (shapely, m): their IfcOpeningElements' plans, and
    the holes of their union (profile voids) less the ``walls`` standing in them."""
    out = [plan_shape(h).intersection(plan_shape(e)) for e in floors for h in e.holes]
    cuts = [section(e, 0.5 * sum(e.z_range)) for e in floors]
    union = shapely.union_all([c for c in cuts if not c.is_empty]) if cuts else Polygon()
    holes = [Polygon(h) for q in polygons_of(shapely.make_valid(union)) for h in q.interiors]
    if holes:
        stand = shapely.union_all([plan_shape(w) for w in walls]) if walls else Polygon()
        out += [h.difference(stand) for h in holes]
    return out


def stair_voids(stairs: list[Element], floor: float) -> list:
    """The plans (shapely, m) of the stairs and ramps of lower storeys that reach the floor
    at ``floor`` (m, world z; their top within FLOOR_TOL_M of it, their bottom below it),
    where they rise within HEADROOM_M of it."""
    return [plan_shape(e, floor - HEADROOM_M, floor + FLOOR_TOL_M) for e in stairs
            if e.ifc_class in STAIRS and e.z_range[1] >= floor - FLOOR_TOL_M and e.z_range[0] < floor - FLOOR_TOL_M]


def atria(lower_spaces: list[Element], floor: float, floors: list[Element]) -> list:
    """The plans (shapely, m) of the spaces of lower storeys that reach more than ATRIUM_M
    above the floor at ``floor`` (m, world z), less the floor slabs (``floors``) over them."""
    tall = [plan_shape(e) for e in lower_spaces if e.z_range[1] > floor + ATRIUM_M and e.z_range[0] < floor]
    if not tall:
        return []
    slab = shapely.union_all([plan_shape(e) for e in floors]) if floors else Polygon()
    return [t.difference(slab) for t in tall]


def floor_openings(footprint: Polygon, floor: float, floors: list[Element], walls: list[Element],
                   stairs: list[Element], lower_spaces: list[Element], voids: list[Element] = ()
                   ) -> tuple[list[list[list[float]]], dict]:
    """The plan rings (m, [[x, y], ...], world x, y) where the storey's floor at ``floor``
    (m, world z) is open to the storey below, cut to ``footprint``, and how many pieces came
    from each kind of evidence, merged ({'slab openings': n, 'stair voids': n, 'atria': n,
    'void spaces': n}); ``voids``: the storey's spaces named as voids (VOID)."""
    kinds = {"slab openings": slab_voids(floors, walls), "stair voids": stair_voids(stairs, floor),
             "atria": atria(lower_spaces, floor, floors), "void spaces": [plan_shape(e) for e in voids]}
    counts, pieces = {}, []
    for kind, shapes in kinds.items():
        one = shapely.union_all([shapely.make_valid(s) for s in shapes]) if shapes else Polygon()
        got = [q for q in polygons_of(one.intersection(footprint))
               if q.area >= MIN_OPENING_M2 and not q.buffer(-MIN_WIDTH_M / 2).is_empty]
        counts[kind] = len(got)
        pieces += got
    if not pieces:
        return [], counts
    merged = clean_polygons(shapely.union_all(pieces), tolerance=0.005, min_area=MIN_OPENING_M2, holes=False)
    rings = [[[round(float(x), 3), round(float(y), 3)] for x, y in list(q.exterior.coords)[:-1]] for q in merged]
    return rings, counts
