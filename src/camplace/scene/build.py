"""Stage 1 - the scene: room, obstacles and the occupancy grid used for occlusion.

World frame: metres, right-handed, z up. The occupancy grid is a dense boolean array
at ``occupancy_resolution``; walls (everything outside the footprint), the floor
(z < 0) and the ceiling (z > height) are occupied, so every ray stays in the room.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import shapely
from shapely.geometry import Polygon

from camplace.core.errors import InputError
from camplace.core.memory import check_memory, memory_limit_bytes
from camplace.spec.schema import SceneSpec

if TYPE_CHECKING:
    from camplace.scene.freespace import FreeSpace

MAX_GRID_BYTES = 4 * 1024**3  # refuse dense grids larger than this (bool = 1 byte/cell)


@dataclass(frozen=True)
class OccupancyGrid:
    """Dense occupancy. occupied: (nx, ny, nz) bool; cell (i,j,k) spans
    origin + [i, i+1) * resolution (metres) on each axis."""

    occupied: np.ndarray
    origin: np.ndarray  # (3,) float64, metres
    resolution: float  # metres

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(self.occupied.shape)  # type: ignore[return-value]

    def cell_of(self, points: np.ndarray) -> np.ndarray:
        """points: (N, 3) metres -> (N, 3) int64 cell indices (may be out of range)."""
        return np.floor((np.asarray(points, float) - self.origin) / self.resolution).astype(np.int64)

    def is_occupied(self, points: np.ndarray) -> np.ndarray:
        """points: (N, 3) metres -> (N,) bool; points outside the grid count as occupied."""
        c = self.cell_of(points)
        inside = np.all((c >= 0) & (c < np.array(self.shape)), axis=1)
        out = np.ones(len(c), dtype=bool)
        ci = c[inside]
        out[inside] = self.occupied[ci[:, 0], ci[:, 1], ci[:, 2]]
        return out

    def cell_centres(self, axis: int) -> np.ndarray:
        n = self.shape[axis]
        return self.origin[axis] + (np.arange(n) + 0.5) * self.resolution


@dataclass(frozen=True)
class Scene:
    """A room with obstacles. footprint: (K, 2) float64 polygon (m); height (m);
    boxes: obstacle name -> (min (3,), max (3,)) metres."""

    name: str
    spec: SceneSpec
    footprint: np.ndarray
    height: float
    boxes: dict[str, tuple[np.ndarray, np.ndarray]]
    occupancy: OccupancyGrid
    base_dir: Path | None = None
    info: dict = field(default_factory=dict)
    free_space: "FreeSpace | None" = None  # walkable free space from scans / OctoMaps (issue 5)
    points: np.ndarray | None = None  # (N, 3) cleaned scan points (scene frame), for surface targets
    viewpoints: np.ndarray | None = None  # (K, 3) scanner positions (scene frame)
    # (4, 4) p_input = T @ [p_scene, 1]: back to the input file's frame (camplace.scene.frames)
    input_from_scene: np.ndarray = field(default_factory=lambda: np.eye(4))
    # prism obstacles: name -> (polygon (K, 2) m, zmin, zmax) (walls imported from plans)
    prisms: dict[str, tuple[np.ndarray, float, float]] = field(default_factory=dict)
    # a building (issue 33): its storeys, lowest first; () for a single room
    storeys: tuple["Storey", ...] = ()

    @property
    def polygon(self) -> Polygon:
        return Polygon(self.footprint)

    @property
    def floor_area(self) -> float:
        return float(self.polygon.area)


@dataclass(frozen=True)
class Storey:
    """One storey of a building scene: ``scene`` is the storey on its own (floor at z = 0,
    plan in building x, y) whose occupancy is a view of the building's grid moved down by
    ``elevation`` (m), so its targets and mounts see what the building sees; ``top``: its
    ceiling in building z (m); ``openings``: where its floor opens to the storey below."""

    name: str
    elevation: float
    top: float
    scene: Scene
    openings: tuple[Polygon, ...] = ()
    budget: int | None = None


def storey_index(storeys: tuple[Storey, ...], z: np.ndarray) -> np.ndarray:
    """(N,) int64: the storey (index into ``storeys``, lowest first) whose floor is the
    highest at or below each building z (N,) m; 0 below the lowest floor."""
    floors = np.array([st.elevation for st in storeys], np.float64)
    k = np.searchsorted(floors, np.asarray(z, np.float64) + 1e-6, side="right") - 1
    return np.clip(k, 0, len(storeys) - 1).astype(np.int64)


def estimate_grid_bytes(spec: SceneSpec) -> int:
    """Cells (= bytes, bool) of the occupancy grid of ``spec``, border layers included."""
    fp = np.asarray(spec.room.footprint, float)
    ext = np.r_[fp.max(0) - fp.min(0), spec.room.height]
    n = np.ceil(ext / spec.occupancy_resolution) + 2
    return int(np.prod(n))


def _validate_footprint(spec: SceneSpec, source: str) -> Polygon:
    poly = Polygon(spec.room.footprint)
    if not poly.is_valid:
        reason = shapely.is_valid_reason(poly)
        raise InputError(f"{source}: room.footprint: not a simple polygon ({reason})")
    if poly.area <= 1e-9:
        raise InputError(f"{source}: room.footprint: polygon has zero area")
    return poly


def build_scene(spec: SceneSpec, base_dir: Path | None = None, source: str = "<scene>",
                progress=None) -> Scene:
    """Build the occupancy grid of a validated scene spec (file obstacles read through
    camplace.scene.loaders; free space derived when a scan or OctoMap is present)."""
    if spec.storeys:
        return build_building(spec, base_dir, source)
    poly = _validate_footprint(spec, source)
    need = estimate_grid_bytes(spec)
    # last guard for direct callers: the pipeline already checked every size against the
    # user's limit (camplace.spec.resources.check_resources) before this point
    check_memory(need, f"{source}: occupancy_resolution: {spec.occupancy_resolution} m", "use a coarser resolution",
                 items=f"{need:.3g} occupancy cells", limit=max(MAX_GRID_BYTES, memory_limit_bytes()))
    res = float(spec.occupancy_resolution)
    fp = np.asarray(spec.room.footprint, float)
    lo = np.r_[fp.min(0), 0.0] - res
    hi = np.r_[fp.max(0), spec.room.height] + res
    shape = tuple(int(v) for v in np.ceil((hi - lo) / res - 1e-9))
    grid = OccupancyGrid(np.zeros(shape, dtype=bool), lo, res)
    xs, ys, zs = (grid.cell_centres(a) for a in range(3))
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    inside = shapely.contains_xy(poly, gx, gy)
    occ = grid.occupied
    occ[~inside, :] = True  # walls: outside the footprint
    occ[:, :, (zs < 0) | (zs > spec.room.height)] = True  # floor and ceiling slabs

    boxes: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    prisms: dict[str, tuple[np.ndarray, float, float]] = {}
    loaded = []
    for i, ob in enumerate(spec.obstacles):
        if ob.prism is not None:
            prisms[ob.name] = (np.asarray(ob.prism.polygon, float), float(ob.prism.z[0]), float(ob.prism.z[1]))
            if ob.occludes:
                rasterize_prism(grid, Polygon(ob.prism.polygon, ob.prism.holes), *ob.prism.z)
            continue
        if ob.is_file:
            from camplace.scene.loaders.obstacles import add_obstacle

            loaded.append(add_obstacle(occ, grid.origin, res, ob, i, base_dir, source, progress))
            continue
        bmin, bmax = np.asarray(ob.box.min, float), np.asarray(ob.box.max, float)
        boxes[ob.name] = (bmin, bmax)
        if ob.occludes:
            rasterize_box(grid, bmin, bmax)
    info = {"grid_shape": shape, "grid_cells": int(np.prod(shape)), "occupied_cells": int(occ.sum()),
            "grid_bytes": int(np.prod(shape))}
    free_space = points = viewpoints = None
    if loaded:
        from camplace.scene.freespace import scene_free_space

        info["obstacle_files"] = {ob.name: lo.report for ob, lo in zip([o for o in spec.obstacles if o.is_file],
                                                                       loaded)}
        free_space, points, viewpoints = scene_free_space(grid, spec, loaded, progress)
        info["free_space"] = free_space.info if free_space is not None else None
    from camplace.scene.frames import input_from_scene

    return Scene(spec.name, spec, fp, float(spec.room.height), boxes, grid, base_dir, info,
                 free_space, points, viewpoints, input_from_scene(spec, info.get("obstacle_files")), prisms)


def rasterize_box(grid: OccupancyGrid, bmin: np.ndarray, bmax: np.ndarray) -> None:
    """Mark (in place) every cell whose centre lies inside [bmin, bmax] as occupied."""
    sl = []
    for a in range(3):
        c = grid.cell_centres(a)
        idx = np.nonzero((c >= bmin[a]) & (c <= bmax[a]))[0]
        if len(idx) == 0:
            return
        sl.append(slice(idx[0], idx[-1] + 1))
    grid.occupied[sl[0], sl[1], sl[2]] = True


def rasterize_prism(grid: OccupancyGrid, poly: Polygon, zmin: float, zmax: float) -> None:
    """Mark (in place) every cell whose centre lies inside ``poly`` (plan, m) or on its
    boundary, and in [zmin, zmax] (m), as occupied (like ``rasterize_box``: a centre on the
    seam of two prisms that share an edge, a mitred wall corner, is in both, not in
    neither); only the polygon's bounding box is tested."""
    x0, y0, x1, y1 = poly.bounds
    idx = []
    for a, (lo, hi) in enumerate(((x0, x1), (y0, y1), (zmin, zmax))):
        c = grid.cell_centres(a)
        k = np.nonzero((c >= lo) & (c <= hi))[0]
        if len(k) == 0:
            return
        idx.append(slice(k[0], k[-1] + 1))
    xs, ys = grid.cell_centres(0)[idx[0]], grid.cell_centres(1)[idx[1]]
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    inside = shapely.intersects_xy(poly, gx, gy)
    grid.occupied[idx[0], idx[1], idx[2]][inside] = True  # a view: slices only


