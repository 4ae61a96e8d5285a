"""Stage 4, ``pixel`` mode: the paper's per-pixel raycasting (Malhotra et al. 2022, sec. IV).

For each candidate, one ray leaves the camera through the centre of every block of
``stride`` x ``stride`` pixels (unprojected through the lens model, so distortion and
fisheye lenses are handled exactly). Each ray is traced with a compiled 3D DDA
(Amanatides & Woo):

1. through the occupancy grid to the first occupied cell (or the range limit);
2. through a bucket grid of the volume targets' voxels (cell = ``voxel_size``) from the
   camera to that hit: a free-space target is covered when the ray passes through its
   voxel (the ``probe`` x voxel_size cube around the target centre) before the hit and
   within range;
3. a surface target is covered when the first occupied cell the ray meets is one of its
   patch's face cells, entered through that face, within range and within the
   region's incidence limit (ray direction vs face normal).

Pixel-density limits (``min_px_per_m``) are tested at the target centre with the same
function as ``voxel`` mode. The result is the same ``Visibility`` as voxel mode.
Where the two differ and why: docs/lenses.md.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Callable

import numba
import numpy as np

from camplace.cameras.models import px_per_m_nb
from camplace.cameras.candidates import Candidates
from camplace.core.errors import InputError
from camplace.spec.quality import target_min_px
from camplace.scene.build import OccupancyGrid
from camplace.targets.build import Targets
from camplace.visibility.voxel import Visibility, chunked_rows, dda_axis, dda_step, target_cos_limits

Progress = Callable[[str, int, int], None]
DEFAULT_STRIDE = 4
DEFAULT_PROBE = 1.0
NO_HIT, BOUNDARY = -2, -1


# ----------------------------------------------------------------------------- kernels
@numba.njit(cache=True, inline="always")
def _first_hit(occ, dist, ox, oy, oz, res, px, py, pz, dx, dy, dz, rng):
    """First occupied cell along the unit ray p + t d, t in [0, rng].

    Returns (t, ix, iy, iz, axis, step): t = distance to the entry of the hit cell (rng
    when nothing is hit: axis = NO_HIT); axis/step = the axis and direction of the DDA
    step that entered the hit cell (axis = BOUNDARY when the ray starts in an occupied
    cell or leaves the grid). ``dist`` (same shape as occ, see ``free_distance``) lets the
    ray jump through empty space: from a cell whose Chebyshev distance to the nearest
    occupied cell is d, every point within (d - 1) cells is free, so the ray advances
    (d - 1) * res at once; pass a (1, 1, 1) array to step cell by cell. Same result."""
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
    t_in = 0.0  # ray parameter where it entered the current cell
    while True:
        if skip:
            dd = dist[ix, iy, iz]
            if dd >= 4:
                t_in = t_in + (dd - 1) * res
                if t_in > rng:
                    return rng, ix, iy, iz, NO_HIT, 0
                ix = int(math.floor((px + t_in * dx - ox) / res))
                iy = int(math.floor((py + t_in * dy - oy) / res))
                iz = int(math.floor((pz + t_in * dz - oz) / res))
                # next boundaries ahead; max() guards rays running along a cell boundary,
                # where rounding can put the recomputed cell behind the ray (an axis the
                # ray is parallel to keeps its 1e30)
                tmx = max(dda_axis(ix, px, dx, ox, res)[1], t_in)
                tmy = max(dda_axis(iy, py, dy, oy, res)[1], t_in)
                tmz = max(dda_axis(iz, pz, dz, oz, res)[1], t_in)
        jx, jy, jz, ux, uy, uz, axis, t = dda_step(ix, iy, iz, tmx, tmy, tmz, sx, sy, sz, tdx, tdy, tdz)
        if t > rng:
            return rng, ix, iy, iz, NO_HIT, 0
        ix, iy, iz, tmx, tmy, tmz = jx, jy, jz, ux, uy, uz
        step = sx if axis == 0 else (sy if axis == 1 else sz)
        t_in = t
        if ix < 0 or iy < 0 or iz < 0 or ix >= nx or iy >= ny or iz >= nz:
            return t, ix, iy, iz, BOUNDARY, 0
        if occ[ix, iy, iz]:
            return t, ix, iy, iz, axis, step


def free_distance(occupancy: OccupancyGrid) -> np.ndarray:
    """(nx, ny, nz) uint8: Chebyshev distance (cells, capped at 255) from each free cell to
    the nearest occupied cell or the grid's outside; 0 on occupied cells."""
    from scipy.ndimage import distance_transform_cdt

    free = np.pad(~occupancy.occupied, 1, constant_values=False)
    d = distance_transform_cdt(free, metric="chessboard")[1:-1, 1:-1, 1:-1]
    return np.minimum(d, 255).astype(np.uint8)


