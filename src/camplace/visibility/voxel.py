"""The ``voxel`` visibility engine (default, fast): sight lines to each target.

For each candidate, the targets within range, inside the image (lens model) and, for
surfaces, seen from their outer side within the incidence limit, are tested for line of
sight with a 3D DDA (camplace.visibility.raywalk) through the occupancy grid; a target
is seen if no occupied cell lies between the camera and it (``probe`` 0, the centre test).
With ``probe`` p > 0 a target is seen when a sight line reaches any part of its
footprint (camplace.visibility.footprint: the central p x voxel_size cube, or the
patch's face cells): its centre, else a lattice of points on the cube faces turned to
the camera, or the patch's face-cell centres, each tested for range, image, incidence
and line of sight (``_probe_kernel``; probe 1 is the pixel engine's and the paper's
rule, docs/lenses.md). One fused numba kernel per
block of candidates (probe 0: camplace.visibility.sightlines.visibility_rows, which culls
the targets by range and view cone first) returns the block's CSR pieces
(``VoxelEngine.rows``); camplace.visibility.engine.compute_visibility maps the blocks over
an executor and the cache.
"""

from __future__ import annotations

import functools
import math
import threading
import weakref
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numba
import numpy as np
import scipy.sparse as sp

from camplace.cameras.models import px_per_m_nb
from camplace.core.errors import InputError
from camplace.core.executors import on_threads
from camplace.spec.quality import target_min_px
from camplace.cameras.candidates import Candidates
from camplace.scene.build import OccupancyGrid
from camplace.targets.build import Targets
from camplace.visibility import engine as _engine
from camplace.visibility import footprint, sightlines
from camplace.visibility.engine import Progress, Visibility, drop_blind_candidates  # noqa: F401 (re-exported)
from camplace.visibility.raywalk import dda_axis, dda_step, segment_clear  # noqa: F401 (re-exported)
from camplace.visibility.sightlines import (SURFACE_OFFSET, _cell_near, _cell_span, _passes_view, cone_limits,
                                            cube_bins, visibility_rows, work_arrays)
DEFAULT_CHUNK = 2048  # candidate rows per block


@numba.njit(cache=True, nogil=True)
def _compact(buf, offs, seen):
    """CSR (indptr, indices) from row pieces: row i holds buf[offs[i]:offs[i] + seen[i]]."""
    n_c = len(seen)
    indptr = np.zeros(n_c + 1, np.int64)
    for i in range(n_c):
        indptr[i + 1] = indptr[i] + seen[i]
    indices = np.empty(indptr[n_c], np.int32)
    for i in range(n_c):  # element by element: a slice assignment compiles its shape-mismatch message (~2 s)
        for k in range(seen[i]):
            indices[indptr[i] + k] = buf[offs[i] + k]
    return indptr, indices


@numba.njit(cache=True, inline="always")
def density_ok(p, R, params, tpos, tnrm, j, min_px):
    """True if target j's centre meets its pixel-density limit ``min_px`` (px/m, 0 = none)
    seen from camera (p, R); computed whether or not the centre projects into the image."""
    if min_px <= 0.0:
        return True
    vx, vy, vz = tpos[j, 0] - p[0], tpos[j, 1] - p[1], tpos[j, 2] - p[2]
    nx_, ny_, nz_ = tnrm[j, 0], tnrm[j, 1], tnrm[j, 2]
    xc = R[0, 0] * vx + R[1, 0] * vy + R[2, 0] * vz
    yc = R[0, 1] * vx + R[1, 1] * vy + R[2, 1] * vz
    zc = R[0, 2] * vx + R[1, 2] * vy + R[2, 2] * vz
    nxc = R[0, 0] * nx_ + R[1, 0] * ny_ + R[2, 0] * nz_
    nyc = R[0, 1] * nx_ + R[1, 1] * ny_ + R[2, 1] * nz_
    nzc = R[0, 2] * nx_ + R[1, 2] * ny_ + R[2, 2] * nz_
    return px_per_m_nb(params, xc, yc, zc, nxc, nyc, nzc) >= min_px


@numba.njit(cache=True, inline="always")
def _sight(occ, origin, res, p, R, params, qx, qy, qz, nx_, ny_, nz_, cos_max, off_len):
    """Sample point q of a target footprint seen from camera (p, R): in range, in the
    image, (surfaces, normal n) within the incidence limit, and a clear segment to q
    (surfaces: to q + n off_len, just outside the face)."""
    if not _passes_view(p, R, params, qx, qy, qz, nx_, ny_, nz_, cos_max, 0.0):
        return False
    return segment_clear(occ, origin[0], origin[1], origin[2], res, p[0], p[1], p[2],
                         qx + nx_ * off_len, qy + ny_ * off_len, qz + nz_ * off_len)


