"""The spatial structure of an IFC model, read without geometry: the length unit, the
storeys (or, in a file without any IfcBuildingStorey, each building standing in for one),
which storey each element belongs to, and the names of the rooms.

An element belongs to the storey its chain of relations leads to: contained in a
spatial element (IfcRelContainedInSpatialStructure), part of an aggregate
(IfcRelAggregates: a stair flight of its stair, a space of its storey), a door or window
filling an opening (IfcRelFillsElement) voiding a wall (IfcRelVoidsElement), furniture
contained in a space, a covering of a space or an element (IfcRelCoversSpaces,
IfcRelCoversBldgElements). One pass over the relations (no per-element lookups).
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass, field, replace
from pathlib import Path

from camplace.core.errors import InputError

SCALE_SYMBOL = {0.001: "mm", 0.01: "cm", 1.0: "m", 0.3048: "ft", 0.0254: "in"}
_WORDS = r"(?:^|[^a-z])({})(?:[^a-z]|$)"
ROOF = re.compile(_WORDS.format("roof|roofs|dach|toit|toiture|techo|tejado|cubierta|tetto|copertura|dak|tak"), re.I)
FOUNDATION = re.compile(_WORDS.format("foundation|fdn|fundament|fundamente|footing|footings|fondation|fondations"
                                      "|cimentacion|cimentación|fondazioni|site|terrain|gelände|gelaende"), re.I)


@dataclass(frozen=True)
class Storey:
    """A storey to plan: ``name`` (unique in the file), ``elevation`` (m, world z of its
    floor), ``key`` (entity id of the IfcBuildingStorey, or of the IfcBuilding standing in
    for one; 0 for a file without either), ``building`` (entity id, 0: none), ``level``:
    where the elevation came from ('placement', 'Elevation'; 'geometry' while nan, until its
    spaces ('lowest space') or its doors and walls ('doors and walls') say it)."""

    name: str
    elevation: float
    key: int
    building: int = 0
    level: str = "placement"

    @property
    def roof_or_foundation(self) -> bool:
        """True when its name says roof or foundation (never the storey a user plans by default)."""
        return bool(ROOF.search(self.name) or FOUNDATION.search(self.name))


@dataclass
class Structure:
    """The storeys (lowest first) and the element -> storey map of a model."""

    storeys: list[Storey]
    parent: dict[int, int]
    synthetic: bool  # no IfcBuildingStorey in the file: buildings stand in for storeys
    names: dict[int, str] = field(default_factory=dict)  # building id -> name
    _memo: dict[int, int] = field(default_factory=dict)

    def storey_key(self, eid: int) -> int:
        """The key of the storey entity ``eid`` belongs to (0: none)."""
        keys = {s.key for s in self.storeys}
        path, x = [], eid
        while x and x not in keys and x not in self._memo and len(path) < 64:
            path.append(x)
            x = self.parent.get(x, 0)
        found = x if x in keys else self._memo.get(x, 0)
        for p in path:
            self._memo[p] = found
        return found

    def above(self, st: Storey) -> Storey | None:
        """The next storey up in the same building (None for the top one)."""
        ups = [s for s in self.storeys if s.building == st.building and s.elevation > st.elevation + 1e-6]
        return min(ups, key=lambda s: s.elevation) if ups else None

    def below(self, st: Storey) -> Storey | None:
        """The next storey down in the same building (None for the lowest)."""
        downs = [s for s in self.storeys if s.building == st.building and s.elevation < st.elevation - 1e-6]
        return max(downs, key=lambda s: s.elevation) if downs else None

    def by_name(self, path: Path, name: str) -> Storey:
        """The storey called ``name`` (exact, else the one case-insensitive match); InputError
        listing the storeys otherwise."""
        hit = [s for s in self.storeys if s.name == name] or [s for s in self.storeys
                                                             if s.name.casefold() == name.casefold()]
        if len(hit) != 1:
            raise InputError(f"{path}: no storey named '{name}'; its storeys are "
                             f"{', '.join(repr(s.name) for s in self.storeys)}", option="storey")
        return hit[0]


def open_model(path: Path):
    """The ifcopenshell model of ``path`` (an IFC STEP file, or an .ifczip holding one);
    InputError naming the file when it is not IFC."""
    import ifcopenshell

    with open(path, "rb") as f:
        head = f.read(64)
    zipped = path.suffix.lower() == ".ifczip"
    if zipped and not head.startswith(b"PK"):
        raise InputError(f"{path}: not an .ifczip file (a zip archive holding an .ifc file)")
    if not zipped and not head.lstrip().startswith(b"ISO-10303-21"):
        raise InputError(f"{path}: not an IFC file (an IFC STEP file starts with 'ISO-10303-21;')")
    try:
        return ifcopenshell.open(str(path), format=".ifcZIP" if zipped else None)
    except Exception as err:  # ifcopenshell raises its own kinds for broken files
        msg = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise InputError(f"{path}: not a readable IFC file ({msg[:120]})") from None


def length_scale(model) -> float:
    """Metres per length unit of the file (IfcUnitAssignment: mm 0.001, m 1, ft 0.3048)."""
    import ifcopenshell.util.unit

    return float(ifcopenshell.util.unit.calculate_unit_scale(model))


def unit_words(model, scale: float) -> str:
    """The file's length unit for the summary, e.g. 'mm (IfcUnitAssignment: MILLI METRE)'."""
    import ifcopenshell.util.unit

    unit = ifcopenshell.util.unit.get_project_unit(model, "LENGTHUNIT")
    symbol = next((s for k, s in SCALE_SYMBOL.items() if abs(k - scale) < 1e-9 * k), f"{scale:g} m")
    if unit is None:
        return f"{symbol} (the file assigns no length unit)"
    said = " ".join(x for x in (getattr(unit, "Prefix", None), getattr(unit, "Name", None)) if x) or unit.is_a()
    return f"{symbol} (IfcUnitAssignment: {said})"


