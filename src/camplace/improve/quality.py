"""High quality within one time budget (issue 37): refinement and relocation chained.

From the discrete solver's placement, each step gets a share of one time budget (s) and
starts from the previous step's best selection; a step that finishes early leaves its time
to the next ones. The default plan (``QUALITY_STEPS``), meant for V of a denser grid
(camplace.workflows.quality: ``quality="high"`` halves the mount spacing):

1. ``refine``: each camera off the grid by the compass search (camplace.improve.refine);
2. ``refine`` again (its search box is centred on the current poses);
3. ``relocate``: each camera moved to the best of a few other candidates, each judged by the
   pose a compass search makes of it (camplace.improve.relocate);
4. ``refine`` once more.

The other steps a plan may name: ``tabu`` (tabu search warm-started from the placement,
camplace.solvers.tabu), ``adaptive`` (rounds of finer candidates around the placement, each
solved again by swap descent and a short tabu; camplace.improve.adaptive), ``kick``
(:func:`kick_refine`: drop two of the least useful cameras, refill by swap descent, refine,
keep it if better) and ``shake``. When the plan ends early (the refinements converged, a
relocation sweep moved nothing), the time left goes to ``shake`` steps (``EXTRA_CYCLE``,
camplace.improve.relocate.shake_relocate: three cameras moved at random among good places, then
refinement, relocation, refinement, kept if better), each with the next seed, until less than
``MIN_CYCLE_S`` is left or ``SHAKE_MAX_FAILS`` shakes in a row found nothing (then the chain
ends before its budget: the run need not wait for nothing).

Measured on standard-store, N_s = 20 (benchmarks/quality.py, docs/benchmarks.md): on the
0.5 m grid, greedy then two refinements reach gap 0.175 in ~3 s, a relocation 0.173; the
earlier plan (tabu, adaptive rounds, refinements on the 1 m grid) ended at 0.178.

Refinement and adaptive rounds append rows to V, so the returned visibility / problem replace
the grid ones; the placement stays a selection of V rows and its cost is recomputed from V.
No step makes the cost worse: each one returns its start when it finds nothing better.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from camplace.improve.adaptive import adaptive_rounds
from camplace.improve.refine import PoseGuard, RowMap, refine_placement
from camplace.improve.relocate import relocate_placement, shake_relocate
from camplace.problem.model import PlacementProblem
from camplace.scene.build import Scene
from camplace.solvers.base import Placement
from camplace.visibility.engine import Visibility

Progress = Callable[[str, int, int], None]
# (step, share of the whole budget): shares are of the budget left when the step starts,
# scaled by the shares of the steps still to come, so unspent time flows on
QUALITY_STEPS: tuple[tuple[str, float], ...] = (("refine", 0.1), ("refine", 0.1), ("relocate", 0.7), ("refine", 0.1))

EXTRA_CYCLE: tuple[tuple[str, float], ...] = (("shake", 1.0),)  # repeated while time is left
MIN_CYCLE_S = 1.5  # the least time left (s) worth another cycle
KICK_MAX_FAILS = 3  # the chain ends after this many kicks in a row found nothing (the run need not wait)
SHAKE_MAX_FAILS = 10  # ... or this many shakes (camplace.improve.relocate.shake_relocate)


@dataclass(frozen=True)
class QualityResult:
    """visibility / problem: V and the problem with the appended rows; placement: the best
    selection on them (solver '<solver>+quality-high'; info['quality']: start_cost, grid_cost -
    the cost before the first step off the grid -, budget_seconds - the chain's wall-clock
    budget, left out of placement.json -, steps); steps: per step dict(step, seconds, cost)."""

    visibility: Visibility
    problem: PlacementProblem
    placement: Placement
    start_cost: float
    steps: list[dict] = field(default_factory=list)


def step_budget(left_s: float, shares: list[float]) -> float:
    """Seconds for the first of the remaining steps: its share of the time left (s), out of
    the shares of all remaining steps (so a step that ended early gives its time to the rest)."""
    total = sum(shares)
    return max(0.0, left_s * shares[0] / total) if total > 0 else 0.0


def kick_refine(scene: Scene, vis: Visibility, problem: PlacementProblem, placement: Placement, time_limit_s: float,
                *, seed: int = 0, drop: int = 2, max_fails: int | None = None, guard: PoseGuard | None = None,
                row_map: RowMap | None = None,
                should_stop: Callable[[], bool] | None = None) -> tuple[Visibility, PlacementProblem, Placement]:
    """Iterated local search for ``time_limit_s`` seconds: drop ``drop`` cameras drawn among
    the 2·drop whose loss is least, refill by swap descent (grid and earlier rows alike),
    refine, keep the result when its cost is lower. The rows raycast stay in V either way.
    ``max_fails``: also end after that many kicks in a row found nothing better (None: never)."""
    from camplace.improve.adaptive import swap_descent

    end = time.perf_counter() + time_limit_s
    rng = np.random.default_rng(seed)
    stop = (lambda: False) if should_stop is None else should_stop
    best = problem.cost(placement.selected)
    fails = 0
    while time.perf_counter() < end - 0.3 and not stop() and (max_fails is None or fails < max_fails):
        sel = np.asarray(placement.selected, np.int64)
        loss = np.array([problem.cost(np.delete(sel, k)) for k in range(len(sel))]) - best
        pool = np.argsort(loss)[: 2 * drop]
        out = rng.choice(pool, size=min(drop, len(pool)), replace=False)
        trial, _ = swap_descent(problem, np.delete(sel, out), time_limit_s=max(0.2, end - time.perf_counter()),
                                should_stop=should_stop)
        rf = refine_placement(scene, vis, problem, replace(placement, selected=trial, objective=problem.cost(trial)),
                              time_limit_s=max(0.2, end - time.perf_counter()), guard=guard, row_map=row_map,
                              should_stop=should_stop)
        vis, problem = rf.visibility, rf.problem
        if rf.refined_cost < best - 1e-9:
            best, placement, fails = rf.refined_cost, rf.placement, 0
        else:  # the same selection on the extended problem (its rows keep their ids)
            placement = replace(placement, objective=problem.cost(placement.selected))
            fails += 1
    return vis, problem, placement


def high_quality(scene: Scene, vis: Visibility, problem: PlacementProblem, placement: Placement,
                 time_limit_s: float = 25.0, *, seed: int = 0, steps: tuple[tuple[str, float], ...] = QUALITY_STEPS,
                 adaptive_rounds_max: int = 3, progress: Progress | None = None, guard: PoseGuard | None = None,
                 row_map: RowMap | None = None, should_stop: Callable[[], bool] | None = None) -> QualityResult:
    """Run ``steps`` (see module doc) from ``placement`` within ``time_limit_s`` seconds of
    wall clock in all; ``should_stop()`` ends the chain between steps (and inside refine and
    adaptive), keeping the best placement so far."""
    from camplace.solvers.tabu import solve_tabu

    t0 = time.perf_counter()
    end = t0 + float(time_limit_s)
    stop = (lambda: False) if should_stop is None else should_stop
    start_cost = problem.cost(placement.selected)
    start_solver, grid_cost, on_grid = placement.solver, start_cost, True
    hist: list[dict] = []
    plan, n, cycle, idle = list(steps), 0, 0, False
    while not stop():
        if n == len(plan):  # time left after the plan: EXTRA_CYCLE steps (kicks), the next seed each
            if end - time.perf_counter() < MIN_CYCLE_S or idle:  # idle: the last kicks found nothing
                break
            plan += list(EXTRA_CYCLE)
            cycle += 1
        name = plan[n][0]
        budget = step_budget(end - time.perf_counter(), [s for _, s in plan[n:]])
        n += 1
        if budget < 0.2:
            continue
        ts = time.perf_counter()
        if name == "tabu":
            p = solve_tabu(problem, time_limit_s=budget, seed=seed + cycle, initial=placement.selected,
                           should_stop=should_stop, max_stall_restarts=None)
            if p.objective < problem.cost(placement.selected) - 1e-9:
                placement = replace(placement, selected=p.selected, objective=p.objective)
        elif name == "refine":
            rf = refine_placement(scene, vis, problem, placement, time_limit_s=budget, progress=progress, guard=guard,
                                  row_map=row_map, should_stop=should_stop)
            vis, problem, placement = rf.visibility, rf.problem, rf.placement
        elif name == "adaptive":
            ar = adaptive_rounds(scene, vis, problem, placement, rounds=adaptive_rounds_max, time_limit_s=budget,
                                 solver="tabu", solver_time_s=budget / (2 * adaptive_rounds_max), progress=progress,
                                 guard=guard, row_map=row_map, should_stop=should_stop)
            vis, problem, placement = ar.visibility, ar.problem, ar.placement
        elif name == "relocate":
            rf = relocate_placement(scene, vis, problem, placement, budget, guard=guard, row_map=row_map,
                                    should_stop=should_stop)
            vis, problem, placement = rf.visibility, rf.problem, rf.placement
        elif name in ("kick", "shake"):
            c0 = problem.cost(placement.selected)
            search, fails = (kick_refine, KICK_MAX_FAILS) if name == "kick" else (shake_relocate, SHAKE_MAX_FAILS)
            vis, problem, placement = search(scene, vis, problem, placement, budget, seed=seed + cycle,
                                             max_fails=fails, guard=guard, row_map=row_map, should_stop=should_stop)
            idle = problem.cost(placement.selected) >= c0 - 1e-9
        else:
            raise ValueError(f"unknown quality step {name!r}")
        on_grid = on_grid and name == "tabu"
        if on_grid:
            grid_cost = float(problem.cost(placement.selected))
        hist.append({"step": name, "seconds": round(time.perf_counter() - ts, 3),
                     "cost": float(problem.cost(placement.selected))})
    sel = np.asarray(placement.selected, np.int64)
    problem.check_feasible(sel)
    info = dict(placement.info, quality={"start_cost": start_cost, "grid_cost": grid_cost,
                                         "budget_seconds": float(time_limit_s), "steps": hist})
    out = replace(placement, selected=sel, objective=problem.cost(sel), status="heuristic",
                  solver=f"{start_solver}+quality-high",
                  seconds=placement.seconds + time.perf_counter() - t0, info=info)
    return QualityResult(vis, problem, out, start_cost, hist)


__all__ = ["EXTRA_CYCLE", "KICK_MAX_FAILS", "MIN_CYCLE_S", "QUALITY_STEPS", "QualityResult", "SHAKE_MAX_FAILS",
           "high_quality", "kick_refine", "step_budget"]
