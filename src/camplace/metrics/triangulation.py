"""Triangulation quality: do two cameras see a target from usefully different directions?

Two cameras triangulate a point well only if their viewing rays meet at the point at an
angle well away from 0° (nearly parallel rays: depth is ill-conditioned) and from 180°
(cameras facing each other across the point: the same line seen from both ends). A
target is *well triangulated* when at least one pair of the selected cameras that see it
meets there at an angle in [min_deg, max_deg] (default [20°, 160°]).

This stage sits after visibility (it needs camera and target positions); the metrics
and the triangulation-aware greedy take its outputs as plain arrays.
"""

from __future__ import annotations

import math
import time

import numba
import numpy as np
import scipy.sparse as sp

from camplace.problem.model import PlacementProblem
from camplace.solvers.base import Placement

DEFAULT_MIN_DEG = 20.0
DEFAULT_MAX_DEG = 160.0


def ray_angle_deg(target: np.ndarray, cam_a: np.ndarray, cam_b: np.ndarray) -> np.ndarray:
    """Angle (degrees) at which the rays cam_a -> target and cam_b -> target meet.

    Inputs broadcast over leading axes, last axis 3 (metres); 0° = same direction,
    180° = cameras on opposite sides of the target on one line."""
    ua = np.asarray(target, float) - np.asarray(cam_a, float)
    ub = np.asarray(target, float) - np.asarray(cam_b, float)
    cross = np.linalg.norm(np.cross(ua, ub), axis=-1)
    return np.degrees(np.arctan2(cross, np.einsum("...i,...i->...", ua, ub)))  # atan2: exact near 0 and 180


def _check_range(min_deg: float, max_deg: float) -> tuple[float, float]:
    if not 0.0 <= min_deg <= max_deg <= 180.0:
        from camplace.core.errors import InputError

        raise InputError(f"triangulation angle range: expected 0 <= min <= max <= 180 degrees, got [{min_deg}, {max_deg}]")
    return math.cos(math.radians(max_deg)), math.cos(math.radians(min_deg))


def well_triangulated(V_sel: sp.csr_matrix, cam_positions: np.ndarray, target_positions: np.ndarray,
                      min_deg: float = DEFAULT_MIN_DEG, max_deg: float = DEFAULT_MAX_DEG) -> np.ndarray:
    """(N_p,) bool: some pair of the k cameras that see the target meets at an angle in
    [min_deg, max_deg]. V_sel: (k, N_p) visibility rows of the selected cameras;
    cam_positions: (k, 3) m; target_positions: (N_p, 3) m."""
    cos_lo, cos_hi = _check_range(min_deg, max_deg)
    n_p = V_sel.shape[1]
    C = sp.csc_matrix(V_sel)
    C.sort_indices()
    counts = np.diff(C.indptr)
    ok = np.zeros(n_p, bool)
    if C.nnz == 0 or counts.max() < 2:
        return ok
    cols = np.repeat(np.arange(n_p), counts)
    u = np.asarray(target_positions, float)[cols] - np.asarray(cam_positions, float)[C.indices]
    u /= np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-12)
    starts = C.indptr[:-1]
    for a in range(int(counts.max()) - 1):
        for b in range(a + 1, int(counts.max())):
            js = np.flatnonzero((counts > b) & ~ok)
            if len(js) == 0:
                continue
            c = np.einsum("ij,ij->i", u[starts[js] + a], u[starts[js] + b])
            ok[js[(c >= cos_lo - 1e-12) & (c <= cos_hi + 1e-12)]] = True
    return ok


def well_triangulated_of_selection(V: sp.csr_matrix, candidate_positions: np.ndarray, target_positions: np.ndarray,
                                   selected: np.ndarray, min_deg: float = DEFAULT_MIN_DEG,
                                   max_deg: float = DEFAULT_MAX_DEG) -> np.ndarray:
    """well_triangulated() for the rows ``selected`` of the full V: (N_p,) bool."""
    sel = np.asarray(selected, np.int64)
    return well_triangulated(V[sel], np.asarray(candidate_positions)[sel], target_positions, min_deg, max_deg)


# ---------------------------------------------------------------------------------------
# Greedy with the triangulation requirement: a camera counts toward Γ_j only if it forms
# a well-conditioned pair at j with another selected camera that sees j.


