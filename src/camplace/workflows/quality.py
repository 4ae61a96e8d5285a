"""The ``quality`` setting of a run (issue 37): ``"default"`` keeps the run as it is;
``"high"`` raycasts a denser candidate grid (``denser_candidates``: each mount's spacing
divided by QUALITY_DENSITY, as long as that stays within QUALITY_MAX_CANDIDATES poses) and
spends one time budget for the whole run (``quality_time_s``, 30 s by default, counted from
the start of ``run``) on the improvement chain of camplace.improve.quality after the discrete
solve, less what the stages before it took and a reserve for the metrics and the output files."""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Callable

from camplace.cameras.candidates import Candidates, build_candidates
from camplace.cameras.models import CameraModel
from camplace.core.errors import InputError
from camplace.improve.quality import high_quality
from camplace.problem.model import PlacementProblem
from camplace.scene.build import Scene
from camplace.solvers import Placement
from camplace.visibility.engine import Visibility

QUALITIES = ("default", "high")
QUALITY_TIME_S = 30.0  # the whole run's seconds with quality="high"
QUALITY_RESERVE_S = 10.0  # kept for the metrics and, on the command line, the output files and report (s)
QUALITY_DENSITY = 2  # quality="high": each mount's spacing divided by this (4x the ceiling positions)
QUALITY_MAX_CANDIDATES = 40_000  # ... unless the denser grid would hold more poses than this


def check_quality(quality: str, quality_time_s: float, *, refine: bool = False, adaptive: int = 0,
                  robust: int = 0) -> None:
    """InputError unless ``quality`` is one of QUALITIES and ``quality_time_s`` a positive
    number of seconds; "high" includes refinement and adaptive rounds, and cannot go with
    ``adaptive`` or ``robust`` (``refine`` is accepted: the chain refines anyway)."""
    if quality not in QUALITIES:
        raise InputError(f"quality: expected one of {', '.join(QUALITIES)}, got {quality!r}", option="quality")
    if not (isinstance(quality_time_s, (int, float)) and quality_time_s > 0 and quality_time_s < float("inf")):
        raise InputError(f"quality_time_s: expected a positive number of seconds, got {quality_time_s!r}",
                         option="quality_time_s")
    if quality == "high" and (adaptive or robust):
        raise InputError("quality: quality=high runs its own adaptive rounds and refinement; leave adaptive=0 "
                         "and robust=0", option="quality")


def denser_candidates(sc: Scene, cameras: dict[str, CameraModel], candidates: Candidates,
                      extra_pitches: tuple[float, ...] = (), density: int = QUALITY_DENSITY,
                      max_candidates: int = QUALITY_MAX_CANDIDATES) -> tuple[Scene, Candidates, str]:
    """(scene, candidates, log line) of a denser grid: every mount's ``spacing`` (m) divided by
    ``density``; the scene's spec carries the new spacing, so the refinement's boxes (half a
    spacing) shrink with it. The scene and ``candidates`` as they are when the denser grid would
    hold more than ``max_candidates`` poses (not even built past twice that, by density² times
    the scene's poses), and for a building (its storeys keep theirs)."""
    if density <= 1 or sc.storeys:
        return sc, candidates, ""
    kept = f"exceeds {max_candidates}; the scene's grid is kept"
    guess = len(candidates) * density ** 2  # ~the denser grid's poses
    if guess > 2 * max_candidates:  # a site: not even built
        return sc, candidates, f"quality high: a {density}x denser grid (~{guess} poses) {kept}"
    mounts = [m.model_copy(update={"spacing": m.spacing / density}) for m in sc.spec.mounts]
    dense_sc = replace(sc, spec=sc.spec.model_copy(update={"mounts": mounts}))
    dense = build_candidates(dense_sc, cameras, extra_pitches)
    if len(dense) > max_candidates:
        return sc, candidates, f"quality high: the {density}x denser grid ({len(dense)} poses) {kept}"
    return dense_sc, dense, (f"quality high: mount spacing / {density}: {len(dense)} poses "
                             f"({len(candidates)} on the scene's grid)")


def high_quality_stage(sc: Scene, vis: Visibility, problem: PlacementProblem, placement: Placement,
                       seconds_left: float, *, should_stop: Callable[[], bool] | None = None, progress=None,
                       log: list | None = None, guard=None,
                       row_map=None) -> tuple[Visibility, PlacementProblem, Placement]:
    """The chain of camplace.improve.quality.high_quality in ``seconds_left`` less
    QUALITY_RESERVE_S (at least 1 s); one log line per step."""
    budget = max(1.0, seconds_left - QUALITY_RESERVE_S)
    t = time.perf_counter()
    q = high_quality(sc, vis, problem, placement, budget, progress=progress, guard=guard, row_map=row_map,
                     should_stop=should_stop)
    if log is not None:
        steps = ", ".join(f"{h['step']} {h['cost']:.6g} ({h['seconds']:.1f} s)" for h in q.steps)
        log.append(f"quality high: cost {q.start_cost:.6g} -> {q.placement.objective:.6g} in "
                   f"{time.perf_counter() - t:.1f} s of {budget:.1f} s: {steps}")
    return q.visibility, q.problem, q.placement


__all__ = ["QUALITIES", "QUALITY_DENSITY", "QUALITY_MAX_CANDIDATES", "QUALITY_RESERVE_S", "QUALITY_TIME_S",
           "check_quality", "denser_candidates", "high_quality_stage"]


AUTO_REFINE_MAX_PAIRS = 200_000_000  # visible pairs of V above which refine="auto" leaves the refinement out


def refine_here(refine: bool | str, n_pairs: int, log: list[str]) -> bool:
    """run()'s ``refine`` as a yes or no: True / False as given; "auto" refines unless V holds
    more than AUTO_REFINE_MAX_PAIRS visible pairs ``n_pairs`` (site scale: each refined pose
    appends a row to V, a copy of it in memory), which a line in ``log`` says."""
    if refine not in (True, False, "auto"):
        raise InputError(f"refine: expected True, False or 'auto', got {refine!r}", option="refine")
    if refine != "auto":
        return bool(refine)
    if n_pairs <= AUTO_REFINE_MAX_PAIRS:
        return True
    log.append(f"refine: left out at this size (V holds {n_pairs:,} visible pairs, more than "
               f"{AUTO_REFINE_MAX_PAIRS:,}: the refinement would copy V); ask for it to run it")
    return False
