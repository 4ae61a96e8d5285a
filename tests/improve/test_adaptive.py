"""Adaptive candidates: finer poses around a placement, swap descent, rounds on the demo."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.sparse as sp

from camplace.improve.adaptive import adaptive_rounds, finer_poses, swap_descent
from camplace.problem.model import PlacementProblem
from camplace.improve.refine import pose_box
from camplace.solvers.base import Placement


def test_finer_poses_are_new_and_within_half_steps(demo_run):
    r = demo_run
    i = int(r.placement.selected[0])
    poses, cids = finer_poses(r.scene, r.visibility, np.array([i]), level=1)
    box = pose_box(r.scene, r.visibility.candidates, i, fraction=0.5)
    # demo mount: spacing 1 m, yaw step 45, pitch step 30, single roll -> offsets 0.5 m, 22.5, 15
    assert box.half[:2].tolist() == [0.5, 0.5] and box.half[3:].tolist() == [22.5, 15.0, 0.0]
    assert 0 < len(poses) <= 9 * 3 * 3 - 1  # the centre pose is already in V
    assert np.all(cids == r.visibility.candidates.camera_ids[i])
    d = poses - box.centre
    d[:, 3] = (d[:, 3] + 180.0) % 360.0 - 180.0
    assert np.all(np.abs(d) <= box.half + 1e-9)
    have = {tuple(np.round(np.r_[p, a] * 1000).astype(int)) for p, a in
            zip(r.visibility.candidates.positions, r.visibility.candidates.angles_deg)}
    assert not any(tuple(np.round(p * 1000).astype(int)) in have for p in poses)


def _brute(problem: PlacementProblem) -> float:
    best = problem.normalizer
    for k in range(problem.budget + 1):
        for c in itertools.combinations(range(problem.n_candidates), k):
            try:
                problem.check_feasible(np.array(c, np.int64))
            except ValueError:
                continue
            best = min(best, problem.cost(np.array(c, np.int64)))
    return best


@pytest.mark.parametrize("seed", range(6))
def test_swap_descent_never_worse_and_feasible(seed):
    rng = np.random.default_rng(seed)
    V = sp.csr_matrix((rng.random((9, 12)) < 0.35).astype(np.uint8))
    prob = PlacementProblem(V, rng.integers(0, 3, 12), np.ones(12), 3, rng.integers(0, 6, 9),
                            rng.choice([1.0, 2.0], 9), 5.0 if seed % 2 else None)
    start = np.zeros(0, np.int64)
    sel, info = swap_descent(prob, start)
    prob.check_feasible(sel)
    assert prob.cost(sel) <= prob.cost(start)
    assert prob.cost(sel) >= _brute(prob) - 1e-9


def test_adaptive_round_lowers_the_cost_on_demo(demo_run):
    r = demo_run
    sel = np.asarray(r.placement.selected[:3], np.int64)
    start = Placement(sel, r.problem.cost(sel), None, "heuristic", "greedy", 0.0)
    res = adaptive_rounds(r.scene, r.visibility, r.problem, start, rounds=1, time_limit_s=30.0)
    assert res.rounds[0]["cost"] == pytest.approx(start.objective)
    assert len(res.rounds) == 2 and res.rounds[1]["new_candidates"] > 0
    assert res.placement.objective < start.objective
    assert res.placement.objective == pytest.approx(res.problem.cost(res.placement.selected))
    res.problem.check_feasible(res.placement.selected)
    assert res.problem.n_candidates == r.problem.n_candidates + res.rounds[1]["new_candidates"]
    assert len(res.placement.selected) <= r.problem.budget
