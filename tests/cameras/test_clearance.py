"""Mount clearance (issue 25): no candidate closer than ``mount_rules.clearance`` to a wall
or obstacle, except the surface it hangs from (known answers: a wall at a known distance)."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.cameras.candidates import build_candidates
from camplace.cameras.models import camera_from_spec
from camplace.cameras.mount_rules import CEILING_BACK, occupied_distance
from camplace.scene.build import build_scene
from tests.conftest import box_room


def wall(x0: float) -> dict:
    """A full-height wall 0.2 m thick from x = x0, across the lower half of the 4 x 4 m room."""
    return {"name": "wall", "box": {"min": [x0, 0.0, 0.0], "max": [x0 + 0.2, 2.0, 3.0]}}


def candidates(spec):
    sc = build_scene(spec)
    return sc, build_candidates(sc, {c.name: camera_from_spec(c) for c in spec.cameras})


def test_distance_to_a_wall_face_and_the_surface_behind():
    sc = build_scene(box_room([wall(2.0)]))
    pts = np.array([[1.95, 1.0, 2.9], [1.9, 1.0, 2.9], [1.85, 1.0, 2.9], [1.0, 3.0, 2.9]])
    d = occupied_distance(sc.occupancy, pts, CEILING_BACK, reach=0.3)
    assert d[:3] == pytest.approx([0.05, 0.1, 0.15], abs=1e-9)
    assert d[3] == np.inf  # nothing within reach (the ceiling 0.1 m above lies behind)
    up = occupied_distance(sc.occupancy, pts[3:], np.zeros(3), reach=0.3)  # no mount surface: the ceiling counts
    assert up == pytest.approx([0.1], abs=1e-9)


@pytest.mark.parametrize("x0, kept", [(3.05, False), (3.1, True)])
def test_a_grid_point_too_close_to_a_wall_is_dropped(x0, kept):
    sc, c = candidates(box_room([wall(x0)]))  # the wall's face 0.05 / 0.1 m from the grid points (3, 1), (3, 2)
    near = np.isclose(c.positions[:, 0], 3.0) & (c.positions[:, 1] <= 2.0)
    assert near.sum() == (2 if kept else 0)
    assert c.info["dropped_clearance"] == (0 if kept else 2)
    d = occupied_distance(sc.occupancy, c.positions, CEILING_BACK, reach=0.1)
    assert np.all(d >= 0.1 - 1e-6)


def test_clearance_zero_keeps_them_and_wall_mounts_keep_their_wall():
    spec = box_room([wall(3.05)])
    spec = spec.model_copy(update={"mount_rules": spec.mount_rules.model_copy(update={"clearance": 0.0})})
    assert candidates(spec)[1].info["dropped_clearance"] == 0
    mounts = [{"kind": "wall", "camera": "cam", "height": 2.0, "yaw_deg": [0], "pitch_deg": [30]}]
    c = candidates(box_room(mounts=mounts))[1]  # 5 cm off the wall behind: that wall does not count
    assert len(c) == 16 and c.info["dropped_clearance"] == 0
