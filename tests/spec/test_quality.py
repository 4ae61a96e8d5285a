"""Image quality: pixel density from the lens model, DORI levels, density limits in both modes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camplace.cameras.models import CameraModel
from camplace.cameras.candidates import Candidates, location_ids_of, rotation_from_ypr
from camplace.core.errors import InputError
from camplace.spec.quality import DORI_PX_PER_M, px_per_m_value, target_min_px
from camplace.scene.build import build_scene
from camplace.targets.build import build_targets
from camplace.visibility.voxel import compute_visibility
from camplace.visibility.pixel import compute_pixel_visibility

from conftest import box_room

PIN = CameraModel.pinhole_from_fov("p", (640, 640), (60, 60), max_range=20)
F = 320 / math.tan(math.radians(30))  # 554.26 px


def test_dori_levels_and_numbers():
    assert DORI_PX_PER_M == {"detect": 25.0, "observe": 62.5, "recognise": 125.0, "recognize": 125.0,
                             "identify": 250.0}
    assert px_per_m_value("Identify") == 250.0 and px_per_m_value(80) == 80.0 and px_per_m_value(None) == 0.0
    with pytest.raises(ValueError, match="DORI"):
        px_per_m_value("see")


def test_scene_key_accepts_numbers_and_level_names():
    for value, want in (("observe", 62.5), (40, 40.0), ("recognize", 125.0)):
        spec = box_room(targets=[{"name": "w", "kind": "volume", "heights": [1.0], "coverage": 1,
                                  "min_px_per_m": value}])
        assert spec.targets[0].min_px_per_m_value == want
    with pytest.raises(InputError) as err:
        box_room(targets=[{"name": "w", "kind": "volume", "heights": [1.0], "coverage": 1, "min_px_per_m": "see"}])
    assert "targets[0].min_px_per_m" in str(err.value)
    with pytest.raises(InputError, match="min_px_per_m"):
        box_room(targets=[{"name": "w", "kind": "volume", "heights": [1.0], "coverage": 1, "min_px_per_m": -3}])


def test_pinhole_density_is_f_over_depth():
    pts = np.array([[0.0, 0.0, 2.0], [1.0, 0.5, 2.0], [-0.8, 0.3, 4.0]])
    assert np.allclose(PIN.px_per_m(pts), F / pts[:, 2], rtol=1e-6)
    cam = CameraModel.from_intrinsics("k", "pinhole", (640, 480), 500.0, 400.0, 320, 240)
    assert cam.px_per_m(np.array([[0.0, 0.0, 2.0]]))[0] == pytest.approx(200.0, rel=1e-6)  # min(fx, fy) / z


def test_density_on_an_oblique_surface_uses_the_surface_plane():
    """A patch on the axis tilted 60 deg: along the tilt the image shrinks by cos 60 deg."""
    n = np.array([[math.sin(math.radians(60)), 0.0, -math.cos(math.radians(60))]])
    assert PIN.px_per_m(np.array([[0.0, 0.0, 2.0]]), n)[0] == pytest.approx(F / 2 * 0.5, rel=1e-5)


def test_fisheye_density_from_its_jacobian():
    """Equidistant fisheye: on the axis f / z like a pinhole; at angle theta the tangential
    scale is f theta / (d sin theta) and the radial one f / d: the minimum is f / d."""
    fish = CameraModel.from_fov("f", "fisheye", (1000, 1000), (180, 180))
    f = fish.fx
    assert fish.px_per_m(np.array([[0.0, 0.0, 3.0]]))[0] == pytest.approx(f / 3, rel=1e-6)
    th = math.radians(70)
    p = 2.0 * np.array([[math.sin(th), 0.0, math.cos(th)]])
    assert fish.px_per_m(p)[0] == pytest.approx(f / 2.0, rel=1e-5)


@pytest.fixture(scope="module")
def corridor():
    """A 12 m x 2 m corridor, targets at z = 1 every 0.25 m; a camera at (0.3, 1, 1) looking +x."""
    def make(limit):
        t = [{"name": "w", "kind": "volume", "heights": [1.0], "coverage": 1}]
        if limit is not None:
            t[0]["min_px_per_m"] = limit
        spec = box_room(footprint=[[0, 0], [12, 0], [12, 2], [0, 2]], targets=t)
        sc = build_scene(spec)
        return sc, build_targets(sc)
    p = np.array([[0.3, 1.0, 1.0]])
    cands = Candidates(p, rotation_from_ypr(0.0, 0.0, 0.0), np.zeros((1, 3)), np.zeros(1, np.int32),
                       location_ids_of(p), (PIN,))
    return make, cands


@pytest.mark.parametrize("mode", ["voxel", "pixel"])
def test_density_limit_drops_far_targets(corridor, mode):
    """identify = 250 px/m: kept iff depth x - 0.3 <= f / 250 = 2.217 m."""
    make, cands = corridor

    def V(limit):
        sc, t = make(limit)
        if mode == "voxel":
            return t, compute_visibility(sc.occupancy, t, cands).V.toarray()[0].astype(bool)
        return t, compute_pixel_visibility(sc.occupancy, t, cands, stride=2, probe=0.0).V.toarray()[0].astype(bool)

    t, free = V(None)
    t2, ident = V("identify")
    _, numeric = V(250)
    assert np.array_equal(ident, numeric)
    depth = t.positions[:, 0] - 0.3
    assert free.sum() > ident.sum() > 0
    assert depth[free].max() > 8  # without the limit the camera sees far down the corridor
    assert np.array_equal(ident, free & (depth <= F / 250))
    assert np.array_equal(target_min_px(t2), np.full(len(t2), 250.0))
