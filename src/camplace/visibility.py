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
from typing import Callable

import numba
import numpy as np
import scipy.sparse as sp

from camplace.cameras import project_nb
from camplace.candidates import Candidates
from camplace.scene import OccupancyGrid
from camplace.targets import Targets

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
    dx, dy, dz = x1 - x0, y1 - y0, z1 - z0
    inf = 1e30
    sx = 1 if dx > 0 else -1
    sy = 1 if dy > 0 else -1
    sz = 1 if dz > 0 else -1
    if dx != 0.0:
        tmx = ((ix + (1 if dx > 0 else 0)) * res + ox - x0) / dx
        tdx = res / abs(dx)
    else:
        tmx, tdx = inf, inf
    if dy != 0.0:
        tmy = ((iy + (1 if dy > 0 else 0)) * res + oy - y0) / dy
        tdy = res / abs(dy)
    else:
        tmy, tdy = inf, inf
    if dz != 0.0:
        tmz = ((iz + (1 if dz > 0 else 0)) * res + oz - z0) / dz
        tdz = res / abs(dz)
    else:
        tmz, tdz = inf, inf
    n_max = abs(ex - ix) + abs(ey - iy) + abs(ez - iz) + 1
    for _ in range(n_max):
        if ix < 0 or iy < 0 or iz < 0 or ix >= nx or iy >= ny or iz >= nz:
            return False
        if occ[ix, iy, iz]:
            return False
        if ix == ex and iy == ey and iz == ez:
            return True
        if tmx <= tmy and tmx <= tmz:
            if tmx > 1.0:
                return True
            ix += sx
            tmx += tdx
        elif tmy <= tmz:
            if tmy > 1.0:
                return True
            iy += sy
            tmy += tdy
        else:
            if tmz > 1.0:
                return True
            iz += sz
            tmz += tdz
    return True


@numba.njit(cache=True, inline="always")
def _passes_view(cam_p, R, params, tx, ty, tz, nx_, ny_, nz_, cos_max):
    """Range, image and incidence tests of one (camera, target) pair."""
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
    return True


@numba.njit(cache=True, parallel=True)
def _visibility_kernel(occ, origin, res, cam_pos, cam_rot, cam_ids, cam_params,
                       tpos, tnrm, tcos):
    """CSR (indptr, indices) of V for a chunk of candidates."""
    n_c = cam_pos.shape[0]
    n_t = tpos.shape[0]
    counts = np.zeros(n_c, np.int64)
    for i in numba.prange(n_c):
        params = cam_params[cam_ids[i]]
        k = 0
        for j in range(n_t):
            if _passes_view(cam_pos[i], cam_rot[i], params, tpos[j, 0], tpos[j, 1], tpos[j, 2],
                            tnrm[j, 0], tnrm[j, 1], tnrm[j, 2], tcos[j]):
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
        for j in range(n_t):
            nx_, ny_, nz_ = tnrm[j, 0], tnrm[j, 1], tnrm[j, 2]
            if not _passes_view(p, cam_rot[i], params, tpos[j, 0], tpos[j, 1], tpos[j, 2], nx_, ny_, nz_, tcos[j]):
                continue
            ex = tpos[j, 0] + nx_ * off_len
            ey = tpos[j, 1] + ny_ * off_len
            ez = tpos[j, 2] + nz_ * off_len
            if segment_clear(occ, origin[0], origin[1], origin[2], res, p[0], p[1], p[2], ex, ey, ez):
                buf[k] = j
                k += 1
        seen[i] = k - offs[i]
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


def visibility_block(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                     start: int, stop: int) -> sp.csr_matrix:
    """V rows [start, stop) as a CSR block (stop - start, N_p)."""
    occ = occupancy.occupied.view(np.uint8)
    params = np.stack([c.params for c in candidates.cameras])
    indptr, indices = _visibility_kernel(
        occ, occupancy.origin.astype(np.float64), float(occupancy.resolution),
        np.ascontiguousarray(candidates.positions[start:stop], dtype=np.float64),
        np.ascontiguousarray(candidates.rotations[start:stop], dtype=np.float64),
        np.ascontiguousarray(candidates.camera_ids[start:stop], dtype=np.int64), params,
        np.ascontiguousarray(targets.positions, dtype=np.float64),
        np.ascontiguousarray(targets.normals, dtype=np.float64), target_cos_limits(targets))
    data = np.ones(len(indices), dtype=np.uint8)
    return sp.csr_matrix((data, indices, indptr), shape=(stop - start, len(targets)))


def compute_visibility(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                       chunk_size: int = 512, progress: Progress | None = None) -> Visibility:
    """V for every candidate (rows in candidate order). Candidates are processed in chunks
    (the unit of work for executors); inside a chunk the kernel runs parallel threads."""
    t0 = time.perf_counter()
    n = len(candidates)
    bounds = [(s, min(s + chunk_size, n)) for s in range(0, n, chunk_size)]
    blocks = []
    for k, (s, e) in enumerate(bounds):
        blocks.append(visibility_block(occupancy, targets, candidates, s, e))
        if progress:
            progress("visibility", k + 1, len(bounds))
    V = sp.vstack(blocks, format="csr") if blocks else sp.csr_matrix((0, len(targets)), dtype=np.uint8)
    V.sort_indices()
    return Visibility(V.astype(np.uint8), candidates, targets, "voxel",
                      {"seconds": time.perf_counter() - t0, "nnz": int(V.nnz), "chunks": len(bounds)})


def drop_blind_candidates(vis: Visibility) -> Visibility:
    """Remove candidates that see no target (rows of V with no entry)."""
    keep = np.diff(vis.V.indptr) > 0
    info = dict(vis.info, dropped_blind=int((~keep).sum()))
    return Visibility(vis.V[keep], vis.candidates.subset(keep), vis.targets, vis.mode, info)