@numba.njit(cache=True, inline="always")
def _ray_hits_cube(px, py, pz, dx, dy, dz, cx, cy, cz, h, t_end):
    """True if the segment p + t d, t in [0, t_end], meets the cube of half-size h at c."""
    t0, t1 = 0.0, t_end
    for a in range(3):
        if a == 0:
            p, d, c = px, dx, cx
        elif a == 1:
            p, d, c = py, dy, cy
        else:
            p, d, c = pz, dz, cz
        lo, hi = c - h, c + h
        if d == 0.0:
            if p < lo or p > hi:
                return False
        else:
            ta = (lo - p) / d
            tb = (hi - p) / d
            if ta > tb:
                ta, tb = tb, ta
            if ta > t0:
                t0 = ta
            if tb < t1:
                t1 = tb
            if t0 > t1:
                return False
    return True


@numba.njit(cache=True, inline="always")
def _ray_near_centre(px, py, pz, dx, dy, dz, cx, cy, cz, k, t_end):
    """True if the unit ray passes the point c at a depth t* in [0, t_end] within a
    perpendicular distance of k * t* (k = the ray's angular footprint radius)."""
    wx, wy, wz = cx - px, cy - py, cz - pz
    t = wx * dx + wy * dy + wz * dz
    if t < 0.0 or t > t_end:
        return False
    perp2 = wx * wx + wy * wy + wz * wz - t * t
    return perp2 <= (k * t) * (k * t)


@numba.njit(cache=True, inline="always")
def _density_ok(p, R, params, tpos, tnrm, j, min_px):
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


