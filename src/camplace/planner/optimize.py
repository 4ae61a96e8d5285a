"""Optimise the rest: the locked cameras stay (as the site's existing cameras,
camplace.workflows.sites.Site: the solvers see Γ' = max(Γ − c_locked, 0)), the chosen
solver fills ``budget − locked`` from the grid candidates within a time limit, in a
background thread. Progress and incumbents (camplace.solvers.contract.Hooks) are kept as
events for the page's event stream; cancel sets should_stop, and the solver's best
placement so far is kept (camplace.workflows.run.solve_stoppable)."""

from __future__ import annotations

import itertools
import threading
import time
from dataclasses import dataclass, field, replace

import numpy as np

from camplace.planner.errors import ApiError
from camplace.planner.scoring import rows_matrix
from camplace.visibility.engine import Visibility

PROGRESS_EVERY_S = 0.05  # at most one progress event per stage this often (the last one always)
_ids = itertools.count(1)


@dataclass
class Job:
    """One optimisation: ``events`` [(name, data)] in order ('progress', then 'done' or
    'error'); ``stop`` asks the solver to stop; ``finished`` once the last event is in."""

    id: str
    solver: str
    events: list = field(default_factory=list)
    stop: threading.Event = field(default_factory=threading.Event)
    finished: bool = False
    thread: threading.Thread | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)

    def emit(self, name: str, data: dict, last: bool = False) -> None:
        with self.lock:
            self.events.append((name, data))
            self.finished = self.finished or last

    def since(self, k: int) -> tuple[list, bool]:
        """The events from index k and whether the job has finished."""
        with self.lock:
            return list(self.events[k:]), self.finished


def locked_site(session):
    """(Site of the locked cameras, grid Visibility without the grid poses at their
    positions): the locked cameras as existing ones, their rows already raycast."""
    from camplace.workflows.sites import Site

    locked = [c for c in session.cams if c.locked]
    grid = session.vis
    if not locked:
        return None, grid
    cands = session._candidates(np.array([c.position for c in locked]), np.array([c.angles for c in locked]),
                                [c.lens for c in locked])
    V = rows_matrix([c.row for c in locked], len(session.targets))
    site = Site(None, cands, tuple(c.id for c in locked), V)
    numbered = replace(grid.candidates, location_ids=np.arange(len(grid.candidates), dtype=np.int64))
    keep = site.admit(numbered).location_ids  # Site's rule: no new camera at a locked camera's position
    if len(keep) < len(grid.candidates):
        grid = Visibility(grid.V[keep], grid.candidates.subset(keep), grid.targets, grid.mode, dict(grid.info),
                          grid.engine)
    return site, grid


def solver_problem(session, site, grid: Visibility, budget: int):
    """The problem the solver sees: the grid, ``budget`` new cameras, the scene's type limits
    and money budget, Γ reduced by the locked cameras' coverage."""
    from camplace.problem.model import with_type_limits
    from camplace.workflows.run import problem_from_visibility

    spec = session.scene.spec
    money = spec.placement.money_budget
    if money is not None and site is not None:
        money = max(money - float(sum(site.existing.cameras[k].cost for k in site.existing.camera_ids)), 0.0)
    problem = problem_from_visibility(grid, budget, money)
    problem = with_type_limits(problem, grid.candidates.camera_ids, [c.name for c in grid.candidates.cameras],
                               spec.mount_rules.max_per_type)
    return problem if site is None else site.solver_problem(problem)


def start(session, request: dict) -> Job:
    """POST /api/optimize (request from camplace.planner.bodies.optimize_request) -> the running Job."""
    with session.lock:
        session._idle()
        n_locked = sum(c.locked for c in session.cams)
        if request["budget"] < n_locked:
            raise ApiError(f"budget: {request['budget']} is below the {n_locked} locked cameras (the budget counts "
                           f"them)", "budget")
        job = Job(f"job{next(_ids)}", request["solver"])
        session.busy = job.id
        session.job = job
        site, grid = locked_site(session)
    job.thread = threading.Thread(target=_work, args=(session, job, site, grid, request), daemon=True,
                                  name=f"camplace-planner-{job.id}")
    job.thread.start()
    return job


def _work(session, job: Job, site, grid: Visibility, request: dict) -> None:
    from camplace.workflows.run import solve_stoppable

    t0 = time.perf_counter()
    best = {"objective": None, "bound": None}
    last = {"stage": None, "t": 0.0}

    def progress(stage: str, done: int, total: int) -> None:
        now = time.perf_counter()
        if stage == last["stage"] and done < total and now - last["t"] < PROGRESS_EVERY_S:
            return
        last.update(stage=stage, t=now)
        job.emit("progress", {"stage": stage, "done": int(done), "total": int(total), **best})

    def on_incumbent(objective: float, bound) -> None:
        best["objective"] = float(objective)
        if bound is not None and np.isfinite(bound):
            best["bound"] = float(bound)
        job.emit("progress", {"stage": "incumbent", "done": 0, "total": 0, **best})

    try:
        n_locked = 0 if site is None else site.n_existing
        problem = solver_problem(session, site, grid, request["budget"] - n_locked)
        progress("solve", 0, 1)
        placement = solve_stoppable(problem, request["solver"], time_limit_s=request["time_limit_s"],
                                    should_stop=job.stop.is_set, progress=progress, on_incumbent=on_incumbent)
        progress("viewsheds", 0, len(placement.selected))
        c = grid.candidates
        new = []
        for n, i in enumerate(np.asarray(placement.selected, np.int64)):
            pos, ang, lens = c.positions[i].copy(), c.angles_deg[i].copy(), int(c.camera_ids[i])
            row = np.sort(grid.V.indices[grid.V.indptr[i]:grid.V.indptr[i + 1]]).astype(np.int32)
            new.append(session.grid_cam(pos, ang, lens, row))
            progress("viewsheds", n + 1, len(placement.selected))
        session.replace_unlocked(new, t0)
        state = session.state()
        state["optimize"] = {"job": job.id, "solver": request["solver"], "status": placement.status,
                             "objective": float(placement.objective), "seconds": round(time.perf_counter() - t0, 3),
                             "bound": None if placement.bound is None else float(placement.bound)}
        session.busy = None
        state["busy"] = None
        job.emit("done", state, last=True)
    except Exception as err:  # noqa: BLE001 - reported on the event stream, the session is unchanged
        session.busy = None
        job.emit("error", {"error": f"optimize: {err}", "field": "optimize"}, last=True)
