"""Lenses as sold (issue 27): intrinsics from sensor + focal length, the range from the
DORI pixel density, varifocal settings as candidates, the scene keys and their errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camplace.cameras.candidates import build_candidates, lens_settings
from camplace.cameras.lenses import distance_for_density, focal_px, focal_steps_mm
from camplace.cameras.models import CameraModel, camera_from_spec, cameras_from_spec
from camplace.core.errors import InputError
from camplace.problem.model import type_ids_of
from camplace.scene.build import build_scene
from camplace.spec.loading import parse_scene

from conftest import box_room

DOME = {"name": "dome", "resolution": [2688, 1520], "pixel_um": 2.0, "focal_mm": 4, "price": 1.6}
VARI = {"name": "vari", "resolution": [1920, 1080], "sensor_width_mm": 5.568, "focal_mm": [2.8, 12],
        "focal_steps": 3, "cost": 2.5}


def lens_room(cameras, targets=None, spacing=1.0):
    """box_room with these camera types, every one on one ceiling grid."""
    return box_room(cameras=cameras, targets=targets, mounts=[
        {"kind": "ceiling_grid", "camera": [c["name"] for c in cameras], "spacing": spacing,
         "yaw_deg": [0], "pitch_deg": [45]}])


def test_intrinsics_from_sensor_and_focal_are_the_textbook_pinhole():
    """f_px = f_mm / pixel pitch; the principal point at the image centre; the same camera as
    the one given by its field of view 2 atan(W / 2 / f_px)."""
    spec = lens_room([DOME]).cameras[0]
    cam = camera_from_spec(spec)
    assert cam.fx == cam.fy == pytest.approx(4.0 / 0.002) == focal_px(4, 2.0)
    assert (cam.cx, cam.cy) == (2687 / 2, 1519 / 2) and cam.focal_mm == 4.0 and cam.cost == 1.6
    fov = [math.degrees(2 * math.atan(n / 2 / 2000.0)) for n in (2688, 1520)]
    same = CameraModel.pinhole_from_fov("x", (2688, 1520), fov)
    assert same.fx == pytest.approx(cam.fx, rel=1e-12) and same.fy == pytest.approx(cam.fy, rel=1e-12)
    assert cam.fov_deg == pytest.approx(tuple(fov), rel=1e-9)
    vari = camera_from_spec(lens_room([VARI]).cameras[0])  # pitch from the sensor width: 2.9 µm
    assert vari.fx == pytest.approx(2.8 / (5.568 / 1920)) and vari.lens.pixel_um == pytest.approx(2.9)


@pytest.mark.parametrize("model", ["pinhole", "fisheye"])
@pytest.mark.parametrize("f_mm", [2.8, 6.0, 12.0])
def test_a_target_at_the_identify_distance_has_250_px_per_m(model, f_mm):
    """On the optical axis at d = f_px / 250 the projection's Jacobian gives exactly 250 px/m."""
    cam = camera_from_spec(lens_room([dict(VARI, model=model)]).cameras[0]).at_focal(f_mm)
    d = distance_for_density(cam.fx, 250.0)
    assert cam.px_per_m(np.array([[0.0, 0.0, d]]))[0] == pytest.approx(250.0, rel=1e-6)
    assert cam.px_per_m(np.array([[0.0, 0.0, 1.01 * d]]))[0] < 250.0


def test_range_follows_the_least_density_the_targets_need():
    """No max_range: the range is where the axis density falls to the least density a
    required region needs (a region without one: detect, 25 px/m); max_range wins."""
    ident = [{"name": "a", "kind": "volume", "heights": [1.0], "coverage": 1, "min_px_per_m": "identify"},
             {"name": "b", "kind": "volume", "heights": [1.5], "coverage": 0}]  # not required: ignored
    cam = cameras_from_spec(lens_room([DOME], ident))["dome"]
    assert cam.max_range == pytest.approx(2000.0 / 250.0)
    loose = ident[:1] + [{"name": "b", "kind": "volume", "heights": [1.5], "coverage": 1}]
    assert cameras_from_spec(lens_room([DOME], loose))["dome"].max_range == pytest.approx(80.0)
    fixed = cameras_from_spec(lens_room([dict(DOME, max_range=6.0)], ident))["dome"]
    assert fixed.max_range == 6.0 and fixed.at_focal(4.0).max_range == 6.0
    legacy = cameras_from_spec(box_room())["cam"]  # fov_deg types keep today's keys and default
    assert legacy.lens is None and legacy.max_range == 10.0


def test_varifocal_settings_are_candidates_of_one_type():
    """focal_steps settings from min to max (geometric), each a camera model of the same
    type name; every mount pose gets each setting, all at one location; a per-type limit
    counts every setting of the type."""
    assert np.allclose(focal_steps_mm(2.8, 12, 3), [2.8, math.sqrt(2.8 * 12), 12])
    spec = lens_room([DOME, VARI], spacing=2.0)
    cams = cameras_from_spec(spec)
    models, index = lens_settings(cams)
    assert [m.name for m in models] == ["dome", "vari", "vari", "vari"] and index == {"dome": [0], "vari": [1, 2, 3]}
    assert [m.focal_mm for m in models[1:]] == pytest.approx([2.8, math.sqrt(2.8 * 12), 12])
    assert models[3].max_range == pytest.approx(models[1].max_range * 12 / 2.8)  # range grows with f
    c = build_candidates(build_scene(spec), cams)
    n_pos = len(np.unique(c.location_ids))
    assert len(c) == 4 * n_pos and np.array_equal(np.bincount(c.camera_ids), [n_pos] * 4)
    assert np.array_equal(type_ids_of(c.camera_ids, [m.name for m in models]), np.where(c.camera_ids == 0, 0, 1))


@pytest.mark.parametrize("camera, message", [
    (dict(VARI, focal_mm=[12, 2.8]), r"cameras\[0\]\.focal_mm: expected \[min, max\] with min <= max"),
    (dict(DOME, pixel_um=0), r"cameras\[0\]\.pixel_um: expected .*greater than 0"),
    (dict(DOME, sensor_width_mm=5.0), r"cameras\[0\]\.pixel_um: a lens given by 'focal_mm' needs exactly one"),
    (dict(DOME, cost=1.0), r"cameras\[0\]\.price: give either 'price' or 'cost'"),
    (dict(DOME, fov_deg=[90, 60]), r"give exactly one of 'fov_deg', 'intrinsics', 'calibration', 'focal_mm'"),
    (dict(DOME, focal_steps=3), r"cameras\[0\]\.focal_steps: belongs to a varifocal lens"),
    ({"name": "c", "resolution": [640, 480], "fov_deg": [90, 70], "pixel_um": 2.0},
     r"cameras\[0\]\.pixel_um: belongs to a lens given by 'focal_mm'"),
])
def test_bad_lens_keys_are_one_line_errors(camera, message):
    with pytest.raises(InputError, match=message) as e:
        lens_room([camera])
    assert "\n" not in str(e.value)


def test_existing_focal_must_fit_the_lens():
    base = lens_room([VARI]).model_dump(exclude_none=True)
    cam = {"id": "E1", "camera": "vari", "position": [1, 1, 2.9], "yaw_deg": 0, "pitch_deg": 30, "focal_mm": 20}
    with pytest.raises(InputError, match=r"existing\[0\]\.focal_mm: 20.0 mm is outside the lens's range; "
                                         r"expected 2.8..12 mm"):
        parse_scene(dict(base, existing=[cam]))
    assert parse_scene(dict(base, existing=[dict(cam, focal_mm=6)])).existing[0].focal_mm == 6.0
