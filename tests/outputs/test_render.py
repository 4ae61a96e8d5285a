"""Rendered camera views: what a camera sees, labelled per pixel; PNG output and CLI."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from camplace.cameras.models import CameraModel
from camplace.cameras.candidates import rotation_from_ypr
from camplace.outputs.render import FLOOR, WALL, label_grid, render_view, scaled_camera
from camplace.scene.build import build_scene

from camplace.workflows.render import render_camera
from conftest import box_room

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def room():
    pillar = {"name": "pillar", "box": {"min": [3.0, 1.0, 0.0], "max": [3.5, 3.0, 3.0]}}
    return build_scene(box_room(obstacles=[pillar]))


def test_camera_facing_a_wall_sees_only_wall(room):
    """At (0.8, 2, 1.5) looking -x: the wall at x = 0 (0.8 m away) fills the 71 x 36 deg view."""
    cam = CameraModel.pinhole_from_fov("c", (1780, 720), (71, 36))
    view = render_view(room, cam, np.array([0.8, 2.0, 1.5]), rotation_from_ypr(180, 0, 0)[0], width=178)
    assert view.labels.shape == (72, 178) and view.rgb.shape == (72, 178, 3)
    assert np.all(view.labels == WALL)
    assert np.allclose(view.hits[..., 0], 0.0, atol=0.051)  # every ray ends on the wall plane
    # depth along the ray grows off-axis: 0.8 / cos(angle)
    assert view.depth.min() >= 0.8 - 0.051 and view.depth[36, 89] == pytest.approx(0.8, abs=0.051)


def test_camera_facing_an_obstacle_sees_its_colour(room):
    cam = CameraModel.pinhole_from_fov("c", (640, 480), (60, 45))
    view = render_view(room, cam, np.array([2.4, 2.0, 1.5]), rotation_from_ypr(0, 0, 0)[0], width=64)
    pillar = [k for k, n in view.names.items() if n == "pillar"][0]
    assert np.all(view.labels == pillar)
    colours = view.rgb.reshape(-1, 3)
    assert np.ptp(colours / colours.sum(1, keepdims=True), axis=0).max() < 1e-9  # one hue, only shading varies


def test_floor_seen_when_looking_down(room):
    """A 40 deg fisheye 2.9 m up sees a floor disc of radius <= 2.9 tan(28 deg) = 1.54 m (corners)."""
    cam = CameraModel.from_fov("f", "fisheye", (400, 400), (40, 40))
    view = render_view(room, cam, np.array([1.5, 2.0, 2.9]), rotation_from_ypr(0, 90, 0)[0], width=40)
    assert np.all(view.labels == FLOOR)
    assert np.allclose(view.hits[..., 2], 0.0, atol=0.051)


def test_precomputed_free_distance_gives_the_same_image(room):
    """render_view with a cached free_distance (and label grid) draws exactly the image it
    draws computing them itself, from a pose that sees walls, floor and the pillar."""
    from camplace.visibility.raywalk import free_distance

    cam = CameraModel.from_fov("f", "fisheye", (640, 480), (150, 110))
    pos, rot = np.array([0.7, 0.6, 2.6]), rotation_from_ypr(30, 35, 5)[0]
    fresh = render_view(room, cam, pos, rot, width=96)
    cached = render_view(room, cam, pos, rot, width=96, labels=label_grid(room), dist=free_distance(room.occupancy))
    assert len(set(np.unique(fresh.labels).tolist())) >= 3  # the view is not trivial
    for a, b in ((fresh.rgb, cached.rgb), (fresh.depth, cached.depth), (fresh.labels, cached.labels),
                 (fresh.hits, cached.hits)):
        assert np.array_equal(a, b)
    with pytest.raises(ValueError, match="shape"):
        render_view(room, cam, pos, rot, width=96, dist=np.zeros((1, 1, 1), np.uint8))


def test_report_views_compute_the_distance_transform_once(demo_run, monkeypatch):
    """camera_views renders one view per camera but computes free_distance once."""
    import camplace.outputs.render
    from camplace.outputs.report_html import camera_views

    calls = []
    real = camplace.outputs.render.free_distance

    def counting(occ):
        calls.append(1)
        return real(occ)

    monkeypatch.setattr(camplace.outputs.render, "free_distance", counting)
    sel = demo_run.placement.selected
    views, skipped = camera_views(demo_run.scene, demo_run.visibility, sel, budget_s=1e9)
    assert len(views) == len(sel) >= 2 and skipped == 0
    assert len(calls) == 1


def test_label_grid_names_obstacles(room):
    lab, names = label_grid(room)
    assert set(names.values()) >= {"wall", "floor", "ceiling", "pillar"}
    c = room.occupancy.cell_of(np.array([[3.2, 2.0, 1.0]]))[0]
    assert names[int(lab[tuple(c)])] == "pillar"


def test_scaled_camera_keeps_field_of_view():
    cam = CameraModel.from_intrinsics("o", "opencv", (1280, 720), 900, 900, 640, 360, (-0.2, 0.05, 0, 0, 0))
    small = scaled_camera(cam, 320)
    assert (small.width, small.height) == (320, 180)
    assert np.allclose(small.fov_deg, cam.fov_deg, atol=1e-6)


def test_pixel_rays_are_kept_per_camera_type(room):
    """A second view of the same camera type reuses its rays: the same image, the rays unchanged."""
    from camplace.outputs.render import _pixel_rays

    cam = CameraModel.from_fov("o", "opencv", (640, 480), (90.0, 60.0), distortion=(0.05, 0.0, 0.0, 0.0, 0.0))
    small = scaled_camera(cam, 120)
    assert _pixel_rays(small) is _pixel_rays(scaled_camera(cam, 120))
    assert np.array_equal(_pixel_rays(small), small.pixel_rays(1)) and not _pixel_rays(small).flags.writeable
    R = rotation_from_ypr(np.array([30.0]), np.array([20.0]), np.array([0.0]))[0]
    a = render_view(room, cam, np.array([1.0, 1.0, 2.0]), R, width=120)
    b = render_view(room, cam, np.array([1.0, 1.0, 2.0]), R, width=120)
    assert np.array_equal(a.rgb, b.rgb) and a.rgb.shape == (90, 120, 3)


def test_render_camera_png_and_placement(tmp_path):
    out = tmp_path / "view.png"
    path, view, info = render_camera("demo", 5, out=out, width=120)
    assert path == out and out.read_bytes()[:8] == PNG_MAGIC
    assert info["covered"] > 0 and view.labels.shape[1] == 120
    pl = tmp_path / "placement.json"
    pl.write_text(json.dumps({"cameras": [{"position": [3.0, 2.5, 2.9], "yaw_deg": 90, "pitch_deg": 45,
                                           "roll_deg": 0, "camera": "wide"}]}))
    path2, _, info2 = render_camera("demo", 0, placement=pl, out=tmp_path / "p.png", width=100)
    assert path2.read_bytes()[:8] == PNG_MAGIC and info2["position"] == [3.0, 2.5, 2.9]


def test_render_cli(tmp_path, monkeypatch, capsys):
    from conftest import run_cli

    out = tmp_path / "v.png"
    r = subprocess.run([sys.executable, "-m", "camplace.cli.app", "render", "demo", "--camera", "3", "--out", str(out),
                        "--width", "80"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:8] == PNG_MAGIC
    code, text = run_cli(["render", "demo", "--camera", "99999"], monkeypatch, capsys)  # in-process
    assert code == 2 and "--camera" in text and "Traceback" not in text
