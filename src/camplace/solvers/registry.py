"""The solver registry: every solver by name, the options builder and ``solve``.

    SOLVERS["mip"].solve(problem, build_options("mip", time_limit_s=10), Hooks(should_stop=f))
    solve(problem, "mip", time_limit_s=10, should_stop=f)        # the same, on the reduced problem

``SOLVERS`` is the entry-point group ``camplace.solvers`` (camplace.core.plugins), read at
first use: the built-ins are declared in camplace's pyproject.toml, another package adds
its own the same way; a broken one is reported (a PluginWarning) and skipped. Adding a
solver: docs/solvers.md; camplace.solvers.testing.check_solver is the proof that it
keeps the contract.
"""

from __future__ import annotations

import time
from dataclasses import fields, replace
from typing import Any

from camplace.core.errors import InputError
from camplace.core.plugins import Registry
from camplace.problem.model import PlacementProblem
from camplace.solvers.base import Placement
from camplace.solvers.contract import HOOK_FIELDS, Options, Solver, split_options
from camplace.solvers.reduction import solve_reduced
from camplace.solvers.warmup import DRY_RUN_S, dry_run

GROUP = "camplace.solvers"


def check_plugin(name: str, obj: Any) -> Solver:
    """``obj`` when it is a Solver named ``name`` (the entry point's name); else TypeError."""
    if not isinstance(obj, Solver):
        raise TypeError(f"expected a camplace.solvers.Solver (camplace.solvers.contract.make_solver), got "
                        f"{type(obj).__name__}")
    if obj.name != name:
        raise TypeError(f"the Solver is named {obj.name!r}, the entry point {name!r}")
    return obj


SOLVERS: Registry = Registry(GROUP, check_plugin)  # name -> Solver, loaded at first use


def type_name(tp: Any) -> str:
    """A declared type as written: 'int', 'float | None', 'Placement | ndarray | None'."""
    import types
    import typing

    if isinstance(tp, str):
        return tp
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        return " | ".join(type_name(a) for a in typing.get_args(tp))
    if tp is type(None):
        return "None"
    if isinstance(tp, type) and typing.get_origin(tp) is None:
        return tp.__name__
    return str(tp).replace("typing.", "").replace("collections.abc.", "").replace("NoneType", "None")


def catalogue() -> list[dict]:
    """Every registered solver as plain data: name, summary, distribution ('camplace' for a
    built-in), the tags that hold, and its options (name, type, default), common ones first."""
    from dataclasses import MISSING, asdict, fields

    from camplace.solvers.contract import _field_types

    out = []
    for name, s in SOLVERS.items():
        hints = _field_types(s.options)
        opts = [{"name": f.name, "type": type_name(hints.get(f.name, f.type)),
                 "default": None if f.default is MISSING else f.default} for f in fields(s.options)]
        out.append({"name": name, "summary": s.summary, "distribution": SOLVERS.distribution(name),
                    "tags": [k for k, v in asdict(s.tags).items() if v], "options": opts})
    return out


def get_solver(name: str) -> Solver:
    """The registered Solver ``name``; InputError(option='solver') when there is none."""
    try:
        return SOLVERS[name]
    except (KeyError, TypeError):
        raise InputError(f"solver: unknown solver {name!r}; expected one of {', '.join(sorted(SOLVERS))}",
                         option="solver") from None


def solvers_taking(option: str) -> list[str]:
    """Sorted names of the solvers that take ``option``."""
    return sorted(n for n, s in SOLVERS.items() if option in s.option_names)


def options_of(opts: Options) -> dict[str, Any]:
    """The keyword arguments that give ``opts`` back (every field; the dry run keeps the
    plain values only: no callbacks such as certify's on_state, no id lists of the real problem)."""
    return {f.name: getattr(opts, f.name) for f in fields(opts)}


def build_options(name: str, **kwargs: Any) -> Options:
    """The options of solver ``name`` from keywords (common ones and the solver's own);
    InputError(option=key) for a key it does not take, naming the solvers that do."""
    solver = get_solver(name)
    hooks = [k for k in kwargs if k in HOOK_FIELDS]
    if hooks:
        raise InputError(f"{hooks[0]}: a callback, not an option; pass it in Hooks", option=hooks[0])
    opts, _ = split_options(solver, kwargs, solvers_taking)
    return opts


def solve(problem: PlacementProblem, solver: str = "greedy", *, reduce: bool = True, warm: bool = True,
          **options: Any) -> Placement:
    """Run the named solver: options and hooks (should_stop, progress, on_incumbent) as
    keywords, checked against the solver (InputError for one it does not take). With
    reduce=True (default) the solver sees camplace.problem.model.reduce_problem(problem)
    (same optimum, fewer rows/columns; camplace.solvers.reduction.solve_reduced), except
    solvers tagged needs_positions or needs_start, which always see ``problem``. With warm=True
    (default) the first solve of a solver in a process is preceded by a dry run on a small
    problem (camplace.solvers.warmup), so that compiling its kernels does not eat its time limit."""
    s = get_solver(solver)
    opts, hooks = split_options(s, options, solvers_taking)
    if warm and not s.tags.needs_start:  # the kernels compile here, not inside the solver's time limit
        plain = {k: v for k, v in options_of(opts).items() if v is None or isinstance(v, (bool, int, float, str))}
        dry_run(s.name, problem, lambda small: solve(small, solver, reduce=reduce, warm=False,
                                                     **dict(plain, time_limit_s=DRY_RUN_S)))
    if not reduce or s.tags.needs_positions or s.tags.needs_start:
        return s.solve(problem, opts, hooks)
    t0 = time.perf_counter()

    def run_reduced(red: PlacementProblem) -> Placement:  # the reduction's time counts against the limit
        if opts.time_limit_s is None:
            return s.solve(red, opts, hooks)
        left = max(0.01, opts.time_limit_s - (time.perf_counter() - t0))
        return s.solve(red, replace(opts, time_limit_s=left), hooks)

    return solve_reduced(problem, run_reduced)


__all__ = ["SOLVERS", "build_options", "catalogue", "get_solver", "solve", "solvers_taking", "type_name"]
