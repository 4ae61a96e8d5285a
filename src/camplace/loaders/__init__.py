"""Readers and writers for real spaces: point clouds, meshes and OctoMaps.

One small module per input kind (``pointcloud``, ``mesh``, ``octomap``) plus
``cleanup`` (the optional scan clean-up steps). Every reader raises
:class:`camplace.errors.InputError` with one line naming the file for a missing,
empty or corrupt input. Nothing here prints; progress goes through a callback
``progress(stage, done, total)``.
"""

from __future__ import annotations

from typing import Callable

Progress = Callable[[str, int, int], None]

POINT_CLOUD_SUFFIXES = (".ply", ".pcd", ".xyz", ".csv", ".txt", ".pts", ".las", ".laz")
MESH_SUFFIXES = (".obj", ".ply", ".stl", ".glb", ".gltf", ".off")
OCTOMAP_SUFFIXES = (".bt", ".ot")
