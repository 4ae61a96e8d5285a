"""Clean-up steps real scans need, each optional and each reported.

All functions take points (N, 3) float64 metres and are pure. ``clean_cloud`` runs the
steps in a fixed order - transform, level floor, crop, voxel downsample, outlier
removal - and returns the cleaned cloud plus a report (one dict per step).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from camplace.scene.loaders.pointcloud import PointCloud, voxel_downsample

UP_AXES = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}


def remove_outliers(points: np.ndarray, neighbors: int = 16, std_ratio: float = 2.0) -> np.ndarray:
    """Statistical outlier removal: (N,) bool mask of points to keep. A point is an
    outlier when its mean distance to its ``neighbors`` nearest points exceeds the
    mean of that figure over the cloud by ``std_ratio`` standard deviations."""
    n = len(points)
    if n <= neighbors:
        return np.ones(n, dtype=bool)
    d, _ = cKDTree(points).query(points, k=neighbors + 1, workers=-1)
    mean_d = d[:, 1:].mean(axis=1)
    return mean_d <= mean_d.mean() + std_ratio * mean_d.std()


def crop_mask(points: np.ndarray, lo, hi) -> np.ndarray:
    """(N,) bool: points inside the axis-aligned box [lo, hi] (m)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return np.all((points >= lo) & (points <= hi), axis=1)


def rigid_matrix(scale: float = 1.0, rotate_deg=(0.0, 0.0, 0.0), translate=(0.0, 0.0, 0.0)) -> np.ndarray:
    """4x4 matrix of p -> R(rotate_deg, extrinsic x then y then z) @ (scale * p) + translate."""
    m = np.eye(4)
    m[:3, :3] = Rotation.from_euler("xyz", rotate_deg, degrees=True).as_matrix() * float(scale)
    m[:3, 3] = np.asarray(translate, float)
    return m


def apply_matrix(points: np.ndarray, m: np.ndarray) -> np.ndarray:
    """(N, 3) -> (N, 3): points transformed by a 4x4 matrix."""
    return points @ m[:3, :3].T + m[:3, 3]


def ransac_plane(points: np.ndarray, threshold: float = 0.03, iterations: int = 300,
                 normal_hint=(0.0, 0.0, 1.0), max_tilt_deg: float = 30.0,
                 seed: int = 0) -> tuple[np.ndarray, float, np.ndarray]:
    """The plane n·p + d = 0 with the most points within ``threshold`` (m), its normal
    within ``max_tilt_deg`` of ``normal_hint`` (n is turned to agree with the hint).

    Returns (n (3,) unit, d, inlier mask (N,)). Refined by least squares on the inliers.
    Raises ValueError if no such plane has 3 inliers."""
    rng = np.random.default_rng(seed)
    hint = np.asarray(normal_hint, float)
    hint /= np.linalg.norm(hint)
    cos_tilt = np.cos(np.radians(max_tilt_deg))
    sample = points if len(points) <= 200_000 else points[rng.choice(len(points), 200_000, replace=False)]
    best, best_n, best_d = -1, None, 0.0
    for _ in range(iterations):
        a, b, c = sample[rng.choice(len(sample), 3, replace=False)]
        n = np.cross(b - a, c - a)
        norm = np.linalg.norm(n)
        if norm < 1e-12:
            continue
        n /= norm
        if n @ hint < 0:
            n = -n
        if n @ hint < cos_tilt:
            continue
        d = -n @ a
        count = int(np.count_nonzero(np.abs(sample @ n + d) < threshold))
        if count > best:
            best, best_n, best_d = count, n, d
    if best_n is None or best < 3:
        raise ValueError("no plane found")
    inl = np.abs(points @ best_n + best_d) < threshold
    q = points[inl]
    centre = q.mean(axis=0)
    _, _, vt = np.linalg.svd(q - centre, full_matrices=False)
    n = vt[2] if vt[2] @ hint >= 0 else -vt[2]
    d = -n @ centre
    return n, float(d), np.abs(points @ n + d) < threshold


