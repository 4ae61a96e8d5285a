"""The visibility engines by name: ``ENGINES`` and ``get_engine(mode, **params)``.

Every engine implements camplace.visibility.engine.VisibilityEngine; its parameters are
the fields of its dataclass. ``get_engine`` drops parameters given as None (= the
engine's default) and refuses one the engine does not take (InputError naming it and
the engines that do take it).
"""

from __future__ import annotations

import dataclasses
from typing import Any

from camplace.core.errors import InputError
from camplace.visibility.engine import VisibilityEngine
from camplace.visibility.pixel import PixelEngine
from camplace.visibility.voxel import VoxelEngine

ENGINES: dict[str, type] = {"voxel": VoxelEngine, "pixel": PixelEngine}


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
