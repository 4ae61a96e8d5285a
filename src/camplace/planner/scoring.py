"""The planner's live score (issue 37): the per-target figures of the session's cameras,
kept up to date per change in time proportional to what changed.

A change swaps a few cameras (a turn or a move: one out, one in; undo / redo: the cameras
that differ between two states). :class:`LiveScore` keeps the coverage counts
(``cov``, views per target), the well-triangulated flags (``well``) and each camera's
privacy row, and updates them from the swapped cameras only: ``cov`` by their rows
(+ new − old), ``well`` recomputed (camplace.metrics.triangulation.well_triangulated,
the same function) on the targets those rows touch, privacy from the rows each camera
kept. The metrics then come from the counts (camplace.metrics.coverage.metrics_of_coverage),
so they are identical to ``placement_metrics`` of the whole selection, the scoring of
``camplace evaluate``; tests/planner/test_scoring.py checks that after series of edits.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from camplace.metrics.coverage import Metrics, metrics_of_coverage
from camplace.metrics.triangulation import well_triangulated

FULL_SHARE = 0.25  # a change that swaps more than this share of the cameras is rescored from scratch


def rows_matrix(rows: list[np.ndarray], n_targets: int) -> sp.csr_matrix:
    """(K, n_targets) uint8 CSR with row k = the sorted target ids ``rows[k]``."""
    indptr = np.r_[0, np.cumsum([len(r) for r in rows])].astype(np.int64)
    indices = np.concatenate(rows).astype(np.int32) if rows else np.zeros(0, np.int32)
    return sp.csr_matrix((np.ones(len(indices), np.uint8), indices, indptr), shape=(len(rows), n_targets))


def well_of_targets(cams, targets, which: np.ndarray | None = None) -> np.ndarray:
    """well_triangulated of the cameras ``cams`` (each with ``row`` and ``position``) on the
    targets ``which`` ((n,) sorted ids; None = all): (n,) bool, per target exactly what
    the whole-selection call gives (each target's pairs are its own)."""
    pos = np.array([c.position for c in cams], float).reshape(-1, 3)
    V = rows_matrix([c.row for c in cams], len(targets))
    if which is None:
        return well_triangulated(V, pos, targets.positions)
    return well_triangulated(V[:, which], pos, targets.positions[which])


class LiveScore:
    """Coverage counts, well-triangulated flags and privacy rows of a camera tuple.

    ``targets``: the session's Targets; ``guard``: the privacy guard or None. Cameras are
    the session's Cam objects (``row``, ``position``, ``id``, ``privacy``); they are never
    changed in place, so a camera of both states is the same object."""

    def __init__(self, targets, guard, cams: tuple = ()) -> None:
        self.targets = targets
        self.guard = guard
        self.region_names = tuple(targets.region_names)
        self.cams: tuple = ()
        self.full(cams)

    def full(self, cams: tuple) -> None:
        """Rescore ``cams`` from scratch."""
        self.cams = tuple(cams)
        self.cov = np.zeros(len(self.targets), np.int64)
        for c in self.cams:
            self.cov[c.row] += 1
        self.well = well_of_targets(self.cams, self.targets)

    def change(self, cams: tuple) -> None:
        """Make ``cams`` current, updating from the cameras that left and came (by identity)."""
        cams = tuple(cams)
        now = {id(c) for c in cams}
        before = {id(c) for c in self.cams}
        gone = [c for c in self.cams if id(c) not in now]
        came = [c for c in cams if id(c) not in before]
        if len(gone) + len(came) > max(2, FULL_SHARE * len(cams)):
            self.full(cams)
            return
        for c in gone:
            self.cov[c.row] -= 1
        for c in came:
            self.cov[c.row] += 1
        self.cams = cams
        touched = np.unique(np.concatenate([c.row for c in gone + came] + [np.zeros(0, np.int32)]))
        if len(touched):
            self.well[touched] = well_of_targets(cams, self.targets, touched)

    def metrics(self) -> Metrics:
        """placement_metrics of the current cameras (+ the privacy report with a guard)."""
        t = self.targets
        m = metrics_of_coverage(t.gamma, t.weights, self.cov, t.region_ids, self.region_names, self.well)
        if self.guard is not None:
            from camplace.visibility.privacy import privacy_report_of_seen

            seen = rows_matrix([c.privacy for c in self.cams], len(self.guard.points)) if self.cams else None
            m = replace(m, privacy=privacy_report_of_seen(self.guard, seen, [c.id for c in self.cams]))
        return m
