"""Refinement moves a varifocal lens's focal length continuously (issue 27): a known answer.

One wall camera (it only turns, and here its single yaw and pitch leave only the focal
length free), 1920 px wide, 2.9 µm pixels, a 2.8-12 mm lens with two grid settings, looks
along +x at a 4 m wide strip 5.9-6.1 m away that needs identify (250 px/m). At 2.8 mm
(f = 966 px) the strip is beyond the identify distance (3.9 m); at 12 mm (f = 4138 px) the
view is 26° wide and misses the strip's ends. Every target is seen between f = 250 x 6.125 /
2.9 µm = 5.3 mm (density at the far row; the nearer rows need less) and the focal length
whose half field of view reaches the strip's ends, 2 m at 5.875 m: 960 / (2 / 5.875) x 2.9 µm
= 8.2 mm. Refinement from the 12 mm grid choice must land in [5.3, 8.2] mm and cover all.
"""

from __future__ import annotations

import numpy as np
import pytest

from camplace.spec.loading import parse_scene

SCENE = {"name": "focal", "voxel_size": 0.25, "occupancy_resolution": 0.05,
         "room": {"footprint": [[0, 0], [8, 0], [8, 6], [0, 6]], "height": 3.0},
         "cameras": [{"name": "vf", "resolution": [1920, 1080], "pixel_um": 2.9, "focal_mm": [2.8, 12],
                      "focal_steps": 2}],
         "mounts": [{"kind": "wall", "camera": "vf", "height": 1.5, "walls": [[[0, 2.5], [0, 3.5]]], "yaw_deg": [0],
                     "pitch_deg": [0]}],
         "targets": [{"name": "rest", "kind": "volume", "heights": [1.5], "coverage": 0}],
         "zones": [{"name": "strip", "polygon": [[5.8, 1], [6.2, 1], [6.2, 5], [5.8, 5]], "coverage": 1,
                    "min_px_per_m": "identify"}]}


def test_refinement_zooms_a_varifocal_lens_to_the_known_range():
    from camplace.workflows.run import run

    r = run(parse_scene(SCENE), budget=1, refine=True, refine_time_s=30)
    info = r.placement.info["refine"]
    assert info["grid_cost"] == 10.0 and info["moved"] == 1  # 12 mm sees 22 of the 32 strip targets
    c = r.visibility.candidates
    (i,) = r.placement.selected
    cam = c.cameras[int(c.camera_ids[i])]
    assert cam.name == "vf" and 5.3 <= cam.focal_mm <= 8.2 and r.metrics.cost == 0.0
    assert cam.fx == pytest.approx(cam.focal_mm / 0.0029) and cam.max_range == pytest.approx(cam.fx / 250.0)
    assert np.allclose(c.positions[i], [0.05, 3.0, 1.5]) and np.allclose(c.angles_deg[i], 0.0)  # only zoomed
    # the appended row is the truth: the refined setting raycast afresh sees the whole strip
    strip = np.flatnonzero(r.visibility.targets.gamma > 0)
    assert set(strip) <= set(r.visibility.V[i].indices)
