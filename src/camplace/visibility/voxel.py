"""Stage 4 - visibility: the sparse matrix V (N_g x N_p) of which candidate sees which target.

``voxel`` mode (default): for each candidate, the targets within range, inside the image
(lens model) and, for surfaces, seen from their outer side within the incidence limit,
are tested for line of sight with a 3D DDA (Amanatides & Woo) through the occupancy
grid; a target is seen if no occupied cell lies between the camera and it. One fused
numba kernel per chunk of candidates, parallel over candidates; chunks map over a
local executor. V is built as CSR straight from the kernel (never dense).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numba
import numpy as np
import scipy.sparse as sp

from camplace.cameras.models import project_nb, px_per_m_nb
from camplace.spec.quality import target_min_px
from camplace.cameras.candidates import Candidates
from camplace.scene.build import OccupancyGrid
from camplace.targets.build import Targets

Progress = Callable[[str, int, int], None]
SURFACE_OFFSET = 0.75  # surface rays end this many occupancy cells outside the face


@dataclass(frozen=True)
class Visibility:
    """V: (N_g, N_p) CSR uint8, 1 where candidate i sees target j; rows follow
    ``candidates``, columns follow ``targets``."""

    V: sp.csr_matrix
    candidates: Candidates
    targets: Targets
    mode: str = "voxel"
    info: dict = field(default_factory=dict)


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
def _passes_view(cam_p, R, params, tx, ty, tz, nx_, ny_, nz_, cos_max, min_px=0.0):
    """Range, image, incidence and pixel-density (``min_px`` px/m, 0 = none) tests of one
    (camera, target) pair."""
    vx, vy, vz = tx - cam_p[0], ty - cam_p[1], tz - cam_p[2]
    d2 = vx * vx + vy * vy + vz * vz
    rng = params[7]
    if d2 > rng * rng or d2 <= 1e-18:
        return False
    # camera frame: p_cam = R^T v
    xc = R[0, 0] * vx + R[1, 0] * vy + R[2, 0] * vz
    yc = R[0, 1] * vx + R[1, 1] * vy + R[2, 1] * vz
    zc = R[0, 2] * vx + R[1, 2] * vy + R[2, 2] * vz
    _, _, ok = project_nb(params, xc, yc, zc)
    if not ok:
        return False
    if nx_ != 0.0 or ny_ != 0.0 or nz_ != 0.0:
        c = -(vx * nx_ + vy * ny_ + vz * nz_) / math.sqrt(d2)  # cos of incidence (view ray vs normal)
        if c <= 0.0 or c < cos_max:
            return False
    if min_px > 0.0:
        # density on the surface plane (normal in the camera frame) or across the view ray
        nxc = R[0, 0] * nx_ + R[1, 0] * ny_ + R[2, 0] * nz_
        nyc = R[0, 1] * nx_ + R[1, 1] * ny_ + R[2, 1] * nz_
        nzc = R[0, 2] * nx_ + R[1, 2] * ny_ + R[2, 2] * nz_
        if px_per_m_nb(params, xc, yc, zc, nxc, nyc, nzc) < min_px:
            return False
    return True


@numba.njit(cache=True, inline="always")
def _cell_span(lo: float, cell: float, n: int, p: float, rng: float) -> tuple[int, int]:
    """Index range [a, b] of the grid cells along one axis within rng of coordinate p."""
    a = int(math.floor((p - rng - lo) / cell))
    b = int(math.floor((p + rng - lo) / cell))
    return max(a, 0), min(b, n - 1)


@numba.njit(cache=True, inline="always")
def _cell_near(grid, cx: int, cy: int, px: float, py: float, rng: float) -> bool:
    """True if the xy rectangle of cell (cx, cy) comes within rng (+1 um) of (px, py)."""
    x0, y0, c = grid[0], grid[1], grid[2]
    dx = max(x0 + cx * c - px, 0.0, px - (x0 + (cx + 1) * c))
    dy = max(y0 + cy * c - py, 0.0, py - (y0 + (cy + 1) * c))
    r = rng + 1e-6
    return dx * dx + dy * dy <= r * r


@numba.njit(cache=True, parallel=True)
def _visibility_kernel(occ, origin, res, cam_pos, cam_rot, cam_ids, cam_params,
                       tpos, tnrm, tcos, grid, cell_start, cell_tids, tpx):
    """CSR (indptr, indices) of V for a chunk of candidates, indices ascending per row.

    Targets are bucketed in an xy grid (``grid`` = [x0, y0, cell, nx, ny], CSR
    ``cell_start`` / ``cell_tids``, see ``target_grid``): each candidate visits only the
    cells within its max range, so the work scales with the visible pairs, not N_g x N_p."""
    n_c = cam_pos.shape[0]
    gnx, gny = int(grid[3]), int(grid[4])
    counts = np.zeros(n_c, np.int64)
    for i in numba.prange(n_c):
        params = cam_params[cam_ids[i]]
        p = cam_pos[i]
        ax, bx = _cell_span(grid[0], grid[2], gnx, p[0], params[7])
        ay, by = _cell_span(grid[1], grid[2], gny, p[1], params[7])
        k = 0
        for cx in range(ax, bx + 1):
            for cy in range(ay, by + 1):
                if not _cell_near(grid, cx, cy, p[0], p[1], params[7]):
                    continue
                cell = cx * gny + cy
                for q in range(cell_start[cell], cell_start[cell + 1]):
                    j = cell_tids[q]
                    if _passes_view(cam_pos[i], cam_rot[i], params, tpos[j, 0], tpos[j, 1], tpos[j, 2],
                                    tnrm[j, 0], tnrm[j, 1], tnrm[j, 2], tcos[j], tpx[j]):
                        k += 1
        counts[i] = k
    offs = np.zeros(n_c + 1, np.int64)
    for i in range(n_c):
        offs[i + 1] = offs[i] + counts[i]
    buf = np.empty(offs[n_c], np.int32)
    seen = np.zeros(n_c, np.int64)
    off_len = SURFACE_OFFSET * res
    for i in numba.prange(n_c):
        params = cam_params[cam_ids[i]]
        p = cam_pos[i]
        k = offs[i]
        ax, bx = _cell_span(grid[0], grid[2], gnx, p[0], params[7])
        ay, by = _cell_span(grid[1], grid[2], gny, p[1], params[7])
        for cx in range(ax, bx + 1):
            for cy in range(ay, by + 1):
                if not _cell_near(grid, cx, cy, p[0], p[1], params[7]):
                    continue
                cell = cx * gny + cy
                for q in range(cell_start[cell], cell_start[cell + 1]):
                    j = cell_tids[q]
                    nx_, ny_, nz_ = tnrm[j, 0], tnrm[j, 1], tnrm[j, 2]
                    if not _passes_view(p, cam_rot[i], params, tpos[j, 0], tpos[j, 1], tpos[j, 2], nx_, ny_, nz_, tcos[j],
                                        tpx[j]):
                        continue
                    ex = tpos[j, 0] + nx_ * off_len
                    ey = tpos[j, 1] + ny_ * off_len
                    ez = tpos[j, 2] + nz_ * off_len
                    if segment_clear(occ, origin[0], origin[1], origin[2], res, p[0], p[1], p[2], ex, ey, ez):
                        buf[k] = j
                        k += 1
        seen[i] = k - offs[i]
        buf[offs[i]:k].sort()  # cells are visited out of id order: restore ascending ids
    indptr = np.zeros(n_c + 1, np.int64)
    for i in range(n_c):
        indptr[i + 1] = indptr[i] + seen[i]
    indices = np.empty(indptr[n_c], np.int32)
    for i in numba.prange(n_c):
        indices[indptr[i]:indptr[i + 1]] = buf[offs[i]:offs[i] + seen[i]]
    return indptr, indices


def target_cos_limits(targets: Targets) -> np.ndarray:
    """(N_p,) cosine of each target's incidence limit (-1 = no limit, volume targets)."""
    lim = np.cos(np.radians(targets.max_incidence_deg))[targets.region_ids]
    return np.where(targets.is_surface, lim - 1e-12, -1.0)


