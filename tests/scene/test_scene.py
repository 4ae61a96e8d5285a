"""Scene building: occupancy grid, walls, floor, ceiling, boxes."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.scene.build import build_scene
from tests.conftest import box_room


def test_walls_floor_ceiling_and_box_are_occupied():
    scene = build_scene(box_room(obstacles=[{"name": "b", "box": {"min": [1, 1, 0], "max": [2, 2, 1.5]}}]))
    occ = scene.occupancy
    pts = np.array([
        [2.0, 2.0 + 1e-3, -0.02],   # floor slab
        [2.0, 2.5, 3.02],           # ceiling slab
        [-0.02, 2.0, 1.0],          # outside the west wall
        [1.5, 1.5, 1.0],            # inside the box
        [2.5, 2.5, 1.0],            # free
        [1.5, 1.5, 1.7],            # above the box: free
    ])
    assert occ.is_occupied(pts).tolist() == [True, True, True, True, False, False]
    assert scene.floor_area == pytest.approx(16.0)


def test_non_convex_footprint_cells():
    scene = build_scene(box_room(footprint=[[0, 0], [4, 0], [4, 2], [2, 2], [2, 4], [0, 4]]))
    pts = np.array([[3.0, 3.0, 1.0], [1.0, 3.0, 1.0], [3.0, 1.0, 1.0]])
    assert scene.occupancy.is_occupied(pts).tolist() == [True, False, False]


def test_self_intersecting_footprint_is_an_input_error():
    with pytest.raises(InputError, match="room.footprint"):
        build_scene(box_room(footprint=[[0, 0], [4, 4], [4, 0], [0, 4]]))


def test_grid_too_large_is_refused_before_allocating():
    spec = box_room(footprint=[[0, 0], [5000, 0], [5000, 5000], [0, 5000]])
    with pytest.raises(InputError, match="GiB"):
        build_scene(spec)
