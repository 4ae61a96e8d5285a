"""quality="high" (issue 37): refinement and relocation (tabu, adaptive rounds, kicks) in one time budget."""

from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import given, strategies as st

from camplace.core.errors import InputError
from camplace.improve.quality import high_quality, step_budget


@given(st.floats(0.0, 100.0), st.lists(st.floats(0.01, 1.0), min_size=1, max_size=8))
def test_step_budgets_never_exceed_the_time_left(left, shares):
    b = step_budget(left, shares)
    assert 0.0 <= b <= left + 1e-9
    if len(shares) == 1:  # the last step gets all that is left
        assert b == pytest.approx(left)


def test_step_budget_by_hand():
    assert step_budget(10.0, [0.25, 0.25, 0.5]) == pytest.approx(2.5)
    assert step_budget(6.0, [0.2, 0.1]) == pytest.approx(4.0)  # an early end of a step before flows on


def test_chain_on_demo_keeps_its_budget_and_never_worsens(demo_run):
    r = demo_run
    t = time.perf_counter()
    q = high_quality(r.scene, r.visibility, r.problem, r.placement, time_limit_s=3.0)
    took = time.perf_counter() - t
    assert took < 3.0 + 2.5  # a step may overrun by one raycast / one tabu chunk
    assert q.placement.objective <= r.problem.cost(r.placement.selected) + 1e-9
    assert q.placement.objective == pytest.approx(q.problem.cost(q.placement.selected))
    q.problem.check_feasible(q.placement.selected)
    assert q.visibility.V.shape[0] == q.problem.n_candidates
    costs = [h["cost"] for h in q.steps]
    assert all(b <= a + 1e-9 for a, b in zip(costs, costs[1:]))  # no step makes it worse
    assert q.placement.info["quality"]["steps"] == q.steps


@pytest.mark.parametrize("by", ["keyword", "scene key"])
def test_run_quality_high_keeps_the_whole_run_budget(by):
    from camplace.spec.builtin import resolve_scene
    from camplace.workflows.run import run

    spec = resolve_scene("demo")[0]
    if by == "scene key":
        spec = spec.model_copy(update={"placement": spec.placement.model_copy(update={"quality": "high"})})
    t = time.perf_counter()
    r = run(spec, quality_time_s=8.0, **({"quality": "high"} if by == "keyword" else {}))
    took = time.perf_counter() - t
    assert took < 8.0 + 3.0
    assert "quality" in r.placement.info and r.placement.solver.endswith("+quality-high")
    assert r.metrics.grid_cost is not None and r.metrics.cost <= r.metrics.grid_cost + 1e-9
    assert any(line.startswith("quality high:") for line in r.log)
    np.testing.assert_allclose(r.metrics.cost, r.problem.cost(r.placement.selected))


@pytest.mark.parametrize("kw, word", [({"quality": "best"}, "quality: expected one of default, high"),
                                      ({"quality": "high", "adaptive": 2}, "quality: quality=high runs"),
                                      ({"quality": "high", "quality_time_s": 0}, "quality_time_s: expected")])
def test_bad_quality_settings_are_one_line_errors(kw, word):
    from camplace.workflows.run import run

    with pytest.raises(InputError) as e:
        run("demo", **kw)
    assert str(e.value).startswith(word)


def test_kick_refine_never_worsens_and_stays_feasible(demo_run):
    from camplace.improve.quality import kick_refine

    r = demo_run
    start = r.problem.cost(r.placement.selected)
    vis, problem, p = kick_refine(r.scene, r.visibility, r.problem, r.placement, 1.5, seed=1)
    problem.check_feasible(p.selected)
    assert vis.V.shape[0] == problem.n_candidates >= r.problem.n_candidates
    assert p.objective == pytest.approx(problem.cost(p.selected)) and p.objective <= start + 1e-9


def test_a_refined_camera_never_moves_onto_another_cameras_position():
    from camplace.improve.refine import _free_of_others

    poses = np.array([[1.0, 1.0, 3.0, 0, 30, 0, 4.0], [1.5, 1.0, 3.0, 90, 30, 0, 4.0]])
    trial = np.array([[1.5, 1.0, 3.0, 0, 30, 0, 4.0],  # camera 1's position: two cameras, one location
                      [1.5004, 1.0, 3.0, 0, 30, 0, 4.0],  # the same to 1 mm
                      [1.25, 1.0, 3.0, 0, 30, 0, 4.0], [1.0, 1.0, 3.0, 45, 30, 0, 4.0]])
    assert _free_of_others(poses, 0, trial).tolist() == [False, False, True, True]
    assert _free_of_others(poses, 1, trial).tolist() == [True, True, True, False]


def test_kicks_that_find_nothing_end_before_their_time(demo_run):
    from camplace.improve.quality import kick_refine

    r = demo_run
    t = time.perf_counter()
    vis, problem, p = kick_refine(r.scene, r.visibility, r.problem, r.placement, 120.0, seed=1, max_fails=1)
    assert time.perf_counter() - t < 60.0  # each success lowers the cost; the first failure ends it
    assert p.objective <= r.problem.cost(r.placement.selected) + 1e-9
