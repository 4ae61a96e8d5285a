"""Privacy zones as a hard rule (issue 17): which poses see a privacy point.

The privacy points (camplace.targets.build.privacy_targets) are raycast through the same
engine interface as the targets (camplace.visibility.engine.compute_visibility), so a pose
"sees" a privacy point exactly when it would see a target there (lens, range, occlusion,
the engine's probe rule). No kernel knows about privacy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from camplace.cameras.candidates import Candidates, rotation_from_ypr
from camplace.scene.build import OccupancyGrid
from camplace.targets.build import Targets
from camplace.visibility.engine import VisibilityEngine, compute_visibility


@dataclass(frozen=True)
class PrivacyGuard:
    """The privacy points (``points``, a Targets) and how to raycast them (``engine`` on
    ``occupancy``). Called as a pose guard (camplace.improve.refine.PoseGuard):
    ``guard(poses (K, 6), camera_ids (K,))`` -> (K,) bool, True = sees no privacy point."""

    engine: VisibilityEngine
    occupancy: OccupancyGrid
    points: Targets
    cameras: tuple

    def seen_points(self, candidates: Candidates, executor=None, cache_dir=None):
        """(N, P) CSR: which privacy points each candidate sees."""
        return compute_visibility(self.engine, self.occupancy, self.points, candidates, executor=executor,
                                  cache_dir=cache_dir).V

    def sees(self, candidates: Candidates, executor=None, cache_dir=None) -> np.ndarray:
        """(N,) bool: candidates that see at least one privacy point."""
        if len(candidates) == 0:
            return np.zeros(0, bool)
        return np.diff(self.seen_points(candidates, executor, cache_dir).indptr) > 0

    def __call__(self, poses: np.ndarray, camera_ids: np.ndarray, cameras: tuple | None = None) -> np.ndarray:
        """``camera_ids`` index ``cameras`` (default: the guard's own, e.g. a refined focal setting's tuple)."""
        poses = np.atleast_2d(np.asarray(poses, float))
        c = Candidates(poses[:, :3].copy(), rotation_from_ypr(poses[:, 3], poses[:, 4], poses[:, 5]),
                       poses[:, 3:6].copy(), np.asarray(camera_ids, np.int32), np.arange(len(poses), dtype=np.int64),
                       self.cameras if cameras is None else tuple(cameras))
        return ~self.sees(c)


def privacy_report(guard: PrivacyGuard | None, candidates: Candidates, rows: np.ndarray, ids: list[str]) -> dict:
    """metrics.json ``privacy``: the cameras (candidate ``rows``, named ``ids``) that see a
    privacy point: {"zones", "points", "violations", "camera_ids", "points_seen"}; empty
    zones without a guard."""
    if guard is None:
        return {"zones": [], "points": 0, "violations": 0, "camera_ids": [], "points_seen": 0}
    rows = np.asarray(rows, np.int64)
    return privacy_report_of_seen(guard, guard.seen_points(candidates.subset(rows)) if len(rows) else None, ids)


def privacy_report_of_seen(guard: PrivacyGuard, seen, ids: list[str]) -> dict:
    """privacy_report from ``seen`` ((K, P) CSR: the privacy points each of the K cameras
    ``ids`` sees, as guard.seen_points gives; None for no camera): for an editor that keeps
    each camera's row (the planner)."""
    hit = np.diff(seen.indptr) > 0 if seen is not None else np.zeros(0, bool)
    return {"zones": list(guard.points.region_names), "points": int(len(guard.points)),
            "violations": int(hit.sum()), "camera_ids": [str(ids[k]) for k in np.flatnonzero(hit)],
            "points_seen": int(len(np.unique(seen.indices))) if seen is not None else 0}
