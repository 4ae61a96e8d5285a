"""Solvers: one common suite that every registered solver must pass (like sklearn's
check_estimator), then solver-specific checks against brute force."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from camplace.problem.model import PlacementProblem, brute_force_optimum, build_problem, feasible_selections
from camplace.solvers import SOLVERS, solve

STATUSES = {"optimal", "feasible", "time_limit", "interrupted", "heuristic"}
EXACT = {"mip", "paper-mip"}  # proven optimal on tiny instances without a time limit


def brute_force(problem: PlacementProblem) -> tuple[float, np.ndarray]:
    """Optimal cost and one optimal selection by enumeration (tiny problems only)."""
    return brute_force_optimum(problem)


@st.composite
def tiny_problems(draw, max_g: int = 7, max_p: int = 8) -> PlacementProblem:
    n_g = draw(st.integers(1, max_g))
    n_p = draw(st.integers(1, max_p))
    dense = draw(st.lists(st.lists(st.booleans(), min_size=n_p, max_size=n_p), min_size=n_g, max_size=n_g))
    gamma = draw(st.lists(st.integers(0, 3), min_size=n_p, max_size=n_p))
    weights = draw(st.lists(st.sampled_from([1.0, 2.0, 0.5]), min_size=n_p, max_size=n_p))
    locs = draw(st.lists(st.integers(0, max(0, n_g - 2)), min_size=n_g, max_size=n_g))
    budget = draw(st.integers(0, 4))
    return build_problem(sp.csr_matrix(np.array(dense, np.uint8)), np.array(gamma), np.array(weights), budget,
                         np.array(locs))


def random_problem(rng: np.random.Generator, n_g: int, n_p: int, budget: int, density: float = 0.3,
                   n_loc: int | None = None, max_gamma: int = 3) -> PlacementProblem:
    V = sp.random(n_g, n_p, density=density, format="csr", random_state=rng, data_rvs=lambda k: np.ones(k))
    locs = rng.integers(0, n_loc or max(1, n_g // 3), n_g)
    return build_problem(V.astype(np.uint8), rng.integers(1, max_gamma + 1, n_p), None, budget, locs)


def with_positions(problem: PlacementProblem, seed: int = 0) -> PlacementProblem:
    """The problem with random candidate / target positions (m), for solvers tagged needs_positions."""
    from dataclasses import replace

    rng = np.random.default_rng(seed)
    return replace(problem, candidate_positions=rng.uniform(0, 10, (problem.n_candidates, 3)),
                   target_positions=rng.uniform(0, 10, (problem.n_targets, 3)))


def check_placement(name: str, problem: PlacementProblem, p, optimum: float | None = None) -> None:
    """The common contract of every solver's Placement."""
    assert p.status in STATUSES, p.status
    sel = np.asarray(p.selected)
    assert sel.dtype.kind == "i"
    assert np.all(np.diff(sel) > 0), "selected must be sorted and unique"
    if SOLVERS[name].tags.ignores_camera_budget:
        assert len(set(problem.location_ids[sel].tolist())) == len(sel)
    else:
        problem.check_feasible(sel)
    assert p.objective == pytest.approx(problem.cost(sel), rel=1e-9, abs=1e-9)
    assert p.seconds >= 0
    if p.bound is not None:
        assert p.bound <= p.objective + 1e-6 * max(1.0, p.objective)
        if optimum is not None:
            assert p.bound <= optimum + 1e-6 * max(1.0, optimum)
    if optimum is not None and not SOLVERS[name].tags.ignores_camera_budget:
        assert p.objective >= optimum - 1e-9


@pytest.mark.parametrize("name", sorted(SOLVERS))
@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problem=tiny_problems(), reduce=st.booleans())
def test_common_contract(name, problem, reduce):
    """Time limit 1 s: exact solvers finish tiny instances in milliseconds; anytime
    heuristics must stop at the limit (or earlier) and still honour the contract."""
    optimum, _ = brute_force(problem)
    problem = with_positions(problem)
    p = solve(problem, name, reduce=reduce, time_limit_s=1.0, threads=1)
    check_placement(name, problem, p, optimum)
    if name in EXACT:
        assert p.status == "optimal"
        assert p.objective == pytest.approx(optimum, abs=1e-6)


