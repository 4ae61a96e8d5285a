"""A DXF file's modelspace as plan shapes and labels in metres (ezdxf): block references
exploded (nested, MINSERT arrays too; an entity on layer 0 inside a block takes the
reference's layer, as CAD programs draw it), curves flattened, hatches as filled areas,
texts and block attributes as labels. Entities on layers turned off or frozen are left
out and counted; so are entities ezdxf cannot take apart.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from shapely.geometry import LineString, Point, Polygon

from camplace.core.errors import InputError
from camplace.scene.importers import polygons_of

FLATTEN_M = 0.01  # chord error of flattened arcs, bulges and splines (m)
MAX_DEPTH = 8  # nesting depth of block references followed
MAX_COORD_M = 1e7  # a coordinate farther out than this (10,000 km), or not a finite number, is damage: left out
MAX_ENTITIES = 2_000_000  # exploded entities read at most (a guard against runaway arrays)
LINEWORK = {"LINE", "LWPOLYLINE", "POLYLINE", "ARC", "CIRCLE", "ELLIPSE", "SPLINE"}
FILLED = {"HATCH", "MPOLYGON", "SOLID", "TRACE", "3DFACE"}
TEXTS = {"TEXT", "MTEXT", "ATTRIB"}
ANNOTATION = {"DIMENSION", "ARC_DIMENSION", "LARGE_RADIAL_DIMENSION", "LEADER", "MLEADER", "MULTILEADER",
              "ACAD_TABLE", "TOLERANCE", "VIEWPORT"}  # never taken apart into linework


@dataclass
class Shape:
    """One piece of plan geometry (m). ``geom``: a LineString (linework) or a Polygon
    (a filled HATCH / SOLID, a polyline drawn with a width); ``closed``: an outline that
    closes on itself (a closed polyline, circle); ``group``: index of the modelspace
    entity it came from (one block reference = one group), ``handle`` that entity's
    handle; ``part``: the innermost block reference it was drawn in (an index into
    Drawing.parts; -1 for an entity drawn in the modelspace itself)."""

    layer: str
    kind: str
    geom: Any
    closed: bool
    group: int
    part: int
    handle: str


@dataclass
class Label:
    """A text in the plan: TEXT / MTEXT line or block attribute (``tag`` set) at
    ``point`` (m), ``height`` m, in modelspace entity ``group``."""

    point: Point
    text: str
    height: float
    layer: str
    tag: str
    group: int


@dataclass
class Drawing:
    """The plan content of a DXF file in metres: ``shapes``, ``labels``, entity counts
    per (layer, type) after exploding blocks (``inventory``), every block reference at any
    depth (``parts``: (layer, block name, handle of its modelspace entity, the part it
    lies in or -1)), ``scale`` m per drawing unit,
    ``units`` (how the unit was found), ``skipped`` counts, ``notes``."""

    shapes: list[Shape]
    labels: list[Label]
    inventory: Counter
    parts: list[tuple[str, str, str, int]]
    scale: float
    units: str
    skipped: Counter = field(default_factory=Counter)
    notes: list[str] = field(default_factory=list)


def read_dxf(path: Path):
    """(ezdxf document of ``path``, a note or None): a file with structure errors is read
    again by ezdxf's recover mode (what it could rebuild, said in the note); InputError
    naming the file when it is no DXF or nothing of its modelspace survives."""
    import ezdxf
    from ezdxf import recover

    try:
        return ezdxf.readfile(str(path)), None
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"{path}: cannot read the file ({err})") from None
    except Exception as err:  # noqa: BLE001 - ezdxf.DXFError, or a ValueError on a broken handle, ...
        first = str(err).splitlines()[0] if str(err) else type(err).__name__
    try:
        doc, auditor = recover.readfile(str(path))
    except Exception:  # noqa: BLE001 - recover gives up on anything: the file is no DXF
        doc = None
    if doc is None or not len(doc.modelspace()):
        raise InputError(f"{path}: not a DXF file ({first})")
    return doc, (f"the file has structure errors ({first}); read what ezdxf's recover mode rebuilt "
                 f"({len(auditor.fixes)} fixes, {len(auditor.errors)} errors left)")


def read_drawing(doc, scale: float, units: str) -> Drawing:
    """The modelspace of ``doc`` as shapes and labels in metres (``scale`` m per unit)."""
    hidden = {la.dxf.name for la in doc.layers if la.is_off() or la.is_frozen()}
    out = Drawing([], [], Counter(), [], scale, units)
    reader = _Reader(out, scale, hidden)
    for group, e in enumerate(doc.modelspace()):
        reader.entity(e, e.dxf.get("layer", "0"), group, -1, e.dxf.get("handle", ""), 0)
    if hidden and out.skipped["entities on layers turned off or frozen"]:
        out.notes.append(f"left out the layers turned off or frozen: {', '.join(sorted(hidden))}")
    return out


class _Reader:
    """Walks entities into a Drawing (block references followed MAX_DEPTH deep)."""

    def __init__(self, out: Drawing, scale: float, hidden: set[str]) -> None:
        self.out, self.s, self.hidden, self.count = out, scale, hidden, 0
        self.tol = FLATTEN_M / scale

    def entity(self, e, layer: str, group: int, part: int, handle: str, depth: int) -> None:
        kind = e.dxftype()
        if layer in self.hidden:
            self.out.skipped["entities on layers turned off or frozen"] += 1
            return
        self.count += 1
        if self.count > MAX_ENTITIES:
            self.out.skipped["entities past the reading limit"] += 1
            return
        self.out.inventory[(layer, kind)] += 1
        try:
            if kind == "INSERT":
                self._insert(e, layer, group, part, handle, depth)
            elif kind in TEXTS:
                self._text(e, layer, group, "")
            elif kind in LINEWORK or kind in FILLED:
                self._shape(e, kind, layer, group, part, handle)
            elif kind not in ANNOTATION and hasattr(e, "virtual_entities") and depth < MAX_DEPTH:
                # MLINE, and custom objects with proxy graphics (AutoCAD Architecture walls, ...)
                for ve in e.virtual_entities():
                    self.entity(ve, _layer_of(ve, layer), group, part, handle, depth + 1)
        except Exception:  # noqa: BLE001 - one entity ezdxf cannot take apart never fails the import
            self.out.skipped[f"{kind} entities that could not be read"] += 1

    def _insert(self, e, layer: str, group: int, parent: int, handle: str, depth: int) -> None:
        name = e.dxf.name
        for a in e.attribs:
            self._text(a, _layer_of(a, layer), group, str(a.dxf.tag))
        if depth >= MAX_DEPTH:
            self.out.skipped["block references nested too deep"] += 1
            return
        doc = e.doc
        blk = doc.blocks.get(name) if doc is not None else None
        if blk is not None and (blk.block.is_xref or blk.block.is_xref_overlay):
            self.out.skipped[f"external references not loaded ({name})"] += 1
            return
        refs = e.multi_insert() if e.mcount > 1 else [e]
        for ref in refs:
            self.out.parts.append((layer, name, handle, parent))
            part = len(self.out.parts) - 1
            for ve in ref.virtual_entities():
                self.entity(ve, _layer_of(ve, layer), group, part, handle, depth + 1)

    def _text(self, e, layer: str, group: int, tag: str) -> None:
        kind = e.dxftype()
        if kind == "MTEXT":
            text, height, p = e.plain_text(), e.dxf.get("char_height", 0.0), e.dxf.insert
        else:
            text, height = e.plain_text(), e.dxf.get("height", 0.0)
            aligned = e.dxf.get("halign", 0) or e.dxf.get("valign", 0)
            p = e.ocs().to_wcs(e.dxf.align_point if aligned and e.dxf.hasattr("align_point") else e.dxf.insert)
        if self._far([(p.x * self.s, p.y * self.s)]):
            return
        for line in str(text).splitlines():
            line = " ".join(line.split())
            if line:
                self.out.labels.append(Label(Point(p.x * self.s, p.y * self.s), line, float(height) * self.s, layer,
                                             tag, group))

    def _shape(self, e, kind: str, layer: str, group: int, part: int, handle: str) -> None:
        s = self.s
        if kind == "LINE":
            a, b = e.dxf.start, e.dxf.end
            ends = [(a.x * s, a.y * s), (b.x * s, b.y * s)]
            if not self._far(ends):
                self._add(layer, kind, LineString(ends), False, group, part, handle)
            return
        if kind in ("HATCH", "MPOLYGON"):
            from ezdxf import path as dxfpath

            rings = [_xy(p.flattening(self.tol), s) for p in dxfpath.from_hatch(e)]
            if self._far([v for r in rings for v in r]):
                return
            area = even_odd([Polygon(r) for r in rings if len(r) >= 3])
            if not area.is_empty:
                self._add(layer, kind, area, True, group, part, handle)
            return
        if kind == "POLYLINE" and (e.is_poly_face_mesh or e.is_polygon_mesh):
            self.out.skipped["polyline meshes"] += 1
            return
        from ezdxf import path as dxfpath

        p = dxfpath.make_path(e)
        pts = _xy(p.flattening(self.tol), s)
        if len(pts) < 2 or self._far(pts):
            return
        closed = bool(kind in ("CIRCLE", "SOLID", "TRACE", "3DFACE") or getattr(e, "closed", False)
                      or getattr(e, "is_closed", False) or (len(pts) > 3 and np.allclose(pts[0], pts[-1], atol=1e-3)))
        width = float(e.dxf.get("const_width", 0.0) or 0.0) * s if kind == "LWPOLYLINE" else 0.0
        if kind in ("SOLID", "TRACE", "3DFACE") and len(pts) >= 3:
            geom = shapely.make_valid(Polygon(pts))
        elif width >= 0.02:  # a polyline drawn with a width: a filled band
            geom = LineString(pts).buffer(width / 2, cap_style="flat", join_style="mitre")
        else:
            geom = LineString(pts if not closed or np.allclose(pts[0], pts[-1]) else [*pts, pts[0]])
        self._add(layer, kind, geom, closed, group, part, handle)

    def _far(self, pts: list) -> bool:
        """True (and counted) when a coordinate (m) is no finite number or lies beyond MAX_COORD_M."""
        a = np.asarray(pts, float)
        if not a.size or np.isfinite(a).all() and np.abs(a).max() <= MAX_COORD_M:
            return False
        self.out.skipped["entities with coordinates that are no numbers or over 10,000 km out"] += 1
        return True

    def _add(self, layer, kind, geom, closed, group, part, handle) -> None:
        if not geom.is_empty and (geom.length > 0 or geom.area > 0):
            self.out.shapes.append(Shape(layer, kind, geom, closed, group, part, handle))


def _layer_of(ve, parent: str) -> str:
    """The layer an entity inside a block is drawn on: its own, or its reference's when it is on layer 0."""
    layer = ve.dxf.get("layer", "0")
    return parent if layer == "0" else layer


