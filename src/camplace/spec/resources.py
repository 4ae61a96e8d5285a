"""Resource estimates of a scene, from the spec alone: the occupancy grid, target and
candidate sizes, checked against the memory limit (camplace.core.memory) before anything
is allocated."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from camplace.core.memory import format_bytes, memory_error, memory_limit_bytes
from camplace.spec.schema import AngleRange, SceneSpec


# bytes per item, measured roughly on the stage code (arrays + temporaries)
BYTES_PER_OCC_CELL = 1.0  # bool grid
BYTES_PER_OCC_COLUMN = 40.0  # 2D meshgrid + inside test over x, y
BYTES_PER_TARGET = 160.0  # positions, normals, gamma, weights, region ids, masks, visibility inputs
BYTES_PER_TARGET_GRID_CELL = 40.0  # xy meshgrid of the volume grid
BYTES_PER_CANDIDATE = 500.0  # positions, angles, rotations (+ temporaries), ids, visibility counts


@dataclass(frozen=True)
class ResourceEstimate:
    """Sizes a scene will allocate, computed from the spec alone (nothing allocated).
    Each ``items`` entry: (key path to blame, what, count, bytes)."""

    items: tuple[tuple[str, str, float, float], ...]

    @property
    def total_bytes(self) -> float:
        return float(sum(it[3] for it in self.items))

    def count(self, what: str) -> float:
        return float(sum(it[2] for it in self.items if it[1] == what))


def _n_angles(a: Any) -> int:
    if isinstance(a, AngleRange):
        return a.count()
    if isinstance(a, (list, tuple)):
        return len(a)
    return 1


def estimate_resources(spec: SceneSpec) -> ResourceEstimate:
    """Upper estimates of the occupancy grid, target and candidate sizes of a scene."""
    fp = [tuple(map(float, p)) for p in spec.room.footprint]
    w = max(p[0] for p in fp) - min(p[0] for p in fp)
    d = max(p[1] for p in fp) - min(p[1] for p in fp)
    H = float(spec.room.height)
    items: list[tuple[str, str, float, float]] = []
    r = float(spec.occupancy_resolution)
    nx, ny, nz = (math.ceil(e / r) + 2 for e in (w, d, H))
    cells = float(nx) * ny * nz
    items.append(("occupancy_resolution", "occupancy cells", cells,
                  cells * BYTES_PER_OCC_CELL + float(nx) * ny * BYTES_PER_OCC_COLUMN))
    v = float(spec.voxel_size)
    grid_xy = float(math.floor(w / v) + 1) * float(math.floor(d / v) + 1)
    boxes = {o.name: o.box for o in spec.obstacles if getattr(o, "box", None) is not None}
    for i, t in enumerate(spec.targets):
        if t.kind == "volume":
            n = grid_xy * len(t.heights or [])
            items.append((f"targets[{i}]", "targets", n, n * BYTES_PER_TARGET + grid_xy * BYTES_PER_TARGET_GRID_CELL))
        else:
            n = 0.0
            for name in t.of or []:
                b = boxes.get(name)
                if b is None:
                    continue
                ext = [hi - lo for lo, hi in zip(b.min, b.max)]
                for a in range(3):
                    u, q = [k for k in range(3) if k != a]
                    n += 2 * (math.ceil(ext[u] / v) + 1) * (math.ceil(ext[q] / v) + 1)
            items.append((f"targets[{i}]", "targets", n, n * BYTES_PER_TARGET))
    for i, m in enumerate(spec.mounts):
        spacing = getattr(m, "spacing", None)
        if not spacing:
            continue
        if getattr(m, "kind", "") == "ceiling_grid":
            pts = float(math.floor(w / spacing) + 1) * float(math.floor(d / spacing) + 1)
        else:  # wall or other mounts: along the walls (given segments or the footprint's edges)
            segs = getattr(m, "walls", None) or [(fp[k], fp[(k + 1) % len(fp)]) for k in range(len(fp))]
            pts = sum(math.dist(a, b) / spacing + 1 for a, b in segs)
        n = pts * _n_angles(getattr(m, "yaw_deg", 1)) * _n_angles(getattr(m, "pitch_deg", 1)) * \
            _n_angles(getattr(m, "roll_deg", 1)) * _n_settings(spec, m)
        items.append((f"mounts[{i}]", "candidates", n, n * BYTES_PER_CANDIDATE))
    return ResourceEstimate(tuple(items))


def _n_settings(spec, mount) -> int:
    """Camera models a pose of ``mount`` carries: per camera type, its focal settings (issue 27)."""
    kinds = {c.name: c for c in getattr(spec, "cameras", [])}
    names = getattr(mount, "camera_names", None) or [getattr(mount, "camera", None)]
    return max(sum(kinds[n].n_settings if n in kinds else 1 for n in names), 1)


def check_resources(spec: SceneSpec, source: str, limit_bytes: int | None = None) -> ResourceEstimate:
    """Refuse (InputError, with the numbers; option ``max_memory_bytes``) a scene whose grids
    would not fit in ``limit_bytes`` (default: camplace.core.memory.memory_limit_bytes()),
    before anything is allocated."""
    limit = memory_limit_bytes() if limit_bytes is None else int(limit_bytes)
    est = estimate_resources(spec)
    fix = {"occupancy_resolution": "use a coarser occupancy_resolution",
           "targets": "use a coarser voxel_size or fewer heights", "mounts": "use a larger spacing or fewer angles"}
    for path, what, n, b in sorted(est.items, key=lambda it: -it[3]):
        if b > limit:
            key = path if path == "occupancy_resolution" else (
                "voxel_size" if path.startswith("targets") else path + ".spacing")
            value = {"occupancy_resolution": spec.occupancy_resolution, "voxel_size": spec.voxel_size}.get(key)
            shown = f" {value} m" if value is not None else ""
            raise memory_error(f"{source}: {key}:{shown}", b, limit, fix[path.split('[')[0]], items=f"{n:.3g} {what}")
    if est.total_bytes > limit:
        parts = ", ".join(f"{p}: {format_bytes(b)}" for p, _, _, b in sorted(est.items, key=lambda it: -it[3])[:3])
        raise memory_error(f"{source}: the scene", est.total_bytes, limit, f"use coarser grids ({parts})")
    return est