@pytest.mark.parametrize("name", sorted(SOLVERS))
def test_common_takes_options_and_stop(name):
    """Every solver takes the common keyword options and hooks, and a stop request that is
    already set returns a feasible placement marked 'interrupted' (or a finished one)."""
    problem = with_positions(random_problem(np.random.default_rng(3), 30, 60, 5))
    seen = []
    p = solve(problem, name, time_limit_s=20, threads=1, seed=1, should_stop=lambda: True,
              progress=lambda *a: seen.append(a), on_incumbent=lambda o, b: None)
    check_placement(name, problem, p)
    assert p.status in {"interrupted", "optimal", "heuristic", "feasible"}  # stricter: the conformance suite


@pytest.mark.parametrize("name", sorted(SOLVERS))
def test_common_refuses_an_unknown_option(name):
    """An option the solver does not declare is an InputError naming the option (it used to
    be accepted and silently ignored)."""
    from camplace.core.errors import InputError

    problem = random_problem(np.random.default_rng(3), 6, 10, 2)
    with pytest.raises(InputError, match="unknown_but_common") as err:
        solve(problem, name, time_limit_s=1, unknown_but_common=1)
    assert err.value.option == "unknown_but_common"


def test_refusal_names_the_solvers_that_take_the_option():
    from camplace.core.errors import InputError
    from camplace.solvers import build_options

    with pytest.raises(InputError) as err:
        build_options("mip", coverage_gap=0.1)
    assert str(err.value) == ("coverage_gap: solver 'mip' takes no option 'coverage_gap'; solvers that take it: "
                              "min-cameras")
    assert err.value.option == "coverage_gap"
    assert build_options("min-cameras", coverage_gap=0.1, time_limit_s=2).coverage_gap == 0.1


@pytest.mark.parametrize("name", sorted(SOLVERS))
def test_common_zero_budget_and_empty(name):
    problem = with_positions(random_problem(np.random.default_rng(4), 6, 10, 0))
    p = solve(problem, name)
    check_placement(name, problem, p)
    if not SOLVERS[name].tags.ignores_camera_budget:
        assert len(p.selected) == 0 and p.objective == problem.normalizer
    zero = with_positions(build_problem(sp.csr_matrix((3, 4), dtype=np.uint8), np.zeros(4, np.int64), None, 2))
    p = solve(zero, name)
    assert p.objective == 0.0


# ---------------------------------------------------------------------------
# Solver-specific checks

from camplace.solvers.greedy import solve_greedy  # noqa: E402
from camplace.solvers.horster import solve_horster  # noqa: E402
from camplace.solvers.min_cameras import solve_min_cameras  # noqa: E402
from camplace.solvers.mip import build_tight_model, solve_mip  # noqa: E402
from camplace.solvers.paper_mip import load_cbc, solve_paper_mip  # noqa: E402
from camplace.solvers.zhao import solve_zhao  # noqa: E402


@settings(max_examples=30, deadline=None)
@given(problem=tiny_problems(), data=st.data())
def test_mip_equals_brute_force_with_prices_and_money_budget(problem, data):
    costs = np.array(data.draw(st.lists(st.sampled_from([1.0, 2.0, 3.0]), min_size=problem.n_candidates,
                                        max_size=problem.n_candidates)))
    from dataclasses import replace

    p = replace(problem, camera_costs=costs, money_budget=data.draw(st.sampled_from([None, 2.0, 4.0])))
    optimum, _ = brute_force(p)
    got = solve_mip(p)
    p.check_feasible(got.selected)
    assert got.status == "optimal"
    assert got.objective == pytest.approx(optimum, abs=1e-6)
    assert got.bound <= optimum + 1e-6


