"""Free space and walkable area from a scan (or an OctoMap).

- ``detect_floor_ceiling``: the floor and ceiling heights of a z-up cloud, from the
  peaks of its height histogram (horizontal planes hold many points at one z).
- ``carve_observed``: the cells a scanner saw through (ray carving from its viewpoints
  to every occupied cell: a ray counts only if nothing occupied lies on its way, so a
  merged multi-viewpoint scan carves correctly). Space nobody saw - behind shelves,
  inside closed furniture - stays unobserved, hence not free.
- ``compute_free_space``: free = not occupied, observed (when known), farther than a
  clearance from any occupied cell, and connected to the main floor area.
- ``auto_footprint``: a room polygon from the wall band of a scan.

Grids follow camplace.scene.build.OccupancyGrid: (nx, ny, nz) cells of edge ``res`` from
``origin`` (metres).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np
from scipy import ndimage

from camplace.core.errors import InputError



@dataclass(frozen=True)
class FreeSpace:
    """free: (nx, ny, nz) bool, same cells as the occupancy grid: walkable free space.
    observed: (nx, ny, nz) bool cells seen free by a scanner, or None if unknown."""

    free: np.ndarray
    origin: np.ndarray
    resolution: float
    observed: np.ndarray | None = None
    info: dict = field(default_factory=dict)

    def contains(self, points: np.ndarray) -> np.ndarray:
        """points (N, 3) m -> (N,) bool: inside a free cell (outside the grid = False)."""
        c = np.floor((np.asarray(points, float).reshape(-1, 3) - self.origin) / self.resolution).astype(np.int64)
        inside = np.all((c >= 0) & (c < np.array(self.free.shape)), axis=1)
        out = np.zeros(len(c), dtype=bool)
        ci = c[inside]
        out[inside] = self.free[ci[:, 0], ci[:, 1], ci[:, 2]]
        return out

    def observed_at(self, points: np.ndarray) -> np.ndarray:
        """points (N, 3) m -> (N,) bool: within one cell of observed space (True when unknown)."""
        if self.observed is None:
            return np.ones(len(points), dtype=bool)
        c = np.floor((np.asarray(points, float).reshape(-1, 3) - self.origin) / self.resolution).astype(np.int64)
        out = np.zeros(len(c), dtype=bool)
        shape = np.array(self.observed.shape)
        for off in np.array(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij")).reshape(3, -1).T:
            q = c + off
            ok = np.all((q >= 0) & (q < shape), axis=1)
            out[ok] |= self.observed[q[ok, 0], q[ok, 1], q[ok, 2]]
        return out

    @property
    def volume_m3(self) -> float:
        return float(self.free.sum()) * self.resolution ** 3


def grid_memory_bytes(shape: tuple[int, ...], bytes_per_cell: float) -> int:
    return int(math.prod(int(s) for s in shape) * bytes_per_cell)


def check_grid_memory(shape: tuple[int, ...], bytes_per_cell: float, what: str, limit: int | None = None) -> int:
    """The bytes a grid of ``shape`` needs; InputError with the numbers when over ``limit``
    (default: camplace.spec.schema.memory_limit_bytes(), i.e. --max-memory-gb / 80 % of RAM)."""
    if limit is None:
        from camplace.spec.schema import memory_limit_bytes

        limit = memory_limit_bytes()
    need = grid_memory_bytes(shape, bytes_per_cell)
    if need > limit:
        raise InputError(f"{what}: a {'x'.join(str(int(s)) for s in shape)} grid needs {need / 1024**3:.1f} GiB "
                         f"({bytes_per_cell:g} bytes/cell; limit {limit / 1024**3:.1f} GiB); use a coarser "
                         "occupancy_resolution or crop the scan")
    return need


# ------------------------------------------------------------------ floor / ceiling


def detect_floor_ceiling(points: np.ndarray, bin_m: float = 0.02, min_share: float = 0.2) -> dict:
    """Heights of the floor and ceiling of a z-up cloud (N, 3).

    A horizontal plane is a peak of the z histogram (of the cloud thinned to one point
    per 5 cm voxel, so that counts follow area, not nearness to the scanner). The floor is the lowest peak holding
    at least ``min_share`` of the largest peak's points (in the lower half of the z
    range), the ceiling the highest such peak in the upper half (None if no peak there).
    Returns {"floor_z", "ceiling_z", "z_range"} in metres."""
    from camplace.scene.loaders.pointcloud import voxel_downsample

    z = voxel_downsample(np.asarray(points, float), 0.05)[:, 2]  # even density: counts ~ plane area
    lo, hi = np.quantile(z, 0.001), np.quantile(z, 0.999)
    if hi - lo < 4 * bin_m:
        return {"floor_z": float(lo), "ceiling_z": None, "z_range": [float(lo), float(hi)]}
    edges = np.arange(lo - bin_m, hi + 2 * bin_m, bin_m)
    h, _ = np.histogram(z, edges)
    hs = np.convolve(h, [1, 1, 1], mode="same")  # tolerate a plane split across two bins
    mid = 0.5 * (lo + hi)
    centres = 0.5 * (edges[:-1] + edges[1:])
    strong = hs >= min_share * hs.max()
    peaks = strong & (hs >= np.r_[0, hs[:-1]]) & (hs >= np.r_[hs[1:], 0])
    low = np.nonzero(peaks & (centres <= mid))[0]
    high = np.nonzero(peaks & (centres > mid))[0]
    floor = float(centres[low[0]]) if len(low) else float(lo)
    ceiling = float(centres[high[-1]]) if len(high) else None
    return {"floor_z": round(floor, 4), "ceiling_z": None if ceiling is None else round(ceiling, 4),
            "z_range": [round(float(lo), 4), round(float(hi), 4)]}


# ------------------------------------------------------------------ footprint


def auto_footprint(points: np.ndarray, floor_z: float = 0.0, ceiling_z: float | None = None,
                   trim: float = 0.005, cell: float = 0.1) -> np.ndarray:
    """A room polygon (K, 2) from a z-up scan's wall band (0.15 to 0.6 m below the ceiling,
    where only walls remain; without a ceiling 0.3 m above the floor to 0.3 m below the
    top), 0.5 % of extreme x and y trimmed (stray points through openings).

    When the walls close a loop (rasterized at ``cell`` m and closed over 2-cell gaps),
    the polygon is the filled inside of that loop (non-convex rooms keep their shape);
    otherwise (open walls, no ceiling) the convex hull of the points 0.3 m above the floor
    to 0.3 m below the ceiling."""
    from shapely.geometry import MultiPoint, box
    from shapely.ops import unary_union

    p = np.asarray(points, float)

    def _trimmed(b: np.ndarray) -> np.ndarray:
        if len(b) < 10:
            b = p
        lo_, hi_ = np.quantile(b[:, :2], trim, axis=0), np.quantile(b[:, :2], 1 - trim, axis=0)
        return b[np.all((b[:, :2] >= lo_) & (b[:, :2] <= hi_), axis=1)]

    top = ceiling_z if ceiling_z is not None else float(np.quantile(p[:, 2], 0.99))
    wide = _trimmed(p[(p[:, 2] > floor_z + 0.3) & (p[:, 2] < top - 0.3)])
    hull = MultiPoint(wide[:, :2]).convex_hull.simplify(0.05)
    if hull.geom_type != "Polygon" or hull.area < 0.5:
        raise InputError("scan: cannot find a room footprint (the wall band of the scan has no area); "
                         "give --footprint or a scene file")
    if ceiling_z is None:
        return np.asarray(hull.exterior.coords)[:-1]
    # just below the ceiling only walls remain (shelves and people end lower)
    band = _trimmed(p[(p[:, 2] > max(floor_z + 0.3, ceiling_z - 0.6)) & (p[:, 2] < ceiling_z - 0.15)])
    lo, hi = band[:, :2].min(0), band[:, :2].max(0)
    # the walls as a 2D image; their filled inside, if they close
    o = lo - 2 * cell
    ij = np.floor((band[:, :2] - o) / cell).astype(int)
    shape = tuple(np.floor((hi - o) / cell).astype(int) + 3)
    img = np.zeros(shape, bool)
    img[ij[:, 0], ij[:, 1]] = True
    walls = ndimage.binary_closing(img, structure=np.ones((3, 3), bool), iterations=2) | img
    inside = ndimage.binary_fill_holes(walls) & ~walls
    if inside.sum() * cell * cell < 0.5 * hull.area:
        return np.asarray(hull.exterior.coords)[:-1]  # the walls do not close: convex hull
    labels, n = ndimage.label(inside)
    biggest = np.argmax(np.bincount(labels.ravel())[1:]) + 1
    room = ndimage.binary_fill_holes(labels == biggest)  # furniture columns inside belong to the room
    room = ndimage.binary_dilation(room, iterations=1) & (room | walls)  # out to the wall surface
    cells = np.argwhere(room)
    poly = unary_union([box(o[0] + i * cell, o[1] + j * cell, o[0] + (i + 1) * cell, o[1] + (j + 1) * cell)
                        for i, j in cells])
    if poly.geom_type != "Polygon":
        poly = max(poly.geoms, key=lambda g: g.area)
    poly = poly.simplify(cell * 1.5)
    if poly.geom_type != "Polygon" or not poly.is_valid or poly.area < 0.5:
        return np.asarray(hull.exterior.coords)[:-1]
    return np.asarray(poly.exterior.coords)[:-1]


# ------------------------------------------------------------------ carving


@numba.njit(cache=True, parallel=True)
def _carve(occ, observed, ox, oy, oz, res, vps, targets, stop_cells):
    """Mark in ``observed`` the cells on clear rays viewpoint -> target cell centre. A ray
    is clear if it meets no occupied cell before it is within ``stop_cells`` (Chebyshev)
    of its target. Returns the number of clear rays."""
    nx, ny, nz = occ.shape
    n_rays = 0
    for t in numba.prange(targets.shape[0]):
        for v in range(vps.shape[0]):
            x0, y0, z0 = vps[v, 0], vps[v, 1], vps[v, 2]
            x1, y1, z1 = targets[t, 0], targets[t, 1], targets[t, 2]
            ex = int(math.floor((x1 - ox) / res))
            ey = int(math.floor((y1 - oy) / res))
            ez = int(math.floor((z1 - oz) / res))
            for pass_ in range(2):  # pass 0: is the ray clear? pass 1: mark it
                ix = int(math.floor((x0 - ox) / res))
                iy = int(math.floor((y0 - oy) / res))
                iz = int(math.floor((z0 - oz) / res))
                dx, dy, dz = x1 - x0, y1 - y0, z1 - z0
                sx = 1 if dx > 0 else -1
                sy = 1 if dy > 0 else -1
                sz = 1 if dz > 0 else -1
                tdx = res / abs(dx) if dx != 0.0 else 1e30
                tdy = res / abs(dy) if dy != 0.0 else 1e30
                tdz = res / abs(dz) if dz != 0.0 else 1e30
                tmx = ((ix + (1 if dx > 0 else 0)) * res + ox - x0) / dx if dx != 0.0 else 1e30
                tmy = ((iy + (1 if dy > 0 else 0)) * res + oy - y0) / dy if dy != 0.0 else 1e30
                tmz = ((iz + (1 if dz > 0 else 0)) * res + oz - z0) / dz if dz != 0.0 else 1e30
                clear = True
                n_max = abs(ex - ix) + abs(ey - iy) + abs(ez - iz) + 1
                for _ in range(n_max):
                    if ix < 0 or iy < 0 or iz < 0 or ix >= nx or iy >= ny or iz >= nz:
                        clear = False
                        break
                    near = max(abs(ix - ex), abs(iy - ey), abs(iz - ez)) <= stop_cells
                    if occ[ix, iy, iz]:
                        clear = near
                        break
                    if near and pass_ == 0:
                        break
                    if pass_ == 1:
                        observed[ix, iy, iz] = True
                    if tmx <= tmy and tmx <= tmz:
                        ix += sx
                        tmx += tdx
                    elif tmy <= tmz:
                        iy += sy
                        tmy += tdy
                    else:
                        iz += sz
                        tmz += tdz
                if not clear:
                    break
                if pass_ == 1:
                    n_rays += 1
    return n_rays


def carve_observed(occupied: np.ndarray, origin: np.ndarray, res: float, viewpoints: np.ndarray,
                   targets: np.ndarray | None = None, stop_cells: int = 2, progress=None) -> tuple[np.ndarray, int]:
    """(nx, ny, nz) bool cells seen free from ``viewpoints`` (K, 3) m, and the number of
    clear rays. targets: (M, 3) ray ends (default: the centres of all occupied cells
    strictly inside the grid's outer layer)."""
    if targets is None:
        idx = np.argwhere(occupied)
        inner = np.all((idx > 0) & (idx < np.array(occupied.shape) - 1), axis=1)
        targets = origin + (idx[inner] + 0.5) * res
    observed = np.zeros(occupied.shape, dtype=bool)
    vps = np.ascontiguousarray(np.asarray(viewpoints, float).reshape(-1, 3))
    occ = occupied.view(np.uint8)
    n = 0
    chunk = 200_000
    for s in range(0, len(targets), chunk):
        n += _carve(occ, observed, float(origin[0]), float(origin[1]), float(origin[2]), float(res), vps,
                    np.ascontiguousarray(targets[s:s + chunk], dtype=np.float64), int(stop_cells))
        if progress:
            progress("free space", min(s + chunk, len(targets)), len(targets))
    return observed, int(n)


# ------------------------------------------------------------------ free space


def _ball(r: int) -> np.ndarray:
    g = np.arange(-r, r + 1)
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    return x * x + y * y + z * z <= r * r + 1e-9


def compute_free_space(occupied: np.ndarray, origin: np.ndarray, res: float, observed: np.ndarray | None = None,
                       clearance: float = 0.05, floor_z: float = 0.0, connected_to_floor: bool = True,
                       min_floor_share: float = 0.5) -> FreeSpace:
    """Walkable free space of an occupancy grid.

    free = ~occupied & observed (dilated by one cell, to close gaps between rays) & farther
    than ``clearance`` (m) from every occupied cell; with ``connected_to_floor`` only the
    components (6-connected) that touch the layer just above the floor and whose floor
    contact is at least ``min_floor_share`` of the largest one's are kept."""
    check_grid_memory(occupied.shape, 6, "free space")
    free = ~occupied
    info: dict = {"clearance_m": clearance, "cells": int(free.size)}
    if observed is not None:
        obs = ndimage.binary_dilation(observed, structure=np.ones((3, 3, 3), bool))
        free &= obs
        info["observed_cells"] = int(observed.sum())
    r = int(math.ceil(clearance / res - 1e-9))
    if r > 0:
        near = ndimage.binary_dilation(occupied, structure=_ball(r))
        free &= ~near
    if connected_to_floor:
        labels, n = ndimage.label(free)  # 6-connectivity
        k_floor = int(math.floor((floor_z + clearance - origin[2]) / res)) + 1
        k_floor = min(max(k_floor, 0), free.shape[2] - 1)
        layer = labels[:, :, k_floor]
        counts = np.bincount(layer.ravel(), minlength=n + 1)
        counts[0] = 0
        if counts.max() == 0:
            free[:] = False
            info["components_kept"] = 0
        else:
            keep = counts >= min_floor_share * counts.max()
            keep[0] = False
            free = keep[labels]
            info["components"] = int(n)
            info["components_kept"] = int(keep.sum())
        del labels
    info["free_cells"] = int(free.sum())
    info["free_volume_m3"] = round(float(free.sum()) * res ** 3, 3)
    return FreeSpace(free, np.asarray(origin, float), float(res), observed, info)


# ------------------------------------------------------------------ surface normals


def pca_normals(points: np.ndarray, at: np.ndarray, k: int = 20) -> np.ndarray:
    """Unit normals (M, 3) at ``at`` (M, 3): the direction of least spread of the ``k``
    nearest ``points`` (N, 3) (PCA). Sign not oriented."""
    from scipy.spatial import cKDTree

    k = int(min(k, len(points)))
    _, idx = cKDTree(points).query(at, k=k, workers=-1)
    nb = points[idx.reshape(len(at), k)]
    c = nb - nb.mean(axis=1, keepdims=True)
    cov = np.einsum("mki,mkj->mij", c, c)
    _, vec = np.linalg.eigh(cov)
    return vec[:, :, 0]


# ------------------------------------------------------------------ scene glue


def scene_free_space(grid, spec, loaded: list, progress=None):
    """Free space of a scene whose obstacles include files (called by build_scene).

    grid: the scene's OccupancyGrid (obstacles already marked); loaded: the
    LoadedObstacle of each file obstacle. Returns (FreeSpace or None when only meshes
    were loaded, scan points (N, 3) or None, viewpoints (K, 3) or None)."""
    pts = [lo.points for lo in loaded if lo.points is not None and lo.report.get("kind") == "point_cloud"]
    vps = [lo.viewpoints for lo in loaded if len(lo.viewpoints)]
    points = np.concatenate(pts) if pts else None
    viewpoints = np.concatenate(vps) if vps else None
    if not any(lo.report.get("kind") in ("point_cloud", "octomap") for lo in loaded):
        return None, points, viewpoints
    occ, origin, res = grid.occupied, grid.origin, grid.resolution
    need = check_grid_memory(occ.shape, 7, f"scene '{spec.name}': free space")
    observed = None
    info: dict = {"grid_bytes_planned": need}
    if viewpoints is not None:
        # a viewpoint outside the room or inside something (e.g. a default "VIEWPOINT 0 0 0"
        # of a merged scan) cannot have seen this room: ignore it, and say so
        usable = viewpoints[~grid.is_occupied(viewpoints)]
        if len(usable) < len(viewpoints):
            info["viewpoints_ignored"] = int(len(viewpoints) - len(usable))
        if len(usable):
            surface = occ & ~ndimage.binary_erosion(occ, border_value=1)
            idx = np.argwhere(surface)
            observed, n_rays = carve_observed(occ, origin, res, usable, origin + (idx + 0.5) * res,
                                              progress=progress)
            info.update({"carved_from_viewpoints": int(len(usable)), "clear_rays": n_rays})
            seen_share = float(observed.sum()) / max(int((~occ).sum()), 1)
            if seen_share < 0.05:  # the viewpoints saw almost nothing: not this scan's scanners
                info["viewpoints_ignored"] = int(len(viewpoints))
                info["carving_dropped"] = f"the viewpoints saw only {100 * seen_share:.1f} % of the room"
                observed = None
    free_leaves = [lo for lo in loaded if lo.free_lo is not None and len(lo.free_lo)]
    if free_leaves:
        from camplace.scene.loaders.obstacles import mark_boxes

        observed = np.zeros(occ.shape, dtype=bool) if observed is None else observed
        for lo in free_leaves:
            mark_boxes(observed, origin, res, lo.free_lo, lo.free_size)
        info["octomap_free_leaves"] = int(sum(len(lo.free_lo) for lo in free_leaves))
    fs = compute_free_space(occ, origin, res, observed, spec.free_space.clearance, 0.0,
                            spec.free_space.connected_to_floor)
    if observed is not None and spec.free_space.unobserved_occludes:
        # what no scanner saw (inside shelves, behind holes of a sparse shell) blocks sight lines
        unseen = ~ndimage.binary_dilation(observed, structure=np.ones((3, 3, 3), bool))
        info["unobserved_cells_occluding"] = int((unseen & ~occ).sum())
        occ |= unseen
    if points is not None and len(points) > 100:
        info["scan_levels"] = detect_floor_ceiling(points)
    if observed is None:
        info["observed"] = "unknown (no viewpoints, no OctoMap free leaves): free = not occupied"
    fs.info.update(info)
    return fs, points, viewpoints


# ------------------------------------------------------------------ surface targets on scans


def snap_outward(occupancy, positions: np.ndarray, normals: np.ndarray, max_shift: float = 0.15,
                 offset_cells: float = 0.75) -> tuple[np.ndarray, np.ndarray]:
    """Move each surface point (M, 3) out along its normal (M, 3) by whole occupancy cells
    until the point ``offset_cells`` outside it is free (a scanned face is a noisy shell of
    occupied cells, so the labelled box face may lie inside it). Returns (positions, kept
    mask (M,)); points still blocked after ``max_shift`` m are not kept."""
    res = occupancy.resolution
    out = positions.copy()
    done = np.zeros(len(positions), dtype=bool)
    for k in range(int(math.ceil(max_shift / res)) + 1):
        cand = positions + normals * (k * res)
        ok = ~done & ~occupancy.is_occupied(cand + normals * (offset_cells * res))
        out[ok] = cand[ok]
        done |= ok
    return out, done


def scan_surface_targets(scene, lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """Surface targets from the scan inside the box [lo, hi] (m): one per target voxel
    (``voxel_size``) holding scan points (their centroid; occupied cell centres when the
    scene has no points), normal by PCA of the 20 nearest points, turned toward free space
    (then toward the scanners), snapped outward. Returns (positions (M, 3), normals (M, 3))."""
    from camplace.scene.loaders.pointcloud import voxel_downsample

    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    g = scene.occupancy
    if scene.points is not None:
        src = scene.points
    else:
        src = g.origin + (np.argwhere(g.occupied) + 0.5) * g.resolution
    margin = 2 * g.resolution
    near = src[np.all((src >= lo - margin) & (src <= hi + margin), axis=1)]
    inside = near[np.all((near >= lo) & (near <= hi), axis=1)]
    if len(inside) < 3:
        return np.zeros((0, 3)), np.zeros((0, 3))
    pos = voxel_downsample(inside, float(scene.spec.voxel_size))
    nrm = pca_normals(near, pos)
    score = np.zeros(len(pos))
    for k in (1, 2, 3):
        d = nrm * (k * g.resolution)
        score += (~g.is_occupied(pos + d)).astype(float) - (~g.is_occupied(pos - d)).astype(float)
    if scene.viewpoints is not None and len(scene.viewpoints):
        to_vp = scene.viewpoints[np.argmin(np.linalg.norm(pos[:, None, :] - scene.viewpoints[None], axis=2), axis=1)] - pos
        score = np.where(score == 0, np.sign(np.einsum("ij,ij->i", to_vp, nrm)), score)
    nrm = np.where((score < 0)[:, None], -nrm, nrm)
    pos, keep = snap_outward(g, pos, nrm)
    return pos[keep], nrm[keep]


# ------------------------------------------------------------------ a scene from just a scan

DEFAULT_CAMERA = {"name": "wide", "model": "pinhole", "resolution": [1780, 720], "fov_deg": [71, 36],
                  "max_range": 5.0}


def scene_from_cloud(path: str, *, name: str | None = None, level_floor: bool = True, up: str = "+z",
                     scale: float = 1.0, rotate_deg=(0.0, 0.0, 0.0), translate=(0.0, 0.0, 0.0),
                     crop: tuple | None = None, downsample: float | None = 0.02,
                     remove_outliers: bool = True, viewpoints: list | None = None,
                     footprint: list | None = None, heights=(0.5, 1.0, 1.5), coverage: int = 2,
                     budget: int = 20, wall_mount_height: float | None = None,
                     progress=None) -> tuple[dict, dict]:
    """A scene (as a scene-file mapping) from just a scan, with defaults: the scan levelled
    (floor plane -> z = 0), floor and ceiling detected, footprint from the scan's wall band
    (or given), walkable ``kind: volume`` targets at ``heights`` with ``coverage``, a 1 m
    ceiling grid 0.1 m below the detected ceiling (wall mounts too with
    ``wall_mount_height``), the default 71°x36° camera.

    Returns (scene mapping, report: what was detected). The cloud path is stored
    absolute, so the mapping can be used as is or saved next to anything."""
    from pathlib import Path

    from camplace.spec.schema import parse_scene
    from camplace.scene.loaders.obstacles import load_cloud_obstacle

    p = Path(path).expanduser().resolve()
    entry: dict = {"name": "scan", "point_cloud": str(p)}
    tf: dict = {}
    if downsample:
        entry["downsample"] = float(downsample)
    if remove_outliers:
        entry["remove_outliers"] = {"neighbors": 16, "std_ratio": 2.0}
    if viewpoints:
        entry["viewpoints"] = [[float(v) for v in vp] for vp in viewpoints]

    def _obstacle():
        from camplace.spec.schema import Obstacle

        e = dict(entry)
        if tf:
            e["transform"] = dict(tf)
        if crop is not None:
            e["crop"] = {"min": list(crop[0]), "max": list(crop[1])}
        return Obstacle.model_validate(e)

    # 1. the frame: user transform, then (optionally) the floor plane levelled, then the
    # floor moved to z = 0 - folded into one explicit transform, so the scene is reproducible
    from scipy.spatial.transform import Rotation

    from camplace.scene.loaders.cleanup import apply_matrix, level_floor_matrix, rigid_matrix
    from camplace.scene.loaders.pointcloud import load_point_cloud

    try:
        raw = load_point_cloud(p, downsample=0.05, progress=progress)
    except InputError as err:
        raise InputError(f"--cloud: {err}") from None
    m = rigid_matrix(scale, rotate_deg, translate)
    q = apply_matrix(raw.points, m)
    level_info: dict = {}
    if level_floor:
        try:
            ml, level_info = level_floor_matrix(q, up)
        except ValueError:
            raise InputError(f"--cloud {p}: no floor plane within 30° of '{up}' up; give --up or --no-level-floor") from None
        m = ml @ m
        q = apply_matrix(raw.points, m)
    floor = detect_floor_ceiling(q)["floor_z"]
    m[2, 3] -= floor
    tf = {}
    if scale != 1.0:
        tf["scale"] = float(scale)
    rot = m[:3, :3] / float(scale)
    eul = Rotation.from_matrix(rot).as_euler("xyz", degrees=True)
    if np.any(np.abs(eul) > 1e-6):
        tf["rotate_deg"] = [round(float(v), 6) for v in eul]
    if np.any(np.abs(m[:3, 3]) > 1e-9):
        tf["translate"] = [round(float(v), 6) for v in m[:3, 3]]
    # 2. the cleaned cloud in that frame (cached: building the scene reuses it)
    cloud, steps = load_cloud_obstacle(_obstacle(), None, f"--cloud {p}", progress)
    if level_info:
        steps = [{"step": "level_floor", **level_info}, *steps]
    levels = detect_floor_ceiling(cloud.points)
    pts = cloud.points
    ceiling = levels["ceiling_z"]
    height = float(ceiling) if ceiling is not None else float(np.quantile(pts[:, 2], 0.999)) + 0.05
    height = round(height, 3)
    if height <= 0.5:
        raise InputError(f"--cloud {p}: the scan is only {height:.2f} m high above its floor; is it z-up? "
                         "(try --up +y for phone scans, or --no-level-floor)")
    fp = np.asarray(footprint, float) if footprint is not None else auto_footprint(pts, 0.0, ceiling)
    hs = [float(h) for h in heights if 0 < h < height - 0.1]
    if not hs:
        raise InputError(f"--cloud {p}: no target height below the detected ceiling ({height} m)")
    mounts = [{"kind": "ceiling_grid", "camera": "wide", "spacing": 1.0, "offset_below_ceiling": 0.1,
               "yaw_deg": {"start": 0, "stop": 330, "step": 30}, "pitch_deg": [30, 45, 60]}]
    if wall_mount_height is not None:
        mounts.append({"kind": "wall", "camera": "wide", "height": float(wall_mount_height), "spacing": 1.0,
                       "pitch_deg": [20, 35, 50]})
    e = dict(entry)
    if tf:
        e["transform"] = tf
    if crop is not None:
        e["crop"] = {"min": [float(v) for v in crop[0]], "max": [float(v) for v in crop[1]]}
    data = {
        "name": name or p.stem,
        "voxel_size": 0.25,
        "occupancy_resolution": 0.05,
        "room": {"footprint": [[round(float(x), 3), round(float(y), 3)] for x, y in fp], "height": height},
        "obstacles": [e],
        "targets": [{"name": "walkable", "kind": "volume", "heights": hs, "coverage": int(coverage)}],
        "cameras": [dict(DEFAULT_CAMERA)],
        "mounts": mounts,
        "placement": {"budget": int(budget), "solver": "greedy"},
    }
    parse_scene(data, f"--cloud {p}")  # validate now: errors name the option, not a YAML file
    area = float(abs(np.dot(fp[:, 0], np.roll(fp[:, 1], 1)) - np.dot(fp[:, 1], np.roll(fp[:, 0], 1))) / 2)
    report = {"points": len(pts), "cleanup": steps, "floor_z_in_file_frame": floor, "transform": tf, "ceiling_z": ceiling, "height_m": height,
              "footprint_vertices": len(fp), "floor_area_m2": round(area, 2), "viewpoints": len(cloud.viewpoints)}
    return data, report


def describe_free_space(info: dict) -> str:
    """One log line for scene.info['free_space']."""
    out = (f"free space: {info.get('free_volume_m3', 0)} m3 walkable (clearance {info.get('clearance_m')} m, "
           f"grid {info.get('grid_bytes_planned', 0) / 1024**2:.0f} MiB planned)")
    if info.get("carved_from_viewpoints"):
        out += f"; carved from {info['carved_from_viewpoints']} viewpoint(s)"
    if info.get("octomap_free_leaves"):
        out += f"; {info['octomap_free_leaves']:,} OctoMap free leaves"
    if info.get("viewpoints_ignored"):
        out += f"; {info['viewpoints_ignored']} viewpoint(s) ignored ({info.get('carving_dropped', 'outside the room or inside an obstacle')})"
    if "observed" in info:
        out += "; observed space unknown: free = not occupied (give obstacle viewpoints for ray carving)"
    return out
