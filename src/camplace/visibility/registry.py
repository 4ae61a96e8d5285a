"""The visibility engines by name: ``ENGINES`` and ``get_engine(mode, **params)``.

``ENGINES`` is the entry-point group ``camplace.engines`` (camplace.core.plugins), read at
first use: the built-ins (voxel, pixel) are declared in camplace's pyproject.toml, another
package adds its own the same way; a broken one is reported (a PluginWarning) and skipped.
Every engine implements camplace.visibility.engine.VisibilityEngine; its parameters are
the fields of its dataclass. ``get_engine`` drops parameters given as None (= the
engine's default) and refuses one the engine does not take (InputError naming it and
the engines that do take it).
"""

from __future__ import annotations

import dataclasses
from typing import Any

from camplace.core.errors import InputError
from camplace.core.plugins import Registry
from camplace.visibility.engine import Visibility, VisibilityEngine

GROUP = "camplace.engines"
MEMBERS = ("cache_tag", "code_modules", "setup", "rows", "info")


def check_plugin(name: str, obj: Any) -> type:
    """``obj`` when it is an engine class (a dataclass with the VisibilityEngine members and a
    ``chunk_size`` field) whose ``mode`` is ``name``; else TypeError naming what is missing."""
    if not (isinstance(obj, type) and dataclasses.is_dataclass(obj)):
        raise TypeError(f"expected a dataclass implementing camplace.visibility.engine.VisibilityEngine, got {obj!r}")
    missing = [m for m in MEMBERS if not callable(getattr(obj, m, None))]
    if "chunk_size" not in {f.name for f in dataclasses.fields(obj)}:
        missing.append("chunk_size (a field)")
    if missing:
        raise TypeError(f"{obj.__name__} lacks {', '.join(missing)}")
    if getattr(obj, "mode", None) != name:
        raise TypeError(f"{obj.__name__}.mode is {getattr(obj, 'mode', None)!r}, the entry point {name!r}")
    return obj


ENGINES: Registry = Registry(GROUP, check_plugin)  # mode -> engine class, loaded at first use


def engine_params(mode: str) -> tuple[str, ...]:
    """The parameter names the engine ``mode`` takes."""
    return tuple(f.name for f in dataclasses.fields(ENGINES[mode]))


def get_engine(mode: str, **params: Any) -> VisibilityEngine:
    """The engine ``mode`` ('voxel', 'pixel') with ``params`` (None values = defaults)."""
    if mode not in ENGINES:
        raise InputError(f"visibility_mode: expected one of {', '.join(map(repr, ENGINES))}, got {mode!r}",
                         option="visibility_mode")
    given = {k: v for k, v in params.items() if v is not None}
    for k in given:
        if k not in engine_params(mode):
            takers = [m for m in ENGINES if k in engine_params(m)]
            who = f"engines that take it: {', '.join(takers)}" if takers else "no engine takes it"
            raise InputError(f"{k}: the {mode} engine takes no {k} ({who})", option=k)
    try:
        return ENGINES[mode](**given)
    except TypeError as err:  # a required parameter is missing
        raise InputError(f"visibility_mode {mode!r}: {err}", option="visibility_mode") from None


def engine_of(vis: Visibility) -> VisibilityEngine:
    """The engine (with its parameters) that computed ``vis``: ``vis.engine``, or the default
    engine of ``vis.mode`` for a Visibility made without one."""
    return vis.engine if vis.engine is not None else get_engine(vis.mode)


def catalogue() -> list[dict]:
    """Every registered engine as plain data: mode, summary (its docstring's first line),
    distribution ('camplace' for a built-in) and its parameters (name, type, default)."""
    out = []
    for mode, cls in ENGINES.items():
        params = [{"name": f.name, "type": f.type if isinstance(f.type, str) else getattr(f.type, "__name__", str(f.type)),
                   "default": None if f.default is dataclasses.MISSING else f.default}
                  for f in dataclasses.fields(cls)]
        doc = (cls.__doc__ or "").strip().splitlines()
        out.append({"name": mode, "summary": doc[0] if doc else "", "distribution": ENGINES.distribution(mode),
                    "parameters": params})
    return out
