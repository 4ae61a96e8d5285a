"""Small IFC buildings written with ifcopenshell.api (a grid of rooms on each storey),
for tests, examples and benchmarks of the IFC importer (camplace.scene.importers.ifc).

Every solid is an axis-aligned box (an IfcExtrudedAreaSolid of a rectangle). Room
(i, j) of an ``nx`` x ``ny`` grid of ``room`` = (w, d) m rooms spans
[i w, (i+1) w] x [j d, (j+1) d] between wall centre lines; walls are ``wall`` m thick,
spaces are the rooms' clear insides, a door joins each pair of neighbouring rooms and a
window sits in the first room's outer wall (-y side).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from camplace.core.files import atomic_write_text

UNIT_PREFIX = {"mm": "MILLI", "m": None}


@dataclass(frozen=True)
class GridBuilding:
    """The layout of write_grid_building (metres)."""

    nx: int = 2
    ny: int = 1
    room: tuple[float, float] = (5.0, 4.0)
    wall: float = 0.2
    height: float = 3.0  # floor to the slab above
    slab: float = 0.2
    door: tuple[float, float] = (1.0, 2.1)  # width, height
    window: tuple[float, float, float] = (1.2, 1.2, 0.9)  # width, height, sill
    names: tuple[str, ...] = ()  # LongNames of the rooms, row by row (default 'Room i')

    def name(self, k: int) -> str:
        return self.names[k] if k < len(self.names) else f"Room {k + 1}"

    def space_boxes(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(min (3,), max (3,)) of each room's clear inside, row by row."""
        w, d, t = *self.room, self.wall
        return [(np.array([i * w + t / 2, j * d + t / 2, 0.0]), np.array([(i + 1) * w - t / 2, (j + 1) * d - t / 2,
                                                                          self.height]))
                for j in range(self.ny) for i in range(self.nx)]

    def outline_area(self) -> float:
        """The area (m²) of the building's outline, the outer faces of its outer walls (the footprint)."""
        return (self.nx * self.room[0] + self.wall) * (self.ny * self.room[1] + self.wall)


class _Writer:
    """An ifcopenshell model with project, site, building and the Body context."""

    def __init__(self, unit: str):
        import ifcopenshell.api.aggregate  # noqa: F401  (the api modules load on import)
        import ifcopenshell.api.context  # noqa: F401
        import ifcopenshell.api.feature  # noqa: F401
        import ifcopenshell.api.geometry  # noqa: F401
        import ifcopenshell.api.project  # noqa: F401
        import ifcopenshell.api.root  # noqa: F401
        import ifcopenshell.api.spatial  # noqa: F401
        import ifcopenshell.api.unit  # noqa: F401
        from ifcopenshell import api

        self.api = api
        self.scale = 0.001 if unit == "mm" else 1.0  # metres per file unit
        self.m = api.project.create_file(version="IFC4")
        proj = self.entity("IfcProject", "camplace grid building")
        api.unit.assign_unit(self.m, units=[api.unit.add_si_unit(self.m, unit_type="LENGTHUNIT",
                                                                 prefix=UNIT_PREFIX[unit])])
        ctx = api.context.add_context(self.m, context_type="Model")
        self.body = api.context.add_context(self.m, context_type="Model", context_identifier="Body",
                                            target_view="MODEL_VIEW", parent=ctx)
        site = self.entity("IfcSite", "Site")
        self.building = self.entity("IfcBuilding", "Building")
        api.aggregate.assign_object(self.m, products=[site], relating_object=proj)
        api.aggregate.assign_object(self.m, products=[self.building], relating_object=site)

    def entity(self, cls: str, name: str, **attrs):
        e = self.api.root.create_entity(self.m, ifc_class=cls, name=name)
        for k, v in attrs.items():
            setattr(e, k, v)
        return e

    def storey(self, name: str, elevation: float, scale: float, level: bool = True):
        """A storey of the building; ``level=False``: without Elevation and placement."""
        st = self.entity("IfcBuildingStorey", name, Elevation=elevation / scale if level else None)
        if level:
            self.place(st, np.array([0.0, 0.0, elevation]))
        self.api.aggregate.assign_object(self.m, products=[st], relating_object=self.building)
        return st

    def place(self, product, at: np.ndarray) -> None:
        mat = np.eye(4)
        mat[:3, 3] = at
        self.api.geometry.edit_object_placement(self.m, product=product, matrix=mat)

    def box(self, cls: str, name: str, lo: np.ndarray, hi: np.ndarray, storey=None, **attrs):
        """An element whose body is the box [lo, hi] (m, world); contained in ``storey``."""
        e = self.entity(cls, name, **attrs)
        size = np.asarray(hi, float) - np.asarray(lo, float)
        rep = self.api.geometry.add_wall_representation(self.m, context=self.body, length=float(size[0]),
                                                        height=float(size[2]), thickness=float(size[1]))
        self.api.geometry.assign_representation(self.m, product=e, representation=rep)
        self.place(e, np.asarray(lo, float))
        if storey is not None:
            self.api.spatial.assign_container(self.m, products=[e], relating_structure=storey)
        return e

    def footprint_space(self, name: str, lo: np.ndarray, hi: np.ndarray, **attrs):
        """An IfcSpace with no body, only a FootPrint curve: the rectangle lo..hi (m, world) at lo's z."""
        e = self.entity("IfcSpace", name, **attrs)
        ctx = next((c for c in self.m.by_type("IfcGeometricRepresentationSubContext")
                    if c.ContextIdentifier == "FootPrint"), None) or self.api.context.add_context(
            self.m, context_type="Model", context_identifier="FootPrint", target_view="SKETCH_VIEW",
            parent=self.body.ParentContext)
        w, d = (np.asarray(hi, float) - np.asarray(lo, float))[:2] / self.scale
        ring = [(0.0, 0.0), (w, 0.0), (w, d), (0.0, d), (0.0, 0.0)]
        curve = self.m.createIfcPolyline([self.m.createIfcCartesianPoint(p) for p in ring])
        curves = self.m.createIfcGeometricCurveSet([curve])
        rep = self.m.createIfcShapeRepresentation(ctx, "FootPrint", "Curve2D", [curves])
        self.api.geometry.assign_representation(self.m, product=e, representation=rep)
        self.place(e, np.asarray(lo, float))
        return e

    def hole(self, wall, cls: str, name: str, lo: np.ndarray, hi: np.ndarray, storey) -> None:
        """An opening [lo, hi] in ``wall`` filled by a ``cls`` (IfcDoor / IfcWindow) of the same box."""
        opening = self.box("IfcOpeningElement", f"{name} opening", lo, hi)
        self.api.feature.add_feature(self.m, feature=opening, element=wall)
        filling = self.box(cls, name, lo, hi, storey)
        self.api.feature.add_filling(self.m, opening=opening, element=filling)


