"""The voxel engine's kernel: V's rows for a block of candidates, one pass, targets culled by
range and by view cone before the exact tests.

A camera sees nothing outside a cone about its optical axis (``cone_angle``: pinhole, the
image corners; opencv, the model's valid radius; fisheye, its angle limit). At each camera
position the targets in range are sorted once into direction bins (a cube map of
``CUBE_SIDE`` x ``CUBE_SIDE`` cells per face, ``cube_bins``); each orientation at that
position then visits only the bins that meet its cone (widened by the bin's own angular
radius) and, in them, the targets whose direction lies in the cone. The exact tests
(camplace.visibility.voxel._passes_view: range, lens, incidence, pixel density; the DDA
line of sight) decide as before, so V is the same bit for bit: the culling only skips
pairs those tests would refuse. Positions are few and orientations many (standard-store:
99 positions, 3,564 candidates), so the sort is paid once per position.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camplace.cameras.models import project_nb, px_per_m_nb
from camplace.visibility.raywalk import segment_clear

SURFACE_OFFSET = 0.75  # surface rays end this many occupancy cells outside the face
CUBE_SIDE = 8  # direction bins per cube-face edge: 6 x 8 x 8 = 384 bins
CONE_MARGIN = 1e-6  # rad added to every cone and bin angle (rounding of the exact tests)


def cube_bins(side: int = CUBE_SIDE) -> np.ndarray:
    """(6 side^2, 4) float64: each direction bin's unit centre (x, y, z) and angular radius
    (rad, the largest angle from the centre to a direction in the bin: at a corner, as the
    bin is a convex spherical quadrilateral within a hemisphere). Bin order as ``cube_bin``."""
    edges = np.linspace(-1.0, 1.0, side + 1)
    out = np.empty((6 * side * side, 4))
    k = 0
    for face in range(6):
        for i in range(side):
            for j in range(side):
                s0, s1, t0, t1 = edges[i], edges[i + 1], edges[j], edges[j + 1]
                pts = [_face_dir(face, s, t) for s, t in ((s0, t0), (s0, t1), (s1, t0), (s1, t1))]
                c = _face_dir(face, 0.5 * (s0 + s1), 0.5 * (t0 + t1))
                r = max(math.acos(min(1.0, float(np.dot(c, q)))) for q in pts)
                out[k, :3], out[k, 3] = c, r
                k += 1
    return out


def _face_dir(face: int, s: float, t: float) -> np.ndarray:
    """Unit direction of face coordinates (s, t) in [-1, 1]^2 on cube face ``face``
    (0/1: +x/-x, 2/3: +y/-y, 4/5: +z/-z; s, t the other two axes in x, y, z order)."""
    sign = 1.0 if face % 2 == 0 else -1.0
    axis = face // 2
    v = np.empty(3)
    v[axis] = sign
    others = [a for a in range(3) if a != axis]
    v[others[0]], v[others[1]] = s, t
    return v / np.linalg.norm(v)


@numba.njit(cache=True, inline="always")
def cube_bin(vx: float, vy: float, vz: float, side: int) -> int:
    """Direction bin of the non-zero vector v (see ``cube_bins``)."""
    ax, ay, az = abs(vx), abs(vy), abs(vz)
    if ax >= ay and ax >= az:
        face = 0 if vx > 0 else 1
        s = vy / ax
        t = vz / ax
    elif ay >= az:
        face = 2 if vy > 0 else 3
        s = vx / ay
        t = vz / ay
    else:
        face = 4 if vz > 0 else 5
        s = vx / az
        t = vy / az
    i = int((s + 1.0) * 0.5 * side)
    j = int((t + 1.0) * 0.5 * side)
    i = side - 1 if i >= side else (0 if i < 0 else i)
    j = side - 1 if j >= side else (0 if j < 0 else j)
    return (face * side + i) * side + j


def cone_angle(params: np.ndarray) -> float:
    """Half-angle (rad) of a cone about the optical axis outside of which the lens model
    (``camplace.cameras.models.project_nb``; ``params`` from ``CameraModel.params``) puts no
    point inside the image: pinhole, the farthest image corner; opencv, atan of the valid
    undistorted radius; fisheye, its angle limit. Never less than the true one (the tests it
    culls for stay exact)."""
    code, lim = float(params[0]), float(params[16])
    if code == 2.0:
        return min(lim, math.pi)
    if code == 1.0:
        return math.atan(lim)
    w, h, fx, fy, cx, cy = (float(v) for v in params[1:7])
    tx = max(abs(-0.5 - cx), abs(w - 0.5 - cx)) / fx
    ty = max(abs(-0.5 - cy), abs(h - 0.5 - cy)) / fy
    return math.atan(math.hypot(tx, ty))


def cone_limits(cam_params: np.ndarray, bins: np.ndarray) -> np.ndarray:
    """(n_types, n_bins + 1) float64, per camera type (rows of ``cam_params``): the cosine of
    (cone + bin radius) for each direction bin of ``bins`` (a bin whose centre is farther from
    the optical axis holds nothing in view), then the cosine of the cone itself; -2 (no
    limit) where the angle reaches pi. Every angle is widened by CONE_MARGIN."""
    a = np.array([cone_angle(p) for p in np.atleast_2d(cam_params)]) + CONE_MARGIN
    w = np.c_[a[:, None] + bins[None, :, 3] + CONE_MARGIN, a]
    return np.where(w < math.pi, np.cos(np.minimum(w, math.pi)), -2.0)


@numba.njit(cache=True)
def _bin_in_range(p, rng, grid, cell_start, cell_tids, tpos, side, tmp_j, tmp_b, bstart, sj, sv):
    """Targets within ``rng`` m of position p, sorted by direction bin: their ids ``sj[:n]``
    and (vx, vy, vz, |v|) from p ``sv[:n]``, bin b holding sj[bstart[b]:bstart[b + 1]].
    Returns n. Targets at p itself (|v|^2 <= 1e-18, never seen) are left out."""
    gnx, gny = int(grid[3]), int(grid[4])
    ax, bx = _cell_span(grid[0], grid[2], gnx, p[0], rng)
    ay, by = _cell_span(grid[1], grid[2], gny, p[1], rng)
    n = 0
    for b in range(len(bstart)):
        bstart[b] = 0
    for cx in range(ax, bx + 1):
        for cy in range(ay, by + 1):
            if not _cell_near(grid, cx, cy, p[0], p[1], rng):
                continue
            cell = cx * gny + cy
            for q in range(cell_start[cell], cell_start[cell + 1]):
                j = cell_tids[q]
                vx, vy, vz = tpos[j, 0] - p[0], tpos[j, 1] - p[1], tpos[j, 2] - p[2]
                d2 = vx * vx + vy * vy + vz * vz
                if d2 > rng * rng or d2 <= 1e-18:
                    continue
                b = cube_bin(vx, vy, vz, side)
                tmp_j[n], tmp_b[n] = j, b
                bstart[b] += 1
                n += 1
    for b in range(1, len(bstart)):  # bstart[b]: the end of bin b
        bstart[b] += bstart[b - 1]
    for k in range(n - 1, -1, -1):  # each bin filled from its end: bstart[b] becomes its start
        j, b = tmp_j[k], tmp_b[k]
        bstart[b] -= 1
        q = bstart[b]
        sj[q] = j
        vx, vy, vz = tpos[j, 0] - p[0], tpos[j, 1] - p[1], tpos[j, 2] - p[2]
        sv[q, 0], sv[q, 1], sv[q, 2], sv[q, 3] = vx, vy, vz, math.sqrt(vx * vx + vy * vy + vz * vz)
    bstart[len(bstart) - 1] = n
    return n


@numba.njit(cache=True)  # a call, not inlined: the kernels using it compile in half the time
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


def work_arrays(grid_params: np.ndarray, cell_start: np.ndarray, positions: np.ndarray,
                rng: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The kernel's per-position work arrays (ids, bins, sorted ids: int32; vectors (n, 4)
    float64), n = an upper bound on the targets within ``rng`` m of any of ``positions``
    (N, 3): the largest count of the target-grid cells (``grid_params`` / ``cell_start``, see
    camplace.visibility.voxel.TargetGrid) in the square of half-side rng about a position,
    read from a summed-area table."""
    x0, y0, cell = (float(v) for v in grid_params[:3])
    nx, ny = int(grid_params[3]), int(grid_params[4])
    sat = np.zeros((nx + 1, ny + 1), np.int64)
    sat[1:, 1:] = np.diff(cell_start).reshape(nx, ny).cumsum(0).cumsum(1)
    p = np.asarray(positions, float).reshape(-1, 3)
    ax = np.clip(np.floor((p[:, 0] - rng - x0) / cell), 0, nx - 1).astype(np.int64)
    bx = np.clip(np.floor((p[:, 0] + rng - x0) / cell), 0, nx - 1).astype(np.int64) + 1
    ay = np.clip(np.floor((p[:, 1] - rng - y0) / cell), 0, ny - 1).astype(np.int64)
    by = np.clip(np.floor((p[:, 1] + rng - y0) / cell), 0, ny - 1).astype(np.int64) + 1
    n = int((sat[bx, by] - sat[ax, by] - sat[bx, ay] + sat[ax, ay]).max(initial=0))
    return np.empty(n, np.int32), np.empty(n, np.int32), np.empty(n, np.int32), np.empty((n, 4))


