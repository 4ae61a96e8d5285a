"""Triangulation quality: hand-known ray angles, the well-triangulated share, the
triangulation-aware greedy."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from camplace.core.errors import InputError
from camplace.metrics.triangulation import ray_angle_deg, well_triangulated, well_triangulated_of_selection
from camplace.problem.triangulation import effective_coverage

FACING = np.array([[-2.0, 0.0, 1.0], [2.0, 0.0, 1.0]])  # two cameras facing each other across (0, 0, 1)
SIDE = np.array([[-1.0, 0.0, 3.0], [1.0, 0.0, 3.0]])  # side by side 2 m apart, 2 m above the point (0, 0, 1)
P = np.array([0.0, 0.0, 1.0])


def test_facing_cameras_meet_at_180_degrees():
    assert ray_angle_deg(P, FACING[0], FACING[1]) == pytest.approx(180.0)


def test_side_by_side_cameras_meet_at_known_angle():
    # each ray is 1 m across and 2 m down, atan(1/2) off the vertical -> 2 atan(1/2)
    assert ray_angle_deg(P, SIDE[0], SIDE[1]) == pytest.approx(math.degrees(2 * math.atan(0.5)))  # 53.13 deg
    # the same camera twice: 0 deg
    assert ray_angle_deg(P, SIDE[0], SIDE[0]) == pytest.approx(0.0)
    # perpendicular rays
    assert ray_angle_deg(P, [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]) == pytest.approx(90.0)


def test_well_triangulated_by_hand():
    V = sp.csr_matrix(np.ones((2, 1), np.uint8))
    assert not well_triangulated(V, FACING, P[None])[0]  # 180 deg: outside [20, 160]
    assert well_triangulated(V, SIDE, P[None])[0]  # 53 deg: inside
    # configurable range: ask for at least 60 deg and 53 deg is not enough
    assert not well_triangulated(V, SIDE, P[None], min_deg=60, max_deg=160)[0]
    # one camera never triangulates
    assert not well_triangulated(sp.csr_matrix(np.ones((1, 1))), SIDE[:1], P[None])[0]
    # facing pair plus a third camera above: the third pairs with either at 90 deg
    V3 = sp.csr_matrix(np.ones((3, 1), np.uint8))
    assert well_triangulated(V3, np.r_[FACING, [[0.0, 0.0, 3.0]]], P[None])[0]
    with pytest.raises(InputError):
        well_triangulated(V, SIDE, P[None], min_deg=100, max_deg=50)


def test_only_cameras_that_see_the_target_count():
    # camera 0 and 1 side by side, but camera 1 does not see target 1
    V = sp.csr_matrix(np.array([[1, 1], [1, 0]], np.uint8))
    ok = well_triangulated(V, SIDE, np.array([P, P]))
    assert ok.tolist() == [True, False]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-5, 5, allow_nan=False), min_size=9, max_size=9))
def test_angle_is_symmetric_and_in_range(xs):
    t, a, b = np.array(xs[:3]), np.array(xs[3:6]), np.array(xs[6:])
    if min(np.linalg.norm(t - a), np.linalg.norm(t - b)) < 1e-3:
        return
    ang = ray_angle_deg(t, a, b)
    assert 0.0 <= ang <= 180.0
    assert ang == pytest.approx(ray_angle_deg(t, b, a), abs=1e-9)


def test_effective_coverage_counts_cameras_with_a_partner():
    # target seen by the facing pair (no partner for either) and by a third camera above
    cams = np.r_[FACING, [[0.0, 0.0, 3.0]]]
    V2 = sp.csr_matrix(np.ones((2, 1), np.uint8))
    assert effective_coverage(V2, FACING, P[None]).tolist() == [0]
    V3 = sp.csr_matrix(np.ones((3, 1), np.uint8))
    assert effective_coverage(V3, cams, P[None]).tolist() == [3]  # the top one pairs with both


def test_metrics_report_the_share(demo_run):
    r = demo_run
    d = r.metrics.to_dict()
    assert "well_triangulated_pct" in d
    # a well-triangulated target has >= 2 cameras, so the share is at most the triangulatable share
    assert d["well_triangulated_pct"] <= 100.0 - d["non_triangulatable_pct"] + 1e-9
    for reg in d["regions"].values():
        assert 0.0 <= reg["well_triangulated_pct"] <= 100.0 - reg["non_triangulatable_pct"] + 1e-9
    vis = r.visibility
    well = well_triangulated_of_selection(vis.V, vis.candidates.positions, vis.targets.positions,
                                          r.placement.selected)
    assert d["well_triangulated_pct"] == pytest.approx(100.0 * well.mean())
    # a stricter range can only lower the share
    strict = well_triangulated_of_selection(vis.V, vis.candidates.positions, vis.targets.positions,
                                            r.placement.selected, 60.0, 120.0)
    assert strict.sum() <= well.sum()
