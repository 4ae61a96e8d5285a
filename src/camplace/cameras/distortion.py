"""The numpy side of the lens models' distortion (camplace.cameras.models): OpenCV
radial-tangential and fisheye (Kannala-Brandt) mappings, their inverses by Newton
iteration, and the largest radius up to which a mapping is monotonic."""

from __future__ import annotations

import numpy as np


def opencv_distort(x: np.ndarray, y: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normalized undistorted (x, y) -> distorted, OpenCV radial-tangential (d: 8 coefficients)."""
    k1, k2, p1, p2, k3, k4, k5, k6 = d
    r2 = x * x + y * y
    radial = (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)))
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return xd, yd


def fisheye_theta_d(theta: np.ndarray, d: np.ndarray) -> np.ndarray:
    t2 = theta * theta
    return theta * (1 + t2 * (d[0] + t2 * (d[1] + t2 * (d[2] + t2 * d[3]))))


def monotonic_limit(f, hi: float, n: int = 20000) -> float:
    """Largest s in (0, hi] such that f is increasing on [0, s] (sampled)."""
    s = np.linspace(0.0, hi, n + 1)
    v = f(s)
    bad = np.nonzero(np.diff(v) <= 0)[0]
    return float(hi if len(bad) == 0 else s[bad[0]])


def opencv_undistort(xd: np.ndarray, yd: np.ndarray, d: np.ndarray, limit: float,
                      iters: int = 30) -> tuple[np.ndarray, np.ndarray]:
    """Invert the OpenCV distortion by damped Newton steps (numerical 2x2 Jacobian)."""
    x, y = xd.copy(), yd.copy()
    h = 1e-7
    for _ in range(iters):
        fx_, fy_ = opencv_distort(x, y, d)
        ex, ey = fx_ - xd, fy_ - yd
        if np.all(np.abs(ex) + np.abs(ey) < 1e-14):
            break
        ax, ay = opencv_distort(x + h, y, d)
        bx, by = opencv_distort(x, y + h, d)
        j11, j21 = (ax - fx_) / h, (ay - fy_) / h
        j12, j22 = (bx - fx_) / h, (by - fy_) / h
        det = j11 * j22 - j12 * j21
        det = np.where(np.abs(det) < 1e-12, 1e-12, det)
        dx = (j22 * ex - j12 * ey) / det
        dy = (-j21 * ex + j11 * ey) / det
        x, y = x - dx, y - dy
        r = np.hypot(x, y)
        shrink = np.where(r > limit, limit / np.where(r > 0, r, 1.0), 1.0)
        x, y = x * shrink, y * shrink
    return x, y


def fisheye_undistort_theta(rd: np.ndarray, d: np.ndarray, limit: float, iters: int = 30) -> np.ndarray:
    """theta with theta_d(theta) = rd, by Newton's method, clamped to [0, limit]."""
    theta = np.clip(rd, 0.0, limit)
    for _ in range(iters):
        t2 = theta * theta
        f = fisheye_theta_d(theta, d) - rd
        df = 1 + t2 * (3 * d[0] + t2 * (5 * d[1] + t2 * (7 * d[2] + t2 * 9 * d[3])))
        step = f / np.where(np.abs(df) < 1e-12, 1e-12, df)
        theta = np.clip(theta - step, 0.0, limit)
        if np.all(np.abs(step) < 1e-15):
            break
    return theta
