"""Refinement-aware relocation (issue 37): camplace.improve.relocate."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings, strategies as st

from camplace.improve.relocate import _allowed_rows, _best_per_location, relocate_placement
from camplace.problem.model import PlacementProblem


def _tiny(**kw) -> PlacementProblem:
    V = sp.csr_matrix(np.array([[1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1]], np.uint8))
    return PlacementProblem(V, np.ones(3, np.int64), np.ones(3), 2, np.array([0, 0, 1, 2]), **kw)


def test_allowed_rows_by_hand():
    idx, locs = np.array([0, 2]), np.array([0, 1])  # slot 0 at row 0 (location 0), slot 1 at row 2 (location 1)
    np.testing.assert_array_equal(_allowed_rows(_tiny(), idx, 0, locs), [True, True, False, True])
    typed = _tiny(type_ids=np.array([0, 0, 1, 1]), type_limits={0: 1})
    np.testing.assert_array_equal(_allowed_rows(typed, idx, 0, locs), [True, True, False, False])
    priced = _tiny(camera_costs=np.array([1.0, 2.0, 1.0, 1.0]), money_budget=2.0)
    np.testing.assert_array_equal(_allowed_rows(priced, idx, 0, locs), [True, False, False, True])
    off = np.array([-1, 2])  # a slot off V keeps its type and price only by staying put
    assert not _allowed_rows(typed, off, 0, np.array([-1, 1])).any()


def test_best_per_location_by_hand():
    s = np.array([5.0, 9.0, 7.0, -np.inf, 8.0])
    loc = np.array([0, 0, 1, 2, 2])
    np.testing.assert_array_equal(_best_per_location(s, loc, 3), [1, 4, 2])  # row 3 (-inf) never
    np.testing.assert_array_equal(_best_per_location(s, loc, 1), [1])


@settings(deadline=None)  # a loaded machine (the first draw also warms numpy up)
@given(st.lists(st.tuples(st.one_of(st.floats(-1e6, 1e6), st.just(-np.inf)), st.integers(0, 6)), min_size=1,
                max_size=40), st.integers(1, 8))
def test_best_per_location_is_the_best_row_of_the_best_places(rows, top):
    s = np.array([v for v, _ in rows])
    loc = np.array([k for _, k in rows])
    out = _best_per_location(s, loc, top)
    assert len(out) == len(np.unique(loc[out])) <= top  # one per location
    assert np.all(np.isfinite(s[out])) and np.all(np.diff(s[out]) <= 0)  # finite, best first
    for j in out:  # the best row of its location
        assert s[j] == s[loc == loc[j]].max()
    places = {k: s[loc == k].max() for k in np.unique(loc[np.isfinite(s)])}
    assert len(out) == min(top, len(places))  # no better place left out
    if len(out):
        assert all(v <= s[out[-1]] for k, v in places.items() if k not in set(loc[out].tolist()))


@pytest.fixture(scope="module")
def spoiled(demo_run):
    """The demo placement with its first camera moved to the free row that sees least."""
    r = demo_run
    p, sel = r.problem, np.asarray(r.placement.selected, np.int64)
    free = ~np.isin(p.location_ids, p.location_ids[sel])
    nnz = np.diff(p.V.indptr).astype(float)
    nnz[~free] = np.inf
    bad = np.sort(np.r_[sel[1:], int(np.argmin(nnz))])
    return r, replace(r.placement, selected=bad, objective=p.cost(bad))


def test_relocation_brings_a_spoiled_camera_back_and_keeps_the_contract(spoiled):
    r, start = spoiled
    out = relocate_placement(r.scene, r.visibility, r.problem, start, time_limit_s=20.0, top=3, levels=2, max_sweeps=2)
    p, pl = out.problem, out.placement
    assert pl.objective < start.objective - 1e-9  # the useless camera found a better place
    assert pl.objective == pytest.approx(p.cost(pl.selected))
    p.check_feasible(pl.selected)
    assert out.visibility.V.shape[0] == p.n_candidates >= r.problem.n_candidates
    assert pl.info["relocate"]["moves"] >= 1 and pl.solver.endswith("+relocate")
    # the rows of the original problem are unchanged (appended rows come after them)
    n = r.problem.n_candidates
    assert (p.V[:n] != r.problem.V).nnz == 0


def test_relocation_never_worsens_a_refined_placement(demo_run):
    from camplace.improve.refine import refine_placement

    r = demo_run
    rf = refine_placement(r.scene, r.visibility, r.problem, r.placement, time_limit_s=5.0)
    out = relocate_placement(r.scene, rf.visibility, rf.problem, rf.placement, time_limit_s=3.0)
    assert out.placement.objective <= rf.placement.objective + 1e-9
    out.problem.check_feasible(out.placement.selected)


def test_shakes_never_worsen_stay_feasible_and_end_after_their_failures(spoiled):
    import time

    from camplace.improve.relocate import shake_relocate

    r, start = spoiled
    t = time.perf_counter()
    vis, problem, p = shake_relocate(r.scene, r.visibility, r.problem, start, 4.0, seed=2, max_fails=1)
    assert time.perf_counter() - t < 4.0 + 3.0  # a step may overrun by one compass poll
    problem.check_feasible(p.selected)
    assert vis.V.shape[0] == problem.n_candidates >= r.problem.n_candidates
    assert p.objective == pytest.approx(problem.cost(p.selected))
    assert p.objective <= start.objective + 1e-9