@numba.njit(cache=True)
def _pair_ok(cp, a, b, t, cos_lo, cos_hi):
    ax, ay, az = t[0] - cp[a, 0], t[1] - cp[a, 1], t[2] - cp[a, 2]
    bx, by, bz = t[0] - cp[b, 0], t[1] - cp[b, 1], t[2] - cp[b, 2]
    na = math.sqrt(ax * ax + ay * ay + az * az)
    nb = math.sqrt(bx * bx + by * by + bz * bz)
    if na < 1e-12 or nb < 1e-12:
        return False
    c = (ax * bx + ay * by + az * bz) / (na * nb)
    return c >= cos_lo - 1e-12 and c <= cos_hi + 1e-12


@numba.njit(cache=True, inline="always")
def _pair_up(i, j, cp, tp, cams_of, n_cams, paired, cos_lo, cos_hi, mark):
    """The cameras already at target j that pair well with candidate i: returns (i pairs
    with at least one of them, how many of them had no partner yet); with ``mark`` those
    are recorded as paired."""
    own = False
    new = 0
    for q in range(n_cams[j]):
        if _pair_ok(cp, i, cams_of[j, q], tp[j], cos_lo, cos_hi):
            own = True
            if not paired[j, q]:
                new += 1
                if mark:
                    paired[j, q] = True
    return own, new


@numba.njit(cache=True)
def _effective_after_add(i, indptr, indices, cp, tp, cams_of, n_cams, paired, eff, gamma, w, cos_lo, cos_hi, half):
    """Cost drop of adding candidate i on the surrogate coverage e_j + half * (unpaired views
    at j): per target j in row i, e_j grows by (i pairs with some camera at j) + (cameras at
    j that had no partner and pair with i). half > 0 lets a first camera in an empty area
    count for something (a pair needs two cameras, which a one-step greedy cannot see)."""
    gain = 0.0
    for e in range(indptr[i], indptr[i + 1]):
        j = indices[e]
        c0 = eff[j] + half * (n_cams[j] - eff[j])
        if gamma[j] <= c0:
            continue
        own, add = _pair_up(i, j, cp, tp, cams_of, n_cams, paired, cos_lo, cos_hi, False)
        if own:
            add += 1
        e1 = eff[j] + add
        c1 = e1 + half * (n_cams[j] + 1 - e1)
        d0 = gamma[j] - c0
        d1 = max(gamma[j] - c1, 0.0)
        gain += w[j] * (d0 * d0 - d1 * d1)
    return gain


@numba.njit(cache=True)
def _apply_add(i, indptr, indices, cp, tp, cams_of, n_cams, paired, eff, cos_lo, cos_hi):
    for e in range(indptr[i], indptr[i + 1]):
        j = indices[e]
        own, new = _pair_up(i, j, cp, tp, cams_of, n_cams, paired, cos_lo, cos_hi, True)
        eff[j] += new
        q = n_cams[j]
        if q < cams_of.shape[1]:
            cams_of[j, q] = i
            paired[j, q] = own
            n_cams[j] = q + 1
            if own:
                eff[j] += 1


def effective_coverage(V_sel: sp.csr_matrix, cam_positions: np.ndarray, target_positions: np.ndarray,
                       min_deg: float = DEFAULT_MIN_DEG, max_deg: float = DEFAULT_MAX_DEG) -> np.ndarray:
    """(N_p,) int64: how many of the k selected cameras that see each target pair well with
    another selected camera there (the coverage the triangulation requirement counts)."""
    cos_lo, cos_hi = _check_range(min_deg, max_deg)
    k, n_p = V_sel.shape
    V_sel = sp.csr_matrix(V_sel)
    max_c = int(max(k, 1))
    cams_of = np.full((n_p, max_c), -1, np.int64)
    paired = np.zeros((n_p, max_c), np.bool_)
    n_cams = np.zeros(n_p, np.int64)
    eff = np.zeros(n_p, np.int64)
    cp = np.ascontiguousarray(cam_positions, np.float64)
    tp = np.ascontiguousarray(target_positions, np.float64)
    for i in range(k):
        _apply_add(i, V_sel.indptr.astype(np.int64), V_sel.indices.astype(np.int64), cp, tp, cams_of, n_cams, paired,
                   eff, cos_lo, cos_hi)
    return eff


