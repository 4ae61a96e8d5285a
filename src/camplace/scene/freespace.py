"""Free space from a scan (or an OctoMap).

- ``carve_observed``: the cells a scanner saw through (ray carving from its viewpoints
  to every occupied cell: a ray counts only if nothing occupied lies on its way, so a
  merged multi-viewpoint scan carves correctly). Space nobody saw - behind shelves,
  inside closed furniture - stays unobserved, hence not free.
- ``compute_free_space``: free = not occupied, observed (when known), farther than a
  clearance from any occupied cell, and connected to the main floor area.
- ``scene_free_space``: the free space of a scene with file obstacles (build_scene).

Building a scene from a scan alone (floor, ceiling, footprint, surface targets) lives
in camplace.scene.from_scan. Grids follow camplace.scene.build.OccupancyGrid: (nx, ny,
nz) cells of edge ``res`` from ``origin`` (metres).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np
from scipy import ndimage

from camplace.core.memory import check_grid_memory
from camplace.scene.from_scan import detect_floor_ceiling


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