@numba.njit(cache=True, parallel=True)
def _pixel_kernel(occ, dist, origin, res, cam_pos, cam_rot, cam_ids, cam_params, rays, ray_start,
                  bgrid, bshape, b_start, b_ids, thalf, s_keys, s_ids,
                  tpos, tnrm, tcos, tpx, cam_foot, centre_mode, mask):
    """Fill mask (n_c, n_t) uint8: 1 = candidate i covers target j, 2 = rejected by the
    density limit. Returns the number of rays cast per candidate. centre_mode: a volume
    target counts when a ray's footprint (cam_foot[camera] rad) contains its centre,
    instead of when the ray meets its probe cube."""
    n_c = cam_pos.shape[0]
    ox, oy, oz = origin[0], origin[1], origin[2]
    onx, ony, onz = occ.shape
    box, boy, boz, bc = bgrid[0], bgrid[1], bgrid[2], bgrid[3]
    bnx, bny, bnz = bshape[0], bshape[1], bshape[2]
    n_keys = s_keys.shape[0]
    counts = np.zeros(n_c, np.int64)
    for i in numba.prange(n_c):
        cid = cam_ids[i]
        params = cam_params[cid]
        rng = params[7]
        R = cam_rot[i]
        p = cam_pos[i]
        px, py, pz = p[0], p[1], p[2]
        foot = cam_foot[cid]
        row = mask[i]
        for r in range(ray_start[cid], ray_start[cid + 1]):
            cx_, cy_, cz_ = rays[r, 0], rays[r, 1], rays[r, 2]
            dx = R[0, 0] * cx_ + R[0, 1] * cy_ + R[0, 2] * cz_
            dy = R[1, 0] * cx_ + R[1, 1] * cy_ + R[1, 2] * cz_
            dz = R[2, 0] * cx_ + R[2, 1] * cy_ + R[2, 2] * cz_
            t_end, hx, hy, hz, axis, step = _first_hit(occ, dist, ox, oy, oz, res, px, py, pz, dx, dy, dz, rng)
            # surface patch hit
            if axis >= 0 and n_keys > 0:
                face = 2 * axis + (0 if step < 0 else 1)
                key = ((hx * ony + hy) * onz + hz) * 6 + face
                q = np.searchsorted(s_keys, key)
                if q < n_keys and s_keys[q] == key:
                    j = s_ids[q]
                    if row[j] == 0 and (not centre_mode or _ray_near_centre(
                            px, py, pz, dx, dy, dz, tpos[j, 0], tpos[j, 1], tpos[j, 2], foot, t_end + res)):
                        c = -(dx * tnrm[j, 0] + dy * tnrm[j, 1] + dz * tnrm[j, 2])
                        if c > 0.0 and c >= tcos[j]:
                            row[j] = 1 if _density_ok(p, R, params, tpos, tnrm, j, tpx[j]) else 2
            # volume targets: DDA through the bucket grid up to t_end
            jx = int(math.floor((px - box) / bc))
            jy = int(math.floor((py - boy) / bc))
            jz = int(math.floor((pz - boz) / bc))
            if jx < 0 or jy < 0 or jz < 0 or jx >= bnx or jy >= bny or jz >= bnz:
                continue
            sx, tmx, tdx = dda_axis(jx, px, dx, box, bc)
            sy, tmy, tdy = dda_axis(jy, py, dy, boy, bc)
            sz, tmz, tdz = dda_axis(jz, pz, dz, boz, bc)
            while True:
                cell = (jx * bny + jy) * bnz + jz
                for q in range(b_start[cell], b_start[cell + 1]):
                    j = b_ids[q]
                    if row[j] != 0:
                        continue
                    if centre_mode:
                        hit = _ray_near_centre(px, py, pz, dx, dy, dz, tpos[j, 0], tpos[j, 1], tpos[j, 2], foot, t_end)
                    else:
                        hit = _ray_hits_cube(px, py, pz, dx, dy, dz, tpos[j, 0], tpos[j, 1], tpos[j, 2], thalf[j], t_end)
                    if hit:
                        row[j] = 1 if _density_ok(p, R, params, tpos, tnrm, j, tpx[j]) else 2
                jx, jy, jz, tmx, tmy, tmz, _, t = dda_step(jx, jy, jz, tmx, tmy, tmz, sx, sy, sz, tdx, tdy, tdz)
                if t > t_end or jx < 0 or jy < 0 or jz < 0 or jx >= bnx or jy >= bny or jz >= bnz:
                    break
        counts[i] = ray_start[cid + 1] - ray_start[cid]
    return counts


# ----------------------------------------------------------------------------- set-up (numpy)
def volume_buckets(occupancy: OccupancyGrid, targets: Targets, probe: float, voxel_size: float):
    """Bucket grid of the volume targets' probe cubes.

    Returns (bgrid (4,) [x0, y0, z0, cell], bshape (3,) int64, b_start (cells + 1,) int64,
    b_ids (M,) int32, thalf (N_p,) float64 half-size of each target's probe cube). The
    grid covers the occupancy grid and is aligned with the target lattice, so a cube
    registers in the cells it overlaps (one cell for lattice-aligned targets at probe 1)."""
    v = float(voxel_size)
    thalf = np.full(len(targets), 0.5 * probe * v)
    vol = np.nonzero(~targets.is_surface)[0]
    lo = occupancy.origin
    hi = occupancy.origin + np.array(occupancy.shape) * occupancy.resolution
    base = targets.positions[vol].min(0) - 0.5 * v if len(vol) else lo.copy()
    org = base - np.ceil((base - lo) / v - 1e-9) * v
    shape = np.maximum(np.ceil((hi - org) / v - 1e-9).astype(np.int64), 1)
    if len(vol) == 0:
        return (np.r_[org, v], shape, np.zeros(int(np.prod(shape)) + 1, np.int64), np.zeros(0, np.int32), thalf)
    c = targets.positions[vol]
    h = thalf[vol][:, None]
    eps = 1e-7
    a = np.clip(np.floor((c - h - org) / v + eps).astype(np.int64), 0, shape - 1)
    b = np.clip(np.floor((c + h - org) / v - eps).astype(np.int64), 0, shape - 1)
    b = np.maximum(a, b)
    cells, ids = [], []
    span = b - a + 1
    for ox_ in range(int(span[:, 0].max())):
        for oy_ in range(int(span[:, 1].max())):
            for oz_ in range(int(span[:, 2].max())):
                off = np.array([ox_, oy_, oz_])
                ok = np.all(off < span, axis=1)
                cc = a[ok] + off
                cells.append((cc[:, 0] * shape[1] + cc[:, 1]) * shape[2] + cc[:, 2])
                ids.append(vol[ok])
    cells_a, ids_a = np.concatenate(cells), np.concatenate(ids)
    order = np.lexsort((ids_a, cells_a))
    cells_a, ids_a = cells_a[order], ids_a[order]
    b_start = np.searchsorted(cells_a, np.arange(int(np.prod(shape)) + 1)).astype(np.int64)
    return np.r_[org, v], shape, b_start, ids_a.astype(np.int32), thalf


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


