"""Viewsheds: the floor-plan area a camera sees at a working height, from the same raycaster.

A camera's viewshed at height h is the set of plan points (x, y) whose point (x, y, h)
is in range, inside the image through the camera's lens model (``project_nb``) and in
clear line of sight (``camplace.visibility.raywalk.segment_clear``, the voxel engine's
test). It is sampled on a square grid of ``step`` metres around the camera and turned
into shapely polygons by contouring the 0/1 mask (contourpy, matplotlib's contouring),
so it is a filled polygon that stops at walls and has holes behind obstacles, not a
triangle; its vertices are thinned at SIMPLIFY (1 cm: the contour's collinear points). DORI bands (EN/IEC 62676-4, camplace.spec.quality.DORI_PX_PER_M) are the parts
of it where the pixel density across the view ray (``px_per_m_nb``) reaches each level.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numba
import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon

from camplace.cameras.models import CameraModel, project_nb, px_per_m_nb
from camplace.core.executors import on_threads
from camplace.scene.build import OccupancyGrid
from camplace.spec.quality import DORI_PX_PER_M
from camplace.visibility.raywalk import segment_clear

WORKING_HEIGHT = 1.5  # m: the height installers draw fields of view at (faces, hands)
STEP = 0.1  # m between samples of the viewshed grid
SIMPLIFY = 0.01  # m: contour vertices closer than this to the line of their neighbours are dropped
# DORI levels, coarsest first: name -> px/m (the spelling alias "recognize" left out)
DORI_LEVELS: tuple[tuple[str, float], ...] = tuple(
    sorted(((k, v) for k, v in DORI_PX_PER_M.items() if k != "recognize"), key=lambda kv: kv[1]))


@dataclass(frozen=True)
class Viewshed:
    """What one camera sees at ``height`` m. polygon: shapely (Multi)Polygon in plan
    coordinates (m), empty when nothing is seen; bands: DORI level -> the part of
    polygon where the pixel density is at least that level's px/m (nested, coarsest
    first); area: m²; computed: False for a stand-in left empty by a time budget."""

    height: float
    polygon: Polygon | MultiPolygon
    bands: dict[str, Polygon | MultiPolygon] = field(default_factory=dict)
    computed: bool = True

    @property
    def area(self) -> float:
        return float(self.polygon.area)


@numba.njit(cache=True, nogil=True)
def _sample_kernel(occ, origin, res, p, R, params, xs, ys, h, seen, dens):
    """seen[iy, ix] = 1 if (xs[ix], ys[iy], h) is in range, in the image and in sight;
    dens[iy, ix] = its pixel density (px/m) when in range and in the image, else 0."""
    rng = params[7]
    for iy in range(ys.shape[0]):
        for ix in range(xs.shape[0]):
            vx, vy, vz = xs[ix] - p[0], ys[iy] - p[1], h - p[2]
            d2 = vx * vx + vy * vy + vz * vz
            if d2 > rng * rng or d2 <= 1e-18:
                continue
            xc = R[0, 0] * vx + R[1, 0] * vy + R[2, 0] * vz
            yc = R[0, 1] * vx + R[1, 1] * vy + R[2, 1] * vz
            zc = R[0, 2] * vx + R[1, 2] * vy + R[2, 2] * vz
            _, _, ok = project_nb(params, xc, yc, zc)
            if not ok:
                continue
            dens[iy, ix] = px_per_m_nb(params, xc, yc, zc, 0.0, 0.0, 0.0)
            if segment_clear(occ, origin[0], origin[1], origin[2], res, p[0], p[1], p[2], xs[ix], ys[iy], h):
                seen[iy, ix] = 1.0


def sample_grid(occupancy: OccupancyGrid, camera: CameraModel, position: np.ndarray, rotation: np.ndarray,
                height: float = WORKING_HEIGHT, step: float = STEP
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The viewshed's samples: (xs (nx,), ys (ny,) m, seen (ny, nx) 0/1 float, density
    (ny, nx) px/m, 0 outside range or image). The grid covers the camera's range disk at
    ``height`` within the occupancy grid, with one empty sample all round."""
    p = np.asarray(position, np.float64)
    dz = float(height) - p[2]
    r = camera.max_range ** 2 - dz * dz
    lo_g = occupancy.origin[:2]
    hi_g = lo_g + np.array(occupancy.shape[:2]) * occupancy.resolution
    rh = math.sqrt(r) if r > 0 else 0.0
    lo = np.maximum(p[:2] - rh, lo_g) - step
    hi = np.minimum(p[:2] + rh, hi_g) + step
    if r <= 0 or np.any(hi <= lo):
        z = np.zeros((2, 2))
        return np.array([p[0], p[0] + step]), np.array([p[1], p[1] + step]), z, z.copy()
    xs = np.arange(lo[0], hi[0] + step, step)
    ys = np.arange(lo[1], hi[1] + step, step)
    seen = np.zeros((len(ys), len(xs)))
    dens = np.zeros((len(ys), len(xs)))
    occ, origin, R = occupancy.occupied.view(np.uint8), np.asarray(occupancy.origin, np.float64), \
        np.ascontiguousarray(rotation, np.float64)
    on_threads(len(ys), lambda a, b: _sample_kernel(occ, origin, float(occupancy.resolution), p, R, camera.params, xs,
                                                    ys[a:b], float(height), seen[a:b], dens[a:b]), min_rows=16)
    seen[[0, -1], :] = seen[:, [0, -1]] = 0.0  # the border row stays empty: every contour closes
    dens[[0, -1], :] = dens[:, [0, -1]] = 0.0
    return xs, ys, seen, dens


