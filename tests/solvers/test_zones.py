"""The zone solver (camplace.solvers.zones): tiles, exactness on separable and small
problems, serial == parallel, determinism, monotonicity, time limit, stop, checkpoints."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest
import scipy.sparse as sp

from camplace.core.errors import InputError
from camplace.problem.model import PlacementProblem
from camplace.solvers import SOLVERS
from camplace.solvers.mip import solve_mip
from camplace.solvers.zones import checkpoint_path, problem_key, solve_zones
from camplace.solvers.zones_tiles import estimate_range, make_tiling


def floor_problem(seed: int, width: float = 30.0, depth: float = 20.0, n_loc: int = 30, n_t: int = 120,
                  budget: int = 6, range_m: float = 6.0, x0: float = 0.0) -> PlacementProblem:
    """Cameras at n_loc random ceiling spots (3 poses each, 120° sectors) over a width x
    depth floor (m) starting at x = x0, targets on the floor; a pose sees the targets in
    its sector within range_m (80 % of them: occlusion)."""
    rng = np.random.default_rng(seed)
    spots = np.c_[rng.uniform(x0, x0 + width, n_loc), rng.uniform(0, depth, n_loc), np.full(n_loc, 3.0)]
    tp = np.c_[rng.uniform(x0, x0 + width, n_t), rng.uniform(0, depth, n_t), np.zeros(n_t)]
    cp = np.repeat(spots, 3, axis=0)
    sector = np.tile(np.arange(3), n_loc)
    d = tp[None, :, :2] - cp[:, None, :2]
    ang = np.mod(np.arctan2(d[..., 1], d[..., 0]), 2 * np.pi)
    seen = (np.hypot(d[..., 0], d[..., 1]) < range_m) & ((ang // (2 * np.pi / 3)) == sector[:, None])
    seen &= rng.random(seen.shape) < 0.8
    return PlacementProblem(sp.csr_matrix(seen.astype(np.uint8)), rng.integers(1, 4, n_t), rng.uniform(0.5, 2, n_t),
                            budget, np.repeat(np.arange(n_loc), 3), candidate_positions=cp, target_positions=tp)


def two_rooms(seed: int) -> PlacementProblem:
    """Two floor problems 150 m apart in one problem (no candidate sees the other room)."""
    a, b = floor_problem(seed, 12, 10, 8, 40, 3), floor_problem(seed + 1, 12, 10, 8, 40, 3, x0=150.0)
    cat = lambda f: np.concatenate([f(a), f(b)])  # noqa: E731
    return PlacementProblem(sp.block_diag([a.V, b.V], format="csr"), cat(lambda p: p.gamma), cat(lambda p: p.weights),
                            4, cat(lambda p: p.location_ids + (100 if p is b else 0)),
                            candidate_positions=cat(lambda p: p.candidate_positions),
                            target_positions=cat(lambda p: p.target_positions))


def test_two_far_rooms_are_independent_tiles_and_reach_the_mip_optimum():
    for seed in (0, 3, 6):
        p = two_rooms(seed)
        tiling = make_tiling(p, 100.0)
        assert tiling.n_tiles == 2 and all(len(n) == 0 for n in tiling.neighbours)
        assert np.array_equal(tiling.colour, [0, 0])  # independent: one colour, solved together
        z = solve_zones(p, tile_m=100.0)
        m = solve_mip(p)
        assert m.status == "optimal"
        assert z.objective == pytest.approx(m.objective, rel=1e-9, abs=1e-9)
        p.check_feasible(z.selected)


def test_budget_moves_between_rooms():
    """A start with every camera in one room: the tile solves keep counts, the budget
    moves carry cameras to the other room."""
    p = two_rooms(1)
    first = np.flatnonzero(p.candidate_positions[:, 0] < 75)
    start = first[np.unique(p.location_ids[first], return_index=True)[1]][:4]
    z = solve_zones(p, tile_m=100.0, initial=tuple(start))
    assert z.objective >= solve_mip(p).objective - 1e-9
    assert np.any(p.candidate_positions[z.selected, 0] > 75)
    assert sum(s["moves"] for s in z.info["sweeps"]) >= 1
    no_moves = solve_zones(p, tile_m=100.0, initial=tuple(start), moves=False)
    assert no_moves.objective > z.objective


def test_tiling_covers_every_candidate_and_same_colours_share_no_target():
    p = floor_problem(2)
    for shift in (0.0, 4.0):
        t = make_tiling(p, 8.0, shift)
        assert np.array_equal(np.sort(np.concatenate(t.rows)), np.arange(p.n_candidates))
        for a in range(t.n_tiles):
            assert len(np.unique(p.location_ids[t.rows[a]])) == len(np.unique(p.location_ids[t.rows[a]]))
            for b in range(a + 1, t.n_tiles):
                if t.colour[a] == t.colour[b]:
                    assert len(np.intersect1d(t.cols[a], t.cols[b])) == 0
        locs = [set(p.location_ids[r].tolist()) for r in t.rows]
        assert sum(len(s) for s in locs) == len(set().union(*locs))  # a location lies in one tile
    assert 0 < estimate_range(p) <= 6.0


def test_equals_the_monolithic_mip_on_a_small_floor():
    for seed in (1, 2):
        p = floor_problem(seed)
        m = solve_mip(p)
        assert m.status == "optimal"
        z = solve_zones(p, tile_m=12.0)
        assert len(z.info["sweeps"]) >= 2 and z.info["sweeps"][0]["tiles"] > 1
        assert z.objective <= m.objective * (1 + 1e-6) + 1e-9
        assert z.bound is not None and z.bound <= m.objective + 1e-6


def test_serial_equals_process_pool():
    p = floor_problem(4, 40, 20, 40, 160, 8)
    a = solve_zones(p, tile_m=10.0, seed=3)
    b = solve_zones(p, tile_m=10.0, seed=3, workers=2)
    assert b.info["executor"] == "process-pool" and a.info["executor"] == "in-process"
    assert np.array_equal(a.selected, b.selected) and a.objective == b.objective
    assert [s["cost"] for s in a.info["sweeps"]] == [s["cost"] for s in b.info["sweeps"]]


def test_deterministic_for_a_seed_and_never_worse_than_its_start():
    p = floor_problem(5, 40, 20, 40, 160, 8)
    a, b = solve_zones(p, seed=1, tile_m=10.0), solve_zones(p, seed=1, tile_m=10.0)
    assert np.array_equal(a.selected, b.selected)
    g = SOLVERS["greedy-fast"](p)
    assert a.objective <= g.objective and a.info["start_objective"] == pytest.approx(g.objective)  # on the reduced problem
    rng = np.random.default_rng(0)
    start = rng.choice(np.arange(0, p.n_candidates, 3), 8, replace=False)  # one pose per location
    z = solve_zones(p, initial=tuple(start), tile_m=10.0, max_sweeps=1)
    assert z.objective <= p.cost(np.sort(start)) and len(z.info["sweeps"]) == 1
    costs = [z.info["start_objective"]] + [s["cost"] for s in z.info["sweeps"]]
    assert all(x >= y for x, y in zip(costs, costs[1:]))


def test_time_limit_and_stop():
    p = floor_problem(6, 120, 60, 600, 3000, 60, range_m=8.0)
    t0 = time.perf_counter()
    z = solve_zones(p, time_limit_s=1.5, tile_m=10.0)
    assert time.perf_counter() - t0 < 4.5
    p.check_feasible(z.selected)
    assert z.objective == pytest.approx(p.cost(z.selected))
    calls = []

    def stop() -> bool:
        return len(calls) >= 2  # after the start and the bound

    s = solve_zones(p, should_stop=stop, on_incumbent=lambda o, b: calls.append(o), tile_m=10.0)
    assert s.status == "interrupted" and s.objective <= calls[0]
    p.check_feasible(s.selected)


def saved_checkpoint(folder, p) -> tuple[dict, list[int]]:
    """The checkpoint of ``p`` (the solver works on the reduced problem: its key, its candidate
    ids) and its selection in ``p``'s candidate ids."""
    from camplace.solvers.reduction import reduce_with_positions

    red = reduce_with_positions(p)
    saved = json.loads(checkpoint_path(folder, problem_key(red.problem)).read_text())
    return saved, red.lift(np.array(saved["selected"], np.int64)).tolist()


