"""The whole pipeline as one call; the CLI and the Python API both use it.

scene -> targets -> candidates -> visibility -> problem -> solve -> metrics.
Progress goes through a callback ``progress(stage, done, total)``; nothing prints.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from camplace.spec.builtin import resolve_scene
from camplace.cameras.models import CameraModel, cameras_from_spec
from camplace.cameras.candidates import build_candidates
from camplace.problem.feasibility import check_feasibility
from camplace.spec.resources import check_resources
from camplace.spec.schema import SceneSpec
from camplace.core.errors import InputError, Interrupted
from camplace.metrics.coverage import Metrics, compute_metrics
from camplace.problem.model import PlacementProblem, with_type_limits
from camplace.workflows.building import building_visibility, storey_metrics, with_storey_limits
from camplace.workflows.solver_options import check_solver_name, check_solver_options, scene_solver_options
from camplace.scene.build import Scene, build_scene
from camplace.solvers import Placement, solve
from camplace.targets.build import Targets, build_targets
from camplace.core.executors import make_executor
from camplace.visibility.engine import Visibility, drop_blind_candidates
from camplace.visibility.registry import get_engine
from camplace.spec.crowd import crowd_with
from camplace.workflows.crowd import crowd_scores, crowd_stage
from camplace.workflows.quality import (QUALITY_DENSITY, QUALITY_TIME_S, check_quality, denser_candidates,
                                        high_quality_stage, refine_here)
from camplace.workflows.sites import Site, site_of

Progress = Callable[[str, int, int], None]


@dataclass
class RunResult:
    scene: Scene
    visibility: Visibility
    problem: PlacementProblem
    placement: Placement
    metrics: Metrics
    timings_s: dict[str, float] = field(default_factory=dict)
    log: list[str] = field(default_factory=list)


def _stage(progress: Progress | None, name: str) -> None:
    if progress:
        progress(name, 0, 1)


def prepare(scene: str | Path | SceneSpec, progress: Progress | None = None, timings: dict | None = None,
            log: list | None = None, **options) -> tuple[Scene, Visibility]:
    """Scene, targets, candidates and visibility (blind candidates dropped, privacy zones
    respected); the options of :func:`prepare_site`."""
    sc, vis, _ = prepare_site(scene, progress, timings, log, **options)
    return sc, vis


def prepare_site(scene: str | Path | SceneSpec, progress: Progress | None = None,
                 timings: dict | None = None, log: list | None = None, *,
                 should_stop: Callable[[], bool] | None = None, max_memory_bytes: int | None = None,
                 require_feasible: bool = False, workers: int = 1, scheduler: str | None = None,
                 cache_dir: str | Path | None = None, visibility_mode: str = "voxel", stride: int | None = None,
                 probe: float | None = None, keep: str | Path | None = None,
                 extra_pitches: tuple[float, ...] = (),
                 candidate_density: int = 1) -> tuple[Scene, Visibility, Site | None]:
    """Scene, targets, candidates and visibility (blind candidates dropped), and the site
    rules (camplace.workflows.sites: None without privacy zones, existing cameras or ``keep``,
    a previous run's placement file whose cameras stay): candidates that see a privacy
    zone or stand at an existing camera are removed before visibility; the existing
    cameras are raycast once.

    ``candidate_density``: > 1 divides every mount's spacing by it (quality="high",
    camplace.workflows.quality.denser_candidates).

    ``visibility_mode``: ``voxel`` (default, centre test per target) or ``pixel`` (the
    paper's per-pixel raycasting, camplace.visibility.pixel, one ray per ``stride`` x
    ``stride`` pixels, ``probe`` = part of the voxel a ray must cross).

    Visibility chunks run on a Dask cluster when ``scheduler`` (``tcp://host:port``, or
    env CAMPLACE_SCHEDULER) is given, on ``workers`` local processes when > 1, else
    in-process (camplace.core.executors); with ``cache_dir`` V is stored / reused in
    blocks under a content-hash key (camplace.visibility.cache). Same V bit for bit either way;
    both visibility modes.

    Refuses (InputError) a scene whose grids would exceed ``max_memory_bytes`` (default:
    camplace.core.memory.memory_limit_bytes()) before allocating them. Targets that cannot
    reach their coverage are a warning in ``log``, an InputError if ``require_feasible``.
    ``should_stop()`` polled between visibility chunks raises camplace.core.errors.Interrupted."""
    timings = {} if timings is None else timings
    log = [] if log is None else log
    if should_stop is not None:
        progress = _stoppable(progress, should_stop)
    sc, targets, cameras, source = scene_inputs(scene, progress, timings, max_memory_bytes)
    t = time.perf_counter()
    _stage(progress, "candidates")
    cands = build_candidates(sc, cameras, extra_pitches)  # extra: a crowd-aware run's steep views (issue 36)
    if candidate_density > 1:  # quality="high": a denser grid (camplace.workflows.quality)
        sc, cands, note = denser_candidates(sc, cameras, cands, extra_pitches, candidate_density)
        log.extend([note] if note else [])
    timings["candidates"] = time.perf_counter() - t
    t = time.perf_counter()
    engine = get_engine(visibility_mode, stride=stride, probe=probe)
    site = site_of(sc, cameras, engine, keep)
    with make_executor(workers, scheduler) as executor:
        if site is not None:  # privacy zones, existing cameras (camplace.workflows.sites)
            cands = site.admit(cands, executor, cache_dir)
        vis = building_visibility(engine, sc, targets, cands, executor=executor, cache_dir=cache_dir,
                                  progress=progress)  # one call for a single room (camplace.workflows.building)
        if site is not None:
            site.raycast(engine, sc, targets, executor, cache_dir)
    vis = drop_blind_candidates(vis)
    timings["visibility"] = time.perf_counter() - t
    if sc.info.get("obstacle_files"):  # scans, meshes, OctoMaps: what was read and each clean-up step
        from camplace.scene.loaders.obstacles import describe

        log.extend(describe(name, rep) for name, rep in sc.info["obstacle_files"].items())
        if sc.info.get("free_space"):
            from camplace.scene.from_scan import describe_free_space

            log.append(describe_free_space(sc.info["free_space"]))
    if "mount_positions_ruled_out" in cands.info:
        log.append(f"mount rules: {cands.info['mount_positions_ruled_out']} mount positions outside the allowed area"
                   + (f"; {cands.info['explicit_points']} explicit mount points" if cands.info['explicit_points']
                      else ""))
    log.extend(site.log if site is not None else [])
    log.append(f"candidates: {cands.info['generated']} generated, {cands.info['dropped_inside_obstacle']} inside "
               f"obstacles, {cands.info.get('dropped_clearance', 0)} within the {cands.info.get('clearance_m', 0):g} m "
               f"clearance, {vis.info['dropped_blind']} seeing no target, {len(vis.candidates)} kept")
    log.append(f"targets: {len(targets)} ({', '.join(f'{n}: {int((targets.region_ids == r).sum())}' for r, n in enumerate(targets.region_names))})")
    log.append(f"visibility: V {vis.V.shape[0]} x {vis.V.shape[1]}, nnz {vis.V.nnz}")
    if vis.info.get("executor") != "in-process" or "cache" in vis.info:
        log.append(f"visibility: {vis.info['chunks']} chunks on {vis.info.get('executor')}, "
                   f"{vis.info.get('cached_chunks', 0)} from cache {vis.info.get('cache', '(off)')}")
    if vis.V.shape[0] == 0:
        raise InputError(f"{source}: mounts: no candidate pose sees any target ({cands.info['generated']} "
                         f"generated, {len(cands)} in free space); check mounts, cameras (max_range, fov_deg) "
                         f"and targets")
    tg = vis.targets
    _stage(progress, "feasibility")
    feas = check_feasibility(vis.V, tg.gamma, vis.candidates.location_ids, tg.region_ids, tg.region_names)
    if not feas.ok:
        msg = feas.describe(tg.positions, tg.region_ids, tg.region_names)
        if require_feasible:
            raise InputError(f"{source}: targets: {msg} (require_feasible)", option="require_feasible")
        log.append(f"warning: {msg}")
    return sc, vis, site


def scene_inputs(scene: str | Path | SceneSpec, progress: Progress | None = None, timings: dict | None = None,
                 max_memory_bytes: int | None = None) -> tuple[Scene, Targets, dict[str, CameraModel], str]:
    """The stages before candidates: the scene (occupancy), its targets, its camera
    models by name and the scene's source label (for messages); shared by ``prepare``
    and camplace.workflows.evaluate."""
    timings = {} if timings is None else timings
    spec, base_dir, source = resolve_scene(scene)
    check_resources(spec, source, max_memory_bytes)
    t = time.perf_counter()
    _stage(progress, "scene")
    sc = build_scene(spec, base_dir, source, progress=progress)
    if source.startswith("<built-in "):  # as given ('warehouse:1000'): placement.json's builtin_scene
        sc.info["builtin"] = source[len("<built-in "):-1]
    timings["scene"] = time.perf_counter() - t
    t = time.perf_counter()
    _stage(progress, "targets")
    targets = build_targets(sc)
    timings["targets"] = time.perf_counter() - t
    cameras: dict[str, CameraModel] = cameras_from_spec(spec, base_dir)
    return sc, targets, cameras, source


def _stoppable(progress: Progress | None, should_stop: Callable[[], bool]) -> Progress:
    """A progress callback that raises Interrupted between visibility chunks once should_stop() is true."""
    def cb(stage: str, done: int, total: int) -> None:
        if progress:
            progress(stage, done, total)
        if stage == "visibility" and should_stop():
            raise Interrupted(f"stopped during visibility ({done}/{total} chunks done); nothing written")
    return cb


STOP_GRACE_S = 1.0  # seconds a solver gets to honour should_stop() before the pipeline stops waiting


def solve_stoppable(problem: PlacementProblem, solver: str, *, log: list | None = None,
                    grace_s: float = STOP_GRACE_S, **options) -> Placement:
    """``solve(problem, solver, **options)`` that always comes back soon after
    ``options['should_stop']()`` turns true.

    The solver runs in a worker thread (HiGHS and numba release the GIL); this thread
    polls should_stop(). Every built-in solver returns its best placement and bound
    within ``grace_s`` of the request. One that does not (a solver stuck in a phase that
    polls nothing) is left behind, or at once when ``should_stop.hurry()`` (an optional
    method: the user asked twice) turns true: the greedy placement is returned instead
    (1 s at most), with status 'interrupted' and the best lower bound the solver reported
    through on_incumbent (or None)."""
    import threading

    should_stop = options.get("should_stop")
    if should_stop is None:
        return solve(problem, solver, **options)
    hurry = getattr(should_stop, "hurry", lambda: False)
    bound: dict[str, float | None] = {"bound": None}
    user_cb = options.get("on_incumbent")

    def on_incumbent(objective: float, b: float | None) -> None:
        if b is not None and np.isfinite(b):
            bound["bound"] = b if bound["bound"] is None else max(bound["bound"], b)
        if user_cb is not None:
            user_cb(objective, b)

    options["on_incumbent"] = on_incumbent
    out: dict = {}

    def work() -> None:
        try:
            out["placement"] = solve(problem, solver, **options)
        except BaseException as err:  # noqa: BLE001 - handed to the calling thread
            out["error"] = err

    th = threading.Thread(target=work, name=f"camplace-solve-{solver}", daemon=True)
    th.start()
    asked = None
    while th.is_alive():
        th.join(0.05)
        if asked is None and should_stop():
            asked = time.perf_counter()
        if asked is not None and (time.perf_counter() - asked > grace_s or hurry()):
            break
    if "error" in out:
        raise out["error"]
    if "placement" in out:
        return out["placement"]
    fallback_opts = {k: options[k] for k in ("threads", "seed") if k in options}  # the common options only
    g = solve(problem, "greedy", time_limit_s=1.0, warm=False, **fallback_opts)
    b = bound["bound"]
    if b is not None and b > g.objective:  # cannot happen for a valid bound; never report one above the cost
        b = None
    if log is not None:
        log.append(f"warning: solver '{solver}' did not stop within {grace_s:g} s of the interrupt (inside a phase "
                   f"that polls nothing); wrote the greedy placement instead")
    info = dict(g.info, interrupted_solver=solver, fallback="greedy")
    return replace(g, status="interrupted", bound=b, solver=solver, info=info)


def problem_from_visibility(vis: Visibility, budget: int, money_budget: float | None = None) -> PlacementProblem:
    """The placement problem of a visibility result, with candidate and target positions
    (m) for the solvers that need geometry (tag needs_positions)."""
    t = vis.targets
    return PlacementProblem(vis.V, t.gamma, t.weights, int(budget), vis.candidates.location_ids,
                            np.array([vis.candidates.cameras[c].cost for c in vis.candidates.camera_ids]),
                            money_budget, candidate_positions=np.asarray(vis.candidates.positions, np.float64),
                            target_positions=np.asarray(t.positions, np.float64))


def improve_placement(sc: Scene, vis: Visibility, problem: PlacementProblem, placement: Placement, *,
                      refine: bool = False, refine_time_s: float = 60.0, adaptive: int = 0, robust: int = 0,
                      time_limit_s: float | None = None, should_stop: Callable[[], bool] | None = None,
                      progress: Progress | None = None, log: list | None = None,
                      guard=None, timings: dict | None = None,
                      row_map=None, pose_score=None) -> tuple[Visibility, PlacementProblem, Placement]:
    """Beyond the grid (issue 10), after the discrete solve: ``robust`` = 1 minimises the
    worst case over single camera failures (camplace.solvers.robust: swap/tabu heuristic, then the
    scenario MIP, exact on small V, as a large-neighbourhood search on large V); ``adaptive`` rounds of
    finer candidates (camplace.improve.adaptive), then ``refine`` moves each camera off the grid
    (camplace.improve.refine). Adaptive and refine append rows to V, so the returned visibility /
    problem replace the grid ones (the placement stays a selection of V rows). time_limit_s
    caps the robust search (default 60 s) and the adaptive rounds (default 120 s). ``guard``
    (camplace.improve.refine.PoseGuard, e.g. the privacy guard) rejects new poses; ``row_map``
    (camplace.improve.refine.RowMap) turns their raycast rows into the problem's; ``pose_score``
    scores the refinement's trial poses (camplace.improve.refine.refine_poses). Each
    step's wall-clock seconds go to ``timings`` (``robust``, ``adaptive``, ``refine``): they
    are metrics.json figures, never placement.json ones."""
    log = [] if log is None else log
    timings = {} if timings is None else timings
    if robust not in (0, 1):
        raise InputError(f"robust: expected 0 or 1 (single camera failures), got {robust}", option="robust")
    if robust and (refine or adaptive):
        raise InputError("robust: robust=1 cannot be combined with refine=True or adaptive > 0 (they optimise the "
                         "nominal cost)", option="robust")
    if adaptive < 0:
        raise InputError(f"adaptive: expected a non-negative number of rounds, got {adaptive}", option="adaptive")
    if robust:  # the registered solver 'robust' from the nominal placement (stop hook, time limit)
        from camplace.solvers.robust_solver import describe_robust

        t = time.perf_counter()
        nominal = placement
        placement = solve_stoppable(problem, "robust", log=log, nominal=nominal, time_limit_s=time_limit_s or 60.0,
                                    should_stop=should_stop)
        placement = replace(placement, solver=f"{nominal.solver}+robust1")
        timings["robust"] = time.perf_counter() - t
        if "robust" in placement.info:
            log.append(describe_robust(placement.info["robust"]))
    if adaptive:
        from camplace.improve.adaptive import adaptive_rounds

        t = time.perf_counter()
        ar = adaptive_rounds(sc, vis, problem, placement, rounds=adaptive, time_limit_s=time_limit_s or 120.0,
                             progress=progress, guard=guard, row_map=row_map, should_stop=should_stop)
        vis, problem, placement = ar.visibility, ar.problem, ar.placement
        timings["adaptive"] = time.perf_counter() - t
        for h in ar.rounds:
            log.append(f"adaptive round {h['round']}: {h['candidates']} candidates, cost {h['cost']:.6g}")
    if refine:
        from camplace.improve.refine import refine_placement

        t = time.perf_counter()
        rf = refine_placement(sc, vis, problem, placement, time_limit_s=refine_time_s, progress=progress,
                              guard=guard, row_map=row_map, should_stop=should_stop, pose_score=pose_score)
        vis, problem, placement = rf.visibility, rf.problem, rf.placement
        timings["refine"] = time.perf_counter() - t
        log.append(f"refine: cost {rf.grid_cost:.6g} -> {rf.refined_cost:.6g} ({rf.info['moved']} cameras moved, "
                   f"{rf.info['trials']} trial poses, {rf.info['seconds']:.1f} s)")
    return vis, problem, placement


def run(scene: str | Path | SceneSpec, budget: int | None = None, solver: str | None = None,
        progress: Progress | None = None, *, time_limit_s: float | None = None,
        should_stop: Callable[[], bool] | None = None, max_memory_bytes: int | None = None,
        require_feasible: bool = False, workers: int = 1, scheduler: str | None = None,
        cache_dir: str | Path | None = None, visibility_mode: str = "voxel", stride: int | None = None,
        probe: float | None = None, money_budget: float | None = None, refine: bool | str = False,
        refine_time_s: float = 60.0, adaptive: int = 0, robust: int = 0, quality: str | None = None,
        quality_time_s: float = QUALITY_TIME_S,
        triangulation_deg: tuple[float, float] = (20.0, 160.0), well_triangulated: bool = False,
        keep: str | Path | None = None, crowd: dict | None = None, options: dict | None = None,
        **solver_options) -> RunResult:
    """Run every stage on a scene (built-in name, YAML path or spec).

    budget / solver / time_limit_s default to the scene's ``placement`` keys. The solver
    name and budget are checked before any heavy stage. ``should_stop()`` is polled
    between visibility chunks (Interrupted) and by the solver, which then returns its
    best placement with status 'interrupted'. ``keep``: a previous run's placement.json / .csv
    whose cameras stay as existing ones (camplace.workflows.sites; the budget counts new
    cameras). ``crowd``: overrides of the scene's ``crowd:`` keys (camplace.spec.crowd.CROWD_OPTIONS;
    camplace.workflows.crowd: metrics in held-out crowds, and with ``optimise`` the crowd-aware
    problem). ``options``: solver options as a mapping (e.g. the command line's), over the
    scene's ``placement.options``; keyword solver options win over both. ``refine``: True,
    False or "auto" (refine unless V is site-scale: camplace.workflows.quality.refine_here).
    See ``prepare_site`` for the other options."""
    t_run = time.perf_counter()
    timings: dict[str, float] = {}
    log: list[str] = []
    spec, _, source = resolve_scene(scene)
    quality = spec.placement.quality if quality is None else quality
    check_quality(quality, quality_time_s, refine=refine, adaptive=adaptive, robust=robust)
    crowd_spec = crowd_with(spec.crowd, crowd)
    if spec.storeys and crowd_spec is not None and crowd_spec.density:  # crowds are sampled on one floor
        raise InputError(f"{source}: crowd: not available for a building yet; plan one storey at a time for crowds",
                         option="crowd_density")
    if solver is None:
        check_solver_name(spec.placement.solver, f"{source}: placement.solver")
    else:
        check_solver_name(solver, "solver")
    run_solver = "greedy-triangulated" if well_triangulated else solver or spec.placement.solver
    solver_options = {**scene_solver_options(spec, run_solver, source, log), **(options or {}), **solver_options}
    given = check_solver_options(run_solver, solver_options, triangulation_deg)
    if given:
        log.append(f"solver {run_solver}: {given}")
    if budget is not None and (isinstance(budget, bool) or int(budget) != budget or budget < 0):
        raise InputError(f"budget: expected a non-negative integer, got {budget!r}")
    if time_limit_s is not None and not (time_limit_s > 0 and np.isfinite(time_limit_s)):
        raise InputError(f"time limit: expected a positive number of seconds, got {time_limit_s!r}")
    sc, vis, site = prepare_site(scene, progress, timings, log, should_stop=should_stop,
                                 max_memory_bytes=max_memory_bytes, require_feasible=require_feasible, workers=workers,
                                 scheduler=scheduler, cache_dir=cache_dir, visibility_mode=visibility_mode,
                                 stride=stride, probe=probe, keep=keep,
                                 extra_pitches=() if crowd_spec is None else crowd_spec.offers_steep(),
                                 candidate_density=QUALITY_DENSITY if quality == "high" else 1)
    budget = sc.spec.placement.budget if budget is None else budget
    solver = sc.spec.placement.solver if solver is None else solver
    solver_options.setdefault("time_limit_s", sc.spec.placement.time_limit_s if time_limit_s is None else time_limit_s)
    if should_stop is not None:
        solver_options.setdefault("should_stop", should_stop)
    if progress is not None:
        solver_options.setdefault("progress", progress)  # solver stages (greedy, tabu, mip, ...) as bars
    if solver == "zones" and not well_triangulated:  # the tiles run where V ran; sweeps resume from the cache
        _zones_defaults(solver_options, workers, scheduler, cache_dir)
    money = sc.spec.placement.money_budget if money_budget is None else money_budget
    if money is not None and not (money >= 0 and np.isfinite(money)):
        raise InputError(f"money budget: expected a non-negative number, got {money!r}")
    problem = problem_from_visibility(vis, budget, money)
    problem = with_type_limits(problem, vis.candidates.camera_ids, [c.name for c in vis.candidates.cameras],
                               sc.spec.mount_rules.max_per_type)  # new cameras per type (mount_rules)
    problem = with_storey_limits(problem, sc, vis.candidates.positions)  # a building's per-storey budgets
    cp = crowd_stage(sc, vis, problem, crowd_spec, site, workers=workers, scheduler=scheduler, progress=progress,
                     log=log, timings=timings, should_stop=should_stop)  # crowd-aware: the sample-average problem
    if site is not None:  # Γ' = max(Γ - existing coverage, 0): the solvers see what remains
        problem = site.solver_problem(problem)
    solving = problem if cp is None else cp.problem
    t = time.perf_counter()
    _stage(progress, "solve")
    if well_triangulated:  # the greedy with the triangulation requirement (positions come with the problem)
        min_deg, max_deg = triangulation_deg
        placement = solve_stoppable(solving, "greedy-triangulated", log=log, min_deg=min_deg, max_deg=max_deg,
                                    **solver_options)
        log.append(f"greedy-triangulated: triangulation-aware cost {placement.info['triangulated_cost']:.6g}")
    else:
        placement = solve_stoppable(solving, solver, log=log, **solver_options)
    if cp is not None:  # people_cost count: a swap descent that counts the people seen by ≥ Γ^p
        placement = cp.count_step(solving, placement, should_stop=should_stop, log=log)
    timings["solve"] = time.perf_counter() - t
    grid_selected = placement.selected
    stopped = should_stop is not None and should_stop()
    refine = refine_here(refine, vis.V.nnz, log)
    if (refine or adaptive or robust or quality == "high") and stopped:  # interrupted: keep the solver's best
        log.append("beyond the grid: skipped (interrupted)")
    elif quality == "high":  # one time budget for the whole run (camplace.improve.quality)
        t = time.perf_counter()
        vis, solving, placement = high_quality_stage(
            sc, vis, solving, placement, quality_time_s - (t - t_run), should_stop=should_stop, progress=progress,
            log=log, guard=None if site is None else site.guard, row_map=None if cp is None else cp.row_map)
        timings["beyond_grid"] = time.perf_counter() - t
    elif refine or adaptive or robust:
        t = time.perf_counter()
        vis, solving, placement = improve_placement(
            sc, vis, solving, placement, refine=refine, refine_time_s=refine_time_s, adaptive=adaptive,
            robust=robust, should_stop=should_stop, progress=progress, log=log,
            guard=None if site is None else site.guard, timings=timings, row_map=None if cp is None else cp.row_map,
            pose_score=None if cp is None else cp.pose_score(solving))
        timings["beyond_grid"] = time.perf_counter() - t
    if cp is not None and vis.V.shape[0] > problem.n_candidates:  # count again among the new poses too
        placement = cp.count_step(solving, placement, should_stop=should_stop, log=log)
    if cp is not None and cp.stacked:  # back to the empty-store problem (the contract's cost); crowd cost in info
        problem, placement = cp.nominal(vis, problem, placement, grid_selected)
    else:
        problem = solving
    t = time.perf_counter()
    _stage(progress, "metrics")
    if site is not None:  # existing cameras join V and the selection, with the full Γ
        vis, problem, placement = site.fold(vis, problem, placement)
    metrics = placement_metrics(vis, problem, placement.selected, triangulation_deg, sc)
    if site is not None:
        metrics = site.report(vis, placement, metrics)
    metrics = replace(metrics, grid_cost=grid_cost(placement),
                      crowd=crowd_scores(sc, vis, placement, crowd_spec, cp, log, should_stop))  # held-out
    timings["metrics"] = time.perf_counter() - t
    return RunResult(sc, vis, problem, placement, metrics, timings, log)


def _zones_defaults(options: dict, workers: int, scheduler: str | None, cache_dir: str | Path | None) -> None:
    """The zone solver's executor and checkpoint from the run's: its tiles on the same
    Dask scheduler (or ``CAMPLACE_SCHEDULER``) or ``workers`` processes as the visibility
    blocks, and its per-sweep checkpoints under ``cache_dir``/zones (so an interrupted run
    resumes from the cached V blocks and from the last finished sweep)."""
    import os

    from camplace.core.executors import SCHEDULER_ENV

    options.setdefault("workers", workers)
    options.setdefault("scheduler", scheduler or os.environ.get(SCHEDULER_ENV) or None)
    if cache_dir is not None:
        options.setdefault("checkpoint", str(Path(cache_dir).expanduser() / "zones"))


def grid_cost(placement: Placement) -> float | None:
    """The cost of a run's placement before it left the candidate grid (before adaptive
    rounds and refine; existing cameras included); None when it never left it."""
    for step in ("quality", "adaptive", "refine"):
        if isinstance(placement.info.get(step), dict) and "grid_cost" in placement.info[step]:
            return float(placement.info[step]["grid_cost"])
    return None


def placement_metrics(vis: Visibility, problem: PlacementProblem, selected: np.ndarray,
                      triangulation_deg: tuple[float, float] = (20.0, 160.0), scene: Scene | None = None) -> Metrics:
    """Every metric of a selection (rows of vis.V), per region too (and per storey of a
    building ``scene``); shared by ``run`` and camplace.workflows.evaluate so both score a
    placement the same way."""
    from camplace.metrics.triangulation import well_triangulated_of_selection

    well = well_triangulated_of_selection(vis.V, vis.candidates.positions, vis.targets.positions,
                                          selected, *triangulation_deg)
    m = compute_metrics(problem, selected, vis.targets.region_ids, vis.targets.region_names,
                        well_triangulated=well)
    if scene is not None and scene.storeys:
        sel = np.asarray(selected, np.int64)
        m = replace(m, storeys=storey_metrics(scene, problem, sel, vis.candidates.positions[sel],
                                              vis.targets.positions))
    return m
