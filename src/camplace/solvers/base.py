"""The solver output type shared by every solver."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class Placement:
    """selected: (k,) int64 sorted candidate ids (rows of V); objective: cost of the
    selection; bound: proven lower bound on the optimal cost (None if none); status:
    'optimal' | 'feasible' | 'time_limit' | 'interrupted' | 'heuristic'."""

    selected: np.ndarray
    objective: float
    bound: float | None
    status: str
    solver: str
    seconds: float
    info: dict = field(default_factory=dict)

    @property
    def gap(self) -> float | None:
        """Proven relative gap (objective − bound) / objective, 0 when both are 0."""
        if self.bound is None:
            return None
        if self.objective <= 0:
            return 0.0
        return max(0.0, (self.objective - self.bound) / self.objective)


# ---------------------------------------------------------------------------
# The callbacks every solver takes (camplace.solvers.contract has the whole contract):
# should_stop(): polled, when True the solver returns its best placement with status
# 'interrupted'; progress(stage, done, total): progress report; on_incumbent(objective,
# bound_or_None): called when a better placement is found.

ShouldStop = Callable[[], bool]
ProgressFn = Callable[[str, int, int], None]
OnIncumbent = Callable[[float, "float | None"], None]


def stopped(should_stop: ShouldStop | None) -> bool:
    """True when the caller asked the solver to stop."""
    return bool(should_stop is not None and should_stop())


def deadline(time_limit_s: float | None, start: float | None = None) -> float:
    """perf_counter() value at which the time limit runs out, counted from ``start``
    (a perf_counter() value; default now); inf when time_limit_s is None."""
    t0 = time.perf_counter() if start is None else float(start)
    return float("inf") if time_limit_s is None else t0 + max(0.0, float(time_limit_s))


def time_left(end: float) -> float | None:
    """Seconds (>= 0) until the perf_counter() deadline ``end``; None when there is none (inf)."""
    if not np.isfinite(end):
        return None
    return max(0.0, end - time.perf_counter())


def out_of_time(end: float, need_s: float = 0.0) -> bool:
    """True when fewer than ``need_s`` seconds are left before the deadline ``end``."""
    left = time_left(end)
    return left is not None and left < need_s


def limit_left(end: float, time_limit_s: float | None = None) -> float | None:
    """The time limit to hand a phase: the smaller of ``time_limit_s`` and the time left
    before ``end`` (None when neither is set)."""
    left = time_left(end)
    if left is None:
        return time_limit_s
    return left if time_limit_s is None else min(float(time_limit_s), left)


def trivial_placement(problem, name: str, t0: float) -> Placement | None:
    """The proven-optimal answer when nothing can be chosen or nothing needs cover
    (no candidate, budget 0, or zero cost with no camera); else None."""
    import numpy as np

    if problem.n_candidates == 0 or problem.budget == 0 or problem.normalizer == 0:
        cost = problem.normalizer
        return Placement(np.zeros(0, np.int64), cost, cost, "optimal", name, time.perf_counter() - t0, {})
    return None
