"""The ``pixel`` visibility engine: the paper's per-pixel raycasting (Malhotra et al. 2022, sec. IV).

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
function as the voxel engine. ``PixelEngine`` implements camplace.visibility.engine's
interface, so it runs on the same executors and block cache and gives the same kind
of ``Visibility``; the DDA routines are camplace.visibility.raywalk's.
Where the two differ and why: docs/lenses.md.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from camplace.cameras.candidates import Candidates
from camplace.core.errors import InputError
from camplace.spec.quality import target_min_px
from camplace.scene.build import OccupancyGrid
from camplace.targets.build import Targets
from camplace.visibility import engine as _engine
from camplace.visibility.engine import Progress, Visibility
from camplace.visibility.footprint import surface_cell_map  # noqa: F401 (re-exported)
from camplace.visibility.raywalk import dda_axis, dda_step, first_hit, free_distance
from camplace.visibility.voxel import density_ok, target_cos_limits

DEFAULT_STRIDE = 4
DEFAULT_PROBE = 1.0
DEFAULT_CHUNK = 64  # candidate rows per block


# ----------------------------------------------------------------------------- kernels
@numba.njit(cache=True, inline="always")
def _ray_box_span(px, py, pz, dx, dy, dz, lx, ly, lz, hx, hy, hz, t_end):
    """(t0, t1): the part of the segment p + t d, t in [0, t_end], inside the box [l, h]
    (t0 > t1 when it misses)."""
    t0, t1 = 0.0, t_end
    for a in range(3):
        if a == 0:
            p, d, lo, hi = px, dx, lx, hx
        elif a == 1:
            p, d, lo, hi = py, dy, ly, hy
        else:
            p, d, lo, hi = pz, dz, lz, hz
        if d == 0.0:
            if p < lo or p > hi:
                return 1.0, 0.0
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
                return t0, t1
    return t0, t1


@numba.njit(cache=True, inline="always")
def _ray_hits_cube(px, py, pz, dx, dy, dz, cx, cy, cz, h, t_end):
    """True if the segment p + t d, t in [0, t_end], meets the cube of half-size h at c."""
    t0, t1 = _ray_box_span(px, py, pz, dx, dy, dz, cx - h, cy - h, cz - h, cx + h, cy + h, cz + h, t_end)
    return t0 <= t1


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


@numba.njit(cache=True, parallel=True)
def _pixel_kernel(occ, dist, origin, res, cam_pos, cam_rot, cam_ids, cam_params, rays, ray_start,
                  bgrid, bshape, b_start, b_ids, thalf, vbox, s_keys, s_ids,
                  tpos, tnrm, tcos, tpx, cam_foot, centre_mode, mask):
    """Fill mask (n_c, n_t) uint8: 1 = candidate i covers target j, 2 = rejected by the
    density limit. Returns the number of rays cast per candidate. centre_mode: a volume
    target counts when a ray's footprint (cam_foot[camera] rad) contains its centre,
    instead of when the ray meets its probe cube. vbox (6,): a box (lo, hi, m) holding every
    non-empty bucket cell: each ray walks the bucket grid only over its part inside."""
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
            t_end, hx, hy, hz, axis, step = first_hit(occ, dist, ox, oy, oz, res, px, py, pz, dx, dy, dz, rng)
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
                            row[j] = 1 if density_ok(p, R, params, tpos, tnrm, j, tpx[j]) else 2
            # volume targets: DDA through the bucket grid up to t_end
            jx = int(math.floor((px - box) / bc))
            jy = int(math.floor((py - boy) / bc))
            jz = int(math.floor((pz - boz) / bc))
            if jx < 0 or jy < 0 or jz < 0 or jx >= bnx or jy >= bny or jz >= bnz:
                continue
            ta, tb = _ray_box_span(px, py, pz, dx, dy, dz, vbox[0], vbox[1], vbox[2], vbox[3], vbox[4], vbox[5], t_end)
            if ta > tb:
                continue  # no target voxel along this ray before its hit
            t_stop = tb
            t0 = ta - 0.5 * bc
            if t0 > 0.0:  # start half a bucket cell before the box (its margin cells are empty)
                jx = min(max(int(math.floor((px + t0 * dx - box) / bc)), 0), bnx - 1)
                jy = min(max(int(math.floor((py + t0 * dy - boy) / bc)), 0), bny - 1)
                jz = min(max(int(math.floor((pz + t0 * dz - boz) / bc)), 0), bnz - 1)
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
                        row[j] = 1 if density_ok(p, R, params, tpos, tnrm, j, tpx[j]) else 2
                jx, jy, jz, tmx, tmy, tmz, _, t = dda_step(jx, jy, jz, tmx, tmy, tmz, sx, sy, sz, tdx, tdy, tdz)
                if t > t_stop or jx < 0 or jy < 0 or jz < 0 or jx >= bnx or jy >= bny or jz >= bnz:
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


def bucket_box(bgrid: np.ndarray, bshape: np.ndarray, b_start: np.ndarray) -> np.ndarray:
    """(6,) float64 [lo (3,), hi (3,)] m: the box of the non-empty cells of a bucket grid
    (see volume_buckets), one cell wider on every side; an empty box when none holds a target."""
    full = np.nonzero(np.diff(b_start) > 0)[0]
    if len(full) == 0:
        return np.array([1.0, 1.0, 1.0, -1.0, -1.0, -1.0])
    cell = np.stack(np.unravel_index(full, tuple(int(n) for n in bshape)), 1)
    org, c = bgrid[:3], float(bgrid[3])
    return np.r_[org + (cell.min(0) - 1) * c, org + (cell.max(0) + 2) * c].astype(np.float64)


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


def ray_counts(candidates: Candidates, stride: int) -> np.ndarray:
    """(n_cameras,) int64: rays cast per candidate of each camera type (see camera_rays)."""
    return np.array([max(1, c.width // stride) * max(1, c.height // stride) for c in candidates.cameras], np.int64)


@dataclass(frozen=True)
class PixelEngine:
    """The paper's per-pixel raycasting (see the module docstring).

    The target voxel edge is the targets' ``voxel_size`` (the scene's). stride: cast one
    ray per stride x stride pixel block (None = DEFAULT_STRIDE); probe: the part of the
    voxel a ray must pass through, as a fraction of its edge (1 = any part of the voxel,
    the paper's rule; smaller = closer to the target centre; 0 = "centre": the target
    centre must lie in a ray's pixel footprint, the counterpart of the voxel engine's
    centre test; for surfaces, a ray that hits the patch must pass the patch centre
    within its footprint). skip_empty: jump rays through empty space (same V, faster).
    chunk_size: candidate rows per block."""

    stride: int | None = None
    probe: float = DEFAULT_PROBE
    chunk_size: int = DEFAULT_CHUNK
    skip_empty: bool = True
    mode = "pixel"

    def __post_init__(self) -> None:
        stride = DEFAULT_STRIDE if self.stride is None else self.stride
        if int(stride) < 1:
            raise InputError(f"stride: expected a positive integer, got {stride}", option="stride")
        if not 0 <= self.probe <= 1:
            raise InputError(f"probe: expected a fraction in [0, 1], got {self.probe}", option="probe")
        _engine.check_chunk_size(self.chunk_size)
        object.__setattr__(self, "stride", int(stride))

    def cache_tag(self) -> str:
        return f"pixel:stride={self.stride}:probe={float(self.probe)!r}:skip={bool(self.skip_empty)}"

    def code_modules(self) -> tuple:
        return (sys.modules[__name__],)

    def setup(self, occupancy: OccupancyGrid, targets: Targets, candidates: Candidates) -> tuple:
        """The arrays every block of ``_pixel_kernel`` reads (built once, shipped once per worker)."""
        rays, ray_start, foot = camera_rays(candidates, self.stride)
        probe, voxel_size = self.probe, _engine.target_voxel(targets, "visibility_mode")
        centre_mode = probe == 0
        reach = max(c.max_range for c in candidates.cameras) * float(foot.max()) if centre_mode else 0.0
        bprobe = min(1.0, 2.0 * reach / voxel_size) if centre_mode else probe
        bgrid, bshape, b_start, b_ids, thalf = volume_buckets(occupancy, targets, bprobe, voxel_size)
        vbox = bucket_box(bgrid, bshape, b_start)
        s_keys, s_ids = surface_cell_map(occupancy, targets, 1.0 if centre_mode else probe, voxel_size)
        occ = occupancy.occupied.view(np.uint8)
        dist = free_distance(occupancy) if self.skip_empty else np.zeros((1, 1, 1), np.uint8)
        params = np.stack([c.params for c in candidates.cameras])
        world = (occ, dist, occupancy.origin.astype(np.float64), float(occupancy.resolution))
        poses = (np.ascontiguousarray(candidates.positions, dtype=np.float64),
                 np.ascontiguousarray(candidates.rotations, dtype=np.float64),
                 np.ascontiguousarray(candidates.camera_ids, dtype=np.int64))
        tgt = (bgrid, bshape, b_start, b_ids, thalf, vbox, s_keys, s_ids,
               np.ascontiguousarray(targets.positions, dtype=np.float64),
               np.ascontiguousarray(targets.normals, dtype=np.float64), target_cos_limits(targets),
               target_min_px(targets))
        return world, poses, (params, rays, ray_start, foot), tgt, centre_mode, len(targets)

    def rows(self, shared: tuple, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
        world, (pos, rot, cam_ids), (params, rays, ray_start, foot), tgt, centre_mode, n_t = shared
        s, e = start, stop
        mask = np.zeros((e - s, n_t), np.uint8)
        _pixel_kernel(*world, pos[s:e], rot[s:e], cam_ids[s:e], params, rays, ray_start, *tgt, foot, centre_mode,
                      mask)
        rows, cols = np.nonzero(mask == 1)
        indptr = np.zeros(e - s + 1, np.int64)
        np.cumsum(np.bincount(rows, minlength=e - s), out=indptr[1:])
        return indptr, cols.astype(np.int32)

    def info(self, candidates: Candidates, bounds: list, computed: list, seconds: float, shared: tuple | None) -> dict:
        """stride, probe, rays (all candidates), rays_cast (this call), rays_per_s and, when
        the set-up ran, surface_face_cells."""
        per_cam = ray_counts(candidates, self.stride)
        cast = sum(int(per_cam[candidates.camera_ids[s:e]].sum()) for s, e in (bounds[k] for k in computed))
        out = {"stride": self.stride, "probe": self.probe, "rays": int(per_cam[candidates.camera_ids].sum()),
               "rays_cast": cast, "rays_per_s": cast / seconds if seconds > 0 else 0.0}
        if shared is not None:
            out["surface_face_cells"] = int(len(shared[3][6]))  # s_keys
        return out


def compute_pixel_visibility(occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                             stride: int | None = None, probe: float = DEFAULT_PROBE,
                             chunk_size: int = DEFAULT_CHUNK, progress: Progress | None = None,
                             skip_empty: bool = True, executor=None,
                             cache_dir: str | Path | None = None) -> Visibility:
    """V by per-pixel raycasting (rows in candidate order): camplace.visibility.engine.
    compute_visibility of ``PixelEngine(stride, probe, chunk_size, skip_empty)``
    (parameters: PixelEngine). The result does not depend on executor or cache."""
    eng = PixelEngine(stride, probe, chunk_size, skip_empty)
    return _engine.compute_visibility(eng, occupancy, targets, candidates, executor=executor, cache_dir=cache_dir,
                                      progress=progress)
