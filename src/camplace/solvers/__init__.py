"""Stage 6 - solvers. Every solver is ``solve(problem, **options) -> Placement``.

Solvers know no geometry: they see a PlacementProblem. ``solve(problem, "name")``
dispatches through the registry ``SOLVERS``.
"""

from __future__ import annotations

from typing import Callable

from camplace.core.errors import InputError
from camplace.problem.model import PlacementProblem
from camplace.solvers.base import Placement
from camplace.solvers.certify import solve_certify
from camplace.solvers.greedy import solve_greedy
from camplace.solvers.greedy_fast import solve_greedy_fast
from camplace.solvers.polish import solve_greedy_polish
from camplace.solvers.horster import solve_horster
from camplace.solvers.min_cameras import solve_min_cameras
from camplace.solvers.mip import solve_mip
from camplace.solvers.paper_mip import solve_paper_mip
from camplace.solvers.tabu import solve_tabu
from camplace.solvers.zhao import solve_zhao

SOLVERS: dict[str, Callable[..., Placement]] = {
    "greedy": solve_greedy,
    "greedy-fast": solve_greedy_fast,
    "greedy-polish": solve_greedy_polish,
    "mip": solve_mip,
    "paper-mip": solve_paper_mip,
    "zhao": solve_zhao,
    "horster": solve_horster,
    "min-cameras": solve_min_cameras,
    "tabu": solve_tabu,
    "certify": solve_certify,
}


def solve(problem: PlacementProblem, solver: str = "greedy", *, reduce: bool = True, **options) -> Placement:
    """Run the named solver on the problem. With reduce=True (default) the solver sees
    camplace.problem.model.reduce_problem(problem) (same optimum, fewer rows/columns); the
    selection is mapped back, the objective recomputed on the original problem, and
    the sizes before/after are in placement.info['reduction']."""
    try:
        fn = SOLVERS[solver]
    except KeyError:
        raise InputError(f"unknown solver '{solver}'; expected one of {', '.join(sorted(SOLVERS))}") from None
    if not reduce:
        return fn(problem, **options)
    from dataclasses import replace

    from camplace.problem.model import reduce_problem

    red = reduce_problem(problem)
    p = fn(red.problem, **options)
    sel = red.lift(p.selected)
    info = dict(p.info)
    info["reduction"] = red.info
    if isinstance(info.get("order"), list):
        info["order"] = [int(red.candidates[i]) for i in info["order"]]
    return replace(p, selected=sel, objective=problem.cost(sel), info=info)


__all__ = ["Placement", "SOLVERS", "solve"]
