"""Compile a solver's numba kernels before its clock starts.

The first call of a numba kernel in a process compiles it, or loads it from the on-disk
cache: seconds right after an install (or with an empty ``NUMBA_CACHE_DIR``), a few
hundredths of a second later. Inside a solver that time would come out of its time limit:
a 10 s certification whose kernels compile for 6 s proves a gap several times wider than
the same run a minute later. So before the first solve of a solver in a process,
camplace.solvers.registry.solve runs that solver once (``dry_run``) on a small problem cut
from the real one: the same array types, hence the same kernel signatures, compiled (or
loaded) outside the limit. Later solves of that solver in the process skip it.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Callable

import numpy as np

from camplace.problem.model import PlacementProblem

DRY_RUN_S = 0.3  # the dry run's own time limit (compiling is not limited by it)
DRY_CANDIDATES = 40  # candidates of the small problem (spread over the real ones)
DRY_BUDGET = 3
DRY_ROUNDS = 3
NO_DRY_RUN = frozenset({"zones"})  # runs its tiles in worker processes, which load the kernels themselves
_done: set[str] = set()


def small_problem(problem: PlacementProblem, n_candidates: int = DRY_CANDIDATES,
                  budget: int = DRY_BUDGET) -> PlacementProblem | None:
    """``n_candidates`` candidates spread over ``problem``'s (every target kept; the budget
    ``budget`` at most, a money budget that binds as the real one might), or None when
    ``problem`` is too small to need it."""
    n_g = problem.n_candidates
    b = min(int(problem.budget), budget)
    if n_g < 4 or b < 1:
        return None
    rows = np.unique(np.linspace(0, n_g - 1, min(n_candidates, n_g)).astype(np.int64))
    small = problem.take_candidates(rows)
    money = None
    if problem.money_budget is not None and small.camera_costs is not None:
        money = float(np.sort(np.asarray(small.camera_costs, np.float64))[:b].sum())
    for name in ("data", "indices", "indptr"):  # numba compiles a read-only array's kernels apart from a
        if not getattr(problem.V, name).flags.writeable:  # writable one's (V memory-mapped from the cache)
            getattr(small.V, name).flags.writeable = False
    return replace(small, budget=b, money_budget=money)


def dry_run(name: str, problem: PlacementProblem, run: Callable[[PlacementProblem], object]) -> float:
    """Once per process and solver ``name``: ``run(small_problem(problem))`` (the solver with
    the caller's options and a DRY_RUN_S limit), again while it compiles something (at
    most DRY_ROUNDS times), so that its kernels are compiled; returns the seconds spent
    (0.0 when already done or not needed). A failure of the dry run is ignored: the real
    run will meet it and report it."""
    if name in _done or name in NO_DRY_RUN:
        return 0.0
    _done.add(name)
    small = small_problem(problem)
    if small is None:
        return 0.0
    from numba.core import event

    t0 = time.perf_counter()
    for _ in range(DRY_ROUNDS):
        with event.install_recorder("numba:compile") as rec:
            try:
                run(small)
            except Exception:  # noqa: BLE001 - an optimisation only
                return time.perf_counter() - t0
        if not rec.buffer:
            break
    return time.perf_counter() - t0


__all__ = ["DRY_RUN_S", "dry_run", "small_problem"]
