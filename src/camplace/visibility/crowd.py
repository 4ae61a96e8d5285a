"""Visibility in a crowd (issue 28): V_s ⊆ V, the entries of V that crowd sample s does not block.

An entry (i, j) of V survives in sample s when the segment from camera i to target j
passes through no person's cylinder (camplace.targets.crowd: radius r, height h, on the
floor), leaving out the person standing at target j (the one to be seen: the person
whose disc contains the target's (x, y)). V_s is computed from V's entries only - never
a new raycast - by one compiled kernel: the part of the segment between the floor and h
is walked through a 2D grid of the people (2D DDA; each person is listed in every cell its
disc touches) and tested against each listed cylinder exactly (the quadratic of the disc,
clipped to the segment's part below h). Sparse throughout, never densified.

``crowd_rows`` stacks the samples' V_s vertically, rows s · n + i (n = rows of the given
V), block by block through the same executors and assembly as V
(camplace.visibility.engine.chunked_rows: in-process, process pool, Dask).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
import scipy.sparse as sp

from camplace.core.executors import on_threads
from camplace.targets.crowd import Crowds

CHUNK_ROWS = 2048  # rows of V per block (one sample per block)


@dataclass(frozen=True)
class PeopleGrid:
    """The people of every sample on one 2D grid of cells of edge ``cell`` from (x0, y0):
    xy (P, 2) centres; cell_ptr (S, nx · ny + 1) int64 offsets into items (int32 person
    ids) of cell c = ix · ny + iy in sample s; radius / height (m)."""

    xy: np.ndarray
    cell_ptr: np.ndarray
    items: np.ndarray
    x0: float
    y0: float
    cell: float
    nx: int
    ny: int
    radius: float
    height: float

    @property
    def n_samples(self) -> int:
        return self.cell_ptr.shape[0]


def people_grid(crowds: Crowds, lo: np.ndarray, hi: np.ndarray, cell: float | None = None) -> PeopleGrid:
    """The grid of ``crowds`` over the plan box [lo, hi] (2,) m (every camera and target
    inside it); ``cell`` default 2 · radius, at least 0.25 m."""
    r = float(crowds.radius)
    g = float(cell) if cell is not None else max(2.0 * r, 0.25)
    x0, y0 = float(lo[0]) - g, float(lo[1]) - g
    nx = int(math.ceil((float(hi[0]) + g - x0) / g)) + 1
    ny = int(math.ceil((float(hi[1]) + g - y0) / g)) + 1
    S, xy = crowds.n_samples, crowds.xy
    sample = np.repeat(np.arange(S, dtype=np.int64), crowds.counts)
    ids = np.arange(len(xy), dtype=np.int64)
    keys, who = [], []
    ix0 = np.clip(np.floor((xy[:, 0] - r - x0) / g).astype(np.int64), 0, nx - 1)
    ix1 = np.clip(np.floor((xy[:, 0] + r - x0) / g).astype(np.int64), 0, nx - 1)
    iy0 = np.clip(np.floor((xy[:, 1] - r - y0) / g).astype(np.int64), 0, ny - 1)
    iy1 = np.clip(np.floor((xy[:, 1] + r - y0) / g).astype(np.int64), 0, ny - 1)
    span = int(max(np.max(ix1 - ix0, initial=0), np.max(iy1 - iy0, initial=0)))
    for dx in range(span + 1):
        for dy in range(span + 1):
            ok = (ix0 + dx <= ix1) & (iy0 + dy <= iy1)
            keys.append(sample[ok] * (nx * ny) + (ix0[ok] + dx) * ny + iy0[ok] + dy)
            who.append(ids[ok])
    key = np.concatenate(keys) if keys else np.zeros(0, np.int64)
    order = np.argsort(key, kind="stable")
    items = (np.concatenate(who) if who else np.zeros(0, np.int64))[order].astype(np.int32)
    counts = np.bincount(key, minlength=S * nx * ny).reshape(S, nx * ny)
    flat = np.r_[0, np.cumsum(counts)]
    cell_ptr = np.empty((S, nx * ny + 1), np.int64)
    for s in range(S):
        cell_ptr[s] = flat[s * nx * ny:(s + 1) * nx * ny + 1]
    return PeopleGrid(np.ascontiguousarray(xy, np.float64), cell_ptr, items, x0, y0, g, nx, ny, r,
                      float(crowds.height))


@numba.njit(cache=True, inline="always")
def _cell_blocks(ax, ay, dx, dy, bx, by, lo, hi, xy, items, ptr0, ptr1, r):  # pragma: no cover - compiled
    """True when a person listed in a cell (items[ptr0:ptr1]) cuts the plan segment
    (ax, ay) + t (dx, dy), t in [lo, hi], and is not the person at the target (bx, by)."""
    r2 = r * r
    aa = dx * dx + dy * dy
    for k in range(ptr0, ptr1):
        p = items[k]
        qx, qy = xy[p, 0], xy[p, 1]
        ex, ey = qx - bx, qy - by
        if ex * ex + ey * ey < r2:
            continue  # the person standing at the target: the one to be seen
        fx, fy = ax - qx, ay - qy
        cc = fx * fx + fy * fy - r2
        if aa < 1e-18:
            if cc < 0.0:
                return True
            continue
        bb = 2.0 * (dx * fx + dy * fy)
        disc = bb * bb - 4.0 * aa * cc
        if disc <= 0.0:
            continue
        sq = math.sqrt(disc)
        t1 = (-bb - sq) / (2.0 * aa)
        t2 = (-bb + sq) / (2.0 * aa)
        if max(t1, lo) < min(t2, hi) - 1e-12:
            return True
    return False


@numba.njit(cache=True)
def segment_blocked(ax, ay, az, bx, by, bz, xy, items, ptr, x0, y0, g, nx, ny, r, h):  # pragma: no cover
    """True when a person's cylinder (radius r, z in [0, h]) cuts the segment from camera
    (ax, ay, az) to target (bx, by, bz) (m); ptr: (nx · ny + 1,) one sample's cell offsets
    into items; the person whose disc holds (bx, by) is left out."""
    dx, dy, dz = bx - ax, by - ay, bz - az
    if abs(dz) < 1e-15:
        if az < 0.0 or az > h:
            return False
        lo, hi = 0.0, 1.0
    else:
        ta, tb = (0.0 - az) / dz, (h - az) / dz
        lo, hi = max(0.0, min(ta, tb)), min(1.0, max(ta, tb))
        if lo >= hi:
            return False
    px, py = ax + lo * dx, ay + lo * dy
    qx, qy = ax + hi * dx, ay + hi * dy
    ix = min(max(int(math.floor((px - x0) / g)), 0), nx - 1)
    iy = min(max(int(math.floor((py - y0) / g)), 0), ny - 1)
    jx = min(max(int(math.floor((qx - x0) / g)), 0), nx - 1)
    jy = min(max(int(math.floor((qy - y0) / g)), 0), ny - 1)
    ddx, ddy = qx - px, qy - py
    sx = 1 if ddx > 0 else -1
    sy = 1 if ddy > 0 else -1
    inf = 1e300
    if ddx != 0.0:
        tmx = ((x0 + (ix + (1 if sx > 0 else 0)) * g) - px) / ddx
        tdx = g / abs(ddx)
    else:
        tmx, tdx = inf, inf
    if ddy != 0.0:
        tmy = ((y0 + (iy + (1 if sy > 0 else 0)) * g) - py) / ddy
        tdy = g / abs(ddy)
    else:
        tmy, tdy = inf, inf
    steps = abs(jx - ix) + abs(jy - iy) + 1
    for _ in range(steps):
        c = ix * ny + iy
        if ptr[c + 1] > ptr[c] and _cell_blocks(ax, ay, dx, dy, bx, by, lo, hi, xy, items, ptr[c], ptr[c + 1], r):
            return True
        if ix == jx and iy == jy:
            break
        if (tmx < tmy and ix != jx) or iy == jy:
            tmx += tdx
            ix += sx
        else:
            tmy += tdy
            iy += sy
    return False


@numba.njit(cache=True, nogil=True)
def _keep_parts(keep, base, indptr, indices, row0, order, group_ptr, parts, n_parts, n_p, cams, tgts, xy, items,
                ptr, x0, y0, g, nx, ny, r, h):  # pragma: no cover - compiled
    """Fill ``keep`` (entries from ``base``) for the position groups k = part, part + n_parts, ...
    of each part in ``parts``: each (position, target) segment tested once for the whole
    group (rows order[group_ptr[k]:group_ptr[k + 1]] + row0); ``slot``: n_p ints, -1 where
    the target is not yet tested."""
    n_groups = group_ptr.shape[0] - 1
    slot = np.full(n_p, -1, np.int32)
    for part in parts:
        for k in range(part, n_groups, n_parts):
            rows = order[group_ptr[k]:group_ptr[k + 1]] + row0
            total = 0
            for i in rows:
                total += indptr[i + 1] - indptr[i]
            if total == 0:
                continue
            seen = np.empty(total, np.int32)
            blocked = np.empty(total, np.bool_)
            m = 0
            ax, ay, az = cams[rows[0], 0], cams[rows[0], 1], cams[rows[0], 2]
            for i in rows:
                for e in range(indptr[i], indptr[i + 1]):
                    j = indices[e]
                    q = slot[j]
                    if q < 0:
                        q = m
                        slot[j] = m
                        seen[m] = j
                        blocked[m] = segment_blocked(ax, ay, az, tgts[j, 0], tgts[j, 1], tgts[j, 2], xy, items, ptr,
                                                     x0, y0, g, nx, ny, r, h)
                        m += 1
                    keep[e - base] = not blocked[q]
            for q in range(m):
                slot[seen[q]] = -1


MIN_PARTS = 4  # position groups per thread at least (camplace.core.executors.on_threads)


def position_groups(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows (n,) of equal camera positions (n, 3) together: (order (n,) int64, group_ptr (G + 1,) int64)."""
    if len(positions) == 0:
        return np.zeros(0, np.int64), np.zeros(1, np.int64)
    _, inv = np.unique(np.asarray(positions, np.float64), axis=0, return_inverse=True)
    inv = inv.ravel()
    order = np.argsort(inv, kind="stable").astype(np.int64)
    return order, np.r_[0, np.cumsum(np.bincount(inv))].astype(np.int64)


