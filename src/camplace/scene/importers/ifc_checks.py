"""Plausibility of an IFC storey before it becomes a scene (issue 34): an import that
finds nothing says what it found and the option that would fix it (never one the user did
not give as the cause); a footprint under MIN_FOOTPRINT_M2 (a wrong length unit) and a
storey with no free floor end in one line naming the cause and the fix.
"""

from __future__ import annotations

from collections import Counter

import shapely
from shapely.geometry import Polygon

from camplace.core.errors import InputError
from camplace.scene.importers import UNITS_M
from camplace.scene.importers.ifc_geometry import Element

MIN_FOOTPRINT_M2 = 1.0  # no building is smaller
MIN_FREE_M2 = 1.0  # a storey needs at least this much floor free of obstacles
PLAUSIBLE_M2 = (10.0, 1e5)  # the footprint of a building in the right unit
FREE_BELOW_M = 0.5  # the floor is free where no obstacle stands between the floor and this height


def _counts(classes) -> str:
    return ", ".join(f"{c} {n}" for c, n in Counter(classes).most_common(6))


def nothing_found(own: list[Element], may_be: set[int], others: list[str], given: bool) -> tuple[str, str | None]:
    """(the end of the line, the option that fixes it) for a storey with no IfcSpace, floor
    slab or wall: what it holds (``own``: its elements reaching above its floor) and, when
    some could be walls (``may_be``: entity ids), the wall_classes option naming the most
    common; else another storey (``others``: the storeys that have something; ``given``:
    the user named this storey)."""
    cands = [e.ifc_class for e in own if e.eid in may_be]
    if cands:
        best = Counter(cands).most_common(1)[0][0]
        return (f": it holds {_counts(e.ifc_class for e in own)}, none of them shaped like a wall that closes rooms; "
                f"if some of them are walls, name their classes (wall_classes), e.g. wall_classes={best}",
                "wall_classes")
    held = f"it holds {_counts(e.ifc_class for e in own)}" if own else "it holds no element with a body"
    if others:
        return (f": {held}; {'name' if given else 'pick'} a storey that has some (storey): "
                + ", ".join(repr(n) for n in others[:8]), "storey")
    return f": {held}, and no other storey has any", None


def suggested_unit(area_m2: float, metres_per_unit: float) -> str | None:
    """The unit (UNITS_M) in which a footprint of ``area_m2`` read at ``metres_per_unit``
    has a building's area (PLAUSIBLE_M2); None when none does."""
    for unit in ("m", "mm", "cm", "ft", "in"):
        a = area_m2 * (UNITS_M[unit] / metres_per_unit) ** 2
        if PLAUSIBLE_M2[0] <= a <= PLAUSIBLE_M2[1] and abs(UNITS_M[unit] - metres_per_unit) > 1e-12:
            return unit
    return None


def check_footprint(polygon: Polygon, how: str, where: str, units: str, metres_per_unit: float,
                    model_m2: float = 0.0, others: list[str] = ()) -> None:
    """InputError for a footprint (or the elements' extent) under MIN_FOOTPRINT_M2: the
    file's length unit is wrong (option units; ``units``: how the summary words it), the
    line says which unit fits; but where the whole model spans a building (``model_m2``, m²,
    the area of its plan extent), the storey holds only a small thing: pick another storey
    (option storey, ``others``)."""
    if polygon.area >= MIN_FOOTPRINT_M2:
        return
    if model_m2 >= PLAUSIBLE_M2[0]:
        raise InputError(f"{where}: its {how.split(' (')[0]} is {polygon.area:.3g} m² while the model spans "
                         f"{model_m2:.0f} m²: the storey holds no building to plan"
                         + (f"; pick another storey (storey): {', '.join(repr(n) for n in others[:8])}" if others
                            else ""), option="storey" if others else None)
    unit = suggested_unit(polygon.area, metres_per_unit)
    fix = f"give the unit it is drawn in, units={unit}" if unit else "give the unit it is drawn in (units)"
    raise InputError(f"{where}: its {how.split(' (')[0]} is {polygon.area:.3g} m², too small for a "
                     f"building: the file's length unit, {units}, is likely wrong; {fix}", option="units")


def check_free_floor(polygon: Polygon, obstacles: list[dict], where: str, others: list[str]) -> None:
    """InputError when obstacles standing on the floor (below FREE_BELOW_M) leave less than
    MIN_FREE_M2 of the footprint free, naming the classes that cover it and the storeys
    (``others``) to pick instead."""
    low = [o for o in obstacles if "prism" in o and o["prism"]["z"][0] < FREE_BELOW_M < o["prism"]["z"][1]]
    if not low:
        return
    shapes = [Polygon(o["prism"]["polygon"], o["prism"].get("holes")) for o in low]
    covered = shapely.union_all([q.buffer(0) for q in shapes]).intersection(polygon).area
    if polygon.area - covered >= MIN_FREE_M2:
        return
    by_class: Counter = Counter()
    for o, q in zip(low, shapes):
        by_class[o.get("source", {}).get("class", "?")] += q.intersection(polygon).area
    top = ", ".join(f"{c} {a:.1f} m²" for c, a in by_class.most_common(3))
    fix = (f"; pick another storey (storey): {', '.join(repr(n) for n in others[:8])}" if others else
           "; the file models this storey as solid (a massing model?): export its walls, slabs and spaces")
    raise InputError(f"{where}: no free floor: obstacles standing on it cover {covered:.1f} of its "
                     f"{polygon.area:.1f} m² footprint ({top}){fix}", option="storey" if others else None)