def test_checkpoint_resumes(tmp_path):
    p = floor_problem(7, 40, 20, 40, 160, 8)
    one = solve_zones(p, tile_m=10.0, max_sweeps=1, checkpoint=str(tmp_path))
    saved, selected = saved_checkpoint(tmp_path, p)
    assert saved["sweeps"] == 1 and saved["batches"] == 0 and selected == one.selected.tolist()
    again = solve_zones(p, tile_m=10.0, checkpoint=str(tmp_path))
    assert again.info["resumed_from_sweep"] == 1 and again.info["start_objective"] == pytest.approx(one.objective)
    assert again.objective <= one.objective
    other = floor_problem(8, 40, 20, 40, 160, 8)
    assert "resumed_from_sweep" not in solve_zones(other, tile_m=10.0, max_sweeps=1,
                                                   checkpoint=str(tmp_path)).info
    assert problem_key(p) != problem_key(other)
    from dataclasses import replace

    wide = sp.csr_matrix((p.V.data, p.V.indices.astype(np.int64), p.V.indptr.astype(np.int64)), shape=p.V.shape)
    assert problem_key(replace(p, V=wide)) == problem_key(p)  # the stored index dtype does not matter
    assert problem_key(replace(p, budget=p.budget + 1)) != problem_key(p)


