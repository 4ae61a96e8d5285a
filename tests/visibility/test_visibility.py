"""Line of sight, FOV, range and incidence on geometry whose answer is known by hand."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from camplace.cameras.models import CameraModel
from camplace.cameras.candidates import Candidates, rotation_from_ypr
from camplace.scene.build import build_scene
from camplace.targets.build import Targets
from camplace.visibility.voxel import compute_visibility, segment_clear
from tests.conftest import box_room


def _cands(positions, ypr, camera):
    positions = np.atleast_2d(np.asarray(positions, float))
    ypr = np.atleast_2d(np.asarray(ypr, float))
    n = len(positions)
    return Candidates(positions, rotation_from_ypr(ypr[:, 0], ypr[:, 1], ypr[:, 2]), ypr,
                      np.zeros(n, np.int32), np.arange(n), (camera,))


def _targets(positions, normals=None, max_inc=90.0):
    p = np.atleast_2d(np.asarray(positions, float))
    n = np.zeros_like(p) if normals is None else np.atleast_2d(np.asarray(normals, float))
    k = len(p)
    return Targets(p, n, np.ones(k, np.int64), np.ones(k), np.zeros(k, np.int32), ("r",), ("volume",),
                   np.array([max_inc]))


CAM = CameraModel.pinhole_from_fov("cam", (640, 480), (90.0, 70.0), max_range=10.0)


def _seen(scene_spec, cam_pos, ypr, targets, camera=CAM):
    scene = build_scene(scene_spec)
    vis = compute_visibility(scene.occupancy, targets, _cands(cam_pos, ypr, camera))
    return vis.V.toarray()[0].astype(bool)


def test_box_between_camera_and_target_blocks_it():
    t = _targets([[3.5, 2.0, 1.0], [3.5, 0.3, 1.0]])
    free = _seen(box_room(), [0.5, 2.0, 1.0], [0, 0, 0], t)
    assert free.tolist() == [True, True]
    blocked = _seen(box_room(obstacles=[{"name": "b", "box": {"min": [1.5, 1.5, 0], "max": [2.5, 2.5, 2.0]}}]),
                    [0.5, 2.0, 1.0], [0, 0, 0], t)
    assert blocked.tolist() == [False, True]  # the side target stays visible past the box


def test_target_just_inside_and_outside_horizontal_fov():
    # 90 deg horizontal FOV: the edge is 45 deg off-axis; camera at x=0.2 looking +x
    d = 2.0
    inside = [0.2 + d, 2.0 + d * math.tan(math.radians(44.5)), 1.0]
    outside = [0.2 + d, 2.0 - d * math.tan(math.radians(45.5)), 1.0]
    seen = _seen(box_room(footprint=[[0, -1], [4, -1], [4, 5], [0, 5]]), [0.2, 2.0, 1.0], [0, 0, 0],
                 _targets([inside, outside]))
    assert seen.tolist() == [True, False]


def test_target_just_inside_and_outside_range():
    cam = CameraModel.pinhole_from_fov("short", (640, 480), (90.0, 70.0), max_range=2.0)
    seen = _seen(box_room(), [0.5, 2.0, 1.0], [0, 0, 0], _targets([[2.45, 2.0, 1.0], [2.55, 2.0, 1.0]]), cam)
    assert seen.tolist() == [True, False]


def test_target_behind_camera_not_seen():
    seen = _seen(box_room(), [2.0, 2.0, 1.0], [0, 0, 0], _targets([[1.0, 2.0, 1.0]]))
    assert seen.tolist() == [False]


def test_surface_incidence_limit_and_back_side():
    # a box face at x = 2.0 with outward normal -x; the camera looks at it at 50 deg incidence
    spec = box_room(obstacles=[{"name": "b", "box": {"min": [2.0, 1.0, 0], "max": [3.0, 3.0, 2.0]}}])
    target = [2.0, 2.0, 1.0]
    inc = math.radians(50)
    cam_pos = [2.0 - 1.5 * math.cos(inc), 2.0 + 1.5 * math.sin(inc), 1.0]
    yaw = math.degrees(math.atan2(target[1] - cam_pos[1], target[0] - cam_pos[0]))
    for limit, want in ((60.0, True), (40.0, False)):
        seen = _seen(spec, cam_pos, [yaw, 0, 0], _targets([target], [[-1, 0, 0]], max_inc=limit))
        assert seen.tolist() == [want], limit
    # the same patch declared with the opposite normal (+x) faces away from the camera
    seen = _seen(spec, cam_pos, [yaw, 0, 0], _targets([target], [[1, 0, 0]], max_inc=89.0))
    assert seen.tolist() == [False]


def test_non_convex_room_wall_blocks_view():
    # L-shaped room: the corner block (2..4, 2..4) is outside the footprint (a wall)
    spec = box_room(footprint=[[0, 0], [4, 0], [4, 2], [2, 2], [2, 4], [0, 4]])
    cam = [3.5, 1.0, 1.0]  # in the lower arm, looking toward +y/-x
    t = _targets([[1.0, 3.5, 1.0], [1.0, 1.0, 1.0]])
    yaw = math.degrees(math.atan2(3.5 - 1.0, 1.0 - 3.5))
    seen = _seen(spec, cam, [yaw, 0, 0], t, CameraModel.pinhole_from_fov("w", (640, 480), (170.0, 90.0), 10.0))
    # the straight line to (1.0, 3.5) crosses the missing corner? it passes (2.25, 2.25): outside the room
    assert seen.tolist() == [False, True]


def test_segment_clear_hand_cases():
    occ = np.zeros((10, 10, 10), np.uint8)
    occ[5, 5, 5] = 1
    args = (0.0, 0.0, 0.0, 1.0)
    assert not segment_clear(occ, *args, 0.5, 5.5, 5.5, 9.5, 5.5, 5.5)  # through the cell
    assert segment_clear(occ, *args, 0.5, 4.5, 5.5, 9.5, 4.5, 5.5)  # beside it
    assert not segment_clear(occ, *args, 0.5, 0.5, 0.5, 9.5, 9.5, 9.5)  # the diagonal passes (5,5,5)
    assert not segment_clear(occ, *args, 0.5, 0.5, 0.5, 10.5, 0.5, 0.5)  # leaves the grid


def _segment_hits_box(p0, p1, lo, hi) -> bool:
    """Exact slab test: does the segment p0-p1 meet the closed box [lo, hi]?"""
    t0, t1 = 0.0, 1.0
    d = p1 - p0
    for a in range(3):
        if abs(d[a]) < 1e-15:
            if p0[a] < lo[a] or p0[a] > hi[a]:
                return False
            continue
        ta, tb = (lo[a] - p0[a]) / d[a], (hi[a] - p0[a]) / d[a]
        t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
        if t0 > t1:
            return False
    return True


@settings(max_examples=80, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 9), st.floats(0.05, 0.95)), min_size=6, max_size=6),
       st.integers(0, 2**31 - 1))
def test_segment_clear_matches_exact_cell_test(cells_fracs, seed):
    # end points strictly inside cells; tiny irrational offsets rule out exact ties with cell edges
    jitter = 1e-6 * np.array([np.pi, np.e, np.sqrt(2), np.sqrt(3), np.sqrt(5), np.sqrt(7)])
    coords = [c + f + j for (c, f), j in zip(cells_fracs, jitter)]
    rng = np.random.default_rng(seed)
    occ = (rng.random((10, 10, 10)) < 0.08).astype(np.uint8)
    p0, p1 = np.array(coords[:3]), np.array(coords[3:])
    occ[tuple(np.floor(p0).astype(int))] = 0
    occ[tuple(np.floor(p1).astype(int))] = 0
    want = not any(_segment_hits_box(p0, p1, np.array(c, float), np.array(c, float) + 1) for c in np.argwhere(occ))
    assert segment_clear(occ, 0.0, 0.0, 0.0, 1.0, *p0, *p1) == want


def test_dda_walks_the_cells_a_ray_crosses():
    """dda_axis / dda_step (shared by segment_clear and the pixel-mode kernels): a ray from
    (0.05, 0.05, 0.05) along (2, 1, 0) / sqrt(5) through 0.1 m cells crosses x = 0.1 at
    t = 0.05 sqrt(5) / 2 = 0.056, then y = 0.1 at 0.05 sqrt(5) = 0.112, then x = 0.2 at
    0.15 sqrt(5) / 2 = 0.168; it never steps along z (parallel: both t are 1e30)."""
    from camplace.visibility.raywalk import dda_axis, dda_step

    d = np.array([2.0, 1.0, 0.0]) / math.sqrt(5.0)
    p = np.array([0.05, 0.05, 0.05])
    (sx, tmx, tdx), (sy, tmy, tdy), (sz, tmz, tdz) = (dda_axis(0, p[a], d[a], 0.0, 0.1) for a in range(3))
    assert (sx, sy, sz) == (1, 1, -1) and tmz == tdz == 1e30
    assert math.isclose(tmx, 0.05 / d[0]) and math.isclose(tdx, 0.1 / d[0]) and math.isclose(tmy, 0.05 / d[1])
    ix = iy = iz = 0
    cells, ts = [], []
    for _ in range(3):
        ix, iy, iz, tmx, tmy, tmz, axis, t = dda_step(ix, iy, iz, tmx, tmy, tmz, sx, sy, sz, tdx, tdy, tdz)
        cells.append((ix, iy, iz, axis))
        ts.append(t)
    assert cells == [(1, 0, 0, 0), (1, 1, 0, 1), (2, 1, 0, 0)]
    assert np.allclose(ts, [0.05 / d[0], 0.05 / d[1], 0.15 / d[0]])
    assert dda_axis(3, 0.35, -0.5, 0.0, 0.1)[:2] == (-1, (3 * 0.1 + 0.0 - 0.35) / -0.5)
