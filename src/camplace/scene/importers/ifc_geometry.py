"""Element geometry of an IFC model (ifcopenshell.geom, world coordinates, metres) and the
plan shapes derived from it: xy footprints (shapely), cross-sections at a height and the
extruded z bands (prisms) of piecewise-prismatic elements such as walls with openings,
cut to a storey's z range. Pure numpy + shapely past the tessellation (no mesh library).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon

from camplace.scene.importers import polygons_of

MIN_EXTENT_M = 0.01  # an element cut to less than this (z) lies outside the storey
MAX_BANDS = 12  # more distinct z levels than this: not a prism stack (one conservative prism instead)
# ifcopenshell's CGAL kernel with OpenCASCADE for what it cannot do: 3-6x faster than the default on
# Revit models (mapped furniture, walls with openings), the same plans (docs/plans.md, measured time)
KERNEL = "hybrid-cgal-simple-opencascade"


@dataclass(frozen=True)
class Element:
    """One IFC element's body. vertices: (V, 3) float64 m (world); faces: (F, 3) int64;
    ``eid``: the entity's id in the file (0 when unknown)."""

    guid: str
    ifc_class: str
    name: str
    vertices: np.ndarray
    faces: np.ndarray
    eid: int = 0
    holes: tuple = ()  # the Elements of its openings (IfcOpeningElement), cut in plan by z_bands

    @property
    def z_range(self) -> tuple[float, float]:
        return float(self.vertices[:, 2].min()), float(self.vertices[:, 2].max())

    def moved(self, dz: float = 0.0, factor: float = 1.0) -> "Element":
        """The element scaled by ``factor`` about the origin, then moved down by ``dz`` m."""
        return Element(self.guid, self.ifc_class, self.name, self.vertices * factor - np.array([0.0, 0.0, dz]),
                       self.faces, self.eid, tuple(h.moved(dz, factor) for h in self.holes))

    def with_holes(self, holes: list) -> "Element":
        """The element with these openings (Elements) to cut."""
        return Element(self.guid, self.ifc_class, self.name, self.vertices, self.faces, self.eid, tuple(holes))


def _iterator(settings, model, elements: list):
    """ifcopenshell's geometry iterator over ``elements`` with KERNEL (the default kernel
    where this ifcopenshell has no such choice)."""
    import ifcopenshell.geom

    try:
        return ifcopenshell.geom.iterator(settings, model, 1, include=elements, geometry_library=KERNEL)
    except (TypeError, ValueError, RuntimeError):
        return ifcopenshell.geom.iterator(settings, model, 1, include=elements)


def _shapes(model, elements: list, curves: bool = False, whole: bool = False):
    """(iterator shape, (V, 3) world vertices in m) of each of ``elements`` that has a body
    (``curves``: a plan curve instead, such as a space's FootPrint; ``whole``: openings
    not cut out)."""
    import ifcopenshell.geom

    if not elements:
        return
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    if whole:
        settings.set("disable-opening-subtractions", True)
    if curves:
        settings.set("dimensionality", 2)  # curves only
    it = _iterator(settings, model, elements)
    if not it.initialize():
        return
    while True:
        sh = it.get()
        yield sh, np.asarray(sh.geometry.verts, float).reshape(-1, 3)
        if not it.next():
            break


def element_shapes(model, elements: list) -> list[Element]:
    """The triangulated bodies of ``elements`` (entity instances of ``model``) in world
    coordinates (metres, whatever the file's units), in file order; elements without a
    body are left out. Openings are not cut from their hosts in 3D (the kernel's booleans
    were 90 % of the tessellation time: a 96-room storey's 212 walls 2.2 s, 0.2 s without):
    each host carries its openings' bodies (``holes``), which z_bands cuts from its plan
    sections. One thread: the iterator's threads made it slower on 2 cores (docs/plans.md)."""
    out = _bodies(model, elements, whole=True)
    voids = {e.id(): [r.RelatedOpeningElement for r in getattr(e, "HasOpenings", None) or ()] for e in elements}
    cut = _bodies(model, list({o.id(): o for os_ in voids.values() for o in os_}.values()))
    by_id = {o.eid: o for o in cut}
    return [e.with_holes([by_id[o.id()] for o in voids.get(e.eid, ()) if o.id() in by_id]) if voids.get(e.eid)
            else e for e in out]