@numba.njit(cache=True, nogil=True)
def visibility_rows(occ, origin, res, cam_pos, cam_rot, cam_ids, cam_params, tpos, tnrm, tcos, grid, cell_start,
                    cell_tids, tpx, bins, limits, rng, tmp_j, tmp_b, sj, sv):
    """CSR (indptr, indices) of V for a chunk of candidates, each row's indices in the order
    its direction bins are visited (camplace.visibility.voxel sorts them).

    Targets are bucketed in an xy grid (``grid`` = [x0, y0, cell, nx, ny], CSR
    ``cell_start`` / ``cell_tids``, camplace.visibility.voxel.target_grid); at each new
    camera position the targets within ``rng`` m (the largest range of the chunk's cameras)
    are sorted into the direction bins ``bins`` (``cube_bins``; work arrays ``tmp_j``,
    ``tmp_b``, ``sj``, ``sv`` from ``work_arrays``), and each candidate visits only the bins
    and targets within its view cone (``limits``, ``cone_limits``), so the work scales with
    the pairs in view. A pair that passes the view tests is walked at once (surface targets to
    ``SURFACE_OFFSET`` x res outside the face), a seen target appended to a buffer that
    doubles when full (memory O(pairs seen)). Consecutive candidates at one position walk
    each target's line once (``los``)."""
    n_c, n_p, nb = cam_pos.shape[0], tpos.shape[0], bins.shape[0]
    side = int(round(math.sqrt(nb / 6)))
    indptr = np.zeros(n_c + 1, np.int64)
    buf = np.empty(max(1024, 64 * n_c), np.int32)
    k = 0
    off_len = SURFACE_OFFSET * res
    los = np.full(n_p, -1, np.int8)  # from the current position: -1 not walked, 0 blocked, 1 clear
    walked = np.empty(n_p, np.int32)
    n_walked = 0
    bstart = np.zeros(nb + 1, np.int64)
    for i in range(n_c):
        p = cam_pos[i]
        if i == 0 or p[0] != cam_pos[i - 1, 0] or p[1] != cam_pos[i - 1, 1] or p[2] != cam_pos[i - 1, 2]:
            for n in range(n_walked):  # a new position: forget the lines walked from the last one
                los[walked[n]] = -1
            n_walked = 0
            _bin_in_range(p, rng, grid, cell_start, cell_tids, tpos, side, tmp_j, tmp_b, bstart, sj, sv)
        ti = cam_ids[i]
        params, R = cam_params[ti], cam_rot[i]
        zx, zy, zz = R[0, 2], R[1, 2], R[2, 2]  # the optical axis
        cc = limits[ti, nb]
        for b in range(nb):
            if zx * bins[b, 0] + zy * bins[b, 1] + zz * bins[b, 2] < limits[ti, b]:
                continue
            for q in range(bstart[b], bstart[b + 1]):
                if zx * sv[q, 0] + zy * sv[q, 1] + zz * sv[q, 2] < sv[q, 3] * cc:
                    continue
                j = sj[q]
                if los[j] == 0:  # its line from here is blocked: not seen, whatever the view tests say
                    continue
                nx_, ny_, nz_ = tnrm[j, 0], tnrm[j, 1], tnrm[j, 2]
                if not _passes_view(p, R, params, tpos[j, 0], tpos[j, 1], tpos[j, 2], nx_, ny_, nz_, tcos[j], tpx[j]):
                    continue
                if los[j] < 0:
                    los[j] = segment_clear(occ, origin[0], origin[1], origin[2], res, p[0], p[1], p[2],
                                           tpos[j, 0] + nx_ * off_len, tpos[j, 1] + ny_ * off_len,
                                           tpos[j, 2] + nz_ * off_len)
                    walked[n_walked] = j
                    n_walked += 1
                if los[j] == 1:
                    if k == len(buf):  # full: twice the room (copied element by element: a slice
                        big = np.empty(2 * k, np.int32)  # assignment compiles numba's shape-mismatch
                        for n in range(k):  # message, ~2 s on a new install)
                            big[n] = buf[n]
                        buf = big
                    buf[k] = j
                    k += 1
        indptr[i + 1] = k
    return indptr, buf[:k].copy()
