"""Frames: the scene frame a scene is built in, and the frame of the file it came from.

A scene read from a file (scan, mesh, OctoMap) is built in the **scene frame**: the
file's points moved by the obstacle's ``transform`` keys (scale, rotate_deg, translate:
camplace.spec.schema.CloudTransform, what ``scene_from_cloud`` writes after levelling
the floor) and, with ``transform.level_floor: true``, by the floor levelling found when
the cloud is loaded. The **input frame** is the file's own frame.

Convention, everywhere in camplace: ``input_from_scene`` is a 4x4 float64 matrix T with

    p_input = T @ [p_scene, 1]      (homogeneous; metres in the scene frame)

so its inverse maps the file's points into the scene: p_scene = T⁻¹ @ [p_file, 1]. It is
a rigid transform (rotation + translation) unless the obstacle scales the file
(``transform.scale`` s ≠ 1, e.g. a scan in millimetres): then its 3x3 block is R / s.
A camera's world-from-camera rotation maps with the rotation part only
(``rotation_part``). For a scene of box obstacles only, T is the identity.

Which file defines the input frame: the first file obstacle (``point_cloud``, ``mesh``
or ``octomap``, in the scene file's order); its transform (none: identity) gives T.
Other file obstacles may carry other transforms; they do not change T.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from camplace.scene.loaders.cleanup import rigid_matrix
from camplace.spec.schema import CloudTransform, SceneSpec


def scene_from_file(transform: CloudTransform | None, level: np.ndarray | None = None) -> np.ndarray:
    """4x4 M with p_scene = M @ [p_file, 1]: the transform keys (p -> R·(s·p) + t,
    camplace.scene.loaders.cleanup.rigid_matrix), then ``level`` (4x4, the floor
    levelling of ``level_floor: true``) when given."""
    m = np.eye(4) if transform is None else rigid_matrix(transform.scale, transform.rotate_deg, transform.translate)
    return m if level is None else np.asarray(level, np.float64) @ m


def invert(T: np.ndarray) -> np.ndarray:
    """Inverse of a 4x4 similarity (s·R, t) in closed form (exact transpose for rotations)."""
    T = np.asarray(T, np.float64)
    A, t = T[:3, :3], T[:3, 3]
    s2 = float(np.cbrt(np.linalg.det(A))) ** 2
    out = np.eye(4)
    out[:3, :3] = A.T / s2
    out[:3, 3] = -out[:3, :3] @ t
    return out


def rotation_part(T: np.ndarray) -> np.ndarray:
    """The 3x3 rotation of a 4x4 similarity (its scale divided out)."""
    A = np.asarray(T, np.float64)[:3, :3]
    return A / float(np.cbrt(np.linalg.det(A)))


def map_poses(T: np.ndarray, positions: np.ndarray, rotations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Poses moved by the 4x4 T: positions (N, 3) -> T @ [p, 1]; world-from-camera
    rotations (N, 3, 3) -> rotation_part(T) @ R (camera axes stay OpenCV's)."""
    T = np.asarray(T, np.float64)
    p = np.asarray(positions, np.float64).reshape(-1, 3) @ T[:3, :3].T + T[:3, 3]
    R = np.einsum("ij,njk->nik", rotation_part(T), np.asarray(rotations, np.float64).reshape(-1, 3, 3))
    return p, R


def level_matrix(report: Mapping | None) -> np.ndarray | None:
    """The 4x4 floor levelling a loaded point cloud reported (its ``cleanup`` step
    ``level_floor``, key ``matrix``), or None when it was not levelled."""
    for step in (report or {}).get("cleanup", ()):
        if step.get("step") == "level_floor" and "matrix" in step:
            return np.asarray(step["matrix"], np.float64)
    return None


def input_from_scene(spec: SceneSpec, obstacle_reports: Mapping[str, Mapping] | None = None) -> np.ndarray:
    """4x4 float64 T, p_input = T @ [p_scene, 1]: the inverse of the first file
    obstacle's scene_from_file (identity without file obstacles). ``obstacle_reports``:
    obstacle name -> its load report (Scene.info['obstacle_files']), for the floor
    levelling of ``transform.level_floor: true``."""
    for ob in spec.obstacles:
        if ob.is_file:
            level = level_matrix((obstacle_reports or {}).get(ob.name))
            return invert(scene_from_file(ob.transform, level))
    return np.eye(4)
