"""Element geometry of an IFC model (ifcopenshell.geom, world coordinates, metres) and the
plan shapes derived from it: triangles clipped to a z range, xy footprints (shapely) and
extruded z bands (prisms) of piecewise-prismatic elements such as walls with openings.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon

from camplace.scene.importers import polygons_of

MIN_EXTENT_M = 0.01  # an element clipped to less than this (z) lies outside the storey
MAX_BANDS = 12  # more distinct z levels than this: not a prism stack (a mesh instead)


@dataclass(frozen=True)
class Element:
    """One IFC element's body. vertices: (V, 3) float64 m (world); faces: (F, 3) int64."""

    guid: str
    ifc_class: str
    name: str
    vertices: np.ndarray
    faces: np.ndarray

    @property
    def z_range(self) -> tuple[float, float]:
        return float(self.vertices[:, 2].min()), float(self.vertices[:, 2].max())


def element_shapes(model, elements: list) -> list[Element]:
    """The triangulated bodies of ``elements`` (entity instances of ``model``) in world
    coordinates (metres, whatever the file's units); elements without a body are left out.
    Openings are cut from their hosts (walls get their door and window holes); in file order."""
    import ifcopenshell.geom

    if not elements:
        return []
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    it = ifcopenshell.geom.iterator(settings, model, min(os.cpu_count() or 1, 8), include=elements)
    out: list[tuple[int, Element]] = []
    if not it.initialize():
        return []
    while True:
        sh = it.get()
        v = np.asarray(sh.geometry.verts, float).reshape(-1, 3)
        f = np.asarray(sh.geometry.faces, np.int64).reshape(-1, 3)
        if len(f):
            out.append((sh.id, Element(sh.guid, sh.type, sh.name or "", v, f)))
        if not it.next():
            break
    return [e for _, e in sorted(out, key=lambda t: t[0])]  # file order, whatever the threads did


def clip_z(el: Element, zmin: float, zmax: float) -> Element | None:
    """The element cut to zmin <= z <= zmax (left open at the cuts: the grid's floor and
    ceiling close it); None when less than MIN_EXTENT_M of it is left."""
    lo, hi = el.z_range
    if min(hi, zmax) - max(lo, zmin) < MIN_EXTENT_M:
        return None
    if lo >= zmin and hi <= zmax:
        return el
    import trimesh

    m = trimesh.Trimesh(el.vertices, el.faces, process=False)
    for origin, normal in (((0, 0, zmin), (0, 0, 1)), ((0, 0, zmax), (0, 0, -1))):
        m = m.slice_plane(origin, normal, cap=False)  # capping needs extra libraries (and prints)
        if m is None or len(m.faces) == 0:
            return None
    return Element(el.guid, el.ifc_class, el.name, np.asarray(m.vertices, float), np.asarray(m.faces, np.int64))


def plan_shape(el: Element, min_nz: float = 0.1):
    """The element projected to xy (shapely, m²): the union of its non-vertical triangles."""
    tri = el.vertices[el.faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(n, axis=1)
    keep = (area2 > 1e-12) & (np.abs(n[:, 2]) > min_nz * np.maximum(area2, 1e-300))
    if not keep.any():
        return Polygon()
    polys = shapely.polygons(tri[keep][:, :, :2])
    return shapely.union_all(shapely.make_valid(polys))


def section(el: Element, z: float):
    """The element's cross-section at height z (shapely): the closed outlines cut by the
    plane z, even-odd filled (holes stay holes)."""
    import trimesh

    m = trimesh.Trimesh(el.vertices, el.faces, process=False)
    seg = trimesh.intersections.mesh_plane(m, (0, 0, 1), (0, 0, z))
    if len(seg) == 0:
        return Polygon()
    lines = shapely.linestrings(np.round(seg[:, :, :2], 6))
    faces = polygons_of(shapely.polygonize(list(shapely.get_parts(shapely.union_all(lines)))))
    out = Polygon()
    for f in faces:
        out = out.symmetric_difference(f)
    return out


def z_bands(el: Element, tol: float = 1e-3) -> list[tuple[float, float, object]] | None:
    """The element as a stack of prisms: (zmin, zmax, xy section) per band between its
    distinct vertex heights, equal neighbours merged; None when it has more than
    MAX_BANDS levels (not piecewise prismatic enough; keep it a mesh)."""
    levels = np.unique(np.round(el.vertices[:, 2] / tol) * tol)
    if len(levels) < 2 or len(levels) > MAX_BANDS + 1:
        return None
    bands: list[tuple[float, float, object]] = []
    for z0, z1 in zip(levels[:-1], levels[1:]):
        s = section(el, 0.5 * (z0 + z1))
        if s.is_empty:
            continue
        if bands and abs(bands[-1][1] - z0) < tol and bands[-1][2].symmetric_difference(s).area < 1e-6:
            bands[-1] = (bands[-1][0], float(z1), bands[-1][2])
        else:
            bands.append((float(z0), float(z1), s))
    return bands


def merged_mesh(elements: list[Element]) -> tuple[np.ndarray, np.ndarray]:
    """All elements as one triangle list: (V, 3) float64 vertices, (F, 3) int64 faces."""
    if not elements:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    offs = np.cumsum([0] + [len(e.vertices) for e in elements[:-1]])
    return (np.concatenate([e.vertices for e in elements]),
            np.concatenate([e.faces + o for e, o in zip(elements, offs)]).astype(np.int64))
