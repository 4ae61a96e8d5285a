"""Real sites in a run (issue 17): privacy zones, existing cameras and ``keep``.

- Privacy: every candidate that sees a privacy point (camplace.visibility.privacy) is
  removed before visibility and solving; refined and adaptive poses go through the same
  guard. Existing cameras that see one are reported (metrics.json ``privacy``), not removed.
- Existing cameras (``existing:`` in the scene, and the cameras of ``keep``, a previous
  run's placement.json / .csv) are raycast once with the run's engine. The solvers get
  the problem with Γ' = max(Γ − c_exist, 0), where c_exist is the existing coverage: the
  same cost Σ w max(Γ − c_exist − c_new, 0)² for every selection, so no solver changes and
  the budget counts new cameras only (``min-cameras`` answers "how many more"). After
  solving (and refining: existing cameras are never moved), :meth:`Site.fold` appends the
  existing rows to V and selects them, with the full Γ: visibility.npz, the selection in
  placement.json and metrics.json then agree with the cost recomputed from V
  (docs/output-contract.md, "Existing cameras").
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from camplace.cameras.candidates import Candidates, lens_settings, location_ids_of, merge_cameras, rotation_from_ypr
from camplace.cameras.models import CameraModel
from camplace.cameras.placement_files import Poses, candidates_from_poses, read_placement
from camplace.metrics.coverage import Metrics
from camplace.problem.gains import shortfall_cost
from camplace.problem.model import PlacementProblem
from camplace.problem.offset import offset_gamma
from camplace.scene.build import Scene
from camplace.solvers.base import Placement
from camplace.targets.build import Targets, privacy_targets
from camplace.visibility.engine import Visibility, VisibilityEngine, compute_visibility
from camplace.visibility.privacy import PrivacyGuard, privacy_report


def read_keep(path: str | Path) -> Poses:
    """A previous run's cameras (placement.json or .csv); JSON cameras keep their ``id``
    when they have one (existing cameras of that run), else their candidate id."""
    poses = read_placement(path)
    p = Path(path)
    if p.suffix.lower() == ".json":
        data = json.loads(p.read_text(encoding="utf-8"))
        cams = data.get("cameras") if isinstance(data, dict) else data
        ids = tuple(str(c.get("id", poses.ids[k])) for k, c in enumerate(cams))
        poses = replace(poses, ids=ids)
    return poses


def scene_existing(sc: Scene) -> Poses | None:
    """The scene's ``existing:`` cameras (a list, or a placement CSV/JSON path relative to the scene file)."""
    ex = sc.spec.existing
    if ex is None or (isinstance(ex, list) and not ex):
        return None
    if isinstance(ex, str):
        p = Path(ex).expanduser()
        return read_keep(p if p.is_absolute() or sc.base_dir is None else Path(sc.base_dir) / p)
    ang = np.array([[e.yaw_deg, e.pitch_deg, e.roll_deg] for e in ex], float)
    return Poses(tuple(e.id for e in ex), np.array([e.position for e in ex], float),
                 rotation_from_ypr(ang[:, 0], ang[:, 1], ang[:, 2]), ang, tuple(e.camera for e in ex),
                 f"{sc.spec.name}: existing", focal_mm=tuple(e.focal_mm for e in ex))


def _position_keys(positions: np.ndarray) -> list[tuple]:
    return [tuple(k) for k in np.round(np.asarray(positions, float) * 1000).astype(np.int64).tolist()]