def _walls(b: GridBuilding) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(axis 'x'/'y', lo, hi) of every wall segment: one per room side, corners overlapping."""
    w, d, t, h = *b.room, b.wall, b.height
    out = []
    for j in range(b.ny + 1):
        for i in range(b.nx):
            out.append(("x", np.array([i * w - t / 2, j * d - t / 2, 0.0]), np.array([(i + 1) * w + t / 2,
                                                                                      j * d + t / 2, h])))
    for i in range(b.nx + 1):
        for j in range(b.ny):
            out.append(("y", np.array([i * w - t / 2, j * d - t / 2, 0.0]), np.array([i * w + t / 2,
                                                                                      (j + 1) * d + t / 2, h])))
    return out


def _door_box(axis: str, lo: np.ndarray, hi: np.ndarray, b: GridBuilding) -> tuple[np.ndarray, np.ndarray]:
    """The door opening in the middle of an inner wall segment (a little deeper than the wall)."""
    a = 0 if axis == "x" else 1
    mid = 0.5 * (lo[a] + hi[a])
    olo, ohi = lo.copy(), hi.copy()
    olo[a], ohi[a] = mid - b.door[0] / 2, mid + b.door[0] / 2
    olo[1 - a] -= 0.05
    ohi[1 - a] += 0.05
    olo[2], ohi[2] = 0.0, b.door[1]
    return olo, ohi


def write_grid_building(path: str | Path, b: GridBuilding = GridBuilding(), unit: str = "m",
                        roof_storey: bool = True, floors: tuple[str, ...] = ("Ground Floor",), *,
                        spaces_in: str = "storey", space_body: str = "body", storey_levels: bool = True) -> Path:
    """Write the grid building as IFC4 (lengths in ``unit``: 'mm' or 'm'): one storey per
    name in ``floors`` (the first at z = 0, each b.height + b.slab above the last), each
    with the rooms (IfcSpace, LongName), walls, doors and the window on a floor slab;
    with ``roof_storey`` a storey 'Roof' at the slab above the top floor. The ways real
    files differ: ``spaces_in='building'`` aggregates the spaces to the building, not their
    storey; ``space_body='footprint'`` gives them only a FootPrint curve, no body;
    ``storey_levels=False`` writes the storeys without Elevation and placement."""
    wr = _Writer(unit)
    scale = 0.001 if unit == "mm" else 1.0
    W, D = b.nx * b.room[0], b.ny * b.room[1]
    t = b.wall
    for n, floor in enumerate(floors):
        st = wr.storey(floor, n * (b.height + b.slab), scale, storey_levels)
        _floor(wr, b, st, n * (b.height + b.slab), n, wr.building if spaces_in == "building" else st, space_body)
    if roof_storey:
        top = (len(floors) - 1) * (b.height + b.slab) + b.height
        roof = wr.storey("Roof", top, scale)
        wr.box("IfcSlab", "Roof slab", np.array([-t / 2, -t / 2, top]), np.array([W + t / 2, D + t / 2, top + b.slab]),
               roof)
    return atomic_write_text(Path(path), wr.m.to_string())


def write_ring_room(path: str | Path, size: tuple[float, float] = (4.0, 3.0), wall: float = 0.2,
                    height: float = 3.0, roof_level: str | None = None) -> Path:
    """Write a room whose four walls are one IfcWall, its profile the ``size`` (m) rectangle
    with a hole ``wall`` m in from it (an IfcArbitraryProfileDefWithVoids extruded
    ``height`` m), as SketchUp, Blender and FreeCAD exports model a room's walls; one
    storey, no IfcSpace, no slab. ``roof_level``: a second storey of that name on the walls
    holding only an IfcRoof over the room (as Revit's 'Level 1' holding the roof)."""
    wr = _Writer("m")
    m = wr.m
    st = wr.storey("Ground Floor", 0.0, 1.0)
    (w, d), t = size, wall

    def ring(x0, y0, x1, y1):
        pts = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]
        return m.createIfcPolyline([m.createIfcCartesianPoint((float(x), float(y))) for x, y in pts])

    profile = m.createIfcArbitraryProfileDefWithVoids("AREA", None, ring(0, 0, w, d), [ring(t, t, w - t, d - t)])
    origin = m.createIfcAxis2Placement3D(m.createIfcCartesianPoint((0.0, 0.0, 0.0)), None, None)
    solid = m.createIfcExtrudedAreaSolid(profile, origin, m.createIfcDirection((0.0, 0.0, 1.0)), float(height))
    walls = wr.entity("IfcWall", "Walls")
    wr.api.geometry.assign_representation(m, product=walls, representation=m.createIfcShapeRepresentation(
        wr.body, "Body", "SweptSolid", [solid]))
    wr.place(walls, np.zeros(3))
    wr.api.spatial.assign_container(m, products=[walls], relating_structure=st)
    if roof_level:
        wr.box("IfcRoof", "Roof", np.array([0.0, 0.0, height]), np.array([w, d, height + t]),
               wr.storey(roof_level, height, 1.0))
    return atomic_write_text(Path(path), m.to_string())


