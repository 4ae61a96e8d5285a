"""Crowds in a run and an evaluation (issue 28).

- ``score_in_crowd``: the crowd metrics of a placement (camplace.metrics.crowd) on the
  held-out crowds (stream camplace.targets.crowd.SCORE): only the selected rows of V are
  thinned, so scoring costs a few milliseconds whatever the size of V.
  With them, how well it sees the people themselves (issue 36: the points on the people of
  the held-out crowds, camplace.visibility.people; metrics.json ``crowd.people``).
- ``crowd_problem``: a crowd-aware run's problem (camplace.problem.people): the
  sample-average squared shortfall of the points on the people of the ``samples`` crowds
  of stream OPTIMISE, each seen past the shelves and the other people, mixed with the
  empty-store cost by ``people_weight``. Existing cameras see the same people
  (Γ^p' = max(Γ^p − c_exist, 0)). Its ``row_map`` gives the refinement's and the
  adaptive rounds' new poses their views of the same people, and
  ``nominal`` turns the solved placement back into one of the empty-store problem (the
  output contract: objective = cost recomputed from the written V), keeping the crowd
  objective and bound in ``placement.info['crowd']``.
- ``people_cost: count`` (the default): ``CrowdProblem.count_step`` follows the solver's grid
  placement with a swap descent that also counts the optimisation crowds' people seen by
  ≥ Γ^p cameras (camplace.improve.people; issue 36: the squared cost valued a person point's
  first view 3 times its second, and the optimisers bought first views, not triangulations).
  With ``max_cost_rise`` r (the cost cap) the descents and the refinement's pose scores
  refuse any move that lifts the empty-store part of the cost above (1 + r) × its value at
  the reference placement: the greedy grid solve of the empty-store part of the same
  problem (same candidates, budget and rules; ``CrowdProblem.cost_limit``).

With nobody in any sample (density 0) the crowd-aware problem is the problem itself:
every result equals the run without a crowd.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from camplace.cameras.candidates import Candidates
from camplace.improve.people import PeopleCountObjective, people_swap
from camplace.improve.refine import extend_problem
from camplace.metrics.crowd import CrowdMetrics, crowd_metrics, people_metrics, spread
from camplace.problem.crowd import sample_coverage
from camplace.problem.gains import shortfall_cost
from camplace.problem.model import PlacementProblem
from camplace.problem.people import mixed_rows, people_problem
from camplace.scene.build import Scene
from camplace.solvers.base import Placement
from camplace.solvers.registry import solve
from camplace.spec.crowd import CrowdSpec
from camplace.targets.build import Targets
from camplace.targets.crowd import OPTIMISE, SCORE, Crowds, sample_crowds
from camplace.targets.people import People, people_targets, person_coverage
from camplace.visibility.crowd import PeopleGrid, crowd_rows, people_grid
from camplace.visibility.engine import Visibility, VisibilityEngine, raycast_rows
from camplace.visibility.people import people_rows
from camplace.visibility.registry import engine_of

SHOWN_HEIGHT = 1.5  # m: the report's default height (faces), the volume target height nearest to it
COUNT_SWAP_S = 60.0  # s: at most this long for people_cost count's swap descent


def crowd_info(crowd: CrowdSpec, crowds: Crowds) -> dict:
    """What the crowds were, for metrics.json ``crowd``."""
    return {"density": float(crowd.density), "zones": {k: float(v) for k, v in crowd.zones.items()},
            "radius": float(crowd.radius), "height": float(crowd.height), "seed": int(crowd.seed),
            "samples": crowds.n_samples, "held_out": True, "persons": spread(crowds.counts),
            "walkable_m2": round(float(crowds.info.get("walkable_m2", 0.0)), 3)}


def report_height(targets: Targets, wanted: float | None) -> float | None:
    """The volume target height (m) nearest ``wanted`` (default SHOWN_HEIGHT); None without volume targets."""
    z = np.unique(np.round(targets.positions[~targets.is_surface, 2], 6))
    if len(z) == 0:
        return None
    want = SHOWN_HEIGHT if wanted is None else float(wanted)
    return float(z[np.argmin(np.abs(z - want))])


def _grid(sc: Scene, crowds: Crowds) -> PeopleGrid:
    """The people grid over the room's plan box (every camera, target and person is inside)."""
    fp = np.asarray(sc.footprint, float)
    return people_grid(crowds, fp.min(0), fp.max(0))