def _parents(model) -> dict[int, int]:
    """Entity id -> id of what it belongs to (spatial container, aggregate, opening, host)."""
    parent: dict[int, int] = {}

    def rels(cls):
        try:
            return model.by_type(cls)
        except RuntimeError:  # not in this schema
            return []

    for rel in rels("IfcRelAggregates"):
        for o in rel.RelatedObjects or ():
            parent[o.id()] = rel.RelatingObject.id()
    for rel in rels("IfcRelContainedInSpatialStructure"):
        for o in rel.RelatedElements or ():
            parent.setdefault(o.id(), rel.RelatingStructure.id())
    for rel in rels("IfcRelFillsElement"):
        parent.setdefault(rel.RelatedBuildingElement.id(), rel.RelatingOpeningElement.id())
    for rel in rels("IfcRelVoidsElement"):
        parent.setdefault(rel.RelatedOpeningElement.id(), rel.RelatingBuildingElement.id())
    for rel in rels("IfcRelCoversSpaces"):  # a ceiling covering of a space (IFC4 RelatingSpace, IFC2X3 RelatedSpace)
        space = getattr(rel, "RelatingSpace", None) or getattr(rel, "RelatedSpace", None)
        for o in (rel.RelatedCoverings or ()) if space is not None else ():
            parent.setdefault(o.id(), space.id())
    for rel in rels("IfcRelCoversBldgElements"):  # a covering of a slab or wall
        for o in rel.RelatedCoverings or ():
            parent.setdefault(o.id(), rel.RelatingBuildingElement.id())
    for rel in rels("IfcRelNests"):
        for o in rel.RelatedObjects or ():
            parent.setdefault(o.id(), rel.RelatingObject.id())
    return parent


def _placement_z(entity, scale: float) -> float | None:
    import ifcopenshell.util.placement

    if getattr(entity, "ObjectPlacement", None) is None:
        return None
    try:
        return float(ifcopenshell.util.placement.get_local_placement(entity.ObjectPlacement)[2, 3]) * scale
    except Exception:  # an unusual placement (grid, linear): fall back to the attribute
        return None


