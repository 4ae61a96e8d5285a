"""Solve on the reduced problem and map the answer back (camplace.problem.model.reduce_problem)."""

from __future__ import annotations

from dataclasses import replace
from typing import Callable

from camplace.problem.model import PlacementProblem, reduce_problem
from camplace.solvers.base import Placement


def solve_reduced(problem: PlacementProblem, run: Callable[[PlacementProblem], Placement]) -> Placement:
    """``run`` on reduce_problem(problem) (same optimum, fewer rows/columns): the selection
    is lifted to original candidate ids, the objective recomputed on ``problem``, the sizes
    before/after are in info['reduction'] and info['order'] (if any) is mapped back."""
    red = reduce_problem(problem)
    p = run(red.problem)
    sel = red.lift(p.selected)
    info = dict(p.info)
    info["reduction"] = red.info
    if isinstance(info.get("order"), list):
        info["order"] = [int(red.candidates[i]) for i in info["order"]]
    return replace(p, selected=sel, objective=problem.cost(sel), info=info)


__all__ = ["solve_reduced"]
