"""``frustum``: visibility without occlusion - a target is seen when it lies within
``range_scale`` x the camera's range and inside its image (and, for a surface target, in
front of its face). Nothing blocks a sight line, so V is an upper bound of the voxel
engine's V: a quick what-if for an empty room, or a bound on what any placement can see.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

from camplace.core.errors import InputError


@dataclass(frozen=True)
class FrustumEngine:
    """Range and image tests only, no occlusion (see the module docstring). range_scale:
    fraction of each camera's max_range that counts (0, 1]; chunk_size: candidate rows per block."""

    range_scale: float = 1.0
    chunk_size: int = 256
    mode = "frustum"

    def __post_init__(self) -> None:
        if not 0.0 < float(self.range_scale) <= 1.0:
            raise InputError(f"range_scale: expected a fraction in (0, 1], got {self.range_scale}",
                             option="range_scale")
        if int(self.chunk_size) < 1:
            raise InputError(f"chunk_size: expected a positive integer, got {self.chunk_size}", option="chunk_size")

    def cache_tag(self) -> str:
        return f"frustum:range_scale={float(self.range_scale)!r}"

    def code_modules(self) -> tuple:
        return (sys.modules[__name__],)

    def setup(self, occupancy, targets, candidates) -> tuple:
        return targets.positions, targets.normals, candidates

    def rows(self, shared: tuple, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
        pts, normals, cands = shared
        surface = np.any(normals != 0, axis=1)
        counts, indices = [], []
        for i in range(start, stop):
            cam = cands.cameras[int(cands.camera_ids[i])]
            d = pts - cands.positions[i]
            _, inside = cam.project(d @ cands.rotations[i])  # camera frame: R^T d
            near = np.einsum("ij,ij->i", d, d) <= (self.range_scale * cam.max_range) ** 2
            facing = ~surface | (np.einsum("ij,ij->i", d, normals) < 0)
            seen = np.flatnonzero(inside & near & facing).astype(np.int32)
            counts.append(len(seen))
            indices.append(seen)
        indptr = np.r_[0, np.cumsum(counts)].astype(np.int64)
        return indptr, (np.concatenate(indices) if indices else np.zeros(0, np.int32))

    def info(self, candidates, bounds, computed, seconds, shared) -> dict:
        return {"range_scale": float(self.range_scale)}