def test_bad_options_and_missing_positions():
    p = floor_problem(0)
    with pytest.raises(InputError) as err:
        solve_zones(p, tile_m=-1.0)
    assert err.value.option == "tile_m"
    from dataclasses import replace

    with pytest.raises(InputError):
        solve_zones(replace(p, candidate_positions=None))
    with pytest.raises(InputError) as err:
        solve_zones(p, initial=(0, 1))  # two poses at one location
    assert err.value.option == "initial"


def test_dask_cluster_equals_serial():
    distributed = pytest.importorskip("distributed")
    p = floor_problem(4, 40, 20, 40, 160, 8)
    a = solve_zones(p, tile_m=10.0, seed=2, max_sweeps=2)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cl:
        b = solve_zones(p, tile_m=10.0, seed=2, max_sweeps=2, scheduler=cl.scheduler_address)
    assert b.info["executor"] == "dask"
    assert np.array_equal(a.selected, b.selected) and a.objective == b.objective


def test_checkpoint_after_each_batch_resumes_mid_sweep(tmp_path):
    """A stop after the first colour batch: the checkpoint says 1 batch done; the restart
    skips that batch and ends where an uninterrupted solve ends."""
    p = floor_problem(9, 40, 20, 40, 160, 8)
    full = solve_zones(p, tile_m=10.0, seed=1)
    n = []
    cut = solve_zones(p, tile_m=10.0, seed=1, checkpoint=str(tmp_path), progress=lambda *a: n.append(a),
                      should_stop=lambda: len(n) >= 1)
    assert cut.status == "interrupted"
    saved, selected = saved_checkpoint(tmp_path, p)
    assert (saved["sweeps"], saved["batches"]) == (0, 1) and selected == cut.selected.tolist()
    again = solve_zones(p, tile_m=10.0, seed=1, checkpoint=str(tmp_path))
    assert (again.info["resumed_from_sweep"], again.info["resumed_batches"]) == (0, 1)
    assert again.objective == pytest.approx(full.objective) and np.array_equal(again.selected, full.selected)
