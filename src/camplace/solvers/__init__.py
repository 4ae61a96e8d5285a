"""camplace.solvers (layer 8): one contract, one registry, one conformance suite.

Every solver is a :class:`Solver` (camplace.solvers.contract): a name, :class:`Tags`, a
frozen options dataclass and one call ``solver.solve(problem, options, hooks) ->
Placement``. ``SOLVERS`` (camplace.solvers.registry) holds them by name: the entry points
of the group ``camplace.solvers``, camplace's own and other packages' (plugins);
``build_options(name, **kwargs)`` refuses an option the solver does not take;
``solve(problem, "name", **options)`` is the convenience entry (options and hooks as
keywords, the problem reduced first). camplace.solvers.testing checks any solver against
the contract. Solvers know no geometry: they see a PlacementProblem.

A plugin needs only this package: ``from camplace.solvers import Placement, Tags,
make_solver`` (and the helpers ``deadline``, ``stopped``, ``time_left`` of a solver's
loop); docs/solvers.md "What a solver may use" lists the problem's constraint interface
and the gain helpers.
"""

from __future__ import annotations

from camplace.solvers.base import Placement, deadline, stopped, time_left
from camplace.solvers.contract import Hooks, Options, Solver, Tags, make_solver
from camplace.solvers.registry import SOLVERS, build_options, get_solver, solve

__all__ = ["Hooks", "Options", "Placement", "SOLVERS", "Solver", "Tags", "build_options", "deadline", "get_solver",
           "make_solver", "solve", "stopped", "time_left"]
