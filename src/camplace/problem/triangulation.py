"""The triangulation requirement: a camera counts toward Γ_j only if it forms a
well-conditioned pair at target j with another selected camera that sees j (their rays
meet at j at an angle in [min_deg, max_deg], default [20°, 160°]).

One home for the pair test: the triangulation-aware greedy
(camplace.solvers.greedy_triangulated) uses ``pair_up`` / ``apply_add``; the metric
(camplace.metrics.triangulation) scores any selection with the same angle range.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import scipy.sparse as sp

from camplace.core.errors import InputError

DEFAULT_MIN_DEG = 20.0
DEFAULT_MAX_DEG = 160.0


def check_angle_range(min_deg: float, max_deg: float) -> tuple[float, float]:
    """(cos max_deg, cos min_deg) after checking 0 <= min_deg <= max_deg <= 180 (InputError)."""
    if not 0.0 <= min_deg <= max_deg <= 180.0:
        raise InputError(f"triangulation angle range: expected 0 <= min <= max <= 180 degrees, got [{min_deg}, {max_deg}]")
    return math.cos(math.radians(max_deg)), math.cos(math.radians(min_deg))


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
def pair_up(i, j, cp, tp, cams_of, n_cams, paired, cos_lo, cos_hi, mark):
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
def apply_add(i, indptr, indices, cp, tp, cams_of, n_cams, paired, eff, cos_lo, cos_hi):
    for e in range(indptr[i], indptr[i + 1]):
        j = indices[e]
        own, new = pair_up(i, j, cp, tp, cams_of, n_cams, paired, cos_lo, cos_hi, True)
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
    cos_lo, cos_hi = check_angle_range(min_deg, max_deg)
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
        apply_add(i, V_sel.indptr.astype(np.int64), V_sel.indices.astype(np.int64), cp, tp, cams_of, n_cams, paired,
                   eff, cos_lo, cos_hi)
    return eff



__all__ = ["DEFAULT_MAX_DEG", "DEFAULT_MIN_DEG", "apply_add", "check_angle_range", "effective_coverage", "pair_up"]