@numba.njit(cache=True, inline="always")
def _part_seen(occ, origin, res, p, R, params, tpos, tnrm, tcos, tpx, j, half, lattice, s_start, s_pts):
    """True if a sight line reaches any sampled part of target j's footprint: its centre
    (the probe-0 test), else (density limit met at the centre) a lattice point on a face
    of its cube (half-edge ``half`` m) that faces the camera, or a face-cell point of
    its patch (surfaces)."""
    cx, cy, cz = tpos[j, 0], tpos[j, 1], tpos[j, 2]
    nx_, ny_, nz_ = tnrm[j, 0], tnrm[j, 1], tnrm[j, 2]
    off_len = SURFACE_OFFSET * res
    if _passes_view(p, R, params, cx, cy, cz, nx_, ny_, nz_, tcos[j], tpx[j]) and segment_clear(
            occ, origin[0], origin[1], origin[2], res, p[0], p[1], p[2],
            cx + nx_ * off_len, cy + ny_ * off_len, cz + nz_ * off_len):
        return True
    if not density_ok(p, R, params, tpos, tnrm, j, tpx[j]):
        return False
    if nx_ != 0.0 or ny_ != 0.0 or nz_ != 0.0:
        for s in range(s_start[j], s_start[j + 1]):
            if _sight(occ, origin, res, p, R, params, s_pts[s, 0], s_pts[s, 1], s_pts[s, 2],
                      nx_, ny_, nz_, tcos[j], off_len):
                return True
        return False
    rx, ry, rz = p[0] - cx, p[1] - cy, p[2] - cz
    if abs(rx) <= half and abs(ry) <= half and abs(rz) <= half:
        return True  # the camera is inside the cube
    for s in range(lattice.shape[0]):
        ux, uy, uz = lattice[s, 0], lattice[s, 1], lattice[s, 2]
        if not ((ux == 1.0 and rx > half) or (ux == -1.0 and rx < -half) or (uy == 1.0 and ry > half)
                or (uy == -1.0 and ry < -half) or (uz == 1.0 and rz > half) or (uz == -1.0 and rz < -half)):
            continue  # on no face turned to the camera: a clear line to it crosses a front face first
        if _sight(occ, origin, res, p, R, params, cx + half * ux, cy + half * uy, cz + half * uz,
                  0.0, 0.0, 0.0, -1.0, 0.0):
            return True
    return False


@numba.njit(cache=True, parallel=True)
def _probe_kernel(occ, origin, res, cam_pos, cam_rot, cam_ids, cam_params, tpos, tnrm, tcos, tpx,
                  grid, cell_start, cell_tids, half, pad, lattice, s_start, s_pts):
    """CSR (indptr, indices) of V under the any-part rule (``_part_seen``) for a chunk of
    candidates, each row in cell order (``_sorted_rows`` sorts them). Pass 1 bounds each row by
    the targets within range + ``pad`` (m, the footprints' reach from their centres); pass 2 tests them."""
    n_c = cam_pos.shape[0]
    gnx, gny = int(grid[3]), int(grid[4])
    counts = np.zeros(n_c, np.int64)
    for i in numba.prange(n_c):
        p = cam_pos[i]
        reach = cam_params[cam_ids[i]][7] + pad
        ax, bx = _cell_span(grid[0], grid[2], gnx, p[0], reach)
        ay, by = _cell_span(grid[1], grid[2], gny, p[1], reach)
        k = 0
        for cx in range(ax, bx + 1):
            for cy in range(ay, by + 1):
                if _cell_near(grid, cx, cy, p[0], p[1], reach):
                    k += cell_start[cx * gny + cy + 1] - cell_start[cx * gny + cy]
        counts[i] = k
    offs = np.zeros(n_c + 1, np.int64)
    for i in range(n_c):
        offs[i + 1] = offs[i] + counts[i]
    buf = np.empty(offs[n_c], np.int32)
    seen = np.zeros(n_c, np.int64)
    for i in numba.prange(n_c):
        params = cam_params[cam_ids[i]]
        p, R = cam_pos[i], cam_rot[i]
        reach = params[7] + pad
        k = offs[i]
        ax, bx = _cell_span(grid[0], grid[2], gnx, p[0], reach)
        ay, by = _cell_span(grid[1], grid[2], gny, p[1], reach)
        for cx in range(ax, bx + 1):
            for cy in range(ay, by + 1):
                if not _cell_near(grid, cx, cy, p[0], p[1], reach):
                    continue
                cell = cx * gny + cy
                for q in range(cell_start[cell], cell_start[cell + 1]):
                    j = cell_tids[q]
                    dx, dy, dz = tpos[j, 0] - p[0], tpos[j, 1] - p[1], tpos[j, 2] - p[2]
                    if dx * dx + dy * dy + dz * dz > reach * reach:
                        continue
                    if _part_seen(occ, origin, res, p, R, params, tpos, tnrm, tcos, tpx, j, half, lattice,
                                  s_start, s_pts):
                        buf[k] = j
                        k += 1
        seen[i] = k - offs[i]
    return _compact(buf, offs, seen)  # ids in cell order: _sorted_rows sorts them


