"""Small IFC files for the rules of the IFC importer whose answer is known by hand (issue 34
and 33), written with ifcopenshell.api like camplace.scene.importers.ifc_build: walls
exported under another class (a Tekla precast 'WAND' as IfcBeam), a suspended ceiling
under a mono-pitch roof, and two storeys whose upper floor is opened by a slab opening, a
stair and a double-height space.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from camplace.core.files import atomic_write_text
from camplace.scene.importers.ifc_build import GridBuilding, _floor, _Writer


def _outer_walls(wr: _Writer, cls: str, name: str, size: tuple[float, float], wall: float, z: tuple[float, float],
                 storey) -> None:
    """Four elements of ``cls`` on the rectangle [0, w] x [0, d] (centre lines, m), ``wall`` m
    thick, from z[0] to z[1], corners overlapping."""
    (w, d), t = size, wall
    boxes = [((-t / 2, -t / 2), (w + t / 2, t / 2)), ((-t / 2, d - t / 2), (w + t / 2, d + t / 2)),
             ((-t / 2, -t / 2), (t / 2, d + t / 2)), ((w - t / 2, -t / 2), (w + t / 2, d + t / 2))]
    for k, ((x0, y0), (x1, y1)) in enumerate(boxes):
        wr.box(cls, f"{name} {k + 1}", np.array([x0, y0, z[0]]), np.array([x1, y1, z[1]]), storey)


def write_beam_walls(path: str | Path, size: tuple[float, float] = (6.0, 4.0), wall: float = 0.2,
                     height: float = 2.8, cls: str = "IfcBeam", standing: bool = True, unit: str = "m",
                     block: bool = False, chimney: str | None = None) -> Path:
    """One storey 'Undefined' whose four outer walls are ``cls`` elements named 'WAND' (as a
    Tekla precast export), no IfcSpace, no slab: footprint (w + wall) x (d + wall) m².
    ``standing=False``: the same elements lie as 0.4 m beams at the top (no wall shape);
    ``unit``: the file's length unit ('m' or 'mm'; lengths are given in m); ``block``: an
    IfcBuildingElementProxy 'Mass' fills the room from the floor to 2 m (no free floor);
    ``chimney``: a second storey of that name at ``height`` holding only a 0.5 x 0.5 x 1 m
    proxy."""
    wr = _Writer(unit)
    st = wr.storey("Undefined", 0.0, wr.scale)
    _outer_walls(wr, cls, "WAND", size, wall, (0.0, height) if standing else (height - 0.4, height), st)
    if chimney:
        wr.box("IfcBuildingElementProxy", "Chimney", np.array([1.0, 1.0, height]), np.array([1.5, 1.5, height + 1.0]),
               wr.storey(chimney, height, wr.scale))
    if block:
        (w, d), t = size, wall
        wr.box("IfcBuildingElementProxy", "Mass", np.array([t / 2, t / 2, 0.0]), np.array([w - t / 2, d - t / 2, 2.0]),
               st)
    return atomic_write_text(Path(path), wr.m.to_string())


def _pitched_roof(wr: _Writer, size: tuple[float, float], eave: float, ridge: float, thick: float, storey):
    """An IfcRoof over [0, w] x [0, d] (m) with 0.1 m eaves around, ``thick`` m thick, its
    underside rising from ``eave`` at its lowest edge (x = -0.1) to ``ridge`` at x = w + 0.1
    (a mono-pitch roof)."""
    m, (w, d) = wr.m, size
    x0, x1 = -0.1, w + 0.1
    z0, z1 = eave, ridge
    pts = [(x0, z0), (x1, z1), (x1, z1 + thick), (x0, z0 + thick), (x0, z0)]
    profile = m.createIfcArbitraryClosedProfileDef("AREA", None, m.createIfcPolyline(
        [m.createIfcCartesianPoint((float(x), float(z))) for x, z in pts]))
    # profile in the xz plane (local y = world z), extruded along local z = world -y from y = d + 0.1
    at = m.createIfcAxis2Placement3D(m.createIfcCartesianPoint((0.0, float(d) + 0.1, 0.0)),
                                     m.createIfcDirection((0.0, -1.0, 0.0)), m.createIfcDirection((1.0, 0.0, 0.0)))
    solid = m.createIfcExtrudedAreaSolid(profile, at, m.createIfcDirection((0.0, 0.0, 1.0)), float(d) + 0.2)
    roof = wr.entity("IfcRoof", "Mono-pitch roof")
    wr.api.geometry.assign_representation(m, product=roof, representation=m.createIfcShapeRepresentation(
        wr.body, "Body", "SweptSolid", [solid]))
    wr.place(roof, np.zeros(3))
    wr.api.spatial.assign_container(m, products=[roof], relating_structure=storey)
    return roof


def write_roofed_house(path: str | Path, size: tuple[float, float] = (6.0, 4.0), wall: float = 0.2,
                       eave: float = 1.74, ridge: float = 3.2, covering: float | None = 2.2,
                       space_height: float | None = None, covering_type: str = "CEILING",
                       covers_space: bool = False) -> Path:
    """One storey 'Ground Floor': four IfcWall 2.6 m high around [0, w] x [0, d] (m), a
    mono-pitch IfcRoof whose underside rises from ``eave`` to ``ridge``, a suspended ceiling
    (IfcCovering CEILING, 20 mm) at ``covering`` m over the room, an IfcSpace
    ``space_height`` m high (None: no covering, no space); ``covering_type``: the covering's
    PredefinedType (ROOFING: a roof's covering, no ceiling); ``covers_space``: the covering
    belongs to the space (IfcRelCoversSpaces), not to the storey (needs ``space_height``)."""
    wr = _Writer("m")
    st = wr.storey("Ground Floor", 0.0, 1.0)
    (w, d), t = size, wall
    _outer_walls(wr, "IfcWall", "Wall", size, wall, (0.0, 2.6), st)
    _pitched_roof(wr, size, eave, ridge, 0.2, st)
    lo, hi = np.array([t / 2, t / 2, 0.0]), np.array([w - t / 2, d - t / 2, 0.0])
    cover = sp = None
    if covering is not None:
        cover = wr.box("IfcCovering", "Suspended ceiling", lo + [0, 0, covering], hi + [0, 0, covering + 0.02],
                       None if covers_space else st, PredefinedType=covering_type)
    if space_height is not None:
        sp = wr.box("IfcSpace", "R01", lo, hi + [0, 0, space_height], LongName="Living")
        wr.api.aggregate.assign_object(wr.m, products=[sp], relating_object=st)
    if covers_space and cover is not None and sp is not None:
        import ifcopenshell.guid

        wr.m.createIfcRelCoversSpaces(ifcopenshell.guid.new(), None, None, None, sp, [cover])
    return atomic_write_text(Path(path), wr.m.to_string())


def write_open_floors(path: str | Path, b: GridBuilding = GridBuilding(), opening=None, stair=None,
                      atrium: bool = False, unit: str = "m", void: str | None = None) -> Path:
    """The grid building (ifc_build.GridBuilding, in m) on two storeys, 'Ground Floor' at 0
    and 'First Floor' at b.height + b.slab, with the first floor opened to the ground floor:
    ``opening`` (x0, y0, x1, y1) an IfcOpeningElement voiding its floor slab; ``stair``
    (x0, y0, x1, y1) an IfcStairFlight of the ground floor (a box) rising to it; ``atrium``:
    the first floor's slab covers only the first column of rooms (x <= b.room[0]) and the
    ground floor's last room is an IfcSpace 'Atrium' two storeys high; ``void``: the first
    floor's last room holds a second IfcSpace of that LongName (e.g. 'Luftraum'). ``unit``:
    the file's length unit ('m' or 'mm'; lengths are given in m)."""
    wr = _Writer(unit)
    up = b.height + b.slab
    ground = wr.storey("Ground Floor", 0.0, wr.scale)
    first = wr.storey("First Floor", up, wr.scale)
    _floor(wr, b, ground, 0.0, 0, ground, "body")
    _floor(wr, b, first, up, 1, first, "body")
    slab = next(e for e in wr.m.by_type("IfcSlab") if e.Name == "1.Floor slab")
    t = b.wall
    if atrium:
        wr.api.root.remove_product(wr.m, product=slab)
        wr.box("IfcSlab", "1.Floor slab", np.array([-t / 2, -t / 2, up - b.slab]),
               np.array([b.room[0], b.ny * b.room[1] + t / 2, up]), first, PredefinedType="FLOOR")
        lo, hi = b.space_boxes()[b.nx * b.ny - 1]
        sp = wr.box("IfcSpace", "A01", lo, hi + [0, 0, up], LongName="Atrium")
        wr.api.aggregate.assign_object(wr.m, products=[sp], relating_object=ground)
    if void is not None:
        lo, hi = b.space_boxes()[b.nx * b.ny - 1]
        sp = wr.box("IfcSpace", "V01", lo + [0, 0, up], hi + [0, 0, up], LongName=void)
        wr.api.aggregate.assign_object(wr.m, products=[sp], relating_object=first)
    if opening is not None:
        x0, y0, x1, y1 = opening
        hole = wr.box("IfcOpeningElement", "Slab opening", np.array([x0, y0, up - b.slab - 0.1]),
                      np.array([x1, y1, up + 0.1]))
        wr.api.feature.add_feature(wr.m, feature=hole, element=slab)
    if stair is not None:
        x0, y0, x1, y1 = stair
        wr.box("IfcStairFlight", "Stair", np.array([x0, y0, 0.0]), np.array([x1, y1, up]), ground)
    return atomic_write_text(Path(path), wr.m.to_string())
