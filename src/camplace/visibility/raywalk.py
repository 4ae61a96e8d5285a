"""Ray walking through a voxel grid, shared by the visibility engines and the renders.

The 3D DDA of Amanatides & Woo: ``dda_axis`` sets a ray up along one axis, ``dda_step``
crosses the nearest cell boundary; ``segment_clear`` walks a segment (voxel engine's
line of sight), ``first_hit`` finds the first occupied cell along a ray (pixel engine,
camplace.outputs.render) and can jump through empty space with ``free_distance``;
``cast_rays`` runs ``first_hit`` for many rays from one point in parallel. Every
routine is compiled with numba; all distances are metres, grids are indexed
``[ix, iy, iz]`` from ``origin`` in cells of ``res`` metres.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camplace.core.executors import on_threads
from camplace.scene.build import OccupancyGrid

NO_HIT, BOUNDARY = -2, -1  # first_hit's axis: nothing hit within range / started inside or left the grid
SKIP_MIN = 3  # first_hit jumps from cells at least this many cells (Chebyshev) from any occupied one


@numba.njit(cache=True, inline="always")
def dda_axis(i: int, p: float, d: float, o: float, size: float) -> tuple[int, float, float]:
    """3D DDA (Amanatides & Woo) set-up along one axis for the ray p + t d through cells of
    ``size`` (m) from origin ``o``, the ray being in cell ``i``: (step +1/-1, t of the next
    cell boundary, t from one boundary to the next); both t are 1e30 (never) when d == 0."""
    step = 1 if d > 0 else -1
    if d != 0.0:
        return step, ((i + (1 if d > 0 else 0)) * size + o - p) / d, size / abs(d)
    return step, 1e30, 1e30


@numba.njit(cache=True, inline="always")
def dda_step(ix: int, iy: int, iz: int, tmx: float, tmy: float, tmz: float, sx: int, sy: int, sz: int,
             tdx: float, tdy: float, tdz: float):
    """One DDA step into the next cell (set-up: ``dda_axis`` per axis): crosses the nearest
    cell boundary. Returns (ix, iy, iz, tmx, tmy, tmz) after the step, the axis stepped
    along (0, 1, 2) and t of the boundary crossed (the ray's entry into the new cell)."""
    if tmx <= tmy and tmx <= tmz:
        return ix + sx, iy, iz, tmx + tdx, tmy, tmz, 0, tmx
    if tmy <= tmz:
        return ix, iy + sy, iz, tmx, tmy + tdy, tmz, 1, tmy
    return ix, iy, iz + sz, tmx, tmy, tmz + tdz, 2, tmz


@numba.njit(cache=True, nogil=True)
def segment_clear(occ: np.ndarray, ox: float, oy: float, oz: float, res: float,
                  x0: float, y0: float, z0: float, x1: float, y1: float, z1: float) -> bool:
    """True if no occupied cell meets the segment p0 -> p1 (3D DDA; out of grid = blocked)."""
    nx, ny, nz = occ.shape
    ix = int(math.floor((x0 - ox) / res))
    iy = int(math.floor((y0 - oy) / res))
    iz = int(math.floor((z0 - oz) / res))
    ex = int(math.floor((x1 - ox) / res))
    ey = int(math.floor((y1 - oy) / res))
    ez = int(math.floor((z1 - oz) / res))
    sx, tmx, tdx = dda_axis(ix, x0, x1 - x0, ox, res)
    sy, tmy, tdy = dda_axis(iy, y0, y1 - y0, oy, res)
    sz, tmz, tdz = dda_axis(iz, z0, z1 - z0, oz, res)
    n_max = abs(ex - ix) + abs(ey - iy) + abs(ez - iz) + 1
    for _ in range(n_max):
        if ix < 0 or iy < 0 or iz < 0 or ix >= nx or iy >= ny or iz >= nz:
            return False
        if occ[ix, iy, iz]:
            return False
        if ix == ex and iy == ey and iz == ez:
            return True
        jx, jy, jz, ux, uy, uz, _, t = dda_step(ix, iy, iz, tmx, tmy, tmz, sx, sy, sz, tdx, tdy, tdz)
        if t > 1.0:
            return True
        ix, iy, iz, tmx, tmy, tmz = jx, jy, jz, ux, uy, uz
    return True


@numba.njit(cache=True, inline="always")
def first_hit(occ, dist, ox, oy, oz, res, px, py, pz, dx, dy, dz, rng):
    """First occupied cell along the unit ray p + t d, t in [0, rng].

    Returns (t, ix, iy, iz, axis, step): t = distance to the entry of the hit cell (rng
    when nothing is hit: axis = NO_HIT); axis/step = the axis and direction of the DDA
    step that entered the hit cell (axis = BOUNDARY when the ray starts in an occupied
    cell or leaves the grid). ``dist`` (same shape as occ, see ``free_distance``) lets the
    ray jump through empty space: from a cell whose Chebyshev distance to the nearest
    occupied cell is d, the cube of cells within (d - 1) is free, so the ray jumps to
    where it leaves that cube (the DDA state advanced by whole boundary crossings, no
    re-flooring); pass a (1, 1, 1) array to step cell by cell. Same result."""
    nx, ny, nz = occ.shape
    skip = dist.shape[0] == nx and dist.shape[1] == ny and dist.shape[2] == nz
    ix = int(math.floor((px - ox) / res))
    iy = int(math.floor((py - oy) / res))
    iz = int(math.floor((pz - oz) / res))
    if ix < 0 or iy < 0 or iz < 0 or ix >= nx or iy >= ny or iz >= nz or occ[ix, iy, iz]:
        return 0.0, ix, iy, iz, BOUNDARY, 0
    sx, tmx, tdx = dda_axis(ix, px, dx, ox, res)
    sy, tmy, tdy = dda_axis(iy, py, dy, oy, res)
    sz, tmz, tdz = dda_axis(iz, pz, dz, oz, res)
    # boundaries crossed per unit of t along each axis (the jumps count crossings with them)
    ux_, uy_, uz_ = abs(dx) / res, abs(dy) / res, abs(dz) / res
    while True:
        if skip:
            dd = dist[ix, iy, iz]
            if dd >= SKIP_MIN:
                # every cell within k = dd - 1 cells (Chebyshev) is free: jump to where the ray
                # leaves that cube, crossing each axis's boundaries before it (at most k)
                k = dd - 1
                te = min(tmx + k * tdx, tmy + k * tdy, tmz + k * tdz)
                if te > rng:
                    return rng, ix, iy, iz, NO_HIT, 0
                mx, my, mz = _crossings(tmx, ux_, te, k), _crossings(tmy, uy_, te, k), _crossings(tmz, uz_, te, k)
                ix, iy, iz = ix + sx * mx, iy + sy * my, iz + sz * mz
                tmx, tmy, tmz = tmx + mx * tdx, tmy + my * tdy, tmz + mz * tdz
        jx, jy, jz, ux, uy, uz, axis, t = dda_step(ix, iy, iz, tmx, tmy, tmz, sx, sy, sz, tdx, tdy, tdz)
        if t > rng:
            return rng, ix, iy, iz, NO_HIT, 0
        ix, iy, iz, tmx, tmy, tmz = jx, jy, jz, ux, uy, uz
        step = sx if axis == 0 else (sy if axis == 1 else sz)
        if ix < 0 or iy < 0 or iz < 0 or ix >= nx or iy >= ny or iz >= nz:
            return t, ix, iy, iz, BOUNDARY, 0
        if occ[ix, iy, iz]:
            return t, ix, iy, iz, axis, step


@numba.njit(cache=True, inline="always")
def _crossings(tm: float, per_t: float, te: float, k: int) -> int:
    """Cell boundaries at tm, tm + 1 / per_t, ... that lie at or before te, at most k."""
    if tm > te:
        return 0
    return min(k, int((te - tm) * per_t) + 1)


@numba.njit(cache=True, nogil=True)
def _cast_rays_kernel(occ, dist, origin, res, p, dirs, max_t, t_out, cell_out, axis_out):
    for r in range(dirs.shape[0]):
        t, ix, iy, iz, axis, step = first_hit(occ, dist, origin[0], origin[1], origin[2], res, p[0], p[1], p[2],
                                              dirs[r, 0], dirs[r, 1], dirs[r, 2], max_t)
        t_out[r] = t if axis != NO_HIT else np.inf
        cell_out[r, 0], cell_out[r, 1], cell_out[r, 2] = ix, iy, iz
        axis_out[r] = axis


def cast_rays(occupied: np.ndarray, dist: np.ndarray, origin: np.ndarray, res: float, position: np.ndarray,
              dirs: np.ndarray, max_t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``first_hit`` of every unit ray ``dirs`` (M, 3) from ``position`` (3,) m, up to
    ``max_t`` m, in parallel. occupied: (nx, ny, nz) bool grid from ``origin`` (3,) m in
    cells of ``res`` m; dist: its ``free_distance`` (or a (1, 1, 1) array).

    Returns (t (M,) m to the hit cell's entry, inf when nothing is hit; cell (M, 3) int64
    the cell where the ray ended; axis (M,) int64 the axis that entered it, or BOUNDARY)."""
    n = len(dirs)
    t = np.empty(n)
    cell = np.empty((n, 3), np.int64)
    axis = np.empty(n, np.int64)
    occ, origin, pos = occupied.view(np.uint8), np.asarray(origin, np.float64), np.asarray(position, np.float64)
    dirs = np.ascontiguousarray(dirs, dtype=np.float64)
    on_threads(n, lambda a, b: _cast_rays_kernel(occ, dist, origin, float(res), pos, dirs[a:b], float(max_t), t[a:b],
                                                 cell[a:b], axis[a:b]), min_rows=1024)
    return t, cell, axis


def free_distance(occupancy: OccupancyGrid) -> np.ndarray:
    """(nx, ny, nz) uint8: Chebyshev distance (cells, capped at 255) from each free cell to
    the nearest occupied cell or the grid's outside; 0 on occupied cells."""
    from scipy.ndimage import distance_transform_cdt

    free = np.pad(~occupancy.occupied, 1, constant_values=False)
    d = distance_transform_cdt(free, metric="chessboard")[1:-1, 1:-1, 1:-1]
    return np.minimum(d, 255).astype(np.uint8)