def _building_of(eid: int, parent: dict[int, int], buildings: set[int]) -> int:
    x, n = eid, 0
    while x and x not in buildings and n < 64:
        x, n = parent.get(x, 0), n + 1
    return x if x in buildings else 0


def unique_names(names: list[str], suffixes: list[str]) -> list[str]:
    """``names`` made unique: a repeated one gets its suffix, then #2, #3..."""
    count = Counter(names)
    out = [n if count[n] == 1 or not s else f"{n} ({s})" for n, s in zip(names, suffixes)]
    seen: Counter = Counter()
    for i, n in enumerate(out):
        seen[n] += 1
        if seen[n] > 1:
            out[i] = f"{n} #{seen[n]}"
    return out


def structure(model, scale: float) -> Structure:
    """The model's storeys and element -> storey map (elevations in m: the storey's placement z,
    world, like the geometry; its Elevation attribute, above its building's placement, where
    placements are missing or all equal while the attributes differ; neither: nan, left to
    the geometry). A file without
    IfcBuildingStorey: one storey per IfcBuilding (one for the file without one), its
    elevation left to the geometry."""
    parent = _parents(model)
    buildings = {b.id(): (b.Name or b.LongName or "building") for b in model.by_type("IfcBuilding")}
    ents = list(model.by_type("IfcBuildingStorey"))
    if not ents:
        stand = [(bid, name) for bid, name in buildings.items()] or [(0, "building")]
        sts = [Storey(n, float("nan"), k, k, "geometry") for n, (k, name) in
               zip(unique_names([name for _, name in stand], [str(k) for k, _ in stand]), stand)]
        return Structure(sts, parent, True, buildings)
    placed = [_placement_z(s, scale) for s in ents]
    # Elevation is above the building's own 0.00 (its placement): world z = the building's z + Elevation
    base = {b.id(): _placement_z(b, scale) or 0.0 for b in model.by_type("IfcBuilding")}
    attrs = [None if s.Elevation is None else float(s.Elevation) * scale
             + base.get(_building_of(s.id(), parent, set(buildings)), 0.0) for s in ents]
    use_attr = (any(z is None for z in placed) or (len(set(round(z, 4) for z in placed)) < len(placed)
                                                    and len(set(a for a in attrs if a is not None)) > 1))
    sts = []
    for s, z, a in zip(ents, placed, attrs):
        level, elev = ("placement", z) if not use_attr and z is not None else ("Elevation", a)
        if elev is None:
            level, elev = ("placement", z) if z is not None else ("geometry", float("nan"))
        sts.append(Storey(s.Name or s.LongName or f"storey #{s.id()}", float(elev), s.id(),
                          _building_of(s.id(), parent, set(buildings)), level))
    labels = unique_names([s.name for s in sts], [buildings.get(s.building, "") for s in sts])
    sts = [replace(s, name=n) for s, n in zip(sts, labels)]
    return Structure(sorted(sts, key=lambda s: (s.elevation != s.elevation, s.elevation)), parent, False, buildings)


def is_external(space) -> bool:
    """True for an IfcSpace marked external (IFC2X3 InteriorOrExteriorSpace, IFC4 PredefinedType)."""
    return "EXTERNAL" in (str(getattr(space, "InteriorOrExteriorSpace", "") or "")
                          + str(getattr(space, "PredefinedType", "") or ""))


def room_labels(spaces: list) -> dict[int, str]:
    """Space entity id -> the zone name: its LongName (else Name); where several spaces of
    the list share a LongName, each adds its Name ('Foyer A101', 'Room 5')."""
    base = {s.id(): (s.LongName or s.Name or f"space #{s.id()}").strip() for s in spaces}
    count = Counter(base.values())
    out = {}
    for s in spaces:
        b, name = base[s.id()], (s.Name or "").strip()
        out[s.id()] = f"{b} {name}" if count[b] > 1 and name and name != b else b
    return out


def occupiable(space, label: str) -> bool:
    """False for a space that is no room to plan: external, or named a roof."""
    return not is_external(space) and not ROOF.search(label)
