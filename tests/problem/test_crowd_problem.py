"""Crowds as scenarios (camplace.problem.crowd): the stacked problem's cost is the sample
average of the squared shortfall, and the stacking keeps every entry."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from hypothesis import given, settings, strategies as st

from camplace.problem.crowd import sample_coverage, side_by_side, stacked_problem
from camplace.problem.gains import shortfall_cost
from camplace.problem.model import build_problem


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_stacked_cost_is_the_sample_average(seed):
    rng = np.random.default_rng(seed)
    S, n, n_p = int(rng.integers(1, 5)), int(rng.integers(1, 7)), int(rng.integers(1, 9))
    V = (rng.random((n, n_p)) < 0.6).astype(np.uint8)
    Vs = [V * (rng.random((n, n_p)) < 0.7) for _ in range(S)]
    gamma, w = rng.integers(0, 4, n_p), rng.uniform(0.5, 2, n_p)
    p = build_problem(sp.csr_matrix(V), gamma, w, budget=n)
    rows = sp.csr_matrix(np.vstack(Vs))
    sp_ = stacked_problem(p, rows, S)
    assert (sp_.V != sp.csr_matrix(np.hstack(Vs))).nnz == 0 and abs(sp_.normalizer - p.normalizer) < 1e-9
    sel = np.flatnonzero(rng.random(n) < 0.5)
    cov = sample_coverage(rows, S, sel)
    want = np.mean([shortfall_cost(gamma, w, Vs[s][sel].sum(0)) for s in range(S)])
    assert np.allclose(cov, [Vs[s][sel].sum(0) for s in range(S)])
    assert abs(sp_.cost(sel) - want) < 1e-9 * max(1.0, want)


def test_side_by_side_keeps_sorted_rows():
    a = sp.csr_matrix(np.array([[1, 0, 1], [0, 1, 0]], np.uint8))
    b = sp.csr_matrix(np.array([[0, 0, 1], [1, 1, 0]], np.uint8))
    got = side_by_side(sp.vstack([a, b], format="csr"), 2)
    assert got.has_sorted_indices and got.toarray().tolist() == [[1, 0, 1, 0, 0, 1], [0, 1, 0, 1, 1, 0]]
