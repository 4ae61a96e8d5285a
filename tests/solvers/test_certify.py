"""The certify solver: incumbent + proven bound; bound <= optimum; feasible, exact, reproducible."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings

from camplace.solvers import SOLVERS, solve
from camplace.solvers.certify import solve_certify
from tests.solvers.test_bounds import brute_force, problems, random_problem


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems)
def test_bound_below_optimum_and_incumbent_exact(p):
    opt, _ = brute_force(p)
    r = solve_certify(p, time_limit_s=0.6, threads=1)
    p.check_feasible(r.selected)
    assert r.objective == p.cost(r.selected)
    assert r.bound is not None and r.bound <= opt + 1e-6
    assert r.objective >= opt - 1e-9
    if r.status == "optimal":
        assert r.objective == opt


def test_small_instance_proven_optimal():
    p = random_problem(4, n_g=30, n_p=60, budget=4, n_loc=12, density=0.25)
    r = solve_certify(p, time_limit_s=20, threads=1)
    opt, _ = brute_force(p)
    assert r.objective == opt
    assert r.status == "optimal" and r.gap <= 1e-9  # float round-off only
    assert r.info["incumbent_method"] in {"greedy", "tabu", "reduced-mip"}
    assert r.info["bound_method"]


def test_reports_both_sides_converging():
    p = random_problem(9, n_g=80, n_p=120, budget=6, n_loc=30, density=0.15)
    states = []
    r = solve(p, "certify", time_limit_s=3, threads=2, on_state=states.append, seed=0)
    assert "certify" in SOLVERS and "tabu" in SOLVERS
    assert states
    objs = [s["objective"] for s in states]
    bounds = [s["bound"] for s in states]
    assert objs == sorted(objs, reverse=True)
    assert bounds == sorted(bounds)
    assert all(b <= o + 1e-9 for o, b in zip(objs, bounds))
    assert r.objective == objs[-1] and abs(r.bound - bounds[-1]) < 1e-9
    assert r.gap == states[-1]["gap"] or abs(r.gap - states[-1]["gap"]) < 1e-12


def test_same_seed_same_incumbent_single_thread():
    """With threads=1 and a problem solved to proof, the result is reproducible."""
    p = random_problem(5, n_g=30, n_p=40, budget=3, n_loc=10, density=0.3)
    a = solve_certify(p, time_limit_s=10, threads=1, seed=2)
    b = solve_certify(p, time_limit_s=10, threads=1, seed=2)
    assert a.status == b.status == "optimal"
    assert np.array_equal(a.selected, b.selected) and a.objective == b.objective


def test_certify_on_an_empty_numba_cache_gets_the_gap_of_a_warm_run(tmp_path):
    """`camplace solve INSTANCE --certify 2` right after an install (an empty numba cache):
    its kernels compile before the 2 s start (camplace.solvers.warmup), so it proves the gap
    a second, warm run proves (the compile used to eat the limit: 65 % instead of 2 %; a warm
    run proves the same 2 % gap at 1.5, 2 and 3 s)."""
    import json
    import os
    import subprocess
    import sys

    from camplace.problem.instance import save_problem_npz
    from camplace.workflows.run import prepare, problem_from_visibility

    _, vis = prepare("demo")
    inst = save_problem_npz(tmp_path / "visibility.npz", problem_from_visibility(vis, 8))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba-cache"))
    gaps = []
    for run in ("cold", "warm"):
        r = subprocess.run([sys.executable, "-m", "camplace.cli.app", "--json", "solve", str(inst), "--budget", "8",
                            "--certify", "2", "--out", str(tmp_path / run)], capture_output=True, text=True, env=env,
                           timeout=600)
        assert r.returncode == 0, r.stderr
        gaps.append(json.loads(r.stdout)["gap"])
    cold, warm = gaps
    assert any((tmp_path / "numba-cache").rglob("*.nbi"))  # the first run did fill the empty cache
    assert cold <= warm + 0.01, f"cold gap {cold:.4f}, warm {warm:.4f}"