@pytest.mark.parametrize("seed", range(3))
def test_paper_mip_reaches_the_mip_optimum(seed):
    problem = random_problem(np.random.default_rng(seed), 14, 25, 3, density=0.25, n_loc=7)
    exact = solve_mip(problem)
    assert exact.status == "optimal"
    for engine in ("cbc", "highs"):
        paper = solve_paper_mip(problem, engine=engine)
        assert paper.status == "optimal"
        assert paper.objective == pytest.approx(exact.objective, abs=1e-6)
        assert paper.bound <= exact.objective + 1e-6


def test_cbc_loads_here():
    mip_module, reason = load_cbc()
    assert mip_module is not None, reason


def test_paper_mip_falls_back_to_highs_with_a_message(monkeypatch):
    import camplace.solvers.paper_mip as pm

    monkeypatch.setattr(pm, "load_cbc", lambda: (None, "OSError: cbclib is not defined"))
    problem = random_problem(np.random.default_rng(5), 8, 12, 2)
    with pytest.warns(RuntimeWarning, match="cbclib is not defined"):
        p = solve_paper_mip(problem)
    assert p.info["engine"] == "highs" and "HiGHS" in p.info["fallback"]
    assert p.objective == pytest.approx(solve_mip(problem).objective)


@pytest.mark.parametrize("solver", [solve_mip, solve_paper_mip, solve_zhao])
def test_time_limit_returns_feasible_placement(solver):
    problem = random_problem(np.random.default_rng(11), 300, 900, 12, density=0.08, n_loc=60)
    p = solver(problem, time_limit_s=0.3, threads=1)
    problem.check_feasible(p.selected)
    assert p.status == "time_limit"
    assert len(p.selected) > 0
    assert p.objective == pytest.approx(problem.cost(p.selected))
    assert p.seconds < 15


def test_mip_interrupt_from_callback_keeps_best_placement():
    problem = random_problem(np.random.default_rng(12), 300, 900, 12, density=0.08, n_loc=60)
    calls = {"n": 0}

    def stop() -> bool:
        calls["n"] += 1
        return calls["n"] > 3

    seen = []
    p = solve_mip(problem, should_stop=stop, on_incumbent=lambda o, b: seen.append(o), time_limit_s=30)
    assert p.status == "interrupted"
    problem.check_feasible(p.selected)
    assert seen and p.objective <= seen[0] + 1e-9


def test_build_tight_model_lp_bound_is_below_the_optimum():
    problem = random_problem(np.random.default_rng(2), 10, 20, 3, n_loc=5)
    h = build_tight_model(problem, integer=False)
    h.run()
    lp = h.getInfo().objective_function_value
    assert lp <= brute_force(problem)[0] + 1e-6


def test_local_search_escapes_the_greedy_trap():
    # A sees 4 targets; B and C together see all 6. Greedy takes A, then one of B/C.
    V = sp.csr_matrix(np.array([[1, 1, 1, 1, 0, 0], [1, 1, 0, 0, 1, 0], [0, 0, 1, 1, 0, 1]], np.uint8))
    problem = build_problem(V, np.ones(6, np.int64), None, 2)
    greedy = solve_greedy(problem)
    assert greedy.objective == 1.0 and 0 in greedy.selected
    better = solve_greedy(problem, local_search=True)
    assert better.objective == 0.0 and list(better.selected) == [1, 2]
    assert better.info["local_search_moves"] >= 1


def test_local_search_respects_locations():
    # B and C share a location: the swap to {B, C} is not allowed.
    V = sp.csr_matrix(np.array([[1, 1, 1, 1, 0, 0], [1, 1, 0, 0, 1, 0], [0, 0, 1, 1, 0, 1]], np.uint8))
    problem = build_problem(V, np.ones(6, np.int64), None, 2, np.array([0, 1, 1]))
    p = solve_greedy(problem, local_search=True)
    problem.check_feasible(p.selected)
    assert p.objective == 1.0


@settings(max_examples=30, deadline=None)
@given(problem=tiny_problems())
def test_local_search_never_worse_than_greedy(problem):
    g = solve_greedy(problem)
    ls = solve_greedy(problem, local_search=True)
    problem.check_feasible(ls.selected)
    assert ls.objective <= g.objective + 1e-9


