"""Which elements of an IFC storey are walls: by class (IfcWall and its kin), by the
classes a user names (``wall_classes``), or by their solid's shape whatever their class
(a Tekla precast building exports its walls as IfcBeam named 'WAND').

Wall-shaped: tall (at least MIN_WALL_HEIGHT_M), standing on the storey's floor (its
bottom within FLOOR_TOL_M above, SINK_M below), thin and long in plan (mean width
2·area/perimeter at most the thickest wall, length at least MIN_WALL_LENGTH_M and
ELONGATION times its width), and closing rooms with the other walls (its connected group
of walls: it lies within JOIN_M of the outline of a room of at least MIN_ROOM_M2 that
all the walls enclose once gaps up to DOOR_GAP_M are closed, as precast panels leave a
door's width between them; or it comes within the thickest wall of an IfcSpace).
"""

from __future__ import annotations

from collections import Counter

import numpy as np
import shapely
from shapely.geometry import Polygon

from camplace.core.errors import InputError
from camplace.scene.importers import polygons_of
from camplace.scene.importers.ifc_geometry import Element, plan_hull, plan_shape, section
from camplace.scene.importers.ifc_storey import FLOOR_TOL_M, WALLS

MIN_WALL_HEIGHT_M = 1.5  # a wall reaches at least this far above the floor
SINK_M = 0.5  # a wall may start this far below the floor level (on the foundation, in the slab)
MIN_WALL_LENGTH_M = 0.8
ELONGATION = 3.0  # length / width of a wall at least
JOIN_M = 0.05  # a wall this close to the outline of a room bounds it
UPRIGHT = 0.6  # at one of a quarter, half, three quarters of its height a wall's section covers this much of its plan
MIN_ROOM_M2 = 1.0
DOOR_GAP_M = 1.5  # gaps up to this between walls (doors between panels) are closed when looking for rooms
MAX_FACES = 5000  # a body with more triangles and a fat convex hull is no wall (a tree): its plan is not drawn
NEVER_WALLS = ("IfcDoor", "IfcWindow", "IfcFurnishingElement", "IfcCovering", "IfcDistributionElement",
               "IfcStair", "IfcStairFlight", "IfcRamp", "IfcRampFlight", "IfcRailing", "IfcTransportElement",
               "IfcGeographicElement", "IfcSpace", "IfcColumn", "IfcFooting", "IfcPile")


def wall_class_names(model, classes) -> tuple[str, ...]:
    """The IFC class names of ``classes`` (an iterable of names, any case) as the schema of
    ``model`` spells them; InputError naming the option for one that is not an element
    class of that schema."""
    import ifcopenshell.ifcopenshell_wrapper as w

    schema = w.schema_by_name(model.schema)
    element = schema.declaration_by_name("IfcElement")
    out = []
    for name in classes:
        try:
            decl = schema.declaration_by_name(str(name).strip())
        except (RuntimeError, KeyError, IndexError):
            decl = None
        ok = decl is not None and hasattr(decl, "supertype")
        while ok and decl is not None and decl.name() != element.name():
            decl = decl.supertype()
        if not ok or decl is None:
            raise InputError(f"wall_classes: '{name}' is not an element class of {model.schema}; expected class "
                             "names such as IfcBeam, IfcMember, IfcPlate, IfcBuildingElementProxy",
                             option="wall_classes")
        out.append(schema.declaration_by_name(str(name).strip()).name())
    return tuple(dict.fromkeys(out))


def _shape_ok(el: Element, floor: float, gap: float) -> bool:
    """Tall, standing on the floor at ``floor`` (m, world z), thin and long in plan, upright
    (not a stair's sloping stringer: some section covers UPRIGHT of its plan)."""
    lo, hi = el.z_range
    if not (floor - SINK_M <= lo <= floor + FLOOR_TOL_M and hi - floor >= MIN_WALL_HEIGHT_M):
        return False
    if len(el.faces) > MAX_FACES:  # cheap first: a wall's hull is thin unless the wall turns a corner
        rect = shapely.minimum_rotated_rectangle(plan_hull(el))
        sides = np.diff(np.asarray(rect.exterior.coords)[:3], axis=0) if isinstance(rect, Polygon) else np.zeros((2, 2))
        if min(np.hypot(*sides.T)) > max(gap, 0.05):
            return False
    plan = plan_shape(el)
    if plan.is_empty or plan.area <= 0:
        return False
    width = 2 * plan.area / plan.length  # mean width: a w x l rectangle gives w·l/(w+l)
    length = plan.length / 2 - width
    if not (width <= max(gap, 0.05) and length >= MIN_WALL_LENGTH_M and length >= ELONGATION * width):
        return False
    return any(section(el, lo + f * (hi - lo)).area >= UPRIGHT * plan.area for f in (0.5, 0.25, 0.75))


def _room_edges(plans: list):
    """The outlines (shapely lines) of the rooms the union of ``plans`` (shapely) encloses
    once gaps up to DOOR_GAP_M are closed (rooms of MIN_ROOM_M2 at least)."""
    d = DOOR_GAP_M / 2
    closed = shapely.make_valid(shapely.union_all(plans).buffer(d, join_style="mitre").buffer(-d, join_style="mitre"))
    rings = [h for q in polygons_of(closed) for h in q.interiors if Polygon(h).area >= MIN_ROOM_M2]
    return shapely.union_all([shapely.LineString(h.coords) for h in rings]) if rings else None


def storey_walls(elements: list[Element], kinds: dict, floor: float, gap: float, named: tuple[str, ...],
                 spaces: list[Element], may_be: set[int]) -> tuple[list[Element], Counter, Counter]:
    """The walls among ``elements`` of a storey whose floor is at ``floor`` (m, world z):
    wall classes (WALLS), the classes a user ``named`` (``kinds``: entity id -> (class,
    predefined type, the classes it is an instance of)), and the elements in ``may_be``
    (entity ids of classes that may be walls, not NEVER_WALLS) whose solid is wall-shaped
    and closes rooms with the other walls (``spaces``: the storey's IfcSpaces, m). Returns
    (walls, classes taken by hand, classes taken by shape) with counts."""
    by_class = [e for e in elements if e.ifc_class in WALLS]
    by_hand = [e for e in elements if e.ifc_class not in WALLS and named and set(kinds[e.eid][2]) & set(named)]
    taken = {e.eid for e in by_class + by_hand}
    cands = [e for e in elements if e.eid in may_be and e.eid not in taken and _shape_ok(e, floor, gap)]
    if not cands:
        return by_class + by_hand, Counter(e.ifc_class for e in by_hand), Counter()
    plans = [plan_shape(e) for e in cands]
    edges = _room_edges([plan_shape(e) for e in by_class + by_hand] + plans)
    rooms = shapely.union_all([plan_shape(e) for e in spaces]) if spaces else Polygon()
    near = rooms.buffer(max(gap, JOIN_M)) if not rooms.is_empty else None
    kept = [i for i, q in enumerate(plans) if edges is not None and q.buffer(JOIN_M).intersects(edges)
            or near is not None and q.intersects(near)]
    walls = [cands[i] for i in sorted(kept)]
    return by_class + by_hand + walls, Counter(e.ifc_class for e in by_hand), Counter(e.ifc_class for e in walls)
