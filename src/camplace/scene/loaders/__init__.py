"""Readers and writers for real spaces: point clouds, meshes and OctoMaps.

One small module per input kind (``pointcloud``, ``mesh``, ``octomap``) plus
``cleanup`` (the optional scan clean-up steps). Every reader raises
:class:`camplace.core.errors.InputError` with one line naming the file for a missing,
empty or corrupt input. Nothing here prints; progress goes through a callback
``progress(stage, done, total)``.
"""

from __future__ import annotations

from typing import Callable, Iterator

Progress = Callable[[str, int, int], None]

POINT_CLOUD_SUFFIXES = (".ply", ".pcd", ".xyz", ".csv", ".txt", ".pts", ".las", ".laz")
MESH_SUFFIXES = (".obj", ".ply", ".stl", ".glb", ".gltf", ".off")
OCTOMAP_SUFFIXES = (".bt", ".ot")


def header_lines(raw: bytes) -> Iterator[tuple[str, int]]:
    """The lines of a text header at the start of ``raw`` (ASCII, stripped), each with the
    byte offset just past its newline; stops at the first line without a newline (the
    caller then says which line the header lacks)."""
    pos = 0
    while True:
        end = raw.find(b"\n", pos)
        if end < 0:
            return
        line = raw[pos:end].decode("ascii", "replace").strip()
        pos = end + 1
        yield line, pos