def score_in_crowd(sc: Scene, vis: Visibility, selected: np.ndarray, crowd: CrowdSpec, executor=None,
                   extra: dict | None = None) -> CrowdMetrics:
    """The crowd metrics of ``selected`` (rows of vis.V, full Γ of vis.targets) on the
    ``crowd.score_samples`` held-out crowds; ``extra``: more figures for metrics.json ``crowd``."""
    t = vis.targets
    crowds = sample_crowds(sc, crowd, SCORE)
    sel = np.asarray(selected, np.int64)
    pos = vis.candidates.positions[sel]
    rows = crowd_rows(vis.V[sel], pos, t.positions, crowds, executor=executor,
                      grid=_grid(sc, crowds))
    cov = sample_coverage(rows, crowds.n_samples, np.arange(len(sel)))
    info = crowd_info(crowd, crowds)
    m = crowd_metrics(t.gamma, t.weights, cov, t.region_ids, t.region_names, crowds.sample(0), crowd.radius,
                      crowd.height, info, report_height(t, crowd.report_height))
    people = people_targets(crowds, t, crowd.people_heights, crowd.people_gamma)
    grid = _grid(sc, crowds)
    seen = people_rows(engine_of(vis), sc.occupancy, people, vis.candidates.subset(sel), grid)
    pcov = person_coverage(np.asarray(seen.sum(axis=0)).ravel(), people.n_heights)
    who = np.repeat(np.arange(crowds.n_samples, dtype=np.int64), crowds.counts)
    summary = dict(m.summary, people=people_metrics(pcov, who, crowds.n_samples,
                                                    people.targets.region_ids[::people.n_heights], t.region_names,
                                                    crowd.people_gamma, crowd.people_heights))
    chance = person_chance(sc, vis, sel, crowds, grid, crowd, m.report_height)
    return replace(m, summary=summary, extra={"optimised": False, **(extra or {})}, p_person=chance)


def person_chance(sc: Scene, vis: Visibility, selected: np.ndarray, crowds: Crowds, grid: PeopleGrid,
                  crowd: CrowdSpec, height: float | None) -> np.ndarray | None:
    """(N_p,) for each volume target at ``height`` (m): the share of ``crowds`` in which a
    person standing at its (x, y) (points at ``crowd.people_heights``) is seen by ≥ 2 of the
    ``selected`` cameras past the shelves and the crowd (a crowd person whose disc holds the
    spot is taken to be that person); NaN at every other target. None without such targets."""
    t = vis.targets
    spots = np.flatnonzero(~t.is_surface & (np.abs(t.positions[:, 2] - (height or 0.0)) < 1e-6))
    if height is None or len(spots) == 0:
        return None
    test = Crowds(t.positions[spots, :2], np.array([0, len(spots)], np.int64), crowds.radius, crowds.height)
    people = people_targets(test, t, crowd.people_heights, crowd.people_gamma)
    sel = np.asarray(selected, np.int64)
    cams = vis.candidates.subset(sel)
    V = raycast_rows(engine_of(vis), sc.occupancy, people.targets, cams)
    rows = crowd_rows(V, cams.positions, people.targets.positions, crowds, grid=grid)
    cov = person_coverage(sample_coverage(rows, crowds.n_samples, np.arange(len(sel))), people.n_heights)
    out = np.full(len(t), np.nan)
    out[spots] = np.mean(cov >= 2, axis=0) if crowds.n_samples else 0.0
    return out