def solve_greedy_triangulated(problem: PlacementProblem, candidate_positions: np.ndarray,
                              target_positions: np.ndarray, min_deg: float = DEFAULT_MIN_DEG,
                              max_deg: float = DEFAULT_MAX_DEG, unpaired_weight: float = 0.5,
                              **_: object) -> Placement:
    """Greedy on the triangulation-aware cost Σ_j w_j max(Γ_j − e_j, 0)², where e_j counts
    only the selected cameras at j that form a pair meeting at an angle in [min_deg, max_deg].

    This cost is not submodular (a camera can make an earlier one count), so every step
    re-evaluates every candidate (numba, O(nnz · coverage) per step), by its gain on the
    surrogate coverage e_j + unpaired_weight · (views at j without a partner yet): with
    weight 0 a lone camera in an empty area gains nothing and the greedy only grows
    clusters. A step whose best gain is 0 adds the candidate with the largest
    plain-coverage gain instead. ``objective`` is the plain cost of the selection; the
    triangulation-aware cost is in ``info['triangulated_cost']``."""
    t0 = time.perf_counter()
    cos_lo, cos_hi = _check_range(min_deg, max_deg)
    V = problem.V
    indptr, indices = V.indptr.astype(np.int64), V.indices.astype(np.int64)
    n_g, n_p = V.shape
    max_c = max(problem.budget, 1)
    cams_of = np.full((n_p, max_c), -1, np.int64)
    paired = np.zeros((n_p, max_c), np.bool_)
    n_cams = np.zeros(n_p, np.int64)
    eff = np.zeros(n_p, np.int64)
    cov = np.zeros(n_p, np.int64)
    cp = np.ascontiguousarray(candidate_positions, np.float64)
    tp = np.ascontiguousarray(target_positions, np.float64)
    gamma = problem.gamma.astype(np.int64)
    w = problem.weights.astype(np.float64)
    costs = problem.costs
    spent = 0.0
    used: set[int] = set()
    selected: list[int] = []
    from camplace.solvers.greedy import marginal_gains

    while len(selected) < problem.budget:
        allowed = np.ones(n_g, bool)
        if used:
            allowed &= ~np.isin(problem.location_ids, list(used))
        if problem.money_budget is not None:
            allowed &= costs + spent <= problem.money_budget + 1e-9
        cand = np.flatnonzero(allowed)
        if len(cand) == 0:
            break
        g = _gains_all(cand, indptr, indices, cp, tp, cams_of, n_cams, paired, eff, gamma, w, cos_lo, cos_hi,
                       float(unpaired_weight))
        best = int(cand[int(np.argmax(g))])
        if g.max() <= 0:
            plain = marginal_gains(problem, cov)[cand]
            if plain.max() <= 0:
                break
            best = int(cand[int(np.argmax(plain))])
        _apply_add(best, indptr, indices, cp, tp, cams_of, n_cams, paired, eff, cos_lo, cos_hi)
        cov[indices[indptr[best]:indptr[best + 1]]] += 1
        selected.append(best)
        used.add(int(problem.location_ids[best]))
        spent += float(costs[best])
    sel = np.array(sorted(selected), np.int64)
    from camplace.problem.model import shortfall_cost

    return Placement(sel, problem.cost(sel), None, "heuristic", "greedy-triangulated", time.perf_counter() - t0,
                     {"order": selected, "triangulated_cost": shortfall_cost(gamma, w, eff),
                      "angle_range_deg": [min_deg, max_deg]})


@numba.njit(cache=True)
def _gains_all(cand, indptr, indices, cp, tp, cams_of, n_cams, paired, eff, gamma, w, cos_lo, cos_hi, half):
    out = np.zeros(len(cand))
    for k in range(len(cand)):
        out[k] = _effective_after_add(cand[k], indptr, indices, cp, tp, cams_of, n_cams, paired, eff, gamma, w,
                                      cos_lo, cos_hi, half)
    return out


__all__ = ["DEFAULT_MAX_DEG", "DEFAULT_MIN_DEG", "effective_coverage", "ray_angle_deg", "solve_greedy_triangulated",
           "well_triangulated", "well_triangulated_of_selection"]
