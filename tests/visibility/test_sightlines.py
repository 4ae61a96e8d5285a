"""The voxel kernel's view-cone culling (camplace.visibility.sightlines): it skips only pairs
the exact tests refuse, so V is the brute-force V (every candidate against every target
through ``_passes_view`` and ``segment_clear``) bit for bit, on built-in scenes and on
random scenes, lenses and poses."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from camplace.cameras.candidates import Candidates, rotation_from_ypr
from camplace.cameras.models import CameraModel, project_nb
from camplace.scene.build import OccupancyGrid
from camplace.spec.quality import target_min_px
from camplace.targets.build import Targets
from camplace.visibility.raywalk import segment_clear
from camplace.visibility.sightlines import (SURFACE_OFFSET, _passes_view, cone_angle, cube_bin, cube_bins,
                                           work_arrays)
from camplace.visibility.voxel import compute_visibility, target_cos_limits, target_grid

from conftest import builtin_inputs, same_csr


def brute_force_v(occupancy: OccupancyGrid, targets: Targets, cands: Candidates) -> sp.csr_matrix:
    """V by the definition: every (candidate, target) pair through the exact tests."""
    occ, o, res = occupancy.occupied.view(np.uint8), occupancy.origin.astype(float), float(occupancy.resolution)
    tpos, tnrm = np.asarray(targets.positions, float), np.asarray(targets.normals, float)
    tcos, tpx = target_cos_limits(targets), target_min_px(targets)
    off = SURFACE_OFFSET * res
    rows, cols = [], []
    for i in range(len(cands)):
        p, R = np.asarray(cands.positions[i], float), np.asarray(cands.rotations[i], float)
        params = cands.cameras[int(cands.camera_ids[i])].params
        for j in range(len(tpos)):
            t, n = tpos[j], tnrm[j]
            if _passes_view(p, R, params, t[0], t[1], t[2], n[0], n[1], n[2], tcos[j], tpx[j]) and segment_clear(
                    occ, o[0], o[1], o[2], res, p[0], p[1], p[2], t[0] + n[0] * off, t[1] + n[1] * off,
                    t[2] + n[2] * off):
                rows.append(i)
                cols.append(j)
    return sp.csr_matrix((np.ones(len(rows), np.uint8), (rows, cols)), shape=(len(cands), len(tpos)))


@pytest.mark.parametrize("scene, step", [("demo", 4), ("catalogue-store", 60)])
def test_builtin_v_is_the_brute_force_v(demo_inputs, scene, step):
    """demo: pinhole; catalogue-store: fisheye and two pinhole ranges."""
    sc, t, c = demo_inputs if scene == "demo" else builtin_inputs(scene)
    c = c.subset(np.arange(0, len(c), step))
    ref = brute_force_v(sc.occupancy, t, c)
    assert ref.nnz > 5_000
    same_csr(ref, compute_visibility(sc.occupancy, t, c).V)


def _camera(kind: int, a: float, b: float, k1: float) -> CameraModel:
    if kind == 0:
        return CameraModel.from_intrinsics("p", "pinhole", (64, 48), 30.0 + 40 * a, 30.0 + 40 * b, 10 + 44 * a,
                                           5 + 38 * b, max_range=4.0)
    if kind == 1:
        return CameraModel.from_fov("o", "opencv", (64, 48), (60 + 60 * a, 40 + 50 * b), distortion=(k1, 0.0, 0.0, 0.0, 0.0),
                                    max_range=3.0)
    return CameraModel.from_fov("f", "fisheye", (64, 64), (120 + 80 * a, 120 + 80 * a), max_range=3.5,
                                max_fov_deg=150 + 60 * b)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), kinds=st.lists(st.integers(0, 2), min_size=1, max_size=3),
       ab=st.tuples(st.floats(0, 1), st.floats(0, 1)), k1=st.floats(-0.2, 0.2))
def test_random_scene_v_is_the_brute_force_v(seed, kinds, ab, k1):
    """Random boxes, volume and surface targets, lenses and poses (several per position, so
    the per-position bins and line cache are reused)."""
    rng = np.random.default_rng(seed)
    occ = np.zeros((40, 40, 20), bool)
    for _ in range(4):
        lo = rng.integers(0, [36, 36, 16])
        hi = lo + rng.integers(1, 10, 3)
        occ[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]] = True
    grid = OccupancyGrid(occ, np.zeros(3), 0.1)
    n_t = 80
    pos = rng.uniform([0.05, 0.05, 0.05], [3.95, 3.95, 1.95], (n_t, 3))
    nrm = np.zeros((n_t, 3))
    surf = rng.random(n_t) < 0.4
    nrm[surf, rng.integers(0, 3, surf.sum())] = rng.choice([-1.0, 1.0], surf.sum())
    targets = Targets(pos, nrm, np.ones(n_t, np.int64), np.ones(n_t), surf.astype(np.int32), ("v", "s"),
                      ("volume", "surface"), np.array([90.0, 70.0]))
    cams = tuple(_camera(k, ab[0], ab[1], k1) for k in kinds)
    n_pos, per = 4, 6
    cpos = np.repeat(rng.uniform([0.1, 0.1, 0.2], [3.9, 3.9, 1.9], (n_pos, 3)), per, axis=0)
    ypr = np.c_[rng.uniform(-180, 180, n_pos * per), rng.uniform(-90, 90, n_pos * per), rng.uniform(-30, 30, n_pos * per)]
    ids = rng.integers(0, len(cams), n_pos * per).astype(np.int32)
    cands = Candidates(cpos, rotation_from_ypr(ypr[:, 0], ypr[:, 1], ypr[:, 2]), ypr, ids,
                       np.repeat(np.arange(n_pos), per), cams)
    same_csr(brute_force_v(grid, targets, cands), compute_visibility(grid, targets, cands, grid_cell=0.7).V)


BINS = cube_bins()


@settings(max_examples=200, deadline=None)
@given(v=st.tuples(*[st.floats(-1e3, 1e3, allow_nan=False)] * 3).filter(lambda v: max(map(abs, v)) > 1e-6))
def test_a_direction_lies_within_its_bin(v):
    bins = BINS
    b = cube_bin(*v, 8)
    u = np.asarray(v) / np.linalg.norm(v)
    assert math.acos(min(1.0, float(u @ bins[b, :3]))) <= bins[b, 3] + 1e-9


def test_bins_cover_the_sphere_evenly():
    bins = cube_bins()
    assert bins.shape == (384, 4)
    assert np.allclose(np.linalg.norm(bins[:, :3], axis=1), 1.0)
    # a cube-map cell reaches 6.3-10.1 deg from its centre at side 8
    assert math.radians(6) < bins[:, 3].min() and bins[:, 3].max() < math.radians(10.5)
    assert cube_bin(1.0, 0.0, 0.0, 8) != cube_bin(-1.0, 0.0, 0.0, 8)


def test_pinhole_cone_is_the_image_corner():
    """90 x 70 deg pinhole, principal point centred: corner at atan(hypot(tan 45, tan 35))."""
    cam = CameraModel.pinhole_from_fov("c", (640, 480), (90.0, 70.0))
    want = math.atan(math.hypot((640 / 2) / cam.fx, (480 / 2) / cam.fy))
    assert cone_angle(cam.params) == pytest.approx(want, rel=1e-12)
    assert math.degrees(want) == pytest.approx(math.degrees(math.atan(math.hypot(1.0, math.tan(math.radians(35))))),
                                               abs=0.2)


@settings(max_examples=100, deadline=None)
@given(kind=st.integers(0, 2), a=st.floats(0, 1), b=st.floats(0, 1), k1=st.floats(-0.2, 0.2),
       d=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda d: max(map(abs, d)) > 1e-3))
def test_nothing_in_the_image_lies_outside_the_cone(kind, a, b, k1, d):
    cam = _camera(kind, a, b, k1)
    x, y, z = d
    if project_nb(cam.params, x, y, z)[2]:
        assert math.atan2(math.hypot(x, y), z) <= cone_angle(cam.params) + 1e-9


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), cell=st.floats(0.2, 3.0), rng=st.floats(0.1, 6.0))
def test_work_arrays_hold_every_target_in_range(seed, cell, rng):
    """The kernel writes the targets within range of a position into the work arrays unchecked:
    their length must bound that count for any position, inside the grid or far outside it."""
    r = np.random.default_rng(seed)
    pos = r.uniform([0, 0, 0], [8, 5, 2], (300, 3))
    t = Targets(pos, np.zeros_like(pos), np.ones(300, np.int64), np.ones(300), np.zeros(300, np.int32), ("v",),
                ("volume",), np.array([90.0]))
    g = target_grid(t, cell)
    cams = r.uniform([-10, -10, 0], [18, 15, 3], (20, 3))
    n = len(work_arrays(g.params, g.cell_start, cams, rng)[0])
    d2 = ((pos[None, :, :] - cams[:, None, :]) ** 2).sum(-1)
    assert n >= (d2 <= rng * rng).sum(1).max()