def _floor(wr: _Writer, b: GridBuilding, storey, z0: float, n: int, space_parent, space_body: str) -> None:
    """One storey's floor slab, spaces (aggregated to ``space_parent``; with a body, or only a
    'footprint'), walls, doors and window, lifted by z0 m."""
    up = np.array([0.0, 0.0, z0])
    W, D = b.nx * b.room[0], b.ny * b.room[1]
    t = b.wall
    tag = "" if n == 0 else f"{n}."
    wr.box("IfcSlab", f"{tag}Floor slab", np.array([-t / 2, -t / 2, z0 - b.slab]),
           np.array([W + t / 2, D + t / 2, z0]), storey)
    for k, (lo, hi) in enumerate(b.space_boxes()):
        name = f"{tag}R{k + 1:02d}"
        sp = (wr.box("IfcSpace", name, lo + up, hi + up, LongName=b.name(k)) if space_body == "body"
              else wr.footprint_space(name, lo + up, hi + up, LongName=b.name(k)))
        wr.api.aggregate.assign_object(wr.m, products=[sp], relating_object=space_parent)
    for k, (axis, lo, hi) in enumerate(_walls(b)):
        wall = wr.box("IfcWall", f"{tag}Wall {k + 1}", lo + up, hi + up, storey)
        a = 1 if axis == "x" else 0  # the coordinate across the wall
        c = 0.5 * (lo[a] + hi[a])
        inner = 1e-6 < c < (D if axis == "x" else W) - 1e-6
        if inner:
            dlo, dhi = _door_box(axis, lo, hi, b)
            wr.hole(wall, "IfcDoor", f"{tag}Door {k + 1}", dlo + up, dhi + up, storey)
        elif k == 0:  # the first room's -y wall
            wlo, whi = _door_box(axis, lo, hi, b)
            wlo[2], whi[2] = b.window[2], b.window[2] + b.window[1]
            wlo[0], whi[0] = 0.5 * (lo[0] + hi[0]) - b.window[0] / 2, 0.5 * (lo[0] + hi[0]) + b.window[0] / 2
            wr.hole(wall, "IfcWindow", f"{tag}Window 1", wlo + up, whi + up, storey)
