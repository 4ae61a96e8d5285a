"""Wording of scene-file errors: pydantic's errors -> one line naming the key path and
what was expected, with "did you mean" hints for near-miss names."""

from __future__ import annotations

import difflib
import functools
import math
import re
import typing
from typing import Any

from pydantic import BaseModel, ValidationError

UNION_TAGS = ("range", "list", "value")  # the tags of schema.Angles: noise in a key path


def name_list(names: list[str]) -> str:
    """``'a', 'b', ...`` (at most 8 names), or ``(none defined)``."""
    return ", ".join(f"'{n}'" for n in names[:8]) + (", ..." if len(names) > 8 else "") if names else "(none defined)"


def did_you_mean(word: str, choices: list[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest of ``choices``, or an empty string."""
    close = difflib.get_close_matches(word, choices, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def _loc_to_path(loc: tuple[Any, ...], model: type[BaseModel] | None = None) -> str:
    """pydantic's error location -> ``mounts[0].yaw_deg.step`` (union tags and the branch
    names of ``model``'s unions dropped)."""
    names = _model_names(model) if model is not None else frozenset()
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif part in UNION_TAGS or _is_branch_name(str(part), names):
            continue  # union branch names are noise for the user
        else:
            out += ("." if out else "") + str(part)
    return out


def _is_branch_name(part: str, model_names: frozenset[str]) -> bool:
    """pydantic names the branch of an untagged union by its type ('float', 'list[...]', 'Box', ...)."""
    return part in ("float", "int", "str", "bool", "constrained-float", "constrained-int", "constrained-str") or (
        part.endswith("]") and "[" in part) or part.startswith("function-") or (
        part[:1].isupper() and part in model_names)


@functools.lru_cache(maxsize=None)
def _model_names(model: type[BaseModel]) -> frozenset[str]:
    """Names of every pydantic model reachable from ``model``'s fields (``model`` included)."""
    seen: set[type[BaseModel]] = set()
    todo: list[type[BaseModel]] = [model]
    while todo:
        m = todo.pop()
        if m not in seen:
            seen.add(m)
            for f in m.model_fields.values():
                todo += _models_in(f.annotation)
    return frozenset(m.__name__ for m in seen)


def _models_in(tp: Any) -> list[type[BaseModel]]:
    """Every pydantic model a type annotation may hold (through Annotated, Union, list, tuple, dict)."""
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return [tp]
    if typing.get_origin(tp) is typing.Annotated:
        return _models_in(typing.get_args(tp)[0])
    out: list[type[BaseModel]] = []
    for a in typing.get_args(tp) or ():
        for m in _models_in(a):
            if m not in out:
                out.append(m)
    return out


def _fields_of(model: type[BaseModel], loc: tuple[Any, ...]) -> list[str]:
    """Field names valid at the parent of ``loc`` (for 'did you mean')."""
    cur = [model]
    for part in loc[:-1]:
        if isinstance(part, int) or part in UNION_TAGS:
            continue
        nxt: list[type[BaseModel]] = []
        for m in cur:
            f = m.model_fields.get(str(part))
            if f is not None:
                nxt += [x for x in _models_in(f.annotation) if x not in nxt]
        if not nxt:
            if any(m.__name__ == part for m in cur):  # union branch named by its model
                continue
            return []
        cur = nxt
    names: list[str] = []
    for m in cur:
        names += [k for k in m.model_fields if k not in names]
    return names


_ERROR_ORDER = {"extra_forbidden": 0}  # a mistyped key also shows up as a missing one: name the typo


def format_error_entry(e: dict, model: type[BaseModel] | None = None, missing: tuple[str, ...] = ()) -> tuple[str, str]:
    """One pydantic error -> (key path, message); ``missing``: required keys missing beside it."""
    loc = tuple(e["loc"])
    path = _loc_to_path(loc, model)
    msg = e["msg"]
    t = e["type"]
    ctx = e.get("ctx") or {}
    if t == "scene":
        sub = ctx.get("path", "")
        path = (path + ("." if path and not sub.startswith("[") else "") + sub) if sub else path
        return path, ctx.get("message", msg)
    if t == "extra_forbidden":
        key = str(loc[-1])
        hint = did_you_mean(key, list(missing)) or (did_you_mean(key, _fields_of(model, loc)) if model else "")
        return path, f"unknown key '{key}'{hint}"
    if t == "missing":
        return path, "required key is missing"
    if msg.startswith("Value error, "):
        msg = msg[len("Value error, "):]
    msg = re.sub(r"^Input should be ", "expected ", msg)
    msg = re.sub(r"^Input should have ", "expected ", msg)
    inp = e.get("input")
    if isinstance(inp, float) and not math.isfinite(inp):
        msg = "expected a finite number"
    if t == "literal_error" and isinstance(inp, str):
        msg += did_you_mean(inp, re.findall(r"'([^']*)'", str(ctx.get("expected", ""))))
    if "input" in e and not isinstance(inp, (dict, list, tuple, BaseModel)):
        r = repr(inp)
        msg += f" (got {r if len(r) <= 60 else r[:57] + '...'})"
    return path, msg


def format_validation_error(err: ValidationError, source: str, model: type[BaseModel] | None = None) -> str:
    """One line: ``source: key.path: what is wrong`` (the first error; count of the rest)."""
    errors = sorted(err.errors(), key=lambda e: _ERROR_ORDER.get(e["type"], 1))
    first = errors[0]
    missing = tuple(str(e["loc"][-1]) for e in errors
                    if e["type"] == "missing" and tuple(e["loc"][:-1]) == tuple(first["loc"][:-1]))
    path, msg = format_error_entry(first, model, missing)
    more = len(errors) - 1
    tail = f" (and {more} more error{'s' if more > 1 else ''})" if more else ""
    return f"{source}: {path or '<top>'}: {msg}{tail}".replace("\n", " ")
