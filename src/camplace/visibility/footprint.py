"""What part of a target a sight line must reach: the target's footprint, shared by the engines.

A volume target's voxel is the cube of edge ``voxel_size`` about its centre; ``probe``
(a fraction of the edge) shrinks it to the central ``probe`` x voxel_size cube. A surface
target is a patch on an obstacle face: the face cells of the occupancy grid whose centres
lie within ``probe`` x voxel_size / 2 of the patch centre (``surface_cell_map``, at least
the patch centre's own cell). The pixel engine tests rays against these footprints; the
voxel engine (probe > 0) tests sight lines to sample points of them (``cube_lattice``,
``surface_samples``).
"""

from __future__ import annotations

import math

import numpy as np

from camplace.scene.build import OccupancyGrid
from camplace.targets.build import Targets

CUBE_LATTICE = 5  # sample points per cube edge (voxel engine, probe > 0)
CELL_LATTICE = 3  # sample points per face-cell edge (voxel engine, probe > 0, surfaces)
CELL_REACH = 0.45  # the face-cell lattice spans +- this many cells about the cell centre


def cube_lattice(k: int = CUBE_LATTICE) -> np.ndarray:
    """(M, 3) float64 points of a k x k x k lattice on the surface of the cube [-1, 1]^3
    (M = k^3 - (k - 2)^3), the centre (0, 0, 0) excluded."""
    g = np.linspace(-1.0, 1.0, k)
    pts = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    return np.ascontiguousarray(pts[np.any(np.abs(pts) == 1.0, axis=1)])


def surface_cell_map(occupancy: OccupancyGrid, targets: Targets, probe: float, voxel_size: float):
    """Map face cells to surface targets: (keys (K,) int64 sorted, ids (K,) int32).

    key = linear occupancy cell index * 6 + face code (2 * axis + (0 for +, 1 for -)). A
    face cell is an occupied cell whose outward neighbour is free; it belongs to the
    nearest patch centre on the same face plane, and counts when its centre lies within
    max(probe * voxel_size / 2, resolution / 2) of that centre on both in-plane axes."""
    res = float(occupancy.resolution)
    occ = occupancy.occupied
    shape = np.array(occupancy.shape)
    surf = np.nonzero(targets.is_surface)[0]
    if len(surf) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int32)
    v = float(voxel_size)
    core = max(0.5 * probe * v, 0.5 * res) + 1e-9
    m = int(math.ceil(v / res)) + 2
    offs = np.arange(-m // 2 - 1, m // 2 + 2)
    keys_all, ids_all, dist_all = [], [], []
    for j0 in range(0, len(surf), 4096):
        js = surf[j0:j0 + 4096]
        c = targets.positions[js]
        n = targets.normals[js]
        axis = np.argmax(np.abs(n), axis=1)
        sign = np.sign(n[np.arange(len(js)), axis]).astype(np.int64)
        inside = c - n * 0.5 * res
        base = np.floor((inside - occupancy.origin) / res).astype(np.int64)
        for du in offs:
            for dw in offs:
                cell = base.copy()
                uax = (axis + 1) % 3
                wax = (axis + 2) % 3
                cell[np.arange(len(js)), uax] += du
                cell[np.arange(len(js)), wax] += dw
                nb = cell.copy()
                nb[np.arange(len(js)), axis] += sign
                ok = np.all((cell >= 0) & (cell < shape), axis=1) & np.all((nb >= 0) & (nb < shape), axis=1)
                ok[ok] &= occ[cell[ok, 0], cell[ok, 1], cell[ok, 2]] & ~occ[nb[ok, 0], nb[ok, 1], nb[ok, 2]]
                centre = occupancy.origin + (cell + 0.5) * res
                d = np.maximum(np.abs(centre[np.arange(len(js)), uax] - c[np.arange(len(js)), uax]),
                               np.abs(centre[np.arange(len(js)), wax] - c[np.arange(len(js)), wax]))
                ok &= d <= 0.5 * v + res
                lin = (cell[:, 0] * shape[1] + cell[:, 1]) * shape[2] + cell[:, 2]
                face = 2 * axis + (sign < 0)
                keys_all.append((lin * 6 + face)[ok])
                ids_all.append(js[ok])
                dist_all.append(d[ok])
    keys, ids, dist = np.concatenate(keys_all), np.concatenate(ids_all), np.concatenate(dist_all)
    order = np.lexsort((ids, dist, keys))  # by key, then nearest patch first
    keys, ids, dist = keys[order], ids[order], dist[order]
    first = np.r_[True, keys[1:] != keys[:-1]]
    keys, ids, dist = keys[first], ids[first], dist[first]
    keep = dist <= core
    return keys[keep].astype(np.int64), ids[keep].astype(np.int32)


def surface_samples(occupancy: OccupancyGrid, targets: Targets, probe: float, voxel_size: float,
                    per_cell: int = CELL_LATTICE) -> tuple[np.ndarray, np.ndarray]:
    """Sample points of the surface targets' footprints on their face planes.

    ``per_cell`` x ``per_cell`` points on each face cell of ``surface_cell_map`` (a lattice
    over the cell's face, its centre first; in-plane coordinates from the cell, the
    target's plane coordinate along the normal). Returns (start (N_p + 1,) int64 CSR
    offsets by target, points (M, 3) float64 m); volume targets have none."""
    keys, ids = surface_cell_map(occupancy, targets, probe, voxel_size)
    res = float(occupancy.resolution)
    shape = np.array(occupancy.shape, np.int64)
    lin, face = keys // 6, keys % 6
    cell = np.stack([lin // (shape[1] * shape[2]), (lin // shape[2]) % shape[1], lin % shape[2]], 1)
    axis = face // 2
    g = np.linspace(-CELL_REACH, CELL_REACH, per_cell) if per_cell > 1 else np.zeros(1)
    du, dw = (a.ravel() for a in np.meshgrid(g, g, indexing="ij"))
    first = np.argsort(du * du + dw * dw, kind="stable")  # the cell centre first
    du, dw = du[first], dw[first]
    ids = np.repeat(ids, len(du))
    axis = np.repeat(axis, len(du))
    rows = np.arange(len(ids))
    pts = occupancy.origin + (np.repeat(cell, len(du), axis=0) + 0.5) * res
    pts[rows, (axis + 1) % 3] += np.tile(du, len(keys)) * res
    pts[rows, (axis + 2) % 3] += np.tile(dw, len(keys)) * res
    pts[rows, axis] = targets.positions[ids, axis]
    order = np.argsort(ids, kind="stable")
    start = np.zeros(len(targets) + 1, np.int64)
    np.cumsum(np.bincount(ids, minlength=len(targets)), out=start[1:])
    return start, np.ascontiguousarray(pts[order], dtype=np.float64)
