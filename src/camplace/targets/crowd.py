"""Crowd samples (issue 28): where people stand, as vertical cylinders on the floor.

A person is a cylinder of radius r and height h on the floor (z = 0). It may stand where
its whole disc lies on walkable floor: inside the footprint, with nothing occupied from
the floor to its height (for scans: in observed free space), outside every privacy zone.
One sample places round(ρ · A) persons in each part of the floor of density ρ (the
crowd's ``density``, or a zone's own in ``crowd.zones``; A = that part's walkable floor
in m²) by random sequential addition: uniform proposals, each kept when it is at least
2r from every person already placed (so cylinders never overlap). Deterministic: sample
s of stream k draws from ``numpy.random.default_rng([seed, k, s])``; stream 0 holds the
crowds a crowd-aware run optimises over, stream 1 the held-out crowds the metrics use.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np
from scipy import ndimage

from camplace.scene.build import Scene
from camplace.spec.crowd import CrowdSpec
from camplace.targets.zones import in_privacy, zone_owner

OPTIMISE, SCORE = 0, 1  # the two random streams: crowds to optimise over, held-out crowds to score on
PROPOSALS_PER_PERSON = 40  # random proposals per wanted person before a sample gives up


@dataclass(frozen=True)
class Crowds:
    """S crowd samples. xy: (P, 2) float64 person centres (m); ptr: (S + 1,) int64, sample
    s is xy[ptr[s]:ptr[s + 1]]; radius, height: m; info: wanted / placed persons per sample."""

    xy: np.ndarray
    ptr: np.ndarray
    radius: float
    height: float
    info: dict = field(default_factory=dict)

    @property
    def n_samples(self) -> int:
        return len(self.ptr) - 1

    @property
    def counts(self) -> np.ndarray:
        """(S,) int64 persons in each sample."""
        return np.diff(self.ptr)

    @property
    def empty(self) -> bool:
        """True when no sample holds anyone (then V_s = V for every s)."""
        return int(self.ptr[-1]) == 0

    def sample(self, s: int) -> np.ndarray:
        """(n_s, 2) person centres of sample s."""
        return self.xy[self.ptr[s]:self.ptr[s + 1]]


@dataclass(frozen=True)
class Floor:
    """The walkable floor on a grid of cells of edge ``res`` from ``origin`` (2,) m.
    free: (nx, ny) bool walkable floor; stand: (nx, ny) bool a person's centre may be in
    this cell (its whole disc on free floor); part: (nx, ny) int index into ``densities``
    (persons / m²) of each cell's part of the floor."""

    free: np.ndarray
    stand: np.ndarray
    part: np.ndarray
    densities: np.ndarray
    origin: np.ndarray
    res: float

    def areas(self) -> np.ndarray:
        """(K,) walkable floor (m²) of each part."""
        return np.bincount(self.part[self.free], minlength=len(self.densities)) * self.res ** 2


def walkable_floor(scene: Scene, crowd: CrowdSpec) -> Floor:
    """The floor where persons of ``crowd`` may stand in ``scene`` (see module doc)."""
    occ = scene.occupancy
    zc = occ.cell_centres(2)
    layers = (zc > 0) & (zc < crowd.height)
    free = ~occ.occupied[:, :, layers].any(axis=2)
    if scene.free_space is not None:  # scans: only where a scanner saw free space
        free &= scene.free_space.free[:, :, layers].any(axis=2)
    gx, gy = np.meshgrid(occ.cell_centres(0), occ.cell_centres(1), indexing="ij")
    xy = np.c_[gx.ravel(), gy.ravel()]
    zones = list(scene.spec.zones)
    if any(z.privacy for z in zones):
        free &= ~in_privacy(zones, xy).reshape(free.shape)
    res = float(occ.resolution)
    # a centre may stand in a cell whose centre is r + one cell from anything not free
    dist = ndimage.distance_transform_edt(free) * res
    stand = free & (dist >= crowd.radius + res)
    names = list(crowd.zones)
    part = np.zeros(free.shape, np.int64)
    if names:
        owner = zone_owner(zones, xy).reshape(free.shape)
        for k, z in enumerate(zones):
            if z.name in crowd.zones:
                part[owner == k] = 1 + names.index(z.name)
    densities = np.array([crowd.density] + [crowd.zones[n] for n in names], np.float64)
    return Floor(free, stand, part, densities, occ.origin[:2].copy(), res)


