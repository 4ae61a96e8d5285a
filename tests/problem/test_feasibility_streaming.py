"""check_feasibility counts in one pass over V's rows (issue 21): the same unseen / short
targets as the sparse product (locations x candidates) @ V it replaces, on random V."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from camplace.problem.feasibility import check_feasibility


def _reference(V, gamma, loc):
    n_g, n_p = V.shape
    seen = np.bincount(V.indices, minlength=n_p)[:n_p]
    _, li = np.unique(loc, return_inverse=True)
    A = sp.csr_matrix((np.ones(n_g, np.int64), (li.ravel(), np.arange(n_g))), shape=(int(li.max()) + 1, n_g))
    n_loc = np.diff((A @ V.astype(np.int64)).tocsc().indptr)
    return np.nonzero((gamma > 0) & (seen == 0))[0], np.nonzero(n_loc < gamma)[0]


@settings(max_examples=80, deadline=None)
@given(st.integers(1, 25), st.integers(1, 20), st.integers(0, 2**31 - 1), st.floats(0.0, 0.8))
def test_same_as_the_sparse_product(n_g, n_p, seed, density):
    rng = np.random.default_rng(seed)
    V = sp.csr_matrix((rng.random((n_g, n_p)) < density).astype(np.uint8))
    gamma = rng.integers(0, 4, n_p)
    loc = rng.integers(0, max(1, n_g // 2), n_g) * 7 - 3  # arbitrary, unsorted location labels
    regions = rng.integers(0, 2, n_p)
    f = check_feasibility(V, gamma, loc, regions, ("a", "b"))
    unseen, short = _reference(V, gamma, loc)
    assert np.array_equal(f.unseen, unseen) and np.array_equal(f.short, short)
    assert sum(u for u, _ in f.by_region.values()) == len(unseen)
