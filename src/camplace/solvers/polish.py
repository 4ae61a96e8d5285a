"""``greedy-polish``: greedy, then the exact MIP on a restricted candidate set, with a
bound from the full problem (the decomposition of docs/scale.md, option 1).

1. ``greedy-fast`` gives a selection S.
2. The restricted set R = every pose at S's locations (pose changes) + the
   ``extra_per_camera`` × |S| best other candidates by marginal gain at S's coverage.
3. The tight MIP (``mip``, warm-started from greedy, which on R reproduces S) is solved on
   the rows R only; targets that R cannot see become constants and are reduced away.
4. The better of S and the MIP's selection is returned; its cost is recomputed on the
   full problem.

Bound: the restricted MIP's bound is not valid for the full problem (it optimizes over a
subset of the selections), so the reported bound is the full problem's Lagrangian bound
(camplace.solvers.bounds.lagrangian_bound: O(nnz) per subgradient step), None when that
module is unavailable. Status 'optimal' when the bound meets the cost, else 'heuristic'
(or 'interrupted' / 'time_limit').
"""

from __future__ import annotations

import time

import numpy as np

from camplace.problem.gains import marginal_gains
from camplace.problem.model import PlacementProblem
from camplace.solvers.base import OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, stopped
from camplace.solvers.contract import Tags, make_solver
from camplace.solvers.greedy_fast import solve_greedy_fast
from camplace.solvers.mip import solve_mip
from camplace.solvers.reduction import solve_reduced


def restricted_candidates(problem: PlacementProblem, selected: np.ndarray, extra: int) -> np.ndarray:
    """Sorted candidate ids: every pose at the selected locations + the ``extra`` other
    candidates of largest positive marginal gain at the selection's coverage (ties: lowest id)."""
    sel = np.asarray(selected, np.int64)
    loc = np.asarray(problem.location_ids)
    at = np.isin(loc, loc[sel])
    gains = marginal_gains(problem, problem.coverage(sel))
    free = np.flatnonzero(~at & (gains > 0))
    top = free[np.lexsort((free, -gains[free]))][:max(0, int(extra))]
    return np.union1d(np.flatnonzero(at), top).astype(np.int64)


def solve_greedy_polish(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                        seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                        on_incumbent: OnIncumbent | None = None, extra_per_camera: int = 4,
                        mip_time_s: float = 60.0, bound_time_s: float = 10.0) -> Placement:
    """Greedy + MIP polishing on a restricted candidate set + full-problem Lagrangian bound
    (module doc). mip_time_s / bound_time_s cap the two phases (within time_limit_s)."""
    t0 = time.perf_counter()
    end = deadline(time_limit_s)
    g = solve_greedy_fast(problem, time_limit_s=time_limit_s, should_stop=should_stop, progress=progress,
                          on_incumbent=on_incumbent)
    best, best_cost = g.selected, g.objective
    info: dict = {"greedy_objective": g.objective}
    if g.status in ("interrupted", "time_limit") or len(g.selected) == 0 or g.objective <= 0:
        status = g.status if g.status != "heuristic" else ("optimal" if g.objective <= 0 else "heuristic")
        bound = 0.0 if g.objective <= 0 else None
        return Placement(best, best_cost, bound, status, "greedy-polish", time.perf_counter() - t0, info)
    R = restricted_candidates(problem, g.selected, extra_per_camera * len(g.selected))
    sub = problem.take_candidates(R)
    left = end - time.perf_counter()
    m = solve_reduced(sub, lambda q: solve_mip(q, time_limit_s=max(0.1, min(mip_time_s, 0.8 * left)),
                                               threads=threads, seed=seed, should_stop=should_stop,
                                               warm_start=True, local_search=True))
    polished = np.sort(R[np.asarray(m.selected, np.int64)])
    pcost = problem.cost(polished)
    info.update(restricted_candidates=int(len(R)), mip_status=m.status, mip_objective=pcost,
                mip_restricted_bound=m.bound)
    if pcost < best_cost:
        best, best_cost = polished, pcost
        if on_incumbent:
            on_incumbent(best_cost, None)
    bound = None
    cut = stopped(should_stop)
    if not cut and time.perf_counter() < end:
        try:
            from camplace.solvers.bounds import lagrangian_bound
        except ImportError:  # pragma: no cover - bounds module absent
            lagrangian_bound = None
        if lagrangian_bound is not None:
            b = lagrangian_bound(problem, time_limit_s=max(0.1, min(bound_time_s, end - time.perf_counter())),
                                 incumbent_cost=best_cost, coverage=problem.coverage(best),
                                 should_stop=should_stop)
            bound = min(float(b.bound), best_cost)
            info["bound_method"] = b.method
    if cut:
        status = "interrupted"
    elif bound is not None and bound >= best_cost - 1e-9 * max(1.0, best_cost):
        status = "optimal"
    else:
        status = "time_limit" if time.perf_counter() > end else "heuristic"
    return Placement(np.asarray(best, np.int64), best_cost, bound, status, "greedy-polish",
                     time.perf_counter() - t0, info)


GREEDY_POLISH = make_solver("greedy-polish", solve_greedy_polish, Tags(gives_bound=True),
                            summary="Greedy, then the MIP on a restricted candidate set, Lagrangian bound")
