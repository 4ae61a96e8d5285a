"""``random-restarts``: the best of several randomised greedy fills.

Each restart visits the candidates in a random order and adds one whenever it lowers the
cost and keeps every limit (camera budget, one camera per location, money budget, cameras
per type). The cheapest fill wins. Anytime: it stops at the time limit (status
'time_limit') or on a stop request (status 'interrupted') with the best fill so far.
"""

from __future__ import annotations

import time

import numpy as np

from camplace.problem.gains import target_gains
from camplace.solvers import Placement, Tags, make_solver


def random_fill(problem, order: np.ndarray, out_of_time) -> tuple[list[int], bool]:
    """Candidates of ``order`` added while each lowers the cost and keeps every limit;
    (selection, cut short by ``out_of_time()``)."""
    sel: list[int] = []
    used: set[int] = set()
    spent = 0.0
    cov = np.zeros(problem.n_targets, np.int64)
    V = problem.V
    for n, i in enumerate(order):
        if len(sel) >= problem.budget:
            break
        if n % 64 == 0 and out_of_time():
            return sel, True
        loc, price = int(problem.location_ids[i]), float(problem.costs[i])
        if loc in used or (problem.money_budget is not None and spent + price > problem.money_budget + 1e-9):
            continue
        if problem.has_type_limits and not problem.type_ok(np.asarray(sel + [int(i)], np.int64)):
            continue
        row = V.indices[V.indptr[i]:V.indptr[i + 1]]
        if target_gains(problem.gamma[row], problem.weights[row], cov[row]).sum() <= 0:
            continue
        sel.append(int(i))
        used.add(loc)
        spent += price
        cov[row] += 1
    return sel, False


def solve_random_restarts(problem, *, time_limit_s: float | None = None, threads: int | None = None, seed: int = 0,
                          should_stop=None, progress=None, on_incumbent=None, restarts: int = 20) -> Placement:
    """Best of ``restarts`` random greedy fills (see the module docstring)."""
    t0 = time.perf_counter()
    end = float("inf") if time_limit_s is None else t0 + time_limit_s
    rng = np.random.default_rng(seed)
    best = np.zeros(0, np.int64)
    best_cost = problem.cost(best)
    status = "heuristic"
    for k in range(max(1, restarts)):
        if should_stop is not None and should_stop():
            status = "interrupted"
            break
        sel, cut = random_fill(problem, rng.permutation(problem.n_candidates),
                               lambda: time.perf_counter() > end or bool(should_stop and should_stop()))
        sel = np.sort(np.asarray(sel, np.int64))
        cost = problem.cost(sel)
        if cost < best_cost:
            best, best_cost = sel, cost
            if on_incumbent is not None:
                on_incumbent(best_cost, None)
        if progress is not None:
            progress("random-restarts", k + 1, restarts)
        if cut or time.perf_counter() > end:
            status = "interrupted" if should_stop is not None and should_stop() else "time_limit"
            break
    return Placement(best, best_cost, None, status, "random-restarts", time.perf_counter() - t0,
                     {"restarts": int(restarts), "seed": int(seed)})


RANDOM_RESTARTS = make_solver("random-restarts", solve_random_restarts, Tags(deterministic_with_seed=True),
                              summary="Best of several randomised greedy fills (example plugin)")