@dataclass
class CrowdProblem:
    """A crowd-aware run's problem: ``problem`` the people-aware problem (or the problem
    itself when no sample holds anyone, or ``people_weight`` is 0), ``crowds`` the samples
    it averages over, ``people`` the points on their people, ``engine`` / ``occupancy``
    what raycasts new poses' views of them."""

    problem: PlacementProblem
    crowds: Crowds
    grid: PeopleGrid | None
    targets: Targets
    info: dict = field(default_factory=dict)
    seconds_per_sample: float = 0.0  # people-view time (log only: no wall-clock figure in the written results)
    people: People | None = None
    engine: VisibilityEngine | None = None
    occupancy: object = None
    people_weight: float = 1.0
    people_cost: str = "squared"
    count_weight: float = 0.0
    max_cost_rise: float | None = None
    limit: dict | None = None  # the cost cap, once computed: reference cost, limit (cost_limit)

    @property
    def stacked(self) -> bool:
        return self.grid is not None

    def count_step(self, problem: PlacementProblem, placement: Placement, should_stop=None,
                   log: list | None = None) -> Placement:
        """With ``people_cost`` count and people in the crowds: ``placement`` (of ``problem``, this
        crowd problem) after the swap descent of camplace.improve.people, scored on ``problem``
        (status 'heuristic' when it moved); else ``placement`` itself."""
        if not self.stacked or self.people_cost != "count":
            return placement
        start = problem.n_targets - len(self.people.targets)
        limit = self.cost_limit(problem)
        sel, info = people_swap(problem, placement.selected, start, self.people.n_heights, self.count_weight,
                                end=time.perf_counter() + COUNT_SWAP_S, should_stop=should_stop, cost_limit=limit)
        info["cost_before"] = float(placement.objective)
        if limit is not None:  # the empty-store part's cost after the descent (the refinement's start)
            cov = problem.coverage(sel)[:start]
            info["empty_cost"] = self.limit["now"] = shortfall_cost(problem.gamma[:start], problem.weights[:start], cov)
        if log is not None:
            log.append(f"crowd-aware, people cost count: {info['moves']} swaps, people of the optimisation crowds "
                       f"seen by ≥ Γ {info['people_seen_before']} -> {info['people_seen']} of {info['people']}")
        status = placement.status if info["moves"] == 0 else "heuristic"
        return replace(placement, selected=sel, objective=problem.cost(sel), status=status,
                       info=dict(placement.info, people_count=[*placement.info.get("people_count", []), info]))

    def pose_score(self, problem: PlacementProblem):
        """The refinement's pose_score with ``people_cost`` count (J of camplace.improve.people on
        ``problem``, this crowd problem); None otherwise (the cost drop)."""
        if not self.stacked or self.people_cost != "count":
            return None
        start = problem.n_targets - len(self.people.targets)
        limit = self.cost_limit(problem)
        if limit is not None:  # a start above the cap (the grid solve's): the refinement never lifts E past it
            limit = max(limit, self.limit.get("now", limit))
        return PeopleCountObjective(problem, start, self.people.n_heights, self.count_weight,
                                    cost_limit=limit).pose_scores

    def cost_limit(self, problem: PlacementProblem) -> float | None:
        """The cost cap on ``problem`` (this crowd problem, its grid or an extension of it; the
        first call fixes it): (1 + ``max_cost_rise``) × the empty-store part's cost (the columns
        before the people's) at the greedy solve of that part on the grid; None without a cap or
        without an empty-store part (``people_weight`` 1)."""
        start = problem.n_targets - len(self.people.targets)
        if self.max_cost_rise is None or start == 0:
            return None
        if self.limit is None:
            grid = problem.take_candidates(np.arange(self.problem.n_candidates))
            empty = replace(grid, V=sp.csr_matrix(grid.V[:, :start]), gamma=grid.gamma[:start],
                            weights=grid.weights[:start], target_positions=None if grid.target_positions is None
                            else grid.target_positions[:start])
            ref = solve(empty, "greedy").selected
            cost = empty.cost(ref)
            self.limit = {"reference": "greedy on the empty-store part, grid", "reference_cost": cost,
                          "max_cost_rise": float(self.max_cost_rise), "limit": (1 + self.max_cost_rise) * cost}
        return self.limit["limit"]

    def row_map(self, poses: Candidates, rows: sp.csr_matrix) -> sp.csr_matrix:
        """Raycast rows (K, N_p) of new ``poses`` -> their rows of the crowd-aware problem
        (with their views of the same people)."""
        if not self.stacked:
            return rows
        seen = people_rows(self.engine, self.occupancy, self.people, poses, self.grid)
        return mixed_rows(rows, seen, self.people_weight)

    def nominal(self, vis: Visibility, problem: PlacementProblem, placement: Placement,
                grid_selected: np.ndarray) -> tuple[PlacementProblem, Placement]:
        """(``problem`` - the empty-store one - extended over vis's appended rows, the placement
        scored on it): objective = its empty-store cost, bound None; the crowd objective / bound
        (and the crowd grid / refined costs) go to ``info['crowd']``."""
        nominal = extend_problem(problem, vis) if vis.V.shape[0] > problem.n_candidates else problem
        sel = np.asarray(placement.selected, np.int64)
        t = self.targets  # the full Γ (existing cameras' offset keeps the cost, not Σ w Γ'²): eq. 8 as metrics
        norm = float(np.dot(t.weights, t.gamma.astype(np.float64) ** 2))
        crowd = {"samples": self.crowds.n_samples, "seed": int(self.crowds.info.get("seed", 0)),
                 "objective": float(placement.objective), "bound": placement.bound, "status": placement.status,
                 "coverage_gap": float(placement.objective) / norm if norm > 0 else 0.0, **self.info}
        if self.limit is not None:  # the cost cap (in the crowd problem's weights: (1 − people_weight) × w)
            crowd["cost_cap"] = {k: v for k, v in self.limit.items() if k != "now"}
        info = dict(placement.info, crowd=crowd)
        if "people_count" in info:  # count_step's swaps and the people they see (on the grid, after refining)
            crowd["count_steps"] = info.pop("people_count")
        for step in ("adaptive", "refine"):  # their costs were crowd costs: say so, give the empty-store ones
            if isinstance(info.get(step), dict) and "grid_cost" in info[step]:
                d = dict(info[step])
                crowd[f"{step}_grid_cost"] = d["grid_cost"]
                d["grid_cost"] = nominal.cost(grid_selected)
                if "refined_cost" in d:
                    crowd["refined_cost"], d["refined_cost"] = d["refined_cost"], nominal.cost(sel)
                info[step] = d
        return nominal, replace(placement, objective=nominal.cost(sel), bound=None, info=info)


