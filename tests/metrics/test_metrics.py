"""Metrics by hand: coverage gap, non-triangulatable share, histogram, per region."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from camplace.metrics.coverage import compute_metrics
from camplace.problem.model import build_problem


def test_metrics_by_hand():
    V = sp.csr_matrix(np.array([[1, 1, 0, 0], [1, 0, 1, 0]], np.uint8))
    p = build_problem(V, np.array([3, 3, 1, 1]), None, 2)
    m = compute_metrics(p, np.array([0, 1]), np.array([0, 0, 1, 1]), ("vol", "shelf"))
    # coverage [2, 1, 1, 0] -> shortfall [1, 2, 0, 1] -> cost 1 + 4 + 0 + 1
    assert m.cost == 6.0
    assert m.coverage_gap == pytest.approx(6 / 20)
    assert m.non_triangulatable_pct == pytest.approx(75.0)
    assert m.coverage_histogram == {"0": 1, "1": 2, "2": 1}
    assert m.regions["vol"]["cost"] == 5.0 and m.regions["shelf"]["coverage_gap"] == pytest.approx(0.5)
    assert m.regions["shelf"]["targets"] == 2