def _bodies(model, elements: list, whole: bool = False) -> list[Element]:
    """The triangulated bodies of ``elements`` (see element_shapes), in file order."""
    out = []
    for sh, v in _shapes(model, elements, whole=whole):
        f = np.asarray(sh.geometry.faces, np.int64).reshape(-1, 3)
        if len(f):
            out.append(Element(sh.guid, sh.type, sh.name or "", v, f, int(sh.id)))
    return sorted(out, key=lambda e: e.eid)


def footprint_shapes(model, elements: list) -> list[Element]:
    """Flat stand-ins (m, world) for elements without a body, such as an IfcSpace with only a
    FootPrint: their plan curves polygonised (even-odd) and triangulated at their height."""
    out = []
    for sh, v in _shapes(model, elements, curves=True):
        edges = np.asarray(sh.geometry.edges, np.int64).reshape(-1, 2)
        shape = _even_odd(v[edges][:, :, :2]) if len(edges) else Polygon()
        if shape.is_empty:
            continue
        tri = np.array([np.asarray(t.exterior.coords)[:3] for t in shapely.get_parts(
            shapely.constrained_delaunay_triangles(shape)) if t.within(shape.buffer(1e-6))])
        if len(tri):
            verts = np.concatenate([tri.reshape(-1, 2), np.full((tri.size // 2, 1), v[:, 2].min())], axis=1)
            out.append(Element(sh.guid, sh.type, sh.name or "", verts, np.arange(len(verts)).reshape(-1, 3),
                               int(sh.id)))
    return sorted(out, key=lambda e: e.eid)


def _even_odd(segments: np.ndarray):
    """The region (shapely) that closed outlines of (S, 2, 2) xy segments enclose, even-odd
    filled: a face of the noded outlines is inside when a ray from it crosses them an odd
    number of times (a ring wall's hole, a hollow column's core stay empty)."""
    seg = np.round(segments, 6)
    faces = np.asarray(polygons_of(shapely.polygonize(list(shapely.get_parts(
        shapely.union_all(shapely.linestrings(seg)))))), dtype=object)
    if not len(faces):
        return Polygon()
    pts = shapely.get_coordinates(shapely.point_on_surface(faces))  # (F, 2)
    (x0, y0), (x1, y1) = seg[:, 0].T, seg[:, 1].T  # (S,) each
    py = pts[:, 1:2]
    spans = (y0 > py) != (y1 > py)  # (F, S): the segment straddles the ray's height
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = x0 + (py - y0) * (x1 - x0) / (y1 - y0)
    inside = (spans & (xc > pts[:, 0:1])).sum(axis=1) % 2 == 1
    return shapely.union_all(faces[inside]) if inside.any() else Polygon()


def plan_shape(el: Element, zmin: float = -np.inf, zmax: float = np.inf, min_nz: float = 0.1):
    """The element projected to xy (shapely, m²): the union of its non-vertical triangles
    that reach into zmin <= z <= zmax (whole triangles: conservative at the cuts)."""
    tri = el.vertices[el.faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(n, axis=1)
    keep = (area2 > 1e-12) & (np.abs(n[:, 2]) > min_nz * np.maximum(area2, 1e-300))
    if np.isfinite(zmin) or np.isfinite(zmax):
        keep &= (tri[:, :, 2].max(1) >= zmin - 1e-6) & (tri[:, :, 2].min(1) <= zmax + 1e-6)
    if not keep.any():
        return Polygon()
    polys = shapely.polygons(tri[keep][:, :, :2])
    return shapely.union_all(shapely.make_valid(polys))


def plan_hull(el: Element, zmin: float = -np.inf, zmax: float = np.inf):
    """The convex hull (shapely, xy m) of the element's triangles that reach into zmin..zmax
    (a cheap, conservative stand-in for plan_shape)."""
    tri = el.vertices[el.faces]
    keep = (tri[:, :, 2].max(1) >= zmin - 1e-6) & (tri[:, :, 2].min(1) <= zmax + 1e-6)
    return shapely.multipoints(tri[keep].reshape(-1, 3)[:, :2]).convex_hull if keep.any() else Polygon()


def plane_segments(el: Element, z: float) -> np.ndarray:
    """(S, 2, 2) xy segments (m) where the plane at height z cuts the element's triangles
    (z should not be one of its vertex heights)."""
    tri = el.vertices[el.faces]
    d = tri[:, :, 2] - z
    up = d > 0
    cut = up.any(1) & ~up.all(1)
    tri, d, up = tri[cut], d[cut], up[cut]
    if not len(tri):
        return np.zeros((0, 2, 2))
    changes, points = [], []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        changes.append(up[:, a] != up[:, b])
        t = d[:, a] / np.where(changes[-1], d[:, a] - d[:, b], 1.0)
        points.append(tri[:, a, :2] + t[:, None] * (tri[:, b, :2] - tri[:, a, :2]))
    ch, pts = np.stack(changes, 1), np.stack(points, 1)  # (S, 3), (S, 3, 2)
    first_two = np.argsort(~ch, axis=1, kind="stable")[:, :2]  # the two edges that cross
    return np.take_along_axis(pts, first_two[:, :, None], axis=1)


def section(el: Element, z: float):
    """The element's cross-section at height z (shapely): the closed outlines cut by the
    plane z, even-odd filled (holes stay holes), less its openings' sections (``holes``);
    empty for an open surface."""
    seg = plane_segments(el, z)
    cut = _even_odd(seg) if len(seg) else Polygon()
    holes = [h for h in el.holes if h.z_range[0] < z < h.z_range[1]]
    if holes and not cut.is_empty:
        cut = shapely.make_valid(cut.difference(shapely.union_all([section(h, z) for h in holes])))
        cut = shapely.union_all(polygons_of(cut)) if not cut.is_empty else cut
    return cut


def z_bands(el: Element, zmin: float = -np.inf, zmax: float = np.inf, tol: float = 1e-3
            ) -> list[tuple[float, float, object]] | None:
    """The element cut to zmin..zmax as a stack of prisms: (z0, z1, xy section) per band
    between its distinct vertex heights, equal neighbours merged. More than MAX_BANDS
    levels, or no closed section (an open surface model): one band of its plan outline
    over its height (conservative). None when less than MIN_EXTENT_M of it lies in range."""
    lo, hi = el.z_range
    lo, hi = max(lo, zmin), min(hi, zmax)
    if hi - lo < MIN_EXTENT_M:
        return None
    heights = np.concatenate([el.vertices[:, 2]] + [h.vertices[:, 2] for h in el.holes])
    levels = np.unique(np.round(heights / tol) * tol)
    levels = np.concatenate([[lo], levels[(levels > lo + tol) & (levels < hi - tol)], [hi]])
    bands: list[tuple[float, float, object]] = []
    if len(levels) <= MAX_BANDS + 1:
        for z0, z1 in zip(levels[:-1], levels[1:]):
            s = section(el, 0.5 * (z0 + z1))
            if s.is_empty:
                continue
            if bands and abs(bands[-1][1] - z0) < tol and bands[-1][2].symmetric_difference(s).area < 1e-6:
                bands[-1] = (bands[-1][0], float(z1), bands[-1][2])
            else:
                bands.append((float(z0), float(z1), s))
    if not bands:
        shape = plan_shape(el, lo, hi)
        return [(float(lo), float(hi), shape)] if not shape.is_empty else None
    return bands

