"""The solver contract (scikit-learn style): a name, tags, a frozen options type and one call.

    solver.solve(problem, options, hooks) -> Placement

``options`` is an instance of ``solver.options`` (a frozen dataclass: the common fields
time_limit_s, threads, seed of :class:`Options`, plus the solver's own fields with their
defaults); ``hooks`` (:class:`Hooks`) carries the callbacks should_stop, progress and
on_incumbent. The implementation behind a Solver is a plain function

    solve_x(problem, *, time_limit_s, threads, seed, should_stop, progress, on_incumbent, <own options>)

whose keyword-only parameters after the common ones are the solver's options (each with a
default and a type hint); :func:`make_solver` derives the options dataclass from that
signature, so there is one source of truth: the command line, the scene file
(``placement.options``) and Python all build that dataclass, which converts each value to
its declared type or raises InputError naming the option and the type (a string is also
read as YAML: ``'50'``, ``'0.5'``, ``'true'``, ``'none'``, ``'[1, 2]'``).
camplace.solvers.registry holds every Solver; camplace.solvers.testing checks any Solver
against this contract.
"""

from __future__ import annotations

import functools
import inspect
import types
import typing
from dataclasses import dataclass, field, fields, make_dataclass
from typing import Any, Callable, ClassVar

from camplace.core.errors import InputError
from camplace.problem.model import PlacementProblem
from camplace.solvers.base import OnIncumbent, Placement, ProgressFn, ShouldStop

COMMON_FIELDS = ("time_limit_s", "threads", "seed")
HOOK_FIELDS = ("should_stop", "progress", "on_incumbent")


@dataclass(frozen=True)
class Tags:
    """What a solver promises, used by the conformance suite to choose its checks.

    exact: proves the optimum on small problems without a time limit (status 'optimal');
    anytime: can be stopped (time limit, should_stop) and returns its best placement so far;
    gives_bound: Placement.bound is a proven lower bound; money_budget: keeps
    problem.money_budget; ignores_camera_budget: may use more cameras than problem.budget
    (e.g. minimum cameras for a coverage target); needs_positions: needs
    problem.candidate_positions / target_positions (never reduced); needs_start: improves a
    given placement (option ``nominal``; never reduced); deterministic_with_seed: the same
    seed on the same problem gives the same placement (when the time limit is not hit);
    robust_objective: optimises something other than problem.cost (the objective is still
    problem.cost of the selection, but it need not be the minimum)."""

    exact: bool = False
    anytime: bool = True
    gives_bound: bool = False
    money_budget: bool = True
    ignores_camera_budget: bool = False
    needs_positions: bool = False
    needs_start: bool = False
    deterministic_with_seed: bool = True
    robust_objective: bool = False


@dataclass(frozen=True)
class Options:
    """The options every solver takes. time_limit_s: wall-clock seconds (None: the
    solver's default); threads: solver threads (None: the solver's default); seed: random seed.

    Every field is converted to its declared type on construction (a subclass made by
    :func:`options_type` too); a value that does not fit is InputError(option=field).
    ``solver_name``: the solver whose options these are (for messages)."""

    time_limit_s: float | None = None
    threads: int | None = None
    seed: int = 0
    solver_name: ClassVar[str] = ""

    def __post_init__(self) -> None:
        hints = _field_types(type(self))
        for f in fields(self):
            value = getattr(self, f.name)
            converted = convert_option(f.name, value, hints.get(f.name, Any), self.solver_name)
            if converted is not value:
                object.__setattr__(self, f.name, converted)


@functools.cache
def _field_types(cls: type) -> dict[str, Any]:
    try:
        return typing.get_type_hints(cls)
    except Exception:  # noqa: BLE001 - an unresolvable hint is not checked
        return {}


@functools.cache
def _adapter(tp: Any):
    from pydantic import ConfigDict, TypeAdapter

    return TypeAdapter(tp, config=ConfigDict(arbitrary_types_allowed=True))


