"""metrics.json crowd.people (camplace.metrics.crowd.people_metrics, issue 36): known answers."""

from __future__ import annotations

import numpy as np

from camplace.metrics.crowd import people_metrics


def test_people_seen_by_two_and_by_gamma_per_crowd_and_zone():
    cov = np.array([2, 0, 3, 1, 3, 2])  # persons' coverage
    sample = np.array([0, 0, 0, 1, 1, 1])
    region = np.array([0, 0, 1, 0, 1, 1])
    m = people_metrics(cov, sample, 2, region, ["aisle", "till", "office"], 3, [1.25, 1.6])
    assert m["gamma"] == 3 and m["heights"] == [1.25, 1.6]
    assert m["seen_by_2_pct"]["mean"] == 200.0 / 3 and m["seen_by_2_pct"]["std"] == 0.0
    assert (m["seen_by_gamma_pct"]["min"], m["seen_by_gamma_pct"]["max"]) == (100.0 / 3, 100.0 / 3)
    assert m["persons"]["mean"] == 3.0
    aisle = m["regions"]["aisle"]
    assert (aisle["seen_by_2_pct"]["min"], aisle["seen_by_2_pct"]["max"]) == (0.0, 50.0)
    assert m["regions"]["till"]["seen_by_2_pct"]["mean"] == 100.0 and "office" not in m["regions"]
