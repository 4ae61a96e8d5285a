"""Test people in the camera views (issue 36): one crowd sample's people drawn into a
rendered view, as the test people designers place by hand in commercial tools.

Each person is a vertical cylinder (radius, height) on the floor; a pixel whose ray meets
a person's side or top before the scene (camplace.outputs.render.RenderedView.depth)
shows that person, shaded by the side's angle to the ray. Draws only.
"""

from __future__ import annotations

import numpy as np

from camplace.cameras.models import CameraModel
from camplace.outputs.render import RenderedView, scaled_camera

PERSON_RGB = np.array([0.55, 0.43, 0.39])  # the report's person colour (#8d6e63)


def ray_cylinders(origin: np.ndarray, dirs: np.ndarray, xy: np.ndarray, radius: float,
                  height: float) -> tuple[np.ndarray, np.ndarray]:
    """First hit of rays origin (3,) + t · dirs (n, 3) on the cylinders at xy (P, 2) (z in
    [0, height], closed top): (t (n,) in units of dirs, inf where none; shade (n,) in [0.45, 1])."""
    o = np.asarray(origin, float)
    d = np.asarray(dirs, float).reshape(-1, 3)
    best = np.full(len(d), np.inf)
    shade = np.ones(len(d))
    r2 = float(radius) ** 2
    a = d[:, 0] ** 2 + d[:, 1] ** 2
    with np.errstate(invalid="ignore", divide="ignore"):  # misses are inf; inf · 0 is not looked at
        for q in np.asarray(xy, float).reshape(-1, 2):
            _one_cylinder(o, d, a, q, float(radius), float(height), r2, best, shade)
    return best, shade


def _one_cylinder(o, d, a, q, radius, height, r2, best, shade) -> None:
    """ray_cylinders for the person at q (2,): updates best and shade where it is nearer."""
    f = o[:2] - q
    b = 2.0 * (d[:, :2] @ f)
    c = f @ f - r2
    disc = b * b - 4.0 * a * c
    ok = (disc > 0) & (a > 1e-12)
    t = np.full(len(d), np.inf)
    t[ok] = (-b[ok] - np.sqrt(disc[ok])) / (2.0 * a[ok])
    z = o[2] + t * d[:, 2]
    side = ok & (t > 0) & (z >= 0) & (z <= height)
    top = np.full(len(d), np.inf)
    down = d[:, 2] < -1e-12
    top[down] = (height - o[2]) / d[down, 2]
    pt = o[:2] + top[:, None] * d[:, :2]
    on_top = down & (top > 0) & (np.sum((pt - q) ** 2, axis=1) <= r2)
    hit = np.where(side, t, np.inf)
    hit = np.where(on_top & (top < hit), top, hit)
    closer = hit < best
    if closer.any():
        p = o[:2] + hit[closer, None] * d[closer, :2]
        nrm = (p - q) / max(float(radius), 1e-9)
        cos = np.abs(np.sum(nrm * d[closer, :2], axis=1)) / np.sqrt(np.maximum(a[closer], 1e-12))
        shade[closer] = np.where(on_top[closer] & (top[closer] <= hit[closer]), 1.0, 0.45 + 0.55 * cos)
        best[closer] = hit[closer]


def draw_people(view: RenderedView, camera: CameraModel, position: np.ndarray, rotation: np.ndarray,
                xy: np.ndarray, radius: float, height: float) -> RenderedView:
    """``view`` (render_view of this camera and pose) with the people at xy (P, 2) m drawn
    where they are nearer than the scene; labels and depth unchanged outside them."""
    if len(np.asarray(xy).reshape(-1, 2)) == 0:
        return view
    h, w = view.depth.shape
    small = scaled_camera(camera, w)
    dirs = small.pixel_rays(1) @ np.asarray(rotation, float).T  # the rays (and t units) of render_view
    t, shade = ray_cylinders(position, dirs, xy, radius, height)
    depth = view.depth.reshape(-1)
    near = np.isfinite(t) & (t < depth)
    rgb = view.rgb.reshape(-1, 3).copy()
    rgb[near] = PERSON_RGB * shade[near, None]
    d2 = depth.copy()
    d2[near] = t[near]
    return RenderedView(rgb.reshape(h, w, 3), d2.reshape(h, w), view.labels, view.hits, view.scale, view.names)


__all__ = ["draw_people", "ray_cylinders"]
