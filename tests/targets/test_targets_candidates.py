"""Targets and candidates: counts and poses known by hand."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from camplace.spec.builtin import resolve_scene
from camplace.cameras.models import CameraModel
from camplace.cameras.candidates import build_candidates, location_ids_of, rotation_from_ypr, ypr_from_rotation
from camplace.scene.build import build_scene
from camplace.targets.build import build_targets
from tests.conftest import box_room


def test_volume_targets_count_and_obstacle_exclusion():
    # 4 m x 4 m at 0.25 m: 256 voxels per layer; a 1 m x 1 m box removes 16 at 1.0 m, none at 2.0 m
    spec = box_room(obstacles=[{"name": "b", "box": {"min": [1, 1, 0], "max": [2, 2, 1.5]}}],
                    targets=[{"name": "w", "kind": "volume", "heights": [1.0, 2.0], "coverage": 3}])
    t = build_targets(build_scene(spec))
    assert len(t) == 256 - 16 + 256
    assert set(np.unique(t.positions[:, 2])) == {1.0, 2.0}
    assert (t.gamma == 3).all() and not t.is_surface.any()


def test_surface_targets_on_faces_with_outward_normals():
    spec = box_room(obstacles=[{"name": "b", "box": {"min": [1, 1, 0], "max": [2, 3, 1.0]}}],
                    targets=[{"name": "s", "kind": "surface", "of": ["b"], "faces": ["+x", "-y"], "coverage": 1}])
    t = build_targets(build_scene(spec))
    plus_x = t.normals[:, 0] == 1
    minus_y = t.normals[:, 1] == -1
    assert plus_x.sum() == 8 * 4 and minus_y.sum() == 4 * 4  # 2 m x 1 m and 1 m x 1 m faces in 0.25 m patches
    assert np.allclose(t.positions[plus_x, 0], 2.0) and np.allclose(t.positions[minus_y, 1], 1.0)


def test_face_against_wall_has_no_targets():
    spec = box_room(obstacles=[{"name": "b", "box": {"min": [0, 1, 0], "max": [0.5, 3, 1.0]}}],
                    targets=[{"name": "s", "kind": "surface", "of": ["b"], "faces": ["-x", "+x"], "coverage": 1}])
    t = build_targets(build_scene(spec))
    assert (t.normals[:, 0] == 1).all() and len(t) == 8 * 4


def test_ceiling_grid_candidates_and_locations():
    spec = box_room(mounts=[{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0,
                             "yaw_deg": {"start": 0, "stop": 330, "step": 30}, "pitch_deg": [30, 45, 60]}])
    sc = build_scene(spec)
    c = build_candidates(sc, {"cam": CameraModel.pinhole_from_fov("cam", (640, 480), (90, 70))})
    assert len(c) == 9 * 36  # interior grid points (1..3)^2 of a 4 m room
    assert len(np.unique(c.location_ids)) == 9
    assert np.allclose(c.positions[:, 2], 2.9)


def test_paper_store_candidate_count():
    spec, _, _ = resolve_scene("standard-store")
    sc = build_scene(spec)
    c = build_candidates(sc, {"wide": CameraModel.pinhole_from_fov("wide", (1780, 720), (71, 36))})
    assert len(c) == 99 * 36
    assert sc.floor_area == pytest.approx(116.4)


def test_rotation_conventions():
    R = rotation_from_ypr(0, 0, 0)[0]
    assert np.allclose(R[:, 2], [1, 0, 0])   # forward = +x at yaw 0
    assert np.allclose(R[:, 1], [0, 0, -1])  # image down = world down
    R = rotation_from_ypr(90, 30, 0)[0]
    assert np.allclose(R[:, 2], [0, np.cos(np.radians(30)), -np.sin(np.radians(30))])
    assert np.allclose(R[:, 0], [1, 0, 0])   # looking +y, image right = +x


@settings(max_examples=100, deadline=None)
@given(st.floats(0, 359.9), st.floats(-80, 80), st.floats(-170, 170))
def test_rotation_is_proper_and_inverts(yaw, pitch, roll):
    R = rotation_from_ypr(yaw, pitch, roll)
    assert np.allclose(R[0] @ R[0].T, np.eye(3), atol=1e-12) and np.isclose(np.linalg.det(R[0]), 1)
    back = ypr_from_rotation(R)[0]
    assert np.allclose(rotation_from_ypr(*back), R, atol=1e-9)


def test_location_ids_group_equal_positions():
    p = np.array([[0, 0, 1], [1, 0, 1], [0, 0, 1], [1, 0, 1.0004]])
    assert location_ids_of(p).tolist() == [0, 1, 0, 1]
