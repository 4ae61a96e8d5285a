"""People as targets (issue 36): points on the sampled people that the cameras must see.

Each person of a crowd sample (camplace.targets.crowd) carries one point on its axis at
each of the crowd's ``people_heights`` (default torso 1.25 m and head 1.6 m), to be seen
by ``people_gamma`` cameras (default 2: triangulatable). A person belongs to the target
region of the volume target nearest to it in plan (so a zone's DORI pixel density and
weight apply to the people standing in it; the zone of the person in the metrics); the
person's weight is that target's, shared evenly by its points.

Points are ordered sample by sample, person by person, height by height: person p (row
of ``Crowds.xy``) owns points p · H .. p · H + H − 1, sample s owns points
ptr[s] .. ptr[s + 1] − 1 with ptr = H · Crowds.ptr.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from camplace.targets.build import Targets
from camplace.targets.crowd import Crowds


@dataclass(frozen=True)
class People:
    """The people of S crowd samples as targets: ``targets`` (M = P · H points, volume
    targets: Γ people_gamma, weight w_person / H); person (M,) int64 row of the crowds' xy;
    ptr (S + 1,) int64 point offsets per sample; heights (H,) m."""

    targets: Targets
    person: np.ndarray
    ptr: np.ndarray
    heights: np.ndarray

    @property
    def n_samples(self) -> int:
        return len(self.ptr) - 1

    @property
    def n_heights(self) -> int:
        return len(self.heights)

    def sample_slice(self, s: int) -> slice:
        """The points of sample s."""
        return slice(int(self.ptr[s]), int(self.ptr[s + 1]))


def person_regions(base: Targets, xy: np.ndarray) -> np.ndarray:
    """(P,) int64 index of the volume target of ``base`` nearest in plan to each person
    centre xy (P, 2) m; -1 for all when ``base`` has no volume target."""
    vol = np.flatnonzero(~base.is_surface)
    if len(vol) == 0 or len(xy) == 0:
        return np.full(len(xy), -1, np.int64)
    _, k = cKDTree(base.positions[vol, :2]).query(np.asarray(xy, float).reshape(-1, 2))
    return vol[np.asarray(k, np.int64)]


def people_targets(crowds: Crowds, base: Targets, heights, gamma: int) -> People:
    """The points on every person of ``crowds`` at ``heights`` (m) as targets (see module
    doc); region, pixel density, incidence and voxel edge from ``base`` (the run's targets)."""
    z = np.asarray(heights, np.float64).ravel()
    H, P = len(z), len(crowds.xy)
    near = person_regions(base, crowds.xy)
    has = near >= 0
    region = np.where(has, base.region_ids[np.maximum(near, 0)] if len(base) else 0, 0).astype(np.int32)
    w = np.where(has, base.weights[np.maximum(near, 0)] if len(base) else 1.0, 1.0) / max(H, 1)
    pos = np.c_[np.repeat(crowds.xy, H, axis=0), np.tile(z, P)] if P else np.zeros((0, 3))
    names = base.region_names if len(base.region_names) else ("people",)
    kinds = base.region_kinds if len(base.region_kinds) else ("volume",)
    inc = base.max_incidence_deg if len(base.max_incidence_deg) else np.array([90.0])
    px = base.min_px_per_m if base.min_px_per_m is None or len(base.min_px_per_m) else np.zeros(1)
    t = Targets(np.ascontiguousarray(pos, np.float64), np.zeros((P * H, 3)), np.full(P * H, int(gamma), np.int64),
                np.repeat(w, H).astype(np.float64), np.repeat(region, H), names, kinds, inc, px, base.voxel_size)
    return People(t, np.repeat(np.arange(P, dtype=np.int64), H), np.asarray(crowds.ptr, np.int64) * H, z)


def person_coverage(point_coverage: np.ndarray, n_heights: int) -> np.ndarray:
    """(..., P) a person's coverage: the least coverage among its points (a person counts
    as seen by ≥ k cameras when each of its points is), from point coverage (..., P · H)."""
    c = np.asarray(point_coverage)
    return c.reshape(*c.shape[:-1], -1, int(n_heights)).min(axis=-1)


__all__ = ["People", "people_targets", "person_coverage", "person_regions"]
