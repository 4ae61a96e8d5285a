"""The ``voxel`` visibility engine (default, fast): the centre test per target.

For each candidate, the targets within range, inside the image (lens model) and, for
surfaces, seen from their outer side within the incidence limit, are tested for line of
sight with a 3D DDA (camplace.visibility.raywalk) through the occupancy grid; a target
is seen if no occupied cell lies between the camera and it. One fused numba kernel per
block of candidates, parallel over candidates, returns the block's CSR pieces
(``VoxelEngine.rows``); camplace.visibility.engine.compute_visibility maps the blocks over
an executor and the cache.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numba
import numpy as np
import scipy.sparse as sp

from camplace.cameras.models import project_nb, px_per_m_nb
from camplace.core.errors import InputError
from camplace.spec.quality import target_min_px
from camplace.cameras.candidates import Candidates
from camplace.scene.build import OccupancyGrid
from camplace.targets.build import Targets
from camplace.visibility import engine as _engine
from camplace.visibility.engine import Progress, Visibility, drop_blind_candidates  # noqa: F401 (re-exported)
from camplace.visibility.raywalk import dda_axis, dda_step, segment_clear  # noqa: F401 (re-exported)

SURFACE_OFFSET = 0.75  # surface rays end this many occupancy cells outside the face
DEFAULT_CHUNK = 2048  # candidate rows per block


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


@dataclass(frozen=True)
class VoxelEngine:
    """The centre test (see the module docstring). probe: the part of a target's voxel a
    line of sight must reach, as a fraction of its edge: only 0 (the target's centre) is
    implemented; voxel_size: the target voxel edge (m; enters only a probe > 0 rule);
    chunk_size: candidate rows per block; grid_cell: range-culling cell (m; None = the
    smallest range / 8, ``np.inf`` = no culling; V does not depend on it)."""

    probe: float = 0.0
    voxel_size: float | None = None
    chunk_size: int = DEFAULT_CHUNK
    grid_cell: float | None = None
    mode = "voxel"

    def __post_init__(self) -> None:
        if float(self.probe) != 0.0:
            raise InputError(f"probe: the voxel engine implements probe 0 (the target's centre) only, got "
                             f"{self.probe}; the pixel engine takes probe in [0, 1]", option="probe")
        _engine.check_chunk_size(self.chunk_size)

    def cache_tag(self) -> str:
        return f"voxel:probe={float(self.probe)!r}"

    def code_modules(self) -> tuple:
        import sys

        return (sys.modules[__name__],)

    def setup(self, occupancy: OccupancyGrid, targets: Targets, candidates: Candidates) -> tuple:
        """(occupancy, targets, candidates, the targets' range-culling grid)."""
        cell = default_grid_cell(candidates) if self.grid_cell is None else self.grid_cell
        return occupancy, targets, candidates, target_grid(targets, cell)

    def rows(self, shared: tuple, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
        occupancy, targets, candidates, grid = shared
        return _block_arrays(occupancy, targets, candidates, start, stop, grid)

    def info(self, candidates: Candidates, bounds: list, computed: list, seconds: float, shared: Any) -> dict:
        return {}


def compute_visibility(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                       chunk_size: int = DEFAULT_CHUNK, progress: Progress | None = None, executor=None,
                       cache_dir: str | Path | None = None, grid_cell: float | None = None) -> Visibility:
    """V for every candidate by the voxel engine (rows in candidate order):
    ``camplace.visibility.engine.compute_visibility(VoxelEngine(chunk_size=chunk_size,
    grid_cell=grid_cell), ...)``. The result does not depend on chunk_size, executor,
    cache or grid_cell."""
    return _engine.compute_visibility(VoxelEngine(chunk_size=chunk_size, grid_cell=grid_cell), occupancy, targets,
                                      candidates, executor=executor, cache_dir=cache_dir, progress=progress)
