"""Output files as plugins: entry points of the group ``camplace.outputs`` (issue 35).

An entry point loads a callable ``write(out_dir, result) -> list of paths`` (the files it
wrote, inside ``out_dir``). ``OUTPUTS`` (a camplace.core.plugins.Registry) holds them by
name, camplace's own first (declared in its pyproject.toml, e.g. ``bom``: bom.csv), then
other packages' in distribution order. Every command that writes outputs (run, demo,
evaluate, solve, storeys, the planner's save) calls them all through one function,
:func:`write_registered`, once the contract files are in place and before the report, so
report.html links what they wrote and the summary lists it.

``result`` is an :class:`OutputResult`: the dicts of placement.json and metrics.json as
written, and the richer objects of the run where the command has them (None where not:
``camplace solve`` has no scene and no candidates' geometry). A writer must not rely on
what a command does not give; it writes nothing (returns ``[]``) when it cannot.

A plugin that fails to load, or a writer that raises, is one ``PluginWarning`` naming it
(and its distribution); the other writers and the command go on. An error of camplace's
own writers is raised as any other error.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from camplace.core.plugins import OWN_DIST, PluginWarning, Registry

CONTRACT_FILES = ("placement.csv", "placement.json", "metrics.json", "visibility.npz")


@dataclass
class OutputResult:
    """What an output writer is given (``write(out_dir, result)``).

    ``placement``: the dict written to placement.json (docs/output-contract.md; poses in
    ``frame``); ``metrics``: the dict written to metrics.json; ``scene_name``: the scene's
    name; ``solution``: the camplace.solvers.Placement (``selected`` rows of V, ``info``);
    ``scores``: the camplace.metrics.coverage.Metrics; ``problem``: the PlacementProblem
    solved (None for an evaluated placement's problem only where the command has none);
    ``visibility``: the camplace.visibility.engine.Visibility (V, targets, candidates;
    None for ``camplace solve``); ``scene``: the built camplace.scene.build.Scene (None
    for ``solve``); ``arrays``: the arrays of visibility.npz as written; ``timings``:
    seconds per stage; ``frame``: 'scene' or 'input'; ``repeatable``: write nothing that
    changes between identical runs (no dates, no timings); ``written``: name -> path of
    the files written before the writers (the contract files). New fields may be added;
    none will be removed or renamed."""

    placement: dict
    metrics: dict
    scene_name: str
    solution: Any = None
    scores: Any = None
    problem: Any = None
    visibility: Any = None
    scene: Any = None
    arrays: dict | None = None
    timings: dict = field(default_factory=dict)
    frame: str = "scene"
    repeatable: bool = False
    written: dict = field(default_factory=dict)

    @property
    def V(self):
        """The CSR matrix of visibility.npz (N_g × N_p, rows = placement.json's ``candidate_id``)."""
        if self.visibility is not None:
            return self.visibility.V
        return None if self.problem is None else self.problem.V


def check_writer(name: str, obj: Any) -> Callable:
    """An output writer of the entry point ``name``: any callable (TypeError otherwise)."""
    if not callable(obj):
        raise TypeError(f"expected a callable write(out_dir, result), got {type(obj).__name__}")
    return obj


OUTPUTS = Registry("camplace.outputs", check_writer)


def _names(out: Path, name: str, got: Any) -> dict[str, Path]:
    """name (relative to ``out``, '/'-separated) -> path of what writer ``name`` returned."""
    if isinstance(got, (str, Path)) or not hasattr(got, "__iter__"):
        raise TypeError(f"expected a list of the paths it wrote, got {type(got).__name__}")
    paths = {}
    for p in got:
        p = Path(p)  # as the writer made it (out_dir / name: relative to the working folder), else in out_dir
        p = p if p.is_absolute() or p.exists() or not (out / p).exists() else out / p
        try:
            key = p.resolve().relative_to(out.resolve()).as_posix()
        except ValueError:
            raise ValueError(f"wrote {p} outside the output folder {out}") from None
        paths[key] = p
    return paths


def write_registered(out_dir: str | Path, result: OutputResult) -> dict[str, Path]:
    """Call every registered output writer (OUTPUTS, in order) -> name -> path of what they
    wrote. A plugin's writer that raises or returns something else than paths in
    ``out_dir`` is one PluginWarning naming it; camplace's own writers' errors are raised."""
    out = Path(out_dir)
    paths: dict[str, Path] = {}
    for name in list(OUTPUTS):
        writer, dist = OUTPUTS[name], OUTPUTS.distribution(name)
        try:
            paths.update(_names(out, name, writer(out, result)))
        except Exception as err:  # noqa: BLE001 - a plugin's failure is reported, the others go on
            if dist == OWN_DIST:
                raise
            warnings.warn(f"camplace.outputs plugin '{name}' (from {dist}) failed: {type(err).__name__}: {err}",
                          PluginWarning, stacklevel=2)
    return paths


def file_list(names) -> list[str]:
    """The files of an output folder to list or link, from the names written ('/'-separated,
    relative): the contract files first (in CONTRACT_FILES order), then the others sorted, a
    file in a subfolder as its folder ('opencv/'); report.html itself left out."""
    tops: list[str] = []
    for n in names:
        top = n.split("/")[0] + "/" if "/" in n else n
        if top not in tops and top != "report.html":
            tops.append(top)
    return [c for c in CONTRACT_FILES if c in tops] + sorted(t for t in tops if t not in CONTRACT_FILES)


__all__ = ["CONTRACT_FILES", "OUTPUTS", "OutputResult", "check_writer", "file_list", "write_registered"]
