"""Camera lens models, in the OpenCV camera frame (x right, y down, z forward).

Pixel convention (OpenCV): pixel (i, j) has its centre at (u, v) = (i, j); the image
spans u in [-0.5, W - 0.5], v in [-0.5, H - 0.5]. ``fov_deg`` is the full angle
between the outer edges of the outer pixels.

Each model also packs into a flat float64 parameter vector (``params``) that the
compiled visibility kernels read; ``project_nb`` is the kernel-side projection.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

MODEL_CODES = {"pinhole": 0}
N_PARAMS = 16  # [model, W, H, fx, fy, cx, cy, max_range, d0..d7]


@dataclass(frozen=True)
class CameraModel:
    """A lens + sensor. width/height: pixels; fx, fy, cx, cy: pixels; max_range: m."""

    name: str
    model: str
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    max_range: float = 5.0
    distortion: tuple[float, ...] = field(default_factory=tuple)
    cost: float = 1.0

    @classmethod
    def pinhole_from_fov(cls, name: str, resolution: tuple[int, int], fov_deg: tuple[float, float],
                         max_range: float = 5.0, cost: float = 1.0) -> "CameraModel":
        w, h = int(resolution[0]), int(resolution[1])
        fx = (w / 2.0) / math.tan(math.radians(fov_deg[0]) / 2.0)
        fy = (h / 2.0) / math.tan(math.radians(fov_deg[1]) / 2.0)
        return cls(name, "pinhole", w, h, fx, fy, (w - 1) / 2.0, (h - 1) / 2.0, float(max_range), (), float(cost))

    @property
    def fov_deg(self) -> tuple[float, float]:
        """Full horizontal and vertical field of view (degrees), pinhole."""
        return (math.degrees(2 * math.atan((self.width / 2) / self.fx)),
                math.degrees(2 * math.atan((self.height / 2) / self.fy)))

    @property
    def params(self) -> np.ndarray:
        p = np.zeros(N_PARAMS, dtype=np.float64)
        p[:8] = [MODEL_CODES[self.model], self.width, self.height, self.fx, self.fy, self.cx, self.cy, self.max_range]
        d = np.asarray(self.distortion, float)[:8]
        p[8:8 + len(d)] = d
        return p

    def intrinsics(self) -> dict:
        """The ``intrinsics`` object of placement.json."""
        out = {"model": self.model, "width": self.width, "height": self.height,
               "fx": self.fx, "fy": self.fy, "cx": self.cx, "cy": self.cy}
        if self.distortion:
            out["distortion"] = list(self.distortion)
        return out

    def project(self, points_cam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """points_cam: (N, 3) camera-frame metres -> (uv (N, 2) pixels, valid (N,) bool).

        valid = in front of the camera and inside the image (range is not checked here)."""
        p = np.asarray(points_cam, float).reshape(-1, 3)
        z = p[:, 2]
        front = z > 1e-12
        zs = np.where(front, z, 1.0)
        u = self.fx * p[:, 0] / zs + self.cx
        v = self.fy * p[:, 1] / zs + self.cy
        valid = front & (u >= -0.5) & (u <= self.width - 0.5) & (v >= -0.5) & (v <= self.height - 0.5)
        return np.c_[u, v], valid

    def unproject(self, uv: np.ndarray) -> np.ndarray:
        """uv: (N, 2) pixels -> (N, 3) unit rays in the camera frame."""
        uv = np.asarray(uv, float).reshape(-1, 2)
        d = np.c_[(uv[:, 0] - self.cx) / self.fx, (uv[:, 1] - self.cy) / self.fy, np.ones(len(uv))]
        return d / np.linalg.norm(d, axis=1, keepdims=True)


@numba.njit(cache=True, inline="always")
def project_nb(params: np.ndarray, x: float, y: float, z: float) -> tuple[float, float, bool]:
    """Kernel-side projection of one camera-frame point: (u, v, inside-image)."""
    if z <= 1e-12:
        return 0.0, 0.0, False
    u = params[3] * x / z + params[5]
    v = params[4] * y / z + params[6]
    ok = (u >= -0.5) and (u <= params[1] - 0.5) and (v >= -0.5) and (v <= params[2] - 0.5)
    return u, v, ok


def camera_from_spec(spec) -> CameraModel:
    """Build a CameraModel from a validated ``cameras[i]`` entry of the scene file."""
    return CameraModel.pinhole_from_fov(spec.name, spec.resolution, spec.fov_deg, spec.max_range, spec.cost)