def crowd_problem(sc: Scene, vis: Visibility, problem: PlacementProblem, crowd: CrowdSpec, site=None,
                  executor=None, progress=None) -> CrowdProblem:
    """The crowd-aware problem of ``problem`` (full Γ; the run's problem before the site's
    existing-camera offset): see module doc. ``site``: camplace.workflows.sites.Site or None."""
    t0 = time.perf_counter()
    crowds = sample_crowds(sc, crowd, OPTIMISE)
    t = vis.targets
    if crowds.empty or crowd.people_weight == 0:  # nobody to see, or nobody counts: the empty-store problem
        p = site.solver_problem(problem) if site is not None else problem
        return CrowdProblem(p, crowds, None, t, {"persons": spread(crowds.counts)})
    grid = _grid(sc, crowds)
    people = people_targets(crowds, t, crowd.people_heights, crowd.people_gamma)
    engine = engine_of(vis)
    if progress:
        progress("crowd", 0, 1)
    seen = people_rows(engine, sc.occupancy, people, vis.candidates, grid, executor)
    if progress:
        progress("crowd", 1, 1)
    t1 = time.perf_counter()
    base, cov_out = problem, None
    if site is not None:
        base = site.solver_problem(problem)
        if site.existing is not None and len(site.existing):  # existing cameras see some people already
            ex = people_rows(engine, sc.occupancy, people, site.existing, grid)
            cov_out = np.asarray(ex.sum(axis=0)).ravel().astype(np.int64)
    S = crowds.n_samples
    pt = people.targets
    mixed = people_problem(base, seen, pt.gamma, pt.weights / S, crowd.people_weight, pt.positions, cov_out,
                           full_gamma=problem.gamma)
    info = {"persons": spread(crowds.counts), "people_points": len(pt), "people_weight": float(crowd.people_weight),
            "people_gamma": int(crowd.people_gamma), "people_heights": [float(z) for z in crowd.people_heights],
            "people_seen_pct": 100.0 * float(np.mean(np.diff(seen.tocsc().indptr) > 0)) if len(pt) else 0.0}
    info["people_cost"] = crowd.people_cost
    return CrowdProblem(mixed, crowds, grid, t, info, (t1 - t0) / S, people, engine, sc.occupancy,
                        float(crowd.people_weight), crowd.people_cost, float(crowd.people_count_weight),
                        crowd.max_cost_rise)