GRID_CELLS_PER_RANGE = 8  # target-grid cell = smallest max range / this (m)
BRUTE_FORCE_CELL = 1e300  # one cell holding every target: the kernel visits all of them


@dataclass(frozen=True)
class TargetGrid:
    """Targets bucketed by xy cell, for range culling. params: [x0, y0, cell, nx, ny]
    float64 (m, m, m, count, count); cell_start: (nx * ny + 1,) int64 CSR offsets;
    cell_tids: (N_p,) int32 target ids by cell (x-major), ascending inside a cell."""

    params: np.ndarray
    cell_start: np.ndarray
    cell_tids: np.ndarray


def target_grid(targets: Targets, cell: float) -> TargetGrid:
    """Bucket the targets in square xy cells of ``cell`` metres (``np.inf`` = one cell)."""
    pos = np.asarray(targets.positions, np.float64)
    cell = BRUTE_FORCE_CELL if not np.isfinite(cell) else float(cell)
    if cell <= 0:
        raise ValueError(f"target grid cell must be > 0 m, got {cell}")
    if len(pos) == 0:
        return TargetGrid(np.array([0.0, 0.0, cell, 1.0, 1.0]), np.zeros(2, np.int64), np.zeros(0, np.int32))
    lo = pos[:, :2].min(0)
    hi = pos[:, :2].max(0)
    n = np.maximum(np.floor((hi - lo) / cell).astype(np.int64) + 1, 1)
    c = np.clip(np.floor((pos[:, :2] - lo) / cell).astype(np.int64), 0, n - 1)
    key = c[:, 0] * n[1] + c[:, 1]
    order = np.argsort(key, kind="stable").astype(np.int32)
    start = np.zeros(int(n[0] * n[1]) + 1, np.int64)
    np.cumsum(np.bincount(key, minlength=int(n[0] * n[1])), out=start[1:])
    return TargetGrid(np.array([lo[0], lo[1], cell, float(n[0]), float(n[1])]), start, order)


