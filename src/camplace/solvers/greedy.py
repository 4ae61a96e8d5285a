"""The paper's "Proposed Greedy" with lazy evaluation (CELF), plus 1-swap local search.

The cost is a monotone supermodular function of the selection (its decrease is
submodular), so a candidate's gain only shrinks as cameras are added: stale heap
entries are upper bounds and only the top needs re-evaluation.
"""

from __future__ import annotations

import heapq
import time
from typing import Callable

import numpy as np

from camplace.problem.model import PlacementProblem
from camplace.solvers.base import OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, stopped


def marginal_gains(problem: PlacementProblem, coverage: np.ndarray) -> np.ndarray:
    """(N_g,) float64: cost drop of adding each candidate to a selection with this coverage.

    Adding one view to target j with deficit d = Γ_j − c_j > 0 lowers its cost by
    w_j (d² − (d−1)²) = w_j (2d − 1)."""
    d = np.maximum(problem.gamma - coverage, 0)
    per_target = np.where(d > 0, problem.weights * (2 * d - 1), 0.0)
    return problem.V @ per_target


def row_gain(problem: PlacementProblem, i: int, coverage: np.ndarray) -> float:
    V = problem.V
    cols = V.indices[V.indptr[i]:V.indptr[i + 1]]
    d = problem.gamma[cols] - coverage[cols]
    pos = d > 0
    return float(np.dot(problem.weights[cols][pos], 2 * d[pos] - 1))


def lazy_greedy(problem: PlacementProblem, all_gains: Callable[[np.ndarray], np.ndarray],
                gain_of: Callable[[int, np.ndarray], float], *, end: float = float("inf"),
                should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                stage: str = "greedy") -> tuple[list[int], np.ndarray, int, bool]:
    """CELF greedy for any gain that only shrinks as coverage grows (submodular).

    Adds the candidate of largest positive gain while the budget, the money budget
    and the one-camera-per-location rule allow. Returns (selected in order,
    coverage (N_p,) int64, gain evaluations, interrupted)."""
    cov = np.zeros(problem.n_targets, np.int64)
    gains = all_gains(cov)
    heap = [(-float(g), i, 0) for i, g in enumerate(gains) if g > 0]
    heapq.heapify(heap)
    costs = problem.costs
    money_left = float("inf") if problem.money_budget is None else float(problem.money_budget)
    used_locations: set[int] = set()
    selected: list[int] = []
    evaluations = len(gains)
    step = 0
    interrupted = False
    V = problem.V
    while len(selected) < problem.budget and heap:
        neg, i, stamp = heapq.heappop(heap)
        if int(problem.location_ids[i]) in used_locations or costs[i] > money_left + 1e-12:
            continue
        if stamp == step:
            if -neg <= 0:
                break
            selected.append(i)
            used_locations.add(int(problem.location_ids[i]))
            money_left -= costs[i]
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
    """1-swap descent: exchange a selected camera for an unselected one (another pose at
    its own location or a pose at a free location) while the cost drops; also add a
    camera when the budget allows and it lowers the cost. One sparse mat-vec per
    tried removal. Returns (selection, number of moves, interrupted)."""
    V = problem.V
    sel = list(selected)
    _, loc = np.unique(problem.location_ids, return_inverse=True)
    loc_used = np.zeros(int(loc.max()) + 1 if len(loc) else 0, bool)
    loc_used[loc[sel]] = True
    is_sel = np.zeros(problem.n_candidates, bool)
    is_sel[sel] = True
    costs = problem.costs
    money = float("inf") if problem.money_budget is None else float(problem.money_budget)
    cov = problem.coverage(np.array(sel, np.int64))
    cost = problem.cost(np.array(sel, np.int64))
    moves = 0

    def gains_for(c: np.ndarray) -> np.ndarray:
        d = np.maximum(problem.gamma - c, 0)
        return V @ np.where(d > 0, problem.weights * (2 * d - 1), 0.0)

    def cost_of(c: np.ndarray) -> float:
        d = np.maximum(problem.gamma - c, 0).astype(np.float64)
        return float(np.dot(problem.weights, d * d))

    improved = True
    while improved and cost > 0:
        improved = False
        if len(sel) < problem.budget:  # adds first (only when greedy stopped early or money freed)
            g = gains_for(cov)
            ok = ~is_sel & ~loc_used[loc] & (costs <= money - costs[sel].sum() + 1e-12)
            g = np.where(ok, g, -np.inf)
            i = int(np.argmax(g)) if len(g) else -1
            if i >= 0 and g[i] > 1e-9:
                sel.append(i)
                is_sel[i] = True
                loc_used[loc[i]] = True
                cov[V.indices[V.indptr[i]:V.indptr[i + 1]]] += 1
                cost = cost_of(cov)
                moves += 1
                improved = True
                continue
        for s in list(sel):
            if stopped(should_stop) or time.perf_counter() > end:
                return sel, moves, True
            cols = V.indices[V.indptr[s]:V.indptr[s + 1]]
            cov2 = cov.copy()
            cov2[cols] -= 1
            cost2 = cost_of(cov2)
            g = gains_for(cov2)
            spent = float(costs[sel].sum()) - costs[s]
            ok = ~is_sel & (~loc_used[loc] | (loc == loc[s])) & (costs <= money - spent + 1e-12)
            g = np.where(ok, g, -np.inf)
            i = int(np.argmax(g))
            if not np.isfinite(g[i]):
                continue
            new_cost = cost2 - g[i]
            if new_cost < cost - 1e-9 * max(1.0, cost):
                sel[sel.index(s)] = i
                is_sel[s], is_sel[i] = False, True
                loc_used[loc[s]] = False
                loc_used[loc[i]] = True
                cov = cov2
                cov[V.indices[V.indptr[i]:V.indptr[i + 1]]] += 1
                cost = cost_of(cov)
                moves += 1
                improved = True
                if on_incumbent:
                    on_incumbent(cost, None)
    return sel, moves, False


def solve_greedy(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                 seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                 on_incumbent: OnIncumbent | None = None, local_search: bool = False, cost_scaled: bool = True,
                 **_: object) -> Placement:
    """Add the candidate with the largest cost drop until the budget is spent or no
    candidate lowers the cost; one camera per location (and within the money budget,
    if any). Ties go to the lowest id. local_search=True then runs 1-swap descent
    (:func:`swap_local_search`). Status 'heuristic', or 'interrupted' / 'time_limit'.
    With a money budget and cost_scaled=True: the best of cost-scaled and plain greedy
    (camplace.solvers.catalogue)."""
    if cost_scaled and problem.money_budget is not None:
        from camplace.solvers.catalogue import solve_catalogue_greedy

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