def sample_rows(V: sp.csr_matrix, cam_positions: np.ndarray, target_positions: np.ndarray, grid: PeopleGrid,
                s: int, row0: int = 0, row1: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """V_s rows [row0, row1) as CSR pieces (indptr (rows + 1,) int64 from 0, indices int32);
    V's indices sorted within each row."""
    row1 = V.shape[0] if row1 is None else row1
    indptr = np.asarray(V.indptr, np.int64)
    indices = np.asarray(V.indices, np.int32)
    lo, hi = int(indptr[row0]), int(indptr[row1])
    if hi == lo or grid.cell_ptr[s, -1] == grid.cell_ptr[s, 0]:  # nothing to test, or nobody in this sample
        return indptr[row0:row1 + 1] - lo, indices[lo:hi].copy()
    cams = np.ascontiguousarray(cam_positions, np.float64)
    order, group_ptr = position_groups(cams[row0:row1])
    n_parts = max(1, min(len(group_ptr) - 1, 4 * numba.get_num_threads()))
    keep = np.ones(hi - lo, np.bool_)
    args = (indptr, indices, row0, order, group_ptr)
    rest = (int(V.shape[1]), cams, np.ascontiguousarray(target_positions, np.float64), grid.xy, grid.items,
            grid.cell_ptr[s], grid.x0, grid.y0, grid.cell, grid.nx, grid.ny, grid.radius, grid.height)
    # serial nogil kernel on threads: the parts write disjoint entries of keep
    on_threads(n_parts, lambda a, b: _keep_parts(keep, lo, *args, np.arange(a, b, dtype=np.int64), n_parts, *rest),
               MIN_PARTS)
    rows = np.repeat(np.arange(row1 - row0), np.diff(indptr[row0:row1 + 1]))
    out_ptr = np.r_[0, np.cumsum(np.bincount(rows[keep], minlength=row1 - row0))].astype(np.int64)
    return out_ptr, indices[lo:hi][keep]


def _block(shared: tuple, bounds: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """One executor task: rows [start, stop) of the vertical stack (inside one sample)."""
    V, cams, tgts, grid = shared
    n = V.shape[0]
    s = bounds[0] // n
    return sample_rows(V, cams, tgts, grid, s, bounds[0] - s * n, bounds[1] - s * n)


def crowd_rows(V: sp.csr_matrix, cam_positions: np.ndarray, target_positions: np.ndarray, crowds: Crowds, *,
               executor=None, chunk_size: int = CHUNK_ROWS, progress=None,
               grid: PeopleGrid | None = None) -> sp.csr_matrix:
    """(S · n, N_p) CSR uint8: rows s · n .. (s + 1) · n - 1 are V_s of V's n rows
    (cam_positions (n, 3), target_positions (N_p, 3) m). ``executor``: as for V
    (camplace.core.executors; default in-process); ``progress("crowd", done, total)``."""
    from camplace.visibility.engine import chunked_rows

    V = sp.csr_matrix(V)
    if not V.has_sorted_indices:
        V = V.sorted_indices()
    n, n_p = V.shape
    S = crowds.n_samples
    if grid is None:
        pts = np.r_[np.asarray(cam_positions, float).reshape(-1, 3), np.asarray(target_positions, float)]
        lo = pts[:, :2].min(0) if len(pts) else np.zeros(2)
        hi = pts[:, :2].max(0) if len(pts) else np.zeros(2)
        grid = people_grid(crowds, lo, hi)
    step = max(1, int(chunk_size))
    bounds = [(s * n + a, s * n + min(a + step, n)) for s in range(S) for a in range(0, n, step)]
    if not bounds:
        return sp.csr_matrix((S * n, n_p), dtype=np.uint8)
    shared = (V, np.asarray(cam_positions, np.float64), np.asarray(target_positions, np.float64), grid)
    cb = None if progress is None else (lambda _stage, done, total: progress("crowd", done, total))
    out, _ = chunked_rows(n_p, bounds, _block, lambda: shared, executor, None, cb)
    return out
