"""Test people in the camera views (camplace.outputs.render_people, issue 36)."""

from __future__ import annotations

import numpy as np

from camplace.outputs.render_people import PERSON_RGB, draw_people, ray_cylinders


def test_known_hits():
    o = np.array([0.0, 0.0, 1.0])
    dirs = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.5], [0.0, 1.0, 0.0], [1.0, 0.0, -0.1]])
    t, shade = ray_cylinders(o, dirs, np.array([[3.0, 0.0]]), 0.5, 1.75)
    assert np.isclose(t[0], 2.5) and np.isclose(shade[0], 1.0)  # straight at the side, face on
    assert np.isinf(t[1]) and np.isinf(t[2])  # over the head (z 2.25 at x 2.5), and away from it
    assert np.isclose(t[3], 2.5)
    top, _ = ray_cylinders(np.array([3.0, 0.0, 3.0]), np.array([[0.0, 0.0, -1.0]]), np.array([[3.0, 0.0]]), 0.5, 1.75)
    assert np.isclose(top[0], 1.25)  # from above: the top of the head


def test_a_person_in_front_of_the_camera_is_drawn(demo_inputs):
    from camplace.outputs.render import render_view

    sc, _, c = demo_inputs
    i = 0
    cam = c.cameras[int(c.camera_ids[i])]
    view = render_view(sc, cam, c.positions[i], c.rotations[i], width=64)
    ahead = c.positions[i] + c.rotations[i][:, 2] * 2.0  # 2 m along the optical axis
    drawn = draw_people(view, cam, c.positions[i], c.rotations[i], ahead[None, :2], 0.25, 1.75)
    centre = drawn.rgb[drawn.rgb.shape[0] // 2, drawn.rgb.shape[1] // 2]
    assert np.allclose(centre / PERSON_RGB, centre[0] / PERSON_RGB[0])  # the person's colour, shaded
    assert drawn.depth[drawn.depth.shape[0] // 2, drawn.depth.shape[1] // 2] < view.depth[
        view.depth.shape[0] // 2, view.depth.shape[1] // 2]
    assert draw_people(view, cam, c.positions[i], c.rotations[i], np.zeros((0, 2)), 0.25, 1.75) is view


def test_camera_views_draw_the_test_people(demo_run):
    from camplace.outputs.report_html import camera_views

    r = demo_run
    i = int(r.placement.selected[0])
    c = r.visibility.candidates
    ahead = (c.positions[i] + c.rotations[i][:, 2] * 2.0)[None, :2]
    plain, _ = camera_views(r.scene, r.visibility, r.placement.selected[:1], width=64, budget_s=float("inf"))
    crowd, _ = camera_views(r.scene, r.visibility, r.placement.selected[:1], width=64, budget_s=float("inf"),
                            people=(ahead, 0.25, 1.75))
    assert plain[0]["uri"] != crowd[0]["uri"] and plain[0]["caption"] == crowd[0]["caption"]
