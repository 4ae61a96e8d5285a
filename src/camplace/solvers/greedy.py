"""The paper's "Proposed Greedy" with lazy evaluation (CELF), plus 1-swap local search.

The cost is a monotone supermodular function of the selection (its decrease is
submodular), so a candidate's gain only shrinks as cameras are added: stale heap
entries are upper bounds and only the top needs re-evaluation.
"""

from __future__ import annotations

import heapq
import time
from dataclasses import replace
from typing import Callable

import numpy as np

from camplace.problem.gains import marginal_gains, row_gain  # noqa: F401 (re-exported)
from camplace.problem.model import PlacementProblem, TypeBudget
from camplace.solvers.base import OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, stopped
from camplace.solvers.contract import make_solver
from camplace.solvers.local_search import NominalObjective, swap_search


def lazy_greedy(problem: PlacementProblem, all_gains: Callable[[np.ndarray], np.ndarray],
                gain_of: Callable[[int, np.ndarray], float], *, end: float = float("inf"),
                should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                stage: str = "greedy") -> tuple[list[int], np.ndarray, int, bool]:
    """CELF greedy for any gain that only shrinks as coverage grows (submodular).

    Adds the candidate of largest positive gain while the budget, the money budget,
    the per-type limits and the one-camera-per-location rule allow. Returns (selected in order,
    coverage (N_p,) int64, gain evaluations, interrupted)."""
    cov = np.zeros(problem.n_targets, np.int64)
    gains = all_gains(cov)
    heap = [(-float(g), i, 0) for i, g in enumerate(gains) if g > 0]
    heapq.heapify(heap)
    costs = problem.costs
    money_left = float("inf") if problem.money_budget is None else float(problem.money_budget)
    used_locations: set[int] = set()
    types = TypeBudget(problem)
    selected: list[int] = []
    evaluations = len(gains)
    step = 0
    interrupted = False
    V = problem.V
    while len(selected) < problem.budget and heap:
        neg, i, stamp = heapq.heappop(heap)
        if int(problem.location_ids[i]) in used_locations or costs[i] > money_left + 1e-12 or not types.allows(i):
            continue
        if stamp == step:
            if -neg <= 0:
                break
            selected.append(i)
            used_locations.add(int(problem.location_ids[i]))
            money_left -= costs[i]
            types.add(i)
            cov[V.indices[V.indptr[i]:V.indptr[i + 1]]] += 1
            step += 1
            if progress:
                progress(stage, len(selected), problem.budget)
            if stopped(should_stop) or time.perf_counter() > end:
                interrupted = True
                break
            continue
        g = gain_of(i, cov)
        evaluations += 1
        if g > 0:
            heapq.heappush(heap, (-g, i, step))
    return selected, cov, evaluations, interrupted


def swap_local_search(problem: PlacementProblem, selected: list[int], *, end: float = float("inf"),
                      should_stop: ShouldStop | None = None,
                      on_incumbent: OnIncumbent | None = None) -> tuple[list[int], int, bool]:
    """1-swap descent (first improvement, camplace.solvers.local_search): exchange a selected
    camera for an unselected one (another pose at its own location or a pose at a free
    location) while the cost drops; also add a camera when the budget allows and it lowers
    the cost. One sparse mat-vec per tried removal. Returns (selection, number of moves,
    interrupted)."""
    objective = NominalObjective(problem, rel_tol=1e-9, on_incumbent=on_incumbent)
    sel, info = swap_search(problem, selected, objective, first_improvement=True, end=end, should_stop=should_stop,
                            money_tol=1e-12)
    return sel, info["moves"], info["stopped"] in ("time_limit", "interrupted")


def solve_greedy(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                 seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                 on_incumbent: OnIncumbent | None = None, local_search: bool = False, cost_scaled: bool = True) -> Placement:
    """Add the candidate with the largest cost drop until the budget is spent or no
    candidate lowers the cost; one camera per location (and within the money budget,
    if any). Ties go to the lowest id. local_search=True then runs 1-swap descent
    (:func:`swap_local_search`). Status 'heuristic', or 'interrupted' / 'time_limit'.
    With a money budget and cost_scaled=True: the best of cost-scaled and plain greedy
    (:func:`solve_catalogue_greedy`)."""
    if cost_scaled and problem.money_budget is not None:
        return solve_catalogue_greedy(problem, time_limit_s=time_limit_s, threads=threads, seed=seed,
                                      should_stop=should_stop, progress=progress, on_incumbent=on_incumbent,
                                      local_search=local_search)
    t0 = time.perf_counter()
    end = deadline(time_limit_s)
    selected, cov, evaluations, cut = lazy_greedy(problem, lambda c: marginal_gains(problem, c),
                                                  lambda i, c: row_gain(problem, i, c), end=end,
                                                  should_stop=should_stop, progress=progress)
    info: dict = {"gain_evaluations": evaluations, "order": [int(i) for i in selected]}
    return finish_greedy(problem, selected, info, cut, "greedy", t0, local_search=local_search, end=end,
                         should_stop=should_stop, on_incumbent=on_incumbent)


