"""Points on the sampled people as targets (camplace.targets.people, issue 36)."""

from __future__ import annotations

import numpy as np

from camplace.targets.build import Targets
from camplace.targets.crowd import Crowds
from camplace.targets.people import people_targets, person_coverage


def base() -> Targets:
    """Two volume regions: 'aisle' (x < 5, weight 1, 0 px/m) and 'till' (x >= 5, weight 3, 40 px/m)."""
    pos = np.array([[1.0, 1.0, 1.0], [6.0, 1.0, 1.0]])
    return Targets(pos, np.zeros((2, 3)), np.array([3, 2]), np.array([1.0, 3.0]), np.array([0, 1], np.int32),
                   ("aisle", "till"), ("volume", "volume"), np.array([90.0, 90.0]), np.array([0.0, 40.0]), 0.25)


def test_points_order_region_and_weight():
    cr = Crowds(np.array([[0.5, 2.0], [7.0, 0.0], [2.0, 2.0]]), np.array([0, 2, 3], np.int64), 0.25, 1.75)
    p = people_targets(cr, base(), [1.25, 1.6], 2)
    t = p.targets
    assert t.positions.tolist() == [[0.5, 2.0, 1.25], [0.5, 2.0, 1.6], [7.0, 0.0, 1.25], [7.0, 0.0, 1.6],
                                    [2.0, 2.0, 1.25], [2.0, 2.0, 1.6]]
    assert p.ptr.tolist() == [0, 4, 6] and p.person.tolist() == [0, 0, 1, 1, 2, 2]
    assert t.region_ids.tolist() == [0, 0, 1, 1, 0, 0]  # the zone of the nearest volume target in plan
    assert t.weights.tolist() == [0.5, 0.5, 1.5, 1.5, 0.5, 0.5]  # the person's weight shared by its points
    assert t.gamma.tolist() == [2] * 6 and not t.is_surface.any()
    assert t.region_names == ("aisle", "till") and t.min_px_per_m.tolist() == [0.0, 40.0]


def test_nobody_gives_no_points():
    p = people_targets(Crowds(np.zeros((0, 2)), np.array([0, 0], np.int64), 0.25, 1.75), base(), [1.6], 2)
    assert len(p.targets) == 0 and p.ptr.tolist() == [0, 0] and p.n_samples == 1


def test_a_person_is_seen_as_well_as_its_least_seen_point():
    cov = np.array([[3, 1, 2, 2], [0, 4, 5, 6]])  # two samples, two persons of two points
    assert person_coverage(cov, 2).tolist() == [[1, 2], [0, 5]]