def _xy(vertices, s: float) -> list[tuple[float, float]]:
    return [(v.x * s, v.y * s) for v in vertices]


def even_odd(polys: list[Polygon]):
    """The area of nested boundary rings filled even-odd, as a HATCH fills them (an
    island inside an outer ring is a hole; an island in that hole is filled again)."""
    polys = [q for q in (shapely.make_valid(p) for p in polys) if q.area > 0]
    if len(polys) <= 1:
        return polys[0] if polys else Polygon()
    geoms = np.array(polys, dtype=object)
    inside = shapely.STRtree(geoms).query(shapely.point_on_surface(geoms), predicate="within")
    depth = np.bincount(inside[0], minlength=len(polys)) - 1  # rings holding each ring, itself excluded
    out = Polygon()
    for d in range(int(depth.max()) + 1):
        layer = shapely.unary_union(geoms[depth == d])
        out = out.union(layer) if d % 2 == 0 else out.difference(layer)
    return shapely.make_valid(out)


def filled_polygons(shapes: list[Shape]) -> list[Polygon]:
    """The polygons (m) of filled shapes and closed outlines."""
    out = []
    for sh in shapes:
        if isinstance(sh.geom, LineString):
            if sh.closed and len(sh.geom.coords) >= 4:
                out += polygons_of(shapely.make_valid(Polygon(sh.geom.coords)))
        else:
            out += polygons_of(sh.geom)
    return out
