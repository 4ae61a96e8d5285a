"""Visibility in a crowd (camplace.visibility.crowd): known answers, V_s ⊆ V against a
grid-free reference, density 0 gives V_s = V, and the same V_s under every executor."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings, strategies as st

from camplace.targets.crowd import Crowds
from camplace.visibility.crowd import crowd_rows
from camplace.core.executors import Executor

R, H = 0.25, 1.75
CAM = np.array([[0.0, 0.0, 2.9]])
TARGET = np.array([[4.0, 0.0, 1.0]])  # the sight line is below H from x = 2.42 m on


def crowds(samples: list[list[tuple[float, float]]]) -> Crowds:
    xy = np.array([p for s in samples for p in s], float).reshape(-1, 2)
    return Crowds(xy, np.r_[0, np.cumsum([len(s) for s in samples])].astype(np.int64), R, H)


def seen(cams, targets, cr: Crowds) -> np.ndarray:
    """(S, n, N_p) 0/1 of V_s for V = every camera sees every target."""
    V = sp.csr_matrix(np.ones((len(cams), len(targets)), np.uint8))
    rows = crowd_rows(V, cams, targets, cr)
    return rows.toarray().reshape(cr.n_samples, len(cams), len(targets))


def test_known_answers():
    cases = {"between": [(3.2, 0.0)], "beside": [(3.2, 0.6)], "behind": [(4.8, 0.0)],
             "at the target": [(4.0, 0.1)], "under the high part": [(1.0, 0.0)], "nobody": [],
             "grazing": [(3.2, 0.26)], "at the target and between": [(4.0, 0.1), (3.3, 0.0)]}
    got = dict(zip(cases, seen(CAM, TARGET, crowds(list(cases.values())))[:, 0, 0]))
    assert got == {"between": 0, "beside": 1, "behind": 1, "at the target": 1, "under the high part": 1,
                   "nobody": 1, "grazing": 1, "at the target and between": 0}


def reference(cams, targets, people, r=R, h=H) -> np.ndarray:
    """(n, N_p) bool blocked, every person tested (no grid): the same exact cylinder test."""
    out = np.zeros((len(cams), len(targets)), bool)
    for i, a in enumerate(cams):
        for j, b in enumerate(targets):
            d = b - a
            if abs(d[2]) < 1e-15:
                lo, hi = (0.0, 1.0) if 0 <= a[2] <= h else (1.0, 0.0)
            else:
                ta, tb = -a[2] / d[2], (h - a[2]) / d[2]
                lo, hi = max(0.0, min(ta, tb)), min(1.0, max(ta, tb))
            for q in people:
                if lo >= hi or np.hypot(*(q - b[:2])) < r:
                    continue
                f = a[:2] - q
                aa, bb, cc = d[:2] @ d[:2], 2 * d[:2] @ f, f @ f - r * r
                disc = bb * bb - 4 * aa * cc
                if aa > 1e-18 and disc > 0:
                    t1, t2 = (-bb - np.sqrt(disc)) / (2 * aa), (-bb + np.sqrt(disc)) / (2 * aa)
                    out[i, j] |= max(t1, lo) < min(t2, hi) - 1e-12
    return out


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_grid_kernel_matches_every_person_tested(seed):
    rng = np.random.default_rng(seed)
    cams = np.c_[rng.uniform(0, 6, (4, 2)), rng.uniform(0.5, 3.0, 4)]
    targets = np.c_[rng.uniform(0, 6, (12, 2)), rng.uniform(0.1, 2.0, 12)]
    people = rng.uniform(0, 6, (int(rng.integers(0, 30)), 2))
    got = seen(cams, targets, crowds([people.tolist()]))[0]
    assert np.array_equal(got == 0, reference(cams, targets, people))


@pytest.fixture(scope="module")
def store(demo_inputs):
    from camplace.visibility.engine import compute_visibility
    from camplace.visibility.voxel import VoxelEngine

    sc, t, c = demo_inputs
    vis = compute_visibility(VoxelEngine(), sc.occupancy, t, c)
    from camplace.spec.crowd import CrowdSpec
    from camplace.targets.crowd import sample_crowds

    return vis, sample_crowds(sc, CrowdSpec(density=1.0, samples=3))


def test_v_s_is_a_subset_of_v_and_density_0_gives_v(store):
    vis, cr = store
    n = vis.V.shape[0]
    rows = crowd_rows(vis.V, vis.candidates.positions, vis.targets.positions, cr, chunk_size=97)
    assert rows.shape == (3 * n, vis.V.shape[1]) and rows.has_sorted_indices
    for s in range(3):
        Vs = rows[s * n:(s + 1) * n]
        assert (Vs - Vs.multiply(vis.V)).nnz == 0 and Vs.nnz < vis.V.nnz  # V_s ⊆ V, someone blocks something
    empty = Crowds(np.zeros((0, 2)), np.zeros(3, np.int64), R, H)
    zero = crowd_rows(vis.V, vis.candidates.positions, vis.targets.positions, empty)
    for s in range(2):
        assert (zero[s * n:(s + 1) * n] != vis.V).nnz == 0


class Shipped(Executor):
    """What a process-pool or Dask worker gets: ``shared`` and each task through pickle,
    the blocks answered in reverse order (a spawned pool costs seconds; the benchmark runs one)."""

    name = "shipped"

    def map_unordered(self, fn, shared, tasks):
        import pickle

        there = pickle.loads(pickle.dumps(shared))
        for k in reversed(range(len(tasks))):
            yield k, fn(there, pickle.loads(pickle.dumps(tasks[k])))


def test_same_v_s_through_an_executor(store):
    vis, cr = store
    args = (vis.V, vis.candidates.positions, vis.targets.positions, cr)
    here = crowd_rows(*args)
    there = crowd_rows(*args, executor=Shipped(), chunk_size=200)
    assert (here != there).nnz == 0