def build_building(spec: SceneSpec, base_dir: Path | None = None, source: str = "<scene>") -> Scene:
    """Every storey of ``spec.storeys`` stacked at its elevation in one occupancy grid (building
    x, y, z in m): each storey's room is free between its floor and ceiling inside its
    footprint; everything else (outside walls, slabs between storeys, below the lowest floor,
    above the highest ceiling) is occupied, except where a storey's ``floor_openings`` open the
    slab to the storey below. Obstacles are raised to their storey. Each Storey's scene is that
    storey alone, with its occupancy a view of the building grid (no copy)."""
    res = float(spec.occupancy_resolution)
    names = spec.storey_names
    subs = [spec.storey_spec(n) for n in names]
    elev = [float(spec.storeys[n].elevation) for n in names]
    tops = [e + float(sub.room.height) for e, sub in zip(elev, subs)]
    polys = [_validate_footprint(sub, f"{source}: storeys.{n}") for n, sub in zip(names, subs)]
    xy0 = np.min([np.asarray(sub.room.footprint, float).min(0) for sub in subs], axis=0)
    xy1 = np.max([np.asarray(sub.room.footprint, float).max(0) for sub in subs], axis=0)
    lo, hi = np.r_[xy0, min(elev)] - res, np.r_[xy1, max(tops)] + res
    shape = tuple(int(v) for v in np.ceil((hi - lo) / res - 1e-9))
    need = int(np.prod(shape))
    check_memory(need, f"{source}: occupancy_resolution: {res} m", "use a coarser resolution",
                 items=f"{need:.3g} occupancy cells", limit=max(MAX_GRID_BYTES, memory_limit_bytes()))
    grid = OccupancyGrid(np.ones(shape, dtype=bool), lo, res)
    xs, ys, zs = (grid.cell_centres(a) for a in range(3))
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    occ = grid.occupied
    openings = [tuple(Polygon(o) for o in spec.storeys[n].floor_openings) for n in names]
    for k, (poly, e, top) in enumerate(zip(polys, elev, tops)):
        band = (zs >= e) & (zs <= top)
        occ[:, :, band] &= ~shapely.contains_xy(poly, gx, gy)[:, :, None]
        if k and openings[k]:  # the slab under this storey, open where its floor is
            slab = (zs > tops[k - 1]) & (zs < e)
            hole = shapely.contains_xy(shapely.union_all(openings[k]), gx, gy)
            occ[:, :, slab] &= ~hole[:, :, None]
    boxes: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    prisms: dict[str, tuple[np.ndarray, float, float]] = {}
    for n, sub, e, top in zip(names, subs, elev, tops):
        for ob in sub.obstacles:
            key = f"{n}/{ob.name}"
            if ob.prism is not None:
                z0, z1 = e + max(ob.prism.z[0], 0.0), e + min(ob.prism.z[1], top - e)
                prisms[key] = (np.asarray(ob.prism.polygon, float), z0, z1)
                if ob.occludes and z1 > z0:
                    rasterize_prism(grid, Polygon(ob.prism.polygon, ob.prism.holes), z0, z1)
            elif ob.box is not None:
                bmin = np.asarray(ob.box.min, float) + [0, 0, e]
                bmax = np.asarray(ob.box.max, float) + [0, 0, e]
                bmin[2], bmax[2] = max(bmin[2], e), min(bmax[2], top)
                boxes[key] = (bmin, bmax)
                if ob.occludes and bmax[2] > bmin[2]:
                    rasterize_box(grid, bmin, bmax)
            else:
                raise InputError(f"{source}: storeys.{n}.obstacles: '{ob.name}' is a file obstacle; a building "
                                 f"takes boxes and prisms (scans and meshes: one storey a scene)")
    storeys = []
    for k, (n, sub, e, top, poly) in enumerate(zip(names, subs, elev, tops, polys)):
        k0 = max(int(np.floor((e - lo[2]) / res)) - 1, 0)
        k1 = min(int(np.ceil((top - lo[2]) / res)) + 1, shape[2])
        view = OccupancyGrid(occ[:, :, k0:k1], np.r_[lo[:2], lo[2] + k0 * res - e], res)
        local_boxes = {ob.name: (np.asarray(ob.box.min, float), np.asarray(ob.box.max, float))
                       for ob in sub.obstacles if ob.box is not None}
        local_prisms = {ob.name: (np.asarray(ob.prism.polygon, float), float(ob.prism.z[0]), float(ob.prism.z[1]))
                        for ob in sub.obstacles if ob.prism is not None}
        local = Scene(sub.name, sub, np.asarray(sub.room.footprint, float), float(sub.room.height), local_boxes,
                      view, base_dir, {"storey": n, "elevation_m": e}, prisms=local_prisms)
        storeys.append(Storey(n, e, top, local, openings[k], spec.storeys[n].budget))
    outline = shapely.union_all(polys)
    hull = outline if isinstance(outline, Polygon) and not outline.interiors else outline.convex_hull
    fp = np.asarray(hull.exterior.coords[:-1], float)
    info = {"grid_shape": shape, "grid_cells": need, "occupied_cells": int(occ.sum()), "grid_bytes": need,
            "storeys": [{"name": n, "elevation_m": e, "top_m": t} for n, e, t in zip(names, elev, tops)]}
    return Scene(spec.name, spec, fp, float(max(tops)), boxes, grid, base_dir, info, prisms=prisms,
                 storeys=tuple(storeys))