@numba.njit(cache=True)
def _rsa(prop, label, quota, min_d, x0, y0, cell, nx, ny, out):  # pragma: no cover - compiled
    """Random sequential addition: keep proposal k (prop (M, 2), part label[k]) while its
    part is below quota and it is at least min_d from every kept one; out (M, 2) gets the
    kept centres. Returns how many were kept."""
    head = np.full(nx * ny, -1, np.int64)
    nxt = np.full(prop.shape[0], -1, np.int64)
    count = np.zeros(quota.shape[0], np.int64)
    left = 0
    for r in range(quota.shape[0]):
        left += quota[r]
    n = 0
    d2 = min_d * min_d
    for k in range(prop.shape[0]):
        if left == 0:
            break
        r = label[k]
        if count[r] >= quota[r]:
            continue
        x, y = prop[k, 0], prop[k, 1]
        cx = min(max(int((x - x0) / cell), 0), nx - 1)
        cy = min(max(int((y - y0) / cell), 0), ny - 1)
        ok = True
        for ix in range(max(cx - 1, 0), min(cx + 2, nx)):
            for iy in range(max(cy - 1, 0), min(cy + 2, ny)):
                p = head[ix * ny + iy]
                while p >= 0 and ok:
                    dx, dy = out[p, 0] - x, out[p, 1] - y
                    if dx * dx + dy * dy < d2:
                        ok = False
                    p = nxt[p]
        if ok:
            out[n, 0], out[n, 1] = x, y
            c = cx * ny + cy
            nxt[n] = head[c]
            head[c] = n
            n += 1
            count[r] += 1
            left -= 1
    return n


def sample_crowd(floor: Floor, radius: float, rng: np.random.Generator) -> tuple[np.ndarray, int]:
    """One crowd on ``floor``: ((n, 2) person centres, persons wanted)."""
    want = np.rint(floor.densities * floor.areas()).astype(np.int64)
    cells = [np.flatnonzero((floor.part == k) & floor.stand) for k in range(len(want))]
    want = np.array([w if len(c) else 0 for w, c in zip(want, cells)], np.int64)
    total = int(want.sum())
    if total == 0:
        return np.zeros((0, 2)), 0
    props, labels = [], []
    for k, c in enumerate(cells):
        m = int(want[k]) * PROPOSALS_PER_PERSON
        if m == 0:
            continue
        pick = c[rng.integers(0, len(c), m)]
        ix, iy = np.unravel_index(pick, floor.stand.shape)
        jitter = rng.random((m, 2)) - 0.5
        props.append(floor.origin + (np.c_[ix, iy] + 0.5 + jitter) * floor.res)
        labels.append(np.full(m, k, np.int64))
    prop, label = np.concatenate(props), np.concatenate(labels)
    order = rng.permutation(len(prop))  # the parts' proposals interleaved: no part fills first
    prop, label = np.ascontiguousarray(prop[order]), label[order]
    cell = 2.0 * radius
    lo = prop.min(0)
    nx, ny = (int(v) + 1 for v in np.ceil((prop.max(0) - lo) / cell))
    out = np.empty_like(prop)
    n = _rsa(prop, label, want, 2.0 * radius, lo[0], lo[1], cell, nx, ny, out)
    return out[:n].copy(), total


def sample_crowds(scene: Scene, crowd: CrowdSpec, stream: int = OPTIMISE, n_samples: int | None = None,
                  floor: Floor | None = None) -> Crowds:
    """``n_samples`` crowds (default: ``crowd.samples`` for OPTIMISE, ``crowd.score_samples``
    for SCORE) of random stream ``stream`` (see module doc)."""
    n = int(n_samples if n_samples is not None else crowd.samples if stream == OPTIMISE else crowd.score_samples)
    floor = walkable_floor(scene, crowd) if floor is None else floor
    xs, counts, wanted = [], [], []
    for s in range(n):
        xy, want = sample_crowd(floor, crowd.radius, np.random.default_rng([int(crowd.seed), int(stream), s]))
        xs.append(xy)
        counts.append(len(xy))
        wanted.append(want)
    ptr = np.r_[0, np.cumsum(counts)].astype(np.int64)
    xy = np.concatenate(xs) if xs else np.zeros((0, 2))
    info = {"samples": n, "stream": int(stream), "seed": int(crowd.seed), "persons": counts, "wanted": wanted,
            "walkable_m2": float(floor.areas().sum())}
    return Crowds(xy.astype(np.float64), ptr, float(crowd.radius), float(crowd.height), info)