def default_stride(candidates: Candidates) -> int:
    """The default pixel stride (DEFAULT_STRIDE, see docs/benchmarks.md for its cost)."""
    return DEFAULT_STRIDE


def camera_rays(candidates: Candidates, stride: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit camera-frame rays of every camera type, concatenated: (rays (M, 3), start
    (n_cameras + 1,) int64 offsets per camera id, foot (n_cameras,) float64: the
    footprint radius of one ray in radians, sqrt(2) x half the largest angle between
    neighbouring rays, so the footprints cover the whole image)."""
    parts, foot = [], []
    for cam in candidates.cameras:
        r = cam.pixel_rays(stride)
        parts.append(r)
        g = r.reshape(max(1, cam.height // stride), max(1, cam.width // stride), 3)
        ang = [np.arccos(np.clip(np.einsum("...k,...k->...", g[1:], g[:-1]), -1, 1)).max(initial=0.0),
               np.arccos(np.clip(np.einsum("...k,...k->...", g[:, 1:], g[:, :-1]), -1, 1)).max(initial=0.0)]
        foot.append(math.sqrt(2.0) * 0.5 * max(ang))
    start = np.zeros(len(parts) + 1, np.int64)
    start[1:] = np.cumsum([len(p) for p in parts])
    return np.ascontiguousarray(np.concatenate(parts), dtype=np.float64), start, np.array(foot, np.float64)


def compute_pixel_visibility(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                             voxel_size: float, stride: int | None = None, probe: float = DEFAULT_PROBE,
                             chunk_size: int = 64, progress: Progress | None = None,
                             skip_empty: bool = True, executor=None,
                             cache_dir: str | Path | None = None) -> Visibility:
    """V by per-pixel raycasting (rows in candidate order).

    voxel_size: the target voxel edge (m, the scene's ``voxel_size``); stride: cast one
    ray per stride x stride pixel block (None = ``default_stride``); probe: the part of
    the voxel a ray must pass through, as a fraction of its edge (1 = any part of the
    voxel, the paper's rule; smaller = closer to the target centre; 0 = "centre": the
    target centre must lie in a ray's pixel footprint, the counterpart of voxel mode's
    centre test; for surfaces, a ray that hits the patch must pass the patch centre
    within its footprint). skip_empty: jump rays through empty space (same V, faster).

    Chunks of ``chunk_size`` candidates run on ``executor`` and are stored in / loaded
    from the block cache under ``cache_dir`` exactly as in voxel mode
    (camplace.visibility.voxel.chunked_rows; the cache key adds the mode, stride, probe and
    voxel size). The result does not depend on executor or cache."""
    if stride is None:
        stride = default_stride(candidates)
    if int(stride) < 1:
        raise InputError(f"--stride: expected a positive integer, got {stride}")
    if not 0 <= probe <= 1:
        raise InputError(f"probe: expected a fraction in [0, 1], got {probe}")
    t0 = time.perf_counter()
    stride = int(stride)
    n, n_t = len(candidates), len(targets)
    bounds = [(s, min(s + chunk_size, n)) for s in range(0, n, chunk_size)]
    rays, ray_start, foot = camera_rays(candidates, stride)
    rays_per_cam = np.diff(ray_start)
    store = None
    if cache_dir is not None:
        import camplace.visibility.pixel as _this
        from camplace.visibility.cache import BlockStore
        from camplace.visibility.voxel import visibility_cache_key

        mode = f"pixel:stride={stride}:probe={float(probe)!r}:voxel={float(voxel_size)!r}:skip={bool(skip_empty)}"
        key = visibility_cache_key(occupancy, targets, candidates, mode, chunk_size, (_this,))
        store = BlockStore(cache_dir, key, bounds, n_t)

    setup: dict = {}

    def make_shared() -> tuple:
        shared = _pixel_setup(occupancy, targets, candidates, voxel_size, probe, skip_empty, rays, ray_start, foot)
        setup["surface_face_cells"] = int(len(shared[3][5]))  # s_keys
        return shared

    V, cached = chunked_rows(n_t, bounds, _pixel_chunk_task, make_shared, executor, store, progress)
    secs = time.perf_counter() - t0
    from_cache = set(cached)
    cast = sum(int(rays_per_cam[candidates.camera_ids[s:e]].sum())
               for k, (s, e) in enumerate(bounds) if k not in from_cache)
    info = {"seconds": secs, "nnz": int(V.nnz), "chunks": len(bounds), "stride": stride, "probe": probe,
            "rays": int(rays_per_cam[candidates.camera_ids].sum()), "rays_cast": cast,
            "rays_per_s": cast / secs if secs > 0 else 0.0, "cached_chunks": len(cached),
            "executor": getattr(executor, "name", "in-process"), **setup}
    if store is not None:
        info["cache"] = str(store.dir)
    return Visibility(V, candidates, targets, "pixel", info)


def _pixel_setup(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates, voxel_size: float,
                 probe: float, skip_empty: bool, rays: np.ndarray, ray_start: np.ndarray, foot: np.ndarray) -> tuple:
    """The arrays every chunk of ``_pixel_kernel`` reads (built once, shipped once per worker)."""
    centre_mode = probe == 0
    reach = max(c.max_range for c in candidates.cameras) * float(foot.max()) if centre_mode else 0.0
    bprobe = min(1.0, 2.0 * reach / voxel_size) if centre_mode else probe
    bgrid, bshape, b_start, b_ids, thalf = volume_buckets(occupancy, targets, bprobe, voxel_size)
    s_keys, s_ids = surface_cell_map(occupancy, targets, 1.0 if centre_mode else probe, voxel_size)
    occ = occupancy.occupied.view(np.uint8)
    dist = free_distance(occupancy) if skip_empty else np.zeros((1, 1, 1), np.uint8)
    params = np.stack([c.params for c in candidates.cameras])
    world = (occ, dist, occupancy.origin.astype(np.float64), float(occupancy.resolution))
    poses = (np.ascontiguousarray(candidates.positions, dtype=np.float64),
             np.ascontiguousarray(candidates.rotations, dtype=np.float64),
             np.ascontiguousarray(candidates.camera_ids, dtype=np.int64))
    tgt = (bgrid, bshape, b_start, b_ids, thalf, s_keys, s_ids,
           np.ascontiguousarray(targets.positions, dtype=np.float64),
           np.ascontiguousarray(targets.normals, dtype=np.float64), target_cos_limits(targets), target_min_px(targets))
    return world, poses, (params, rays, ray_start, foot), tgt, centre_mode, len(targets)


def _pixel_chunk_task(shared: tuple, bounds: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """One unit of work for an executor: V rows [start, stop) as (indptr, indices)."""
    world, (pos, rot, cam_ids), (params, rays, ray_start, foot), tgt, centre_mode, n_t = shared
    s, e = bounds
    mask = np.zeros((e - s, n_t), np.uint8)
    _pixel_kernel(*world, pos[s:e], rot[s:e], cam_ids[s:e], params, rays, ray_start, *tgt, foot, centre_mode, mask)
    rows, cols = np.nonzero(mask == 1)
    indptr = np.zeros(e - s + 1, np.int64)
    np.cumsum(np.bincount(rows, minlength=e - s), out=indptr[1:])
    return indptr, cols.astype(np.int32)
