"""Imported walls and other prism obstacles (plans: DXF, plan images, IFC) in plan view.

Every picture of a plan (the report's coverage slices, plan.pdf / plan.svg, plan.dxf)
cuts the prisms at one height as an architect's plan does: what crosses the cut height
is drawn filled ("cut"), what lies wholly below it in outline, what lies above it
(lintels, beams) not at all. Prisms are grouped by their provenance label (the IFC
class, e.g. IfcWall, or the DXF layer; 'wall' for plan images), one legend entry and
colour per label.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon
from shapely.geometry.polygon import orient

WALL_COLOUR = "#4d4d4d"
LABEL_COLOURS = {"window": "#9ecae1", "door": "#d9b38c", "column": "#252525", "slab": "#bdbdbd",
                 "stair": "#8c6bb1", "furnish": "#a1887f", "furn": "#a1887f", "roof": "#bdbdbd"}
OTHER_COLOURS = ("#74a9cf", "#fdae6b", "#78c679", "#f768a1", "#66c2a5", "#e6ab02")  # none of LABEL_COLOURS


@dataclass(frozen=True)
class Wall:
    """One occluding prism obstacle: name, label (provenance: IFC class / DXF layer /
    'wall'), plan polygon with its holes (shapely, m) and z range (m)."""

    name: str
    label: str
    shape: Polygon
    zmin: float
    zmax: float


def obstacle_label(name: str, source: dict | None) -> str:
    """The legend label of an imported obstacle: its IFC class, else its (first) DXF
    layer, else 'wall' (plan images) or 'obstacle'."""
    src = source or {}
    if src.get("class"):
        return str(src["class"])
    if src.get("layer"):
        return str(src["layer"]).split(",")[0]
    return "wall" if name.startswith("wall") else "obstacle"


def scene_walls(scene) -> tuple[Wall, ...]:
    """The occluding prism obstacles of a camplace.scene.build.Scene (holes kept)."""
    out = []
    for ob in scene.spec.obstacles:
        if ob.prism is None or not ob.occludes:
            continue
        shape = shapely.make_valid(Polygon(ob.prism.polygon, ob.prism.holes or []))
        out.append(Wall(ob.name, obstacle_label(ob.name, ob.source), shape, float(ob.prism.z[0]),
                        float(ob.prism.z[1])))
    return tuple(out)


def plan_cut(walls, height: float) -> tuple[dict[str, object], dict[str, object]]:
    """({label: union of the walls crossing ``height`` m}, {label: union of those wholly
    below it}), labels in first-seen order (shapely geometries, m)."""
    cut: dict[str, list] = {}
    below: dict[str, list] = {}
    for w in walls:
        if w.zmin <= height <= w.zmax:
            cut.setdefault(w.label, []).append(w.shape)
        elif w.zmax < height:
            below.setdefault(w.label, []).append(w.shape)
    return ({k: shapely.union_all(v) for k, v in cut.items()}, {k: shapely.union_all(v) for k, v in below.items()})


def label_colours(labels) -> dict[str, str]:
    """label -> fill colour: walls dark grey, windows light blue, doors tan, columns
    black, furniture brown, ...; other labels the colours of OTHER_COLOURS in turn."""
    out: dict[str, str] = {}
    k = 0
    for lab in labels:
        if lab in out:
            continue
        low = lab.lower()
        known = WALL_COLOUR if ("wall" in low or "wand" in low) else next(
            (c for key, c in LABEL_COLOURS.items() if key in low), None)
        if known is None:
            known, k = OTHER_COLOURS[k % len(OTHER_COLOURS)], k + 1
        out[lab] = known
    return out


def rings(geom) -> list[tuple[np.ndarray, list[np.ndarray]]]:
    """(exterior (K, 2), [holes (K, 2)]) of each polygon of a shapely geometry (m)."""
    out = []
    for poly in getattr(geom, "geoms", [geom]):
        if poly.is_empty:
            continue
        if poly.geom_type != "Polygon":
            out += rings(poly) if hasattr(poly, "geoms") else []
            continue
        out.append((np.asarray(poly.exterior.coords, float)[:, :2],
                    [np.asarray(h.coords, float)[:, :2] for h in poly.interiors]))
    return out


def svg_path(geom, digits: int = 3) -> str:
    """An SVG path ('M x,y L ... Z' per ring) of a shapely geometry: fill it even-odd."""
    parts = []
    for ext, holes in rings(geom):
        for ring in [ext, *holes]:
            parts.append("M " + " L ".join(f"{x:.{digits}f},{y:.{digits}f}" for x, y in ring[:-1]) + " Z")
    return " ".join(parts)


def mpl_path(geom):
    """A matplotlib Path of a shapely (Multi)Polygon, holes kept (exteriors counter-clockwise)."""
    from matplotlib.path import Path as MPath

    paths = []
    for poly in getattr(geom, "geoms", [geom]):
        if poly.is_empty or poly.geom_type != "Polygon":
            continue
        poly = orient(poly, 1.0)
        for ring in [poly.exterior, *poly.interiors]:
            paths.append(MPath(np.asarray(ring.coords), closed=True))
    return MPath.make_compound_path(*paths) if paths else None


def prism_mesh(wall: Wall, height: float) -> tuple[np.ndarray, np.ndarray]:
    """A closed triangle mesh of one prism, z clipped to [0, height] m: vertices (V, 3),
    triangles (T, 3) int (caps by constrained Delaunay, sides two triangles per edge)."""
    z0, z1 = max(wall.zmin, 0.0), min(wall.zmax, height)
    verts, tris = [], []
    if z1 <= z0:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    for poly in getattr(wall.shape, "geoms", [wall.shape]):
        if poly.is_empty or poly.geom_type != "Polygon":
            continue
        poly = orient(poly, 1.0)  # exterior counter-clockwise: the sides face outwards
        for tri in shapely.constrained_delaunay_triangles(poly).geoms:
            xy = np.asarray(orient(tri, 1.0).exterior.coords, float)[:3, :2]
            for z, order in ((z0, [0, 2, 1]), (z1, [0, 1, 2])):  # bottom faces down, top up
                n = sum(len(v) for v in verts)
                verts.append(np.column_stack([xy, np.full(3, z)]))
                tris.append(np.array([order]) + n)
        for ring in [poly.exterior, *poly.interiors]:
            xy = np.asarray(ring.coords, float)[:, :2]
            n = sum(len(v) for v in verts)
            m = len(xy)
            verts.append(np.vstack([np.column_stack([xy, np.full(m, z0)]), np.column_stack([xy, np.full(m, z1)])]))
            k = np.arange(m - 1)
            tris.append(np.vstack([np.column_stack([n + k, n + k + 1, n + m + k + 1]),
                                   np.column_stack([n + k, n + m + k + 1, n + m + k])]))
    if not verts:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    return np.vstack(verts), np.vstack(tris).astype(np.int64)