def level_floor_matrix(points: np.ndarray, up: str = "+z", threshold: float = 0.03,
                       seed: int = 0) -> tuple[np.ndarray, dict]:
    """4x4 rigid transform making the dominant floor plane z = 0 with +z up.

    The floor is the largest plane (RANSAC) whose normal is within 30° of ``up``, among
    the lowest 40 % of points along ``up`` (so the ceiling is not taken), on the cloud
    thinned to one point per 0.1 m voxel so that large planes win over dense near ones."""
    hint = np.asarray(UP_AXES[up], float)
    even = voxel_downsample(points, 0.1)  # even density: a plane's count ~ its area, not its nearness
    h = even @ hint
    low = even[h <= np.quantile(h, 0.4)]
    n, d, _ = ransac_plane(low, max(threshold, 0.05), iterations=500, normal_hint=hint, seed=seed)
    z = np.array([0.0, 0.0, 1.0])
    rot, _ = Rotation.align_vectors([z], [n])
    R = rot.as_matrix()
    m = np.eye(4)
    m[:3, :3] = R
    m[2, 3] = d  # a floor point p has n·p = -d; after rotation its z is -d
    inliers = int(np.count_nonzero(np.abs(points @ n + d) < threshold))
    tilt = float(np.degrees(np.arccos(np.clip(n @ hint, -1, 1))))
    return m, {"floor_normal": [round(float(v), 5) for v in n], "tilt_deg": round(tilt, 3),
               "floor_offset_m": round(float(-d), 4), "floor_inliers": inliers}


def clean_cloud(cloud: PointCloud, scale: float = 1.0, rotate_deg=(0.0, 0.0, 0.0), translate=(0.0, 0.0, 0.0),
                level_floor: bool = False, up: str = "+z", crop: tuple | None = None,
                downsample: float | None = None, outliers: tuple[int, float] | None = None) -> tuple[PointCloud, list[dict]]:
    """Run the clean-up steps asked for; returns the cleaned cloud (viewpoints moved by
    the same transform) and a report: one dict per step with the points in and out."""
    p, vp = cloud.points, cloud.viewpoints
    report: list[dict] = []
    if scale != 1.0 or any(rotate_deg) or any(translate):
        m = rigid_matrix(scale, rotate_deg, translate)
        p, vp = apply_matrix(p, m), apply_matrix(vp, m)
        report.append({"step": "transform", "scale": scale, "rotate_deg": list(rotate_deg),
                       "translate": list(translate), "points": len(p)})
    if level_floor:
        try:
            m, info = level_floor_matrix(p, up)
        except ValueError:
            from camplace.core.errors import InputError

            raise InputError(f"{cloud.info.get('path', '<cloud>')}: level_floor: no floor plane found "
                             f"(no plane within 30° of '{up}' up); give a transform instead") from None
        p, vp = apply_matrix(p, m), apply_matrix(vp, m)
        report.append({"step": "level_floor", **info, "matrix": m.tolist(), "points": len(p)})  # scene.frames
    if crop is not None:
        keep = crop_mask(p, crop[0], crop[1])
        report.append({"step": "crop", "min": list(crop[0]), "max": list(crop[1]),
                       "points_in": len(p), "points": int(keep.sum())})
        p = p[keep]
    if downsample:
        n_in = len(p)
        p = voxel_downsample(p, downsample)
        report.append({"step": "downsample", "voxel_m": downsample, "points_in": n_in, "points": len(p)})
    if outliers is not None:
        keep = remove_outliers(p, int(outliers[0]), float(outliers[1]))
        report.append({"step": "remove_outliers", "neighbors": int(outliers[0]), "std_ratio": float(outliers[1]),
                       "points_in": len(p), "points": int(keep.sum())})
        p = p[keep]
    return PointCloud(p, vp, dict(cloud.info, points=len(p))), report
