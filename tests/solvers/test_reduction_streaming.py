"""reduce_streaming (issue 21) is reduce_problem without the copies of V: the same Reduction
bit for bit (rows, columns, weights, maps, info) on random problems, with prices, types
and zero-weight targets, on a warehouse, and on a memory-mapped V; the same lift."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from camplace.problem.model import PlacementProblem, reduce_problem
from camplace.solvers.reduction import reduce_streaming, row_chunks


def same_reduction(a, b) -> None:
    pa, pb = a.problem, b.problem
    assert {k: v for k, v in a.info.items() if k != "seconds"} == {k: v for k, v in b.info.items() if k != "seconds"}
    assert np.array_equal(a.candidates, b.candidates) and np.array_equal(a.target_map, b.target_map)
    assert pa.V.shape == pb.V.shape and pa.V.dtype == pb.V.dtype
    assert np.array_equal(pa.V.indptr, pb.V.indptr) and np.array_equal(pa.V.indices, pb.V.indices)
    assert np.array_equal(pa.V.data, pb.V.data)
    for f in ("gamma", "weights", "location_ids"):
        x, y = getattr(pa, f), getattr(pb, f)
        assert x.dtype == y.dtype and np.array_equal(x, y), f
    assert (pa.camera_costs is None) == (pb.camera_costs is None)
    if pa.camera_costs is not None:
        assert np.array_equal(pa.camera_costs, pb.camera_costs)
    assert (pa.type_ids is None) == (pb.type_ids is None) and pa.type_limits == pb.type_limits
    if pa.type_ids is not None:
        assert np.array_equal(pa.type_ids, pb.type_ids)


@st.composite
def problems(draw):
    n_g, n_p = draw(st.integers(1, 30)), draw(st.integers(1, 25))
    rng = np.random.default_rng(draw(st.integers(0, 2**31 - 1)))
    dense = rng.random((n_g, n_p)) < draw(st.floats(0.05, 0.9))
    if draw(st.booleans()):  # repeated columns and rows: what the merge and dominance rules act on
        dense[:, rng.integers(0, n_p, n_p // 2)] = dense[:, rng.integers(0, n_p, n_p // 2)]
        dense[rng.integers(0, n_g, n_g // 2)] = dense[rng.integers(0, n_g, n_g // 2)]
    V = sp.csr_matrix(dense.astype(np.uint8))
    gamma = rng.integers(0, 4, n_p)
    weights = rng.choice([0.0, 0.5, 1.0, 3.0], n_p)
    loc = rng.integers(0, max(1, n_g // draw(st.integers(1, 6))), n_g)
    costs = rng.choice([1.0, 2.0, 2.5], n_g) if draw(st.booleans()) else None
    kw = {}
    if draw(st.booleans()):
        kw = {"type_ids": rng.integers(0, 3, n_g), "type_limits": {0: int(rng.integers(0, 3))}}
    return PlacementProblem(V, gamma, weights, int(rng.integers(0, 5)), loc, costs, **kw)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems(), st.booleans())
def test_same_reduction_as_reduce_problem(problem, dominance):
    same_reduction(reduce_streaming(problem, dominance), reduce_problem(problem, dominance))


def test_same_reduction_on_a_warehouse_and_on_a_memory_mapped_v(tmp_path):
    from camplace.workflows.run import prepare, problem_from_visibility

    _, vis = prepare("warehouse:300", cache_dir=tmp_path)
    assert not vis.V.indices.flags.writeable and not vis.V.indices.flags.owndata  # read from the mapped cache file
    problem = problem_from_visibility(vis, 12)
    ref = reduce_problem(problem)
    got = reduce_streaming(problem)
    assert ref.info["dropped_dominated_candidates"] > 0 and ref.info["merged_targets"] > 0  # the rules act here
    same_reduction(got, ref)
    sel = np.arange(0, got.problem.n_candidates, max(1, got.problem.n_candidates // 12))[:12]
    assert np.array_equal(got.lift(sel), ref.lift(sel))
    assert got.problem.cost(sel) == problem.cost(got.lift(sel))


def test_hash_collision_falls_back_to_the_exact_path(monkeypatch):
    """Columns whose hashes agree but whose rows differ are never merged."""
    from camplace.solvers import reduction

    V = sp.csr_matrix(np.array([[1, 0, 1], [0, 1, 1], [1, 1, 0]], np.uint8))
    problem = PlacementProblem(V, np.array([1, 1, 1]), np.ones(3), 2, np.arange(3))
    real = reduction._column_hashes

    def colliding(*args):
        cnt, h1, h2 = real(*args)
        return cnt, np.zeros_like(h1), np.zeros_like(h2)  # every column with equal counts collides

    monkeypatch.setattr(reduction, "_column_hashes", colliding)
    same_reduction(reduce_streaming(problem), reduce_problem(problem))
    assert reduce_streaming(problem).problem.n_targets == 3


def test_chunked_build_releases_the_map_and_keeps_the_reduction(tmp_path, monkeypatch):
    """Issue 37: the reduced V is built in row chunks with V's mapped pages released after
    each one; any chunk size gives the same Reduction, and its data is one broadcast byte."""
    from camplace.solvers import reduction
    from camplace.workflows.run import prepare, problem_from_visibility

    _, vis = prepare("warehouse:300", cache_dir=tmp_path)
    problem = problem_from_visibility(vis, 12)
    ref = reduce_problem(problem)
    released = []
    real = reduction.release_pages
    monkeypatch.setattr(reduction, "release_pages", lambda *a: released.append(real(*a)) or released[-1])
    monkeypatch.setattr(reduction, "BUILD_CHUNK_NNZ", 5000)
    got = reduce_streaming(problem)
    same_reduction(got, ref)
    n_chunks = len(row_chunks(problem.V.indptr.astype(np.int64), got.candidates, 5000))
    assert len(released) >= 2 * (n_chunks - 1) > 20 and all(r == 1 for r in released[1:])  # the map, each chunk
    d = got.problem.V.data
    assert d.strides == (0,) and not d.flags.writeable and d.nbytes == got.problem.V.nnz  # a view of one byte


def test_row_chunks_by_hand():
    indptr = np.array([0, 3, 3, 10, 11, 20], np.int64)  # rows of 3, 0, 7, 1, 9 entries
    rows = np.array([0, 2, 3, 4], np.int64)  # 3, 7, 1, 9 entries: cumulative 3, 10, 11, 20
    assert row_chunks(indptr, rows, 10).tolist() == [0, 2, 4]  # 3 + 7 | 1 + 9
    assert row_chunks(indptr, rows, 4).tolist() == [0, 1, 3, 4]  # 3 | 7 + 1 | 9
    assert row_chunks(indptr, rows, 100).tolist() == [0, 4]
    assert row_chunks(indptr, rows[:0], 4).tolist() == [0]