def test_horster_counts_targets_below_their_coverage():
    # targets need Γ = 2. A sees 3 targets, B the same 3, C 2 others. After A, B still adds
    # 3 under-covered targets; Hörster takes B before C (count 3 > 2).
    V = sp.csr_matrix(np.array([[1, 1, 1, 0, 0], [1, 1, 1, 0, 0], [0, 0, 0, 1, 1]], np.uint8))
    problem = build_problem(V, np.full(5, 2), None, 2)
    p = solve_horster(problem)
    assert list(p.selected) == [0, 1]
    assert p.info["order"] == [0, 1]


@settings(max_examples=25, deadline=None)
@given(problem=tiny_problems())
def test_zhao_maximizes_fully_covered_targets(problem):
    best = 0.0
    live = problem.gamma > 0
    for sel in feasible_selections(problem):
        full = (problem.coverage(sel) >= problem.gamma) & live
        best = max(best, float(problem.weights[full].sum()))
    p = solve_zhao(problem)
    if p.status == "optimal" and "zhao_covered" in p.info:
        assert p.info["zhao_covered"] == pytest.approx(best)
    full = (problem.coverage(p.selected) >= problem.gamma) & live
    assert float(problem.weights[full].sum()) == pytest.approx(best)


def fewest_by_brute_force(problem: PlacementProblem, target: float) -> int:
    """Fewest cameras (one per location) with cost <= target, else with the least reachable cost."""
    from dataclasses import replace

    n_loc = len(np.unique(problem.location_ids))
    least, _ = brute_force(replace(problem, budget=n_loc))
    target = max(target, least)
    for sel in feasible_selections(problem, max_size=n_loc):  # by increasing size, budget ignored
        if problem.cost(sel) <= target + 1e-9:
            return len(sel)
    raise AssertionError("unreachable")


@settings(max_examples=30, deadline=None)
@given(problem=tiny_problems(max_g=6, max_p=6), gap=st.sampled_from([None, 0.1, 0.3]))
def test_min_cameras_meets_target_and_is_minimal(problem, gap):
    p = solve_min_cameras(problem, coverage_gap=gap)
    target = 0.0 if gap is None else gap * problem.normalizer
    assert len(np.unique(problem.location_ids[p.selected])) == len(p.selected)
    assert p.objective <= max(target, p.info.get("least_reachable_cost", 0.0)) + 1e-6
    assert p.status == "optimal" and p.info["proven_minimal"]
    assert p.info["lower_bound"] == len(p.selected)
    assert len(p.selected) == fewest_by_brute_force(problem, target)


def test_min_cameras_least_price():
    # two ways to cover: one expensive camera (price 5) or two cheap ones (price 1 each)
    V = sp.csr_matrix(np.array([[1, 1], [1, 0], [0, 1]], np.uint8))
    problem = PlacementProblem(V, np.ones(2, np.int64), np.ones(2), 1, np.arange(3), np.array([5.0, 1.0, 1.0]))
    cheap = solve_min_cameras(problem)
    assert list(cheap.selected) == [1, 2] and cheap.info["camera_price"] == 2.0
    fewest = solve_min_cameras(problem, minimize="count")
    assert list(fewest.selected) == [0]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_mip_fixing_presolve_reaches_the_plain_mip_optimum(seed):
    """Lagrangian fixing drops candidates before HiGHS (the default path) yet proves
    the same optimum as HiGHS on the full model."""
    problem = random_problem(np.random.default_rng(100 + seed), 60, 150, 5, density=0.1, n_loc=20)
    plain = solve_mip(problem, fixing=False, mip_rel_gap=0.0)
    fixed = solve_mip(problem, mip_rel_gap=0.0)
    assert plain.status == fixed.status == "optimal"
    assert fixed.objective == pytest.approx(plain.objective, abs=1e-6)
    assert fixed.bound <= plain.objective + 1e-6
    assert fixed.info["fixing_kept"] <= fixed.info["candidates"]
    check_placement("mip", problem, fixed, plain.objective)
