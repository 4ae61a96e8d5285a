"""camplace: choose where to mount cameras so every place gets the coverage it needs.

The pipeline (see docs/design.md): scene -> targets -> candidates -> visibility ->
problem -> solvers -> metrics -> outputs. The public API is importable from here:
``camplace.run`` (every stage on a scene), ``camplace.workflows.evaluate`` (score a placement
file), ``camplace.solve`` (a solver on a PlacementProblem), the types
``PlacementProblem`` and ``Placement``, the solver registry ``SOLVERS`` with its contract
(``Solver``, ``Hooks``, ``build_options``; camplace.solvers.testing checks a solver). They are
loaded lazily, so ``import camplace`` stays cheap.
"""

from camplace.core.errors import CamplaceError, InputError

__version__ = "0.1.0"

_LAZY = {
    "run": ("camplace.workflows.run", "run"),
    "evaluate": ("camplace.workflows.evaluate", "evaluate"),
    "solve": ("camplace.solvers", "solve"),
    "SOLVERS": ("camplace.solvers", "SOLVERS"),
    "Solver": ("camplace.solvers", "Solver"),
    "Hooks": ("camplace.solvers", "Hooks"),
    "build_options": ("camplace.solvers", "build_options"),
    "Placement": ("camplace.solvers.base", "Placement"),
    "PlacementProblem": ("camplace.problem.model", "PlacementProblem"),
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'camplace' has no attribute {name!r}")


__all__ = ["CamplaceError", "InputError", "__version__", *_LAZY]
