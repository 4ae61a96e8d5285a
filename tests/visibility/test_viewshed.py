"""Viewsheds at a working height: filled polygons clipped by occlusion, with DORI bands."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import Point, box

from camplace.cameras.candidates import rotation_from_ypr
from camplace.cameras.models import CameraModel
from camplace.scene.build import build_scene
from camplace.visibility.viewshed import DORI_LEVELS, dori_distances, viewshed
from conftest import box_room

ROOM = [[0, 0], [8, 0], [8, 6], [0, 6]]
CAM = CameraModel.pinhole_from_fov("c", (1280, 720), (90, 60), max_range=6.0)


def _pose(yaw: float, pitch: float) -> np.ndarray:
    return rotation_from_ypr(yaw, pitch, 0)[0]


@pytest.fixture(scope="module")
def pillar_room():
    pillar = {"name": "pillar", "box": {"min": [3.8, 2.8, 0.0], "max": [4.2, 3.2, 3.0]}}
    return build_scene(box_room(obstacles=[pillar], footprint=ROOM))


@pytest.fixture(scope="module")
def empty_room():
    return build_scene(box_room(footprint=ROOM))


def test_pillar_shadow_is_missing_from_the_polygon(pillar_room, empty_room):
    """Camera at (1, 3, 1.5) looking +x: the pillar at x 3.8..4.2, y 2.8..3.2 casts a wedge
    (its corners seen from the camera) that the polygon leaves out; beside it is seen."""
    p = np.array([1.0, 3.0, 1.5])
    vs = viewshed(pillar_room.occupancy, CAM, p, _pose(0, 0), height=1.5)
    free = viewshed(empty_room.occupancy, CAM, p, _pose(0, 0), height=1.5)
    assert vs.polygon.is_valid and not vs.polygon.is_empty
    for x in (4.6, 5.5, 6.5):  # on the axis behind the pillar: in the shadow
        assert not vs.polygon.contains(Point(x, 3.0)) and free.polygon.contains(Point(x, 3.0))
    assert not vs.polygon.intersects(box(3.85, 2.85, 4.15, 3.15))  # the pillar itself
    for y in (1.5, 4.5):  # beside the wedge, at the same distance
        assert vs.polygon.contains(Point(5.5, y))
    # the wedge behind the pillar, to the end of range (x <= 1 + 6): about 0.5 * (6^2 - 3^2) * 0.4 / 3 m²
    shadow = free.polygon.difference(vs.polygon).area
    assert 1.2 < shadow < 2.6
    assert vs.area < free.area


def test_ceiling_camera_loses_the_shadow_of_a_full_height_pillar(pillar_room):
    p = np.array([1.0, 3.0, 2.8])
    vs = viewshed(pillar_room.occupancy, CAM, p, _pose(0, 30), height=1.5)
    assert vs.polygon.contains(Point(3.0, 3.0))  # in front of the pillar
    assert not vs.polygon.contains(Point(5.0, 3.0))  # behind it


def test_camera_against_a_wall_has_no_polygon_beyond_it(empty_room):
    """Camera 0.1 m from the wall x = 0 looking +x, and one looking at the wall: nothing past it."""
    vs = viewshed(empty_room.occupancy, CAM, np.array([0.1, 3.0, 2.5]), _pose(0, 30))
    assert not vs.polygon.is_empty and vs.polygon.bounds[0] >= -0.05
    back = viewshed(empty_room.occupancy, CAM, np.array([0.1, 3.0, 2.5]), _pose(180, 30))
    assert back.polygon.is_empty or back.polygon.bounds[0] >= -0.05
    assert back.area < 0.05


def test_interior_wall_stops_the_polygon():
    wall = {"name": "wall", "box": {"min": [4.0, 0.0, 0.0], "max": [4.1, 6.0, 3.0]}}
    sc = build_scene(box_room(obstacles=[wall], footprint=ROOM))
    vs = viewshed(sc.occupancy, CAM, np.array([2.0, 3.0, 2.5]), _pose(0, 20))
    assert vs.polygon.bounds[2] <= 4.0 + 0.05 and vs.area > 1.0
    against = viewshed(sc.occupancy, CAM, np.array([3.95, 3.0, 2.5]), _pose(0, 20))
    assert against.polygon.is_empty or against.polygon.bounds[2] <= 4.0 + 0.05


def test_dori_bands_are_nested_inside_the_polygon(empty_room):
    vs = viewshed(empty_room.occupancy, CAM, np.array([1.0, 3.0, 2.8]), _pose(0, 30))
    names = [n for n, _ in DORI_LEVELS]
    assert names == ["detect", "observe", "recognise", "identify"]
    prev = vs.polygon
    for n in names:
        band = vs.bands[n]
        assert band.difference(prev).area < 1e-6
        prev = band
    # a 1280 x 720 px, 90 x 60 deg lens: min(fx, fy) = 623.5 px, identify (250 px/m) to 2.49 m
    assert 0.0 < vs.bands["identify"].area < vs.bands["detect"].area
    d = dori_distances(CAM)
    assert d["identify"] == pytest.approx(min(CAM.fx, CAM.fy) / 250, abs=0.03)  # pinhole on axis: f / z
    assert d["detect"] == pytest.approx(6.0)  # 640 / 25 = 25.6 m: capped at the range


def test_out_of_reach_height_gives_an_empty_viewshed(empty_room):
    short = CameraModel.pinhole_from_fov("s", (640, 480), (60, 45), max_range=1.0)
    vs = viewshed(empty_room.occupancy, short, np.array([2.0, 3.0, 2.9]), _pose(0, 60), height=0.5)
    assert vs.polygon.is_empty and vs.area == 0.0 and all(b.is_empty for b in vs.bands.values())


def test_time_budget_leaves_empty_stand_ins(empty_room):
    from types import SimpleNamespace

    from camplace.visibility.viewshed import viewsheds

    c = SimpleNamespace(cameras=[CAM], camera_ids=np.zeros(3, int), positions=np.array([[1.0, 3.0, 2.5]] * 3),
                        rotations=np.array([_pose(0, 30)] * 3))
    full = viewsheds(empty_room.occupancy, c, [0, 1, 2])
    assert [v.computed for v in full] == [True] * 3 and all(v.area > 1.0 for v in full)
    none = viewsheds(empty_room.occupancy, c, [0, 1, 2], budget_s=0.0)
    assert [v.computed for v in none] == [False] * 3
    assert all(v.polygon.is_empty and set(v.bands) == {n for n, _ in DORI_LEVELS} for v in none)
