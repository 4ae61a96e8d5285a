"""Baseline `horster`: the greedy of Hörster & Lienhart (2006), as the paper ran it.

Each step adds the camera (one per location, within the budget) that covers the most
targets not yet at their required coverage (c_j < Γ_j; weighted by w_j, so a merged
target counts for all the targets it stands for). It stops when the budget is spent
or no camera reaches an under-covered target. The gain of a camera never grows as
others are added, so lazy evaluation (CELF) gives the same result as a full scan.
"""

from __future__ import annotations

import time

import numpy as np

from camplace.problem.model import PlacementProblem
from camplace.solvers.base import OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, stopped
from camplace.solvers.contract import make_solver
from camplace.solvers.greedy import lazy_greedy


def undercovered_gains(problem: PlacementProblem, coverage: np.ndarray) -> np.ndarray:
    """(N_g,) float64: weighted count of targets with c_j < Γ_j each candidate sees."""
    return problem.V @ np.where(coverage < problem.gamma, problem.weights, 0.0)


def solve_horster(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                  seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                  on_incumbent: OnIncumbent | None = None) -> Placement:
    """Hörster & Lienhart greedy (see module docstring). Status 'heuristic' (or
    'interrupted' / 'time_limit' when stopped early)."""
    t0 = time.perf_counter()
    V = problem.V

    def gain_of(i: int, cov: np.ndarray) -> float:
        cols = V.indices[V.indptr[i]:V.indptr[i + 1]]
        return float(problem.weights[cols][cov[cols] < problem.gamma[cols]].sum())

    selected, _, evaluations, cut = lazy_greedy(problem, lambda c: undercovered_gains(problem, c), gain_of,
                                                end=deadline(time_limit_s), should_stop=should_stop,
                                                progress=progress, stage="horster")
    sel = np.array(sorted(selected), np.int64)
    cost = problem.cost(sel)
    if on_incumbent:
        on_incumbent(cost, None)
    status = ("interrupted" if stopped(should_stop) else "time_limit") if cut else "heuristic"
    return Placement(sel, cost, None, status, "horster", time.perf_counter() - t0,
                     {"gain_evaluations": evaluations, "order": [int(i) for i in selected]})


HORSTER = make_solver("horster", solve_horster, summary="Hörster's greedy baseline")