def _sorted_rows(indptr: np.ndarray, indices: np.ndarray, n_cols: int) -> tuple[np.ndarray, np.ndarray]:
    """(indptr, indices) with each row's indices ascending, sorted in place by scipy's CSR sort
    (the kernels visit targets cell by cell, out of id order; sorting inside a kernel compiled
    numba's quicksort, ~1 s on a new install)."""
    m = sp.csr_matrix((np.ones(len(indices), np.uint8), indices, indptr), shape=(len(indptr) - 1, n_cols), copy=False)
    m.sort_indices()
    return indptr, m.indices.astype(np.int32, copy=False)


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


_MEMO: dict = {}  # per-targets arrays of the last Targets seen: refine raycasts a few poses at a time
_MEMO_LOCK = threading.Lock()


def _of_targets(targets: Targets, key, build):
    """``build()``, remembered for the last ``targets`` object (by identity, while it lives;
    Targets is frozen) and ``key``."""
    with _MEMO_LOCK:
        ref = _MEMO.get("targets")
        if ref is None or ref() is not targets:
            _MEMO.clear()
            _MEMO["targets"] = weakref.ref(targets)
        if key not in _MEMO:
            _MEMO[key] = build()
        return _MEMO[key]


def target_grid(targets: Targets, cell: float) -> TargetGrid:
    """Bucket the targets in square xy cells of ``cell`` metres (``np.inf`` = one cell)."""
    return _of_targets(targets, ("grid", float(cell)), lambda: _target_grid(targets, cell))


def _target_grid(targets: Targets, cell: float) -> TargetGrid:
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


@functools.cache
def _bins() -> np.ndarray:
    """The direction bins the kernel culls by view cone with (camplace.visibility.sightlines.cube_bins)."""
    return cube_bins()