def contour_polygons(xs: np.ndarray, ys: np.ndarray, z: np.ndarray, lower: float,
                     upper: float = np.inf) -> Polygon | MultiPolygon:
    """The region lower <= z < upper of the grid field z (ny, nx) on xs (nx,), ys (ny,) m,
    as a valid shapely geometry (holes kept; empty Polygon when none)."""
    import contourpy

    gen = contourpy.contour_generator(xs, ys, z, fill_type=contourpy.FillType.OuterOffset)
    points, offsets = gen.filled(lower, min(upper, np.finfo(np.float64).max))
    polys = []
    for pts, off in zip(points, offsets):
        rings = [pts[a:b] for a, b in zip(off[:-1], off[1:]) if b - a >= 4]
        if rings:
            polys.append(Polygon(rings[0], rings[1:]))
    if not polys:
        return Polygon()
    geom = shapely.make_valid(MultiPolygon(polys) if len(polys) > 1 else polys[0])
    return shapely.union_all([g for g in getattr(geom, "geoms", [geom]) if g.area > 0]) if geom.area > 0 else Polygon()


def viewshed(occupancy: OccupancyGrid, camera: CameraModel, position: np.ndarray, rotation: np.ndarray,
             height: float = WORKING_HEIGHT, step: float = STEP, clip=None) -> Viewshed:
    """The viewshed of one camera pose (position (3,) m, world-from-camera rotation (3, 3))
    at ``height`` m, with its DORI bands (DORI_LEVELS). ``clip`` (a shapely geometry, e.g.
    the free floor at that height) trims the half sample the contour may reach past a wall."""
    xs, ys, seen, dens = sample_grid(occupancy, camera, position, rotation, height, step)
    poly = contour_polygons(xs, ys, seen, 0.5).simplify(SIMPLIFY)
    if clip is not None and not poly.is_empty:
        poly = poly.intersection(clip)
    bands = {}
    for name, level in DORI_LEVELS:
        band = (contour_polygons(xs, ys, dens, level).simplify(SIMPLIFY) if dens.max() >= level
                and not poly.is_empty else Polygon())
        bands[name] = band.intersection(poly) if not band.is_empty else band
    return Viewshed(float(height), poly, bands)


def viewsheds(occupancy: OccupancyGrid, candidates, selected: np.ndarray, height: float = WORKING_HEIGHT,
              step: float = STEP, clip=None, budget_s: float = float("inf")) -> list[Viewshed]:
    """One Viewshed per selected candidate row (camplace.cameras.candidates.Candidates), in
    the order given. Once ``budget_s`` seconds are spent the rest are empty stand-ins
    (``computed`` False)."""
    c, out = candidates, []
    t0 = time.perf_counter()
    for i in np.asarray(selected, np.int64):
        if time.perf_counter() - t0 > budget_s:
            out.append(Viewshed(float(height), Polygon(), {n: Polygon() for n, _ in DORI_LEVELS}, computed=False))
            continue
        out.append(viewshed(occupancy, c.cameras[int(c.camera_ids[i])], c.positions[i], c.rotations[i], height,
                            step, clip))
    return out


def dori_distances(camera: CameraModel, samples: int = 400) -> dict[str, float]:
    """DORI level -> the farthest distance (m) along the optical axis at which the camera
    still reaches that level's pixel density (0.0 when never; at most max_range)."""
    d = np.linspace(camera.max_range / samples, camera.max_range, samples)
    par = camera.params
    dens = np.array([px_per_m_nb(par, 0.0, 0.0, float(t), 0.0, 0.0, 0.0) for t in d])
    out = {}
    for name, level in DORI_LEVELS:
        ok = np.nonzero(dens >= level)[0]
        out[name] = float(d[ok[-1]]) if len(ok) else 0.0
    return out