def describe(cp: CrowdProblem, crowd: CrowdSpec) -> str:
    """The run log's line about a crowd-aware problem."""
    if not cp.stacked:
        return (f"crowd-aware: density {crowd.density:g} /m² places nobody (or people_weight is 0): the problem is "
                f"the empty-store one")
    i = cp.info
    return (f"crowd-aware: {cp.crowds.n_samples} crowds of {i['persons']['mean']:.0f} persons (density "
            f"{crowd.density:g} /m², seed {crowd.seed}); {i['people_points']} points on them (heights "
            f"{', '.join(f'{z:g}' for z in i['people_heights'])} m, Γ {i['people_gamma']}), "
            f"{i['people_seen_pct']:.1f} % seen by some candidate; people weight {i['people_weight']:g}; "
            f"people cost {i['people_cost']}; {cp.seconds_per_sample:.3f} s per sample; the solvers see "
            f"{cp.problem.n_targets} targets")


class _Stopped(Exception):
    """should_stop() turned true between two blocks of V_s."""


def crowd_stage(sc: Scene, vis: Visibility, problem: PlacementProblem, crowd: CrowdSpec | None, site=None, *,
                workers: int = 1, scheduler: str | None = None, progress=None, log: list | None = None,
                timings: dict | None = None, should_stop=None) -> CrowdProblem | None:
    """A run's crowd-aware problem (None unless ``crowd.optimise``): V_s on the run's
    executor (``workers`` / ``scheduler`` as for V), its log line and ``timings['crowd']``.
    ``should_stop()`` is polled between V_s's blocks: once true the crowds are dropped
    (None, said in ``log``) and the run solves the empty-store problem, which its solver
    leaves at once."""
    if crowd is None or not crowd.optimise:
        return None
    from camplace.core.executors import make_executor

    def polled(stage: str, done: int, total: int) -> None:
        if progress:
            progress(stage, done, total)
        if should_stop is not None and should_stop():
            raise _Stopped

    t0 = time.perf_counter()
    if progress:
        progress("crowd", 0, 1)
    try:
        with make_executor(workers, scheduler) as executor:
            cp = crowd_problem(sc, vis, problem, crowd, site, executor, polled)
    except _Stopped:
        if log is not None:
            log.append("crowd-aware: skipped (interrupted while sampling the crowds)")
        return None
    finally:
        if timings is not None:
            timings["crowd"] = time.perf_counter() - t0
    if log is not None:
        log.append(describe(cp, crowd))
    return cp


def crowd_scores(sc: Scene, vis: Visibility, placement: Placement, crowd: CrowdSpec | None,
                 cp: CrowdProblem | None = None, log: list | None = None, should_stop=None) -> CrowdMetrics | None:
    """The metrics.json ``crowd`` of a run's (folded) placement; with a crowd-aware ``cp``
    also what the optimisation reached on its own crowds (``optimisation``). None after an
    interrupt (``should_stop()`` true): scoring the held-out crowds takes seconds."""
    if crowd is None:
        return None
    if should_stop is not None and should_stop():  # interrupted: the contract files come first
        if log is not None:
            log.append("crowd: held-out crowds not scored (interrupted)")
        return None
    extra = {"optimised": cp is not None}
    if cp is not None:
        extra["optimisation"] = placement.info.get("crowd", {"samples": cp.crowds.n_samples})
    m = score_in_crowd(sc, vis, placement.selected, crowd, extra=extra)
    if log is not None:
        s = m.summary
        log.append(f"crowd: {s['samples']} held-out crowds of {s['persons']['mean']:.0f} persons: coverage gap "
                   f"{s['coverage_gap']['mean']:.4f} ± {s['coverage_gap']['std']:.4f}, seen by ≥ Γ "
                   f"{s['seen_by_gamma_pct']['mean']:.1f} %, triangulatable {s['triangulatable_pct']['mean']:.1f} %")
    return m