def describe_type(tp: Any) -> str:
    """Words for a declared option type: 'an integer', 'a number or none', "one of 'a', 'b'"."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(tp)
        words = [describe_type(a) for a in args if a is not type(None)]
        return " or ".join(words + (["none"] if type(None) in args else []))
    if origin is typing.Literal:
        return "one of " + ", ".join(repr(a) for a in typing.get_args(tp))
    simple = {int: "an integer", float: "a number", bool: "true or false", str: "a string", type(None): "none",
              tuple: "a list", list: "a list", dict: "a mapping"}
    if tp in simple or origin in simple:
        return simple.get(tp) or simple[origin]
    if origin is not None and getattr(origin, "__name__", "") in ("Sequence", "Iterable"):
        return "a list"
    if origin is not None and getattr(origin, "__name__", "") == "Callable" or tp is Callable:
        return "a function"
    name = getattr(tp, "__name__", str(tp))
    return "an array" if name == "ndarray" else f"a {name}"


def _from_text(text: str) -> Any:
    """A command-line / YAML string read as a value: 'none' / 'null' / '' -> None, else YAML."""
    if text.strip().lower() in ("none", "null", ""):
        return None
    import yaml

    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return text


def convert_option(name: str, value: Any, tp: Any, solver: str = "") -> Any:
    """``value`` as the declared type ``tp`` of option ``name`` (pydantic's lax conversion:
    '50' -> 50, 3 -> 3.0; a string that does not fit is read as YAML and tried again);
    InputError(option=name) naming the option and the type when it does not fit."""
    if tp is Any:
        return value
    adapter = _adapter(tp)
    from pydantic import ValidationError

    try:
        return adapter.validate_python(value)
    except ValidationError:
        pass
    if isinstance(value, str):
        try:
            return adapter.validate_python(_from_text(value))
        except ValidationError:
            pass
    who = f" (solver '{solver}')" if solver else ""
    raise InputError(f"{name}: expected {describe_type(tp)}{who}, got {value!r}", option=name)


@dataclass(frozen=True)
class Hooks:
    """Callbacks: should_stop() polled, True -> return the best placement with status
    'interrupted'; progress(stage, done, total); on_incumbent(objective, bound_or_None)
    when a better placement (or bound) is found."""

    should_stop: ShouldStop | None = None
    progress: ProgressFn | None = None
    on_incumbent: OnIncumbent | None = None


@dataclass(frozen=True)
class Solver:
    """One registered solver: ``solve(problem, options, hooks) -> Placement``.

    name: registry key; fn: the implementation (see the module doc); options: its frozen
    options dataclass (a subclass of :class:`Options`); tags: :class:`Tags`; summary: one line."""

    name: str
    fn: Callable[..., Placement] = field(repr=False)
    options: type[Options] = field(repr=False)
    tags: Tags = Tags()
    summary: str = ""

    @property
    def option_names(self) -> tuple[str, ...]:
        """Every option this solver takes, the common ones first."""
        return tuple(f.name for f in fields(self.options))

    def solve(self, problem: PlacementProblem, options: Options | None = None,
              hooks: Hooks | None = None) -> Placement:
        """Run on ``problem`` (no reduction: see camplace.solvers.registry.solve). A problem
        with a money budget is refused (InputError) by a solver not tagged money_budget."""
        opts = self.options() if options is None else options
        if not isinstance(opts, self.options):
            raise TypeError(f"solver '{self.name}': options must be {self.options.__name__}, "
                            f"got {type(opts).__name__}")
        if problem.money_budget is not None and not self.tags.money_budget:
            raise InputError(f"solver: '{self.name}' cannot keep a money budget (tag money_budget=False) and the "
                             f"problem has one ({problem.money_budget:g}); choose a solver that keeps it",
                             option="solver")
        h = Hooks() if hooks is None else hooks
        kwargs = {f.name: getattr(opts, f.name) for f in fields(opts)}
        return self.fn(problem, **kwargs, should_stop=h.should_stop, progress=h.progress,
                       on_incumbent=h.on_incumbent)

    def __call__(self, problem: PlacementProblem, **kwargs: Any) -> Placement:
        """``solver(problem, time_limit_s=..., should_stop=..., <own options>)``: options and
        hooks as keywords; an option the solver does not take is an InputError."""
        opts, hooks = split_options(self, kwargs)
        return self.solve(problem, opts, hooks)


def split_options(solver: Solver, kwargs: dict[str, Any],
                  takers: Callable[[str], list[str]] | None = None) -> tuple[Options, Hooks]:
    """(solver.options(...), Hooks(...)) from keyword arguments; InputError(option=key) for
    a key the solver does not take, naming the solvers that do (``takers(key)``, if given)."""
    hooks = Hooks(**{k: kwargs[k] for k in HOOK_FIELDS if k in kwargs})
    own = {k: v for k, v in kwargs.items() if k not in HOOK_FIELDS}
    known = set(solver.option_names)
    for key in own:
        if key not in known:
            others = [] if takers is None else [n for n in takers(key) if n != solver.name]
            tail = (f"; solvers that take it: {', '.join(others)}" if others
                    else f"; it takes: {', '.join(sorted(known))}")
            raise InputError(f"{key}: solver '{solver.name}' takes no option '{key}'{tail}", option=key)
    return solver.options(**own), hooks


def _own_parameters(fn: Callable[..., Placement]) -> list[inspect.Parameter]:
    """The keyword-only parameters of ``fn`` beyond the common options and hooks; checks
    that ``fn`` takes every common option and hook and has no catch-all."""
    params = inspect.signature(fn).parameters
    name = getattr(fn, "__name__", repr(fn))
    missing = [k for k in (*COMMON_FIELDS, *HOOK_FIELDS) if k not in params]
    if missing:
        raise TypeError(f"{name}: a solver must take the keywords {', '.join(missing)}")
    own = []
    for i, p in enumerate(params.values()):
        if p.kind in (p.VAR_KEYWORD, p.VAR_POSITIONAL):
            raise TypeError(f"{name}: a solver takes only the options it declares (no *args / **kwargs)")
        if i == 0 or p.name in COMMON_FIELDS or p.name in HOOK_FIELDS:
            continue
        if p.kind is not p.KEYWORD_ONLY or p.default is p.empty:
            raise TypeError(f"{name}: option '{p.name}' must be keyword-only with a default")
        own.append(p)
    return own


def _hints(fn: Callable[..., Placement]) -> dict[str, Any]:
    """fn's resolved parameter types (a partial: its function's); a hint that does not
    resolve is Any (not checked)."""
    base = fn.func if isinstance(fn, functools.partial) else fn
    try:
        return typing.get_type_hints(base)
    except Exception:  # noqa: BLE001 - resolve one by one below
        pass
    out: dict[str, Any] = {}
    ns = getattr(inspect.unwrap(base), "__globals__", {})
    for k, v in getattr(base, "__annotations__", {}).items():
        try:
            out[k] = eval(v, ns) if isinstance(v, str) else v  # noqa: S307 - the solver's own annotations
        except Exception:  # noqa: BLE001
            out[k] = Any
    return out


def options_type(fn: Callable[..., Placement], name: str) -> type[Options]:
    """The frozen options dataclass of ``fn``: :class:`Options` plus fn's own keyword
    options with fn's defaults and declared types (a mutable default such as a list is
    not allowed; the defaults must fit the types)."""
    own = _own_parameters(fn)
    hints = _hints(fn)
    cls_name = "".join(part.capitalize() for part in name.replace("_", "-").split("-")) + "Options"
    spec = [(p.name, hints.get(p.name, Any), field(default=p.default)) for p in own]
    cls = make_dataclass(cls_name, spec, bases=(Options,), frozen=True, namespace={"solver_name": name})
    try:
        cls()
    except InputError as err:
        raise TypeError(f"{name}: the default of option {err}") from None
    return cls


def make_solver(name: str, fn: Callable[..., Placement], tags: Tags = Tags(), summary: str = "") -> Solver:
    """A Solver whose options are fn's declared keywords (see :func:`options_type`)."""
    doc = (fn.__doc__ or "").strip().splitlines()
    return Solver(name, fn, options_type(fn, name), tags, summary or (doc[0] if doc else ""))


__all__ = ["COMMON_FIELDS", "HOOK_FIELDS", "Hooks", "Options", "Solver", "Tags", "make_solver", "options_type", "split_options"]
