"""Stage 6 - solvers. Every solver is ``solve(problem, **options) -> Placement``.

Solvers know no geometry: they see a PlacementProblem. ``solve(problem, "name")``
dispatches through the registry ``SOLVERS``.
"""

from __future__ import annotations

from typing import Callable

from camplace.errors import InputError
from camplace.problem import PlacementProblem
from camplace.solvers.base import Placement
from camplace.solvers.greedy import solve_greedy

SOLVERS: dict[str, Callable[..., Placement]] = {
    "greedy": solve_greedy,
}


def solve(problem: PlacementProblem, solver: str = "greedy", **options) -> Placement:
    """Run the named solver on the problem."""
    try:
        fn = SOLVERS[solver]
    except KeyError:
        raise InputError(f"unknown solver '{solver}'; expected one of {', '.join(sorted(SOLVERS))}") from None
    return fn(problem, **options)


__all__ = ["Placement", "SOLVERS", "solve"]