def _block_arrays(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                  start: int, stop: int, grid: TargetGrid | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(indptr (rows + 1,) int64, indices (nnz,) int32) of V rows [start, stop), in pieces on
    threads (camplace.core.executors.on_threads; the kernel releases the GIL)."""
    if grid is None:
        grid = target_grid(targets, default_grid_cell(candidates))
    occ = occupancy.occupied.view(np.uint8)
    params = np.stack([c.params for c in candidates.cameras])
    pos, nrm, cos, min_px = _of_targets(targets, "arrays", lambda: (
        np.ascontiguousarray(targets.positions, dtype=np.float64), np.ascontiguousarray(targets.normals, dtype=np.float64),
        target_cos_limits(targets), target_min_px(targets)))
    shared = (pos, nrm, cos, grid.params, grid.cell_start, grid.cell_tids, min_px)
    origin, res = occupancy.origin.astype(np.float64), float(occupancy.resolution)
    limits = cone_limits(params, _bins())

    def piece(a: int, b: int) -> tuple[np.ndarray, np.ndarray]:
        a, b = start + a, start + b
        cp, ids = np.ascontiguousarray(candidates.positions[a:b], dtype=np.float64), np.ascontiguousarray(
            candidates.camera_ids[a:b], dtype=np.int64)
        rng = float(params[ids, 7].max(initial=0.0))
        return _sorted_rows(*visibility_rows(
            occ, origin, res, cp, np.ascontiguousarray(candidates.rotations[a:b], dtype=np.float64), ids, params,
            *shared, _bins(), limits, rng, *work_arrays(grid.params, grid.cell_start, cp, rng)), len(pos))

    parts = on_threads(stop - start, piece, min_rows=4)  # refine casts ~8 poses a call: two threads
    if len(parts) == 1:
        return parts[0]
    offsets = np.cumsum([0] + [len(ix) for _, ix in parts])
    indptr = np.concatenate([[0]] + [ip[1:] + off for (ip, _), off in zip(parts, offsets)]).astype(np.int64)
    return indptr, np.concatenate([ix for _, ix in parts]).astype(np.int32, copy=False)


@dataclass(frozen=True)
class ProbeArrays:
    """The footprints the any-part rule samples (camplace.visibility.footprint): half: the
    probe cube's half-edge (m); pad: the farthest sample from its target centre (m);
    lattice: (M, 3) unit cube-surface points; s_start (N_p + 1,) int64 / s_pts (K, 3)
    float64: the surface targets' face-cell points, CSR by target."""

    half: float
    pad: float
    lattice: np.ndarray
    s_start: np.ndarray
    s_pts: np.ndarray


def probe_arrays(occupancy: OccupancyGrid, targets: Targets, probe: float, voxel_size: float) -> ProbeArrays:
    """The sample points of every target's probe footprint (see ProbeArrays)."""
    res = float(occupancy.resolution)
    half = 0.5 * float(probe) * float(voxel_size)
    s_start, s_pts = footprint.surface_samples(occupancy, targets, probe, voxel_size)
    pad = max(half * math.sqrt(3.0), (max(half, 0.5 * res) + res) * math.sqrt(2.0)) + res
    return ProbeArrays(half, pad, footprint.cube_lattice(), s_start, s_pts)


def _probe_block(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates, start: int, stop: int,
                 grid: TargetGrid, pa: ProbeArrays) -> tuple[np.ndarray, np.ndarray]:
    """(indptr, indices) of V rows [start, stop) under the any-part rule (``_probe_kernel``)."""
    params = np.stack([c.params for c in candidates.cameras])
    return _sorted_rows(*_probe_kernel(
        occupancy.occupied.view(np.uint8), occupancy.origin.astype(np.float64), float(occupancy.resolution),
        np.ascontiguousarray(candidates.positions[start:stop], dtype=np.float64),
        np.ascontiguousarray(candidates.rotations[start:stop], dtype=np.float64),
        np.ascontiguousarray(candidates.camera_ids[start:stop], dtype=np.int64), params,
        np.ascontiguousarray(targets.positions, dtype=np.float64),
        np.ascontiguousarray(targets.normals, dtype=np.float64), target_cos_limits(targets), target_min_px(targets),
        grid.params, grid.cell_start, grid.cell_tids, pa.half, pa.pad, pa.lattice, pa.s_start, pa.s_pts), len(targets))


@dataclass(frozen=True)
class VoxelEngine:
    """Sight lines from each candidate to its targets (see the module docstring).

    probe: the part of a target's voxel a line of sight must reach, as a fraction of its
    edge, in [0, 1]: 0 = the target's centre (the default, the centre test); p > 0 = any
    part of the central p x voxel_size cube (surfaces: of the patch's face cells within
    p x voxel_size / 2 of its centre); 1 = any part of the voxel, the paper's rule (as the
    pixel engine's probe; the voxel edge is the targets' ``voxel_size``); chunk_size:
    candidate rows per block; grid_cell: range-culling cell (m; None = the smallest range / 8,
    ``np.inf`` = no culling; V does not depend on it)."""

    probe: float = 0.0
    chunk_size: int = DEFAULT_CHUNK
    grid_cell: float | None = None
    mode = "voxel"

    def __post_init__(self) -> None:
        if not 0.0 <= float(self.probe) <= 1.0:
            raise InputError(f"probe: expected a fraction in [0, 1], got {self.probe}", option="probe")
        _engine.check_chunk_size(self.chunk_size)

    def cache_tag(self) -> str:
        if float(self.probe) == 0.0:
            return f"voxel:probe={float(self.probe)!r}"
        return f"voxel:probe={float(self.probe)!r}:lattice={footprint.CUBE_LATTICE}x{footprint.CELL_LATTICE}"

    def code_modules(self) -> tuple:
        import sys

        return (sys.modules[__name__], sightlines, footprint)

    def setup(self, occupancy: OccupancyGrid, targets: Targets, candidates: Candidates) -> tuple:
        """(occupancy, targets, candidates, the targets' range-culling grid, the probe's
        ProbeArrays or None for probe 0)."""
        cell = default_grid_cell(candidates) if self.grid_cell is None else self.grid_cell
        pa = (probe_arrays(occupancy, targets, self.probe, _engine.target_voxel(targets, "probe"))
              if float(self.probe) > 0.0 else None)
        return occupancy, targets, candidates, target_grid(targets, cell), pa

    def rows(self, shared: tuple, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
        occupancy, targets, candidates, grid, pa = shared
        if pa is None:
            return _block_arrays(occupancy, targets, candidates, start, stop, grid)
        return _probe_block(occupancy, targets, candidates, start, stop, grid, pa)

    def info(self, candidates: Candidates, bounds: list, computed: list, seconds: float, shared: Any) -> dict:
        return {"probe": float(self.probe)} if float(self.probe) > 0.0 else {}


def compute_visibility(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                       chunk_size: int = DEFAULT_CHUNK, progress: Progress | None = None, executor=None,
                       cache_dir: str | Path | None = None, grid_cell: float | None = None) -> Visibility:
    """V for every candidate by the voxel engine (rows in candidate order):
    ``camplace.visibility.engine.compute_visibility(VoxelEngine(chunk_size=chunk_size,
    grid_cell=grid_cell), ...)``. The result does not depend on chunk_size, executor,
    cache or grid_cell."""
    return _engine.compute_visibility(VoxelEngine(chunk_size=chunk_size, grid_cell=grid_cell), occupancy, targets,
                                      candidates, executor=executor, cache_dir=cache_dir, progress=progress)