def merge_poses(first: Poses | None, second: Poses | None) -> Poses | None:
    """``first`` then the poses of ``second`` at a position (1 mm) ``first`` does not hold."""
    if first is None or second is None:
        return first if second is None else second
    have = set(_position_keys(first.positions))
    new = [k for k, key in enumerate(_position_keys(second.positions)) if key not in have]
    intr = lambda p: list(p.intrinsics) or [None] * len(p)  # noqa: E731
    focal = lambda p: list(p.focal_mm) or [None] * len(p)  # noqa: E731
    return Poses(first.ids + tuple(second.ids[k] for k in new), np.r_[first.positions, second.positions[new]],
                 np.r_[first.rotations, second.rotations[new]], np.r_[first.angles_deg, second.angles_deg[new]],
                 first.lenses + tuple(second.lenses[k] for k in new), f"{first.source} + {second.source}",
                 tuple(intr(first)) + tuple(intr(second)[k] for k in new),
                 tuple(focal(first)) + tuple(focal(second)[k] for k in new))


@dataclass
class Site:
    """A run's site rules: ``guard`` (privacy points, or None), the existing cameras
    (``existing``: Candidates, ``ids``; ``V``: their rows on the targets once raycast)."""

    guard: PrivacyGuard | None
    existing: Candidates | None
    ids: tuple[str, ...] = ()
    V: sp.csr_matrix | None = None
    log: list[str] = field(default_factory=list)

    @property
    def n_existing(self) -> int:
        return 0 if self.existing is None else len(self.existing)

    def admit(self, cands: Candidates, executor=None, cache_dir=None) -> Candidates:
        """The candidates that see no privacy point and stand at no existing camera's location."""
        keep = np.ones(len(cands), bool)
        if self.guard is not None:
            seen = self.guard.sees(cands, executor, cache_dir)
            keep &= ~seen
            self.log.append(f"privacy: {int(seen.sum())} of {len(cands)} candidates see a privacy zone "
                            f"({', '.join(self.guard.points.region_names)}; {len(self.guard.points)} points); removed")
        if self.existing is not None:
            taken = set(_position_keys(self.existing.positions))
            at = np.array([k in taken for k in _position_keys(cands.positions)], bool)
            keep &= ~at
            if at.any():
                self.log.append(f"existing: {int(at.sum())} candidates at an existing camera's position removed")
        return cands.subset(keep) if not keep.all() else cands

    def raycast(self, engine: VisibilityEngine, sc: Scene, targets: Targets, executor=None, cache_dir=None) -> None:
        """Raycast the existing cameras once (their V rows on ``targets``) and report their privacy."""
        if self.existing is None:
            return
        self.V = compute_visibility(engine, sc.occupancy, targets, self.existing, executor=executor,
                                    cache_dir=cache_dir).V
        self.log.append(f"existing: {self.n_existing} cameras ({', '.join(self.ids[:8])}"
                        f"{', ...' if self.n_existing > 8 else ''}), fixed, counted toward coverage, not budget")
        rep = privacy_report(self.guard, self.existing, np.arange(self.n_existing), list(self.ids))
        if rep["violations"]:
            self.log.append(f"warning: privacy: existing camera(s) {', '.join(rep['camera_ids'])} see a privacy "
                            f"zone (reported, not removed)")

    def coverage(self) -> np.ndarray | None:
        """(N_p,) int64 coverage by the existing cameras (None without them)."""
        if self.V is None:
            return None
        return np.bincount(self.V.indices, minlength=self.V.shape[1]).astype(np.int64)

    def solver_problem(self, problem: PlacementProblem) -> PlacementProblem:
        """The problem the solvers see: Γ' = max(Γ − c_exist, 0) (same cost for every selection)."""
        cov = self.coverage()
        if cov is None:
            return problem
        return replace(problem, gamma=offset_gamma(problem.gamma, cov))

    def fold(self, vis: Visibility, problem: PlacementProblem,
             placement: Placement) -> tuple[Visibility, PlacementProblem, Placement]:
        """Append the existing rows to V and select them; the problem gets the full Γ (of
        ``vis.targets``) and budget + existing; the placement's info names the existing rows."""
        if self.V is None:
            return vis, problem, placement
        c, e = vis.candidates, self.existing
        first = vis.V.shape[0]
        rows = np.arange(first, first + self.n_existing, dtype=np.int64)
        loc = (int(c.location_ids.max()) + 1 if len(c) else 0) + location_ids_of(e.positions)
        cams, remap = merge_cameras(c.cameras, e.cameras)  # focal settings may differ (issue 27)
        ang = np.array(e.angles_deg, float)
        ang[:, 0] %= 360.0
        merged = replace(c, positions=np.r_[c.positions, e.positions], rotations=np.r_[c.rotations, e.rotations],
                         angles_deg=np.r_[c.angles_deg, ang],
                         camera_ids=np.r_[c.camera_ids, remap[e.camera_ids]].astype(np.int32),
                         location_ids=np.r_[c.location_ids, loc], cameras=cams)
        V = sp.vstack([vis.V, self.V.astype(vis.V.dtype)], format="csr")
        V.sort_indices()
        vis2 = Visibility(V, merged, vis.targets, vis.mode, dict(vis.info, existing=self.n_existing), vis.engine)
        costs = np.array([cams[k].cost for k in merged.camera_ids], np.float64)
        money = problem.money_budget
        extra = {}
        if getattr(problem, "type_ids", None) is not None:  # per-type limits count new cameras only
            extra["type_ids"] = np.r_[np.asarray(problem.type_ids, np.int64), np.full(self.n_existing, -1)]
        prob2 = replace(problem, V=V, gamma=vis.targets.gamma, budget=problem.budget + self.n_existing, **extra,
                        location_ids=merged.location_ids, camera_costs=costs,
                        money_budget=None if money is None else money + float(costs[rows].sum()),
                        candidate_positions=np.asarray(merged.positions, np.float64))
        sel = np.sort(np.r_[np.asarray(placement.selected, np.int64), rows])
        cost = prob2.cost(sel)
        info = dict(placement.info, existing_ids={int(r): i for r, i in zip(rows, self.ids)}, new_budget=problem.budget,
                    existing_cost=shortfall_cost(prob2.gamma, prob2.weights, self.coverage()))
        return vis2, prob2, replace(placement, selected=sel, objective=cost, info=info)

    def report(self, vis: Visibility, placement: Placement, metrics: Metrics) -> Metrics:
        """metrics with the ``privacy`` and ``existing`` figures of the (folded) placement."""
        ids_of = placement.info.get("existing_ids", {})
        sel = np.asarray(placement.selected, np.int64)
        names = [ids_of.get(int(i), str(int(i))) for i in sel]
        priv = privacy_report(self.guard, vis.candidates, sel, names)
        ex = None
        if ids_of:
            ex = {"cameras": len(ids_of), "ids": list(ids_of.values()), "new_cameras": int(len(sel) - len(ids_of)),
                  "cost_existing_only": float(placement.info.get("existing_cost", 0.0))}
        return replace(metrics, privacy=priv if self.guard is not None else None, existing=ex)


def privacy_guard(sc: Scene, cameras: dict[str, CameraModel] | tuple, engine: VisibilityEngine) -> PrivacyGuard | None:
    """The privacy guard of a scene (its privacy zones' points raycast by ``engine``), or None."""
    pts = privacy_targets(sc)
    cams = lens_settings(cameras)[0] if isinstance(cameras, dict) else tuple(cameras)  # as build_candidates
    return None if pts is None else PrivacyGuard(engine, sc.occupancy, pts, cams)


def site_of(sc: Scene, cameras: dict[str, CameraModel], engine: VisibilityEngine,
            keep: str | Path | None = None) -> Site | None:
    """The site rules of a scene (privacy zones, existing cameras, ``keep``); None when it has none."""
    guard = privacy_guard(sc, cameras, engine)
    poses = merge_poses(scene_existing(sc), None if keep is None else read_keep(keep))
    if guard is None and poses is None:
        return None
    existing = None if poses is None else candidates_from_poses(poses, cameras)
    return Site(guard, existing, () if poses is None else tuple(poses.ids))
