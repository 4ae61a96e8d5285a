"""The shapes of a camera in cameras.ifc, as triangle meshes in the camera's own frame
(metres; OpenCV axes: x right, y down, z forward, the optical centre at the origin): a
small box for the body and, on request, the viewing frustum (a pyramid from the optical
centre to the image corners at the camera's range). Pure numpy; the writer turns them
into IFC geometry (camplace.outputs.cameras_ifc).
"""

from __future__ import annotations

import numpy as np

from camplace.cameras.models import CameraModel

BODY_M = (0.12, 0.10, 0.20)  # width (x), height (y), depth (z) of the body box, m
BODY_FRONT_M = 0.02  # how far the box reaches in front of the optical centre, m

# a box's 12 triangles over the corners numbered by bits (x, y, z) = (i & 1, i & 2, i & 4), outward
_BOX_FACES = [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
              [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]]


def body_mesh(size_m: tuple[float, float, float] = BODY_M) -> tuple[np.ndarray, list[list[int]]]:
    """(vertices (8, 3) m, 12 triangles) of the body box: centred on the optical axis, from
    ``BODY_FRONT_M`` in front of the optical centre back to its depth behind it."""
    w, h, d = size_m
    i = np.arange(8)
    v = np.c_[np.where(i & 1, w / 2, -w / 2), np.where(i & 2, h / 2, -h / 2),
              np.where(i & 4, BODY_FRONT_M, BODY_FRONT_M - d)]
    return v.astype(float), [list(f) for f in _BOX_FACES]


def camera_model(entry: dict) -> CameraModel:
    """The CameraModel of a placement.json camera entry (its ``intrinsics``)."""
    k = entry["intrinsics"]
    return CameraModel.from_intrinsics(str(entry.get("camera", "camera")), str(k.get("model", "pinhole")),
                                       (int(k["width"]), int(k["height"])), float(k["fx"]), float(k["fy"]),
                                       float(k["cx"]), float(k["cy"]), tuple(k.get("distortion") or ()))


def frustum_mesh(camera: CameraModel, range_m: float) -> tuple[np.ndarray, list[list[int]]]:
    """(vertices (5, 3) m, 6 triangles) of the viewing pyramid: the optical centre and the
    rays through the four image corners (pixel edges, distortion inverted), each ``range_m``
    long; a ray at or beyond 90° off axis (a wide fisheye) is held 1° in front of the
    image plane so the pyramid stays closed and convex."""
    w, h = camera.width, camera.height
    rays = camera.unproject(np.array([[-0.5, -0.5], [w - 0.5, -0.5], [w - 0.5, h - 0.5], [-0.5, h - 0.5]]))
    side = np.hypot(rays[:, 0], rays[:, 1])
    z_min = np.sin(np.radians(1.0))
    low = rays[:, 2] < z_min
    if low.any():
        scale = np.sqrt(1.0 - z_min ** 2) / np.maximum(side[low], 1e-12)
        rays[low] = np.c_[rays[low, 0] * scale, rays[low, 1] * scale, np.full(low.sum(), z_min)]
    rays /= np.linalg.norm(rays, axis=1, keepdims=True)
    v = np.vstack([np.zeros(3), rays * float(range_m)])
    # corners 1..4 run clockwise seen from the camera in image axes (x right, y down): outward normals
    faces = [[0, 2, 1], [0, 3, 2], [0, 4, 3], [0, 1, 4], [1, 2, 3], [1, 3, 4]]
    return v, faces


def frustum_range(entry: dict, default_m: float = 5.0) -> float:
    """The frustum's length (m) for a camera entry: its ``range_m``, else its farthest DORI
    distance (``dori_m``), else ``default_m``."""
    if entry.get("range_m"):
        return float(entry["range_m"])
    dori = [float(v) for v in (entry.get("dori_m") or {}).values() if v]
    return max(dori) if dori else float(default_m)


def pose_matrix(position, rotation) -> np.ndarray:
    """(4, 4) world-from-camera matrix of a pose: rotation (3, 3) columns = camera axes in
    world, position (3,) m."""
    m = np.eye(4)
    m[:3, :3] = np.asarray(rotation, float)
    m[:3, 3] = np.asarray(position, float)
    return m
