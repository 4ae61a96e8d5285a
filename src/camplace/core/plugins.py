"""Plugins by the Python packaging convention: entry-point groups, read at first use.

A :class:`Registry` is a read-only mapping ``name -> object`` over one entry-point group
(``camplace.solvers``: each entry point loads a ``camplace.solvers.Solver``;
``camplace.engines``: each loads a visibility engine class). It reads the group the first
time it is used, loads every entry point and checks each object with the registry's
``check(name, obj)``; an entry point that fails to import, to load or to check is
reported once (a :class:`PluginWarning` naming it and its distribution) and skipped, so
one broken plugin never takes the others down. A plugin whose name is taken by an
earlier one (a built-in, or another plugin in distribution order) is skipped the same way.

camplace's own solvers and engines are entry points too, declared in its pyproject.toml.
When camplace runs from a source tree (pyproject.toml beside ``src/camplace``: an
editable install, or ``src`` on the path) the built-ins are read from that file, so a
source tree never disagrees with installed metadata written before its last change;
an installed camplace reads them from its metadata like any plugin.
"""

from __future__ import annotations

import importlib.metadata as md
import threading
import tomllib
import warnings
from collections.abc import MutableMapping
from pathlib import Path
from typing import Any, Callable, Iterator

OWN_DIST = "camplace"
SOURCE_PYPROJECT = Path(__file__).resolve().parents[3] / "pyproject.toml"


class PluginWarning(UserWarning):
    """A plugin (entry point) that could not be loaded or broke its contract; it was skipped."""


def source_entry_points(group: str, pyproject: Path = SOURCE_PYPROJECT) -> list[md.EntryPoint] | None:
    """camplace's entry points of ``group`` from the source tree's pyproject.toml (in the
    declared order), or None when camplace does not run from a source tree."""
    try:
        data = tomllib.loads(pyproject.read_text())
    except (OSError, tomllib.TOMLDecodeError):
        return None
    project = data.get("project", {})
    if project.get("name") != OWN_DIST:
        return None
    table = project.get("entry-points", {}).get(group, {})
    return [md.EntryPoint(name, value, group) for name, value in table.items()]


def _dist_name(ep: md.EntryPoint) -> str:
    dist = getattr(ep, "dist", None)
    return getattr(dist, "name", None) or "?"


def group_entry_points(group: str) -> list[tuple[md.EntryPoint, str]]:
    """(entry point, distribution name) of ``group``: camplace's own first (from the source
    tree when there is one, else from its metadata), then the others by distribution and name."""
    installed = [(ep, _dist_name(ep)) for ep in md.entry_points(group=group)]
    own_src = source_entry_points(group)
    own = ([(ep, OWN_DIST) for ep in own_src] if own_src is not None
           else [(ep, d) for ep, d in installed if d == OWN_DIST])
    others = sorted(((ep, d) for ep, d in installed if d != OWN_DIST), key=lambda x: (x[1], x[0].name))
    return own + others


class Registry(MutableMapping):
    """Name -> object of one entry-point group, loaded at first use (see the module doc).

    ``check(name, obj)`` returns the object to register or raises (TypeError, ValueError)
    with the reason; ``problems``: (name, distribution, reason) of every skipped entry point.
    ``registry[name] = obj`` registers one in this process only (checked the same way;
    e.g. a test's solver), ``del registry[name]`` removes it."""

    def __init__(self, group: str, check: Callable[[str, Any], Any]) -> None:
        self.group = group
        self._check = check
        self._items: dict[str, Any] | None = None
        self._dist: dict[str, str] = {}
        self._origin: dict[str, tuple[Any, str]] = {}  # name -> (object, distribution) as the entry point gave it
        self.problems: list[tuple[str, str, str]] = []
        self._lock = threading.RLock()
        self._loading = False

    def _load(self) -> dict[str, Any]:
        items = self._items
        if items is not None:
            return items
        with self._lock:
            if self._items is not None:
                return self._items
            if self._loading:
                raise RuntimeError(f"{self.group}: a plugin used the registry while it was being loaded")
            self._loading = True
            try:
                self._items = self._read()
            finally:
                self._loading = False
            return self._items

    def _read(self) -> dict[str, Any]:
        items: dict[str, Any] = {}
        self._dist, self._origin, self.problems = {}, {}, []
        for ep, dist in group_entry_points(self.group):
            if ep.name in items:
                self._skip(ep.name, dist, f"the name is taken by the one from {self._dist[ep.name]}")
                continue
            try:
                obj = self._check(ep.name, ep.load())
            except Exception as err:  # noqa: BLE001 - any failure of a plugin is reported and skipped
                self._skip(ep.name, dist, f"{type(err).__name__}: {err}")
                continue
            items[ep.name] = obj
            self._dist[ep.name] = dist
            self._origin[ep.name] = (obj, dist)
        return items

    def _skip(self, name: str, dist: str, why: str) -> None:
        self.problems.append((name, dist, why))
        warnings.warn(f"{self.group} plugin '{name}' (from {dist}) skipped: {why}", PluginWarning, stacklevel=4)

    def distribution(self, name: str) -> str:
        """The distribution that registered ``name`` (``camplace`` for a built-in)."""
        self._load()
        return self._dist[name]

    def reload(self) -> None:
        """Forget what was loaded: the next use reads the entry points again (after
        installing a plugin into a running interpreter)."""
        import importlib

        with self._lock:
            self._items = None
        importlib.invalidate_caches()

    def __getitem__(self, name: str) -> Any:
        return self._load()[name]

    def __setitem__(self, name: str, obj: Any) -> None:
        items = self._load()
        items[name] = self._check(name, obj)
        origin = self._origin.get(name)  # putting back the entry point's own object keeps its distribution
        self._dist[name] = origin[1] if origin is not None and origin[0] is obj else "(registered in this process)"

    def __delitem__(self, name: str) -> None:
        del self._load()[name]
        self._dist.pop(name, None)

    def __iter__(self) -> Iterator[str]:
        return iter(self._load())

    def __len__(self) -> int:
        return len(self._load())

    def __repr__(self) -> str:
        return f"Registry({self.group!r}: {', '.join(self._load())})"


__all__ = ["PluginWarning", "Registry", "group_entry_points", "source_entry_points"]
