"""Refinement in a crowd-aware run (issue 36): steep views count in the pitch steps, and a
wall camera may move up or down its wall (a ceiling camera keeps its height)."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.improve.refine import _valid_positions, pose_box


def test_crowd_aware_boxes_move_pitch_and_wall_height():
    from conftest import box_room

    from camplace.workflows.run import prepare

    spec = box_room(mounts=[{"kind": "wall", "camera": "cam", "height": 2.5, "spacing": 1.0, "pitch_deg": [20]},
                            {"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0, "yaw_deg": [0, 90],
                             "pitch_deg": [45]}])
    sc, plain = prepare(spec)
    _, crowd = prepare(spec, extra_pitches=(75.0, 90.0))
    c, p = crowd.candidates, plain.candidates
    wall = int(np.flatnonzero(np.isclose(c.positions[:, 2], 2.5))[0])
    ceil = int(np.flatnonzero(np.isclose(c.positions[:, 2], 2.9))[0])
    assert {20.0, 75.0, 90.0} <= set(c.angles_deg[c.positions[:, 2] == 2.5, 1])
    bw, bc = pose_box(sc, c, wall), pose_box(sc, c, ceil)
    # wall at 2.5 m in a 3 m room: up to 0.4 m (0.1 m below the ceiling), fraction 0.499 of 1 m
    assert bw.half[2] == pytest.approx(0.4) and bw.half[4] == pytest.approx(0.499 * 15)  # pitches 20, 75, 90
    assert bc.half[2] == 0.0 and bc.half[4] == pytest.approx(0.499 * 15)  # 45, 75, 90
    pw = pose_box(sc, p, int(np.flatnonzero(np.isclose(p.positions[:, 2], 2.5))[0]))
    assert pw.half[2] == 0.0 and pw.half[4] == 0.0  # without a crowd: as before
    trial = np.array([np.r_[bw.centre + [0, 0, dz, 0, 0, 0], 0.0] for dz in (-0.3, 0.2, 0.4, 0.7)])
    assert _valid_positions(bw, sc.occupancy, trial).tolist() == [True, True, True, False]  # 3.2 m: in the ceiling