def default_grid_cell(candidates: Candidates) -> float:
    """Grid cell (m) for range culling: the smallest camera range / GRID_CELLS_PER_RANGE."""
    rng = min((c.max_range for c in candidates.cameras), default=1.0)
    return max(rng / GRID_CELLS_PER_RANGE, 0.05)


def visibility_block(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                     start: int, stop: int, grid: TargetGrid | None = None) -> sp.csr_matrix:
    """V rows [start, stop) as a CSR block (stop - start, N_p). ``grid``: the targets'
    range-culling grid (built here when None; ``target_grid(targets, np.inf)`` = no culling)."""
    indptr, indices = _block_arrays(occupancy, targets, candidates, start, stop, grid)
    data = np.ones(len(indices), dtype=np.uint8)
    return sp.csr_matrix((data, indices, indptr), shape=(stop - start, len(targets)))


def _block_arrays(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                  start: int, stop: int, grid: TargetGrid | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(indptr (rows + 1,) int64, indices (nnz,) int32) of V rows [start, stop)."""
    if grid is None:
        grid = target_grid(targets, default_grid_cell(candidates))
    occ = occupancy.occupied.view(np.uint8)
    params = np.stack([c.params for c in candidates.cameras])
    indptr, indices = _visibility_kernel(
        occ, occupancy.origin.astype(np.float64), float(occupancy.resolution),
        np.ascontiguousarray(candidates.positions[start:stop], dtype=np.float64),
        np.ascontiguousarray(candidates.rotations[start:stop], dtype=np.float64),
        np.ascontiguousarray(candidates.camera_ids[start:stop], dtype=np.int64), params,
        np.ascontiguousarray(targets.positions, dtype=np.float64),
        np.ascontiguousarray(targets.normals, dtype=np.float64), target_cos_limits(targets),
        grid.params, grid.cell_start, grid.cell_tids, target_min_px(targets))
    return indptr, indices


def _chunk_task(shared: tuple, bounds: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """One unit of work for an executor: shared = (occupancy, targets, candidates, grid)."""
    occupancy, targets, candidates, grid = shared
    return _block_arrays(occupancy, targets, candidates, bounds[0], bounds[1], grid)


def visibility_cache_key(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                         mode: str, chunk_size: int, extra_modules: tuple = ()) -> str:
    """Content hash of everything V depends on, code version included. ``mode`` names the
    method and its parameters; ``extra_modules``: more modules whose code decides V."""
    from camplace.cameras import models as _cameras_mod
    from camplace.spec import quality as _quality_mod
    from camplace.visibility import voxel as _vis_mod
    from camplace.visibility.cache import code_version, content_key

    mods = (_vis_mod, _cameras_mod, _quality_mod, *extra_modules)  # the code that decides V
    occ = OccupancyGrid(np.packbits(occupancy.occupied, axis=None), occupancy.origin, occupancy.resolution)
    return content_key("visibility", code_version(*mods), mode, int(chunk_size),
                       occupancy.occupied.shape, occ, targets, candidates)


def chunked_rows(n_cols: int, bounds: list[tuple[int, int]], task: Callable, make_shared: Callable[[], object],
                 executor=None, store=None, progress: Progress | None = None) -> tuple[sp.csr_matrix, list[int]]:
    """A CSR 0/1 matrix (uint8) built as row blocks: block k (rows bounds[k]) is
    ``task(shared, bounds[k])`` -> (indptr (rows + 1,) int64, indices (nnz,) int32).

    The blocks not in ``store`` (a camplace.visibility.cache.BlockStore, or None) run on ``executor``
    (camplace.visibility.executors; default in-process) and are stored as they arrive; ``shared``
    = ``make_shared()`` is built only when a block must be computed. The matrix is then
    assembled block by block (from the store when there is one), never densified.
    Returns (matrix, indices of the blocks loaded from the store)."""
    from camplace.visibility.executors import InProcessExecutor

    n = bounds[-1][1] if bounds else 0
    blocks: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    nnz = np.zeros(len(bounds), np.int64)
    todo, cached = [], []
    for k in range(len(bounds)):
        got = store.nnz(k) if store is not None else None
        if got is None:
            todo.append(k)
        else:
            nnz[k] = got
            cached.append(k)
    done = len(cached)
    if progress:
        progress("visibility", done, len(bounds))
    shared = None
    if todo:
        shared = make_shared()
        ex = executor if executor is not None else InProcessExecutor()
        for t, (indptr, indices) in ex.map_unordered(task, shared, [bounds[k] for k in todo]):
            k = todo[t]
            nnz[k] = len(indices)
            if store is not None:
                store.save(k, indptr, indices)
            else:
                blocks[k] = (indptr, indices)
            done += 1
            if progress:
                progress("visibility", done, len(bounds))
    indptr = np.zeros(n + 1, np.int64)
    indices = np.empty(int(nnz.sum()), np.int32)
    pos = 0
    for k, (s, e) in enumerate(bounds):
        blk = blocks.pop(k) if store is None else store.load(k)
        if blk is None:  # pragma: no cover - a block vanished from the cache during the run
            shared = make_shared() if shared is None else shared
            blk = task(shared, (s, e))
        bp, bi = blk
        indptr[s + 1:e + 1] = bp[1:] + pos
        indices[pos:pos + len(bi)] = bi
        pos += len(bi)
    V = sp.csr_matrix((np.ones(len(indices), np.uint8), indices, indptr), shape=(n, n_cols))
    return V, cached


def compute_visibility(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                       chunk_size: int = 2048, progress: Progress | None = None, executor=None,
                       cache_dir: str | Path | None = None, grid_cell: float | None = None) -> Visibility:
    """V for every candidate (rows in candidate order).

    Candidates are processed in chunks of ``chunk_size`` rows, the unit of work of the
    ``executor`` (camplace.visibility.executors; default in-process; inside a chunk the kernel
    runs parallel threads). Chunks stream back as CSR blocks and are copied into the
    final CSR arrays, never densified. With ``cache_dir`` each block is also stored
    under a content-hash key (camplace.visibility.cache): finished blocks are loaded instead of
    recomputed (a second run, or a run resumed after an interruption), and V is then
    assembled block by block from disk (peak memory ~ one V + one block; without the
    cache, the blocks and V coexist during the assembly). ``grid_cell``: range-culling
    cell (m; default smallest range / 8; ``np.inf`` disables culling). The result does
    not depend on executor, cache or grid_cell."""
    t0 = time.perf_counter()
    n, n_p = len(candidates), len(targets)
    bounds = [(s, min(s + chunk_size, n)) for s in range(0, n, chunk_size)]
    store = None
    if cache_dir is not None:
        from camplace.visibility.cache import BlockStore

        key = visibility_cache_key(occupancy, targets, candidates, "voxel", chunk_size)
        store = BlockStore(cache_dir, key, bounds, n_p)

    def make_shared() -> tuple:
        grid = target_grid(targets, default_grid_cell(candidates) if grid_cell is None else grid_cell)
        return occupancy, targets, candidates, grid

    V, cached = chunked_rows(n_p, bounds, _chunk_task, make_shared, executor, store, progress)
    info = {"seconds": time.perf_counter() - t0, "nnz": int(V.nnz), "chunks": len(bounds),
            "cached_chunks": len(cached), "executor": getattr(executor, "name", "in-process")}
    if store is not None:
        info["cache"] = str(store.dir)
    return Visibility(V, candidates, targets, "voxel", info)


def drop_blind_candidates(vis: Visibility) -> Visibility:
    """Remove candidates that see no target (rows of V with no entry). The empty rows
    hold no entries, so V's data and indices are shared, not copied."""
    counts = np.diff(vis.V.indptr)
    keep = counts > 0
    info = dict(vis.info, dropped_blind=int((~keep).sum()))
    indptr = np.r_[0, np.cumsum(counts[keep])].astype(vis.V.indptr.dtype)
    V = sp.csr_matrix((vis.V.data, vis.V.indices, indptr), shape=(int(keep.sum()), vis.V.shape[1]), copy=False)
    return Visibility(V, vis.candidates.subset(keep), vis.targets, vis.mode, info)