def finish_greedy(problem: PlacementProblem, selected: list[int], info: dict, cut: bool, name: str, t0: float, *,
                  local_search: bool, end: float, should_stop=None, on_incumbent=None) -> Placement:
    """Shared tail of the greedy solvers: report the incumbent, optional 1-swap, status, Placement."""
    if on_incumbent:
        on_incumbent(problem.cost(np.array(selected, np.int64)), None)
    if local_search and not cut:
        greedy_cost = problem.cost(np.array(selected, np.int64))
        selected, moves, cut = swap_local_search(problem, selected, end=end, should_stop=should_stop,
                                                 on_incumbent=on_incumbent)
        info.update(local_search_moves=moves, greedy_objective=greedy_cost)
    sel = np.array(sorted(selected), dtype=np.int64)
    status = "heuristic"
    if cut:
        status = "interrupted" if stopped(should_stop) else "time_limit"
    info["local_search"] = bool(local_search)
    return Placement(sel, problem.cost(sel), None, status, name, time.perf_counter() - t0, info)


# ---------------------------------------------------------------------------
# Under a money budget (camplace.solvers.catalogue has the method's notes)

MIN_PRICE = 1e-9  # a free camera gets this price in the ratio (it is then always worth taking first)


def cost_scaled_greedy(problem: PlacementProblem, *, end: float = float("inf"), should_stop: ShouldStop | None = None,
                       progress: ProgressFn | None = None) -> tuple[list[int], int, bool]:
    """CELF greedy on gain / price; returns (selected in order, evaluations, interrupted)."""
    price = np.maximum(problem.costs, MIN_PRICE)
    sel, _, ev, cut = lazy_greedy(problem, lambda c: marginal_gains(problem, c) / price,
                                  lambda i, c: row_gain(problem, i, c) / price[i], end=end, should_stop=should_stop,
                                  progress=progress, stage="greedy (cost-scaled)")
    return sel, ev, cut


def solve_catalogue_greedy(problem: PlacementProblem, *, time_limit_s: float | None = None,
                           threads: int | None = None, seed: int = 0, should_stop: ShouldStop | None = None,
                           progress: ProgressFn | None = None, on_incumbent: OnIncumbent | None = None,
                           local_search: bool = False) -> Placement:
    """Best of the cost-scaled and the plain greedy (both within the money budget, if
    any), then optional 1-swap descent. Status 'heuristic' (or 'time_limit' /
    'interrupted'); info['variant'] says which greedy won."""
    t0 = time.perf_counter()
    end = deadline(time_limit_s)
    runs = {}
    scaled, ev1, cut1 = cost_scaled_greedy(problem, end=end, should_stop=should_stop, progress=progress)
    runs["cost-scaled"] = scaled
    plain, _, ev2, cut2 = lazy_greedy(problem, lambda c: marginal_gains(problem, c),
                                      lambda i, c: row_gain(problem, i, c), end=end, should_stop=should_stop,
                                      progress=progress)
    runs["plain"] = plain
    costs = {k: problem.cost(np.array(v, np.int64)) for k, v in runs.items()}
    variant = min(costs, key=lambda k: (costs[k], k != "cost-scaled"))
    selected = list(runs[variant])
    cut = cut1 or cut2
    if on_incumbent:
        on_incumbent(costs[variant], None)
    info: dict = {"variant": variant, "greedy_costs": costs, "gain_evaluations": ev1 + ev2,
                  "order": [int(i) for i in selected]}
    if local_search and not cut:
        selected, moves, cut = swap_local_search(problem, selected, end=end, should_stop=should_stop,
                                                 on_incumbent=on_incumbent)
        info["local_search_moves"] = moves
    sel = np.array(sorted(int(i) for i in selected), np.int64)
    status = "heuristic"
    if cut:
        status = "interrupted" if stopped(should_stop) else "time_limit"
    info["local_search"] = bool(local_search)
    info["money_spent"] = float(problem.costs[sel].sum()) if len(sel) else 0.0
    return Placement(sel, problem.cost(sel), None, status, "greedy", time.perf_counter() - t0, info)


def solve_greedy_ls(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                    seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                    on_incumbent: OnIncumbent | None = None, cost_scaled: bool = True) -> Placement:
    """Greedy, then 1-swap local search (:func:`solve_greedy` with local_search=True)."""
    p = solve_greedy(problem, time_limit_s=time_limit_s, threads=threads, seed=seed, should_stop=should_stop,
                     progress=progress, on_incumbent=on_incumbent, local_search=True, cost_scaled=cost_scaled)
    return replace(p, solver="greedy-ls")


def solve_greedy_money(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                       seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                       on_incumbent: OnIncumbent | None = None, local_search: bool = False) -> Placement:
    """:func:`solve_catalogue_greedy` as the solver 'greedy-money'."""
    p = solve_catalogue_greedy(problem, time_limit_s=time_limit_s, threads=threads, seed=seed,
                               should_stop=should_stop, progress=progress, on_incumbent=on_incumbent,
                               local_search=local_search)
    return replace(p, solver="greedy-money")


GREEDY = make_solver("greedy", solve_greedy, summary="The paper's greedy (lazy CELF); local_search: 1-swap after")
GREEDY_LS = make_solver("greedy-ls", solve_greedy_ls, summary="Greedy, then 1-swap local search")
GREEDY_MONEY = make_solver("greedy-money", solve_greedy_money,
                           summary="Best of cost-scaled and plain greedy under a money budget")
