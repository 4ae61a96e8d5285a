"""Triangulation quality: do two cameras see a target from usefully different directions?

Two cameras triangulate a point well only if their viewing rays meet at the point at an
angle well away from 0° (nearly parallel rays: depth is ill-conditioned) and from 180°
(cameras facing each other across the point: the same line seen from both ends). A
target is *well triangulated* when at least one pair of the selected cameras that see it
meets there at an angle in [min_deg, max_deg] (default [20°, 160°]).

This stage scores any selection (it needs camera and target positions); the pair test
that the triangulation-aware greedy counts with lives in camplace.problem.triangulation.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from camplace.problem.triangulation import DEFAULT_MAX_DEG, DEFAULT_MIN_DEG, check_angle_range


def ray_angle_deg(target: np.ndarray, cam_a: np.ndarray, cam_b: np.ndarray) -> np.ndarray:
    """Angle (degrees) at which the rays cam_a -> target and cam_b -> target meet.

    Inputs broadcast over leading axes, last axis 3 (metres); 0° = same direction,
    180° = cameras on opposite sides of the target on one line."""
    ua = np.asarray(target, float) - np.asarray(cam_a, float)
    ub = np.asarray(target, float) - np.asarray(cam_b, float)
    cross = np.linalg.norm(np.cross(ua, ub), axis=-1)
    return np.degrees(np.arctan2(cross, np.einsum("...i,...i->...", ua, ub)))  # atan2: exact near 0 and 180


def well_triangulated(V_sel: sp.csr_matrix, cam_positions: np.ndarray, target_positions: np.ndarray,
                      min_deg: float = DEFAULT_MIN_DEG, max_deg: float = DEFAULT_MAX_DEG) -> np.ndarray:
    """(N_p,) bool: some pair of the k cameras that see the target meets at an angle in
    [min_deg, max_deg]. V_sel: (k, N_p) visibility rows of the selected cameras;
    cam_positions: (k, 3) m; target_positions: (N_p, 3) m."""
    cos_lo, cos_hi = check_angle_range(min_deg, max_deg)
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


__all__ = ["DEFAULT_MAX_DEG", "DEFAULT_MIN_DEG", "ray_angle_deg", "well_triangulated", "well_triangulated_of_selection"]
