"""Stage 2 - targets: the N_p points that must be seen, with their required coverage.

``volume`` regions are free-space voxel centres of the walkable area at given heights;
``surface`` regions are voxel-sized patches on named obstacles' faces, with outward
normals and an incidence-angle limit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from camplace.spec.schema import TargetRegion
from camplace.core.errors import InputError
from camplace.scene.build import Scene
from camplace.targets.zones import in_polygon, keep_mask, layer_points, privacy_heights, zone_region

FACE_AXES = {"+x": (0, 1.0), "-x": (0, -1.0), "+y": (1, 1.0), "-y": (1, -1.0), "+z": (2, 1.0), "-z": (2, -1.0)}
DEFAULT_FACES = ("+x", "-x", "+y", "-y")


@dataclass(frozen=True)
class Targets:
    """positions: (N, 3) float64 m; normals: (N, 3) float64 unit outward normal, zeros
    for volume targets; gamma: (N,) int64 required coverage Γ; weights: (N,) float64;
    region_ids: (N,) int32 index into region_names; max_incidence_deg: (R,) per region;
    voxel_size: the target voxel edge (m, the scene's ``voxel_size``: the cell each target
    stands for, which a visibility engine's probe rule reads; None when unknown)."""

    positions: np.ndarray
    normals: np.ndarray
    gamma: np.ndarray
    weights: np.ndarray
    region_ids: np.ndarray
    region_names: tuple[str, ...]
    region_kinds: tuple[str, ...]
    max_incidence_deg: np.ndarray
    min_px_per_m: np.ndarray | None = None  # (R,) px/m per region, 0 = no limit (issue 4)
    voxel_size: float | None = None

    def __len__(self) -> int:
        return len(self.positions)

    @property
    def is_surface(self) -> np.ndarray:
        """(N,) bool: True for surface targets."""
        return np.any(self.normals != 0, axis=1)


def volume_targets(scene: Scene, region: TargetRegion) -> np.ndarray:
    """Free-space voxel centres inside the footprint at each height: (M, 3) metres."""
    return layer_points(scene, region.heights)


def surface_targets(scene: Scene, region: TargetRegion) -> tuple[np.ndarray, np.ndarray]:
    """Patches of size <= voxel_size on the named boxes' faces.

    Returns (positions (M, 3), outward normals (M, 3)). Patches whose outside is
    occupied (a face against a wall or another obstacle) are dropped.
    """
    v = float(scene.spec.voxel_size)
    pos, nrm = [], []
    for name in region.of or []:
        if name not in scene.boxes:
            raise InputError(f"targets '{region.name}': obstacle '{name}' has no box to put surface targets on")
        bmin, bmax = scene.boxes[name]
        for face in region.faces or DEFAULT_FACES:
            axis, sign = FACE_AXES[face]
            u, w = [a for a in range(3) if a != axis]
            # clip the face to the room (a box may poke through the ceiling or floor)
            lo = bmin.copy()
            hi = bmax.copy()
            lo[2], hi[2] = max(lo[2], 0.0), min(hi[2], scene.height)
            if hi[u] <= lo[u] or hi[w] <= lo[w]:
                continue
            nu, nw = (max(1, int(np.ceil((hi[a] - lo[a]) / v - 1e-9))) for a in (u, w))
            cu = lo[u] + (np.arange(nu) + 0.5) * (hi[u] - lo[u]) / nu
            cw = lo[w] + (np.arange(nw) + 0.5) * (hi[w] - lo[w]) / nw
            gu, gw = np.meshgrid(cu, cw, indexing="ij")
            p = np.zeros((gu.size, 3))
            p[:, u], p[:, w] = gu.ravel(), gw.ravel()
            p[:, axis] = bmax[axis] if sign > 0 else bmin[axis]
            n = np.zeros_like(p)
            n[:, axis] = sign
            pos.append(p)
            nrm.append(n)
    if not pos:
        return np.zeros((0, 3)), np.zeros((0, 3))
    p, n = np.concatenate(pos), np.concatenate(nrm)
    labels = {o.name for o in scene.spec.obstacles if not o.occludes}
    if labels & set(region.of or []):  # labelled boxes on a scan: step out of the scanned shell
        from camplace.scene.from_scan import snap_outward

        p, keep = snap_outward(scene.occupancy, p, n)
        return p[keep], n[keep]
    outside = p + n * 0.75 * scene.occupancy.resolution
    keep = ~scene.occupancy.is_occupied(outside)
    return p[keep], n[keep]


def stack_targets(parts: list[Targets], storeys, prefix: bool = True) -> Targets:
    """The targets of each storey (local z) as one set in building z: positions raised by
    each storey's elevation, regions named 'Storey/region', a storey's targets over its own
    floor openings (no floor there) dropped."""
    pos, keep_parts, names, offset, rid = [], [], [], 0, []
    for t, st in zip(parts, storeys):
        keep = np.ones(len(t), bool)
        for hole in st.openings:
            keep &= ~in_polygon(list(hole.exterior.coords), t.positions[:, :2])
        keep_parts.append(keep)
        pos.append(t.positions[keep] + [0.0, 0.0, st.elevation])
        rid.append(t.region_ids[keep] + offset)
        names.extend(f"{st.name}/{n}" if prefix else n for n in t.region_names)
        offset += len(t.region_names)
    cat = lambda attr: np.concatenate([getattr(t, attr)[k] for t, k in zip(parts, keep_parts)])  # noqa: E731
    return Targets(np.concatenate(pos), cat("normals"), cat("gamma"), cat("weights"),
                   np.concatenate(rid).astype(np.int32), tuple(names),
                   tuple(k for t in parts for k in t.region_kinds),
                   np.concatenate([t.max_incidence_deg for t in parts]),
                   np.concatenate([np.zeros(len(t.region_names)) if t.min_px_per_m is None else t.min_px_per_m
                                   for t in parts]), parts[0].voxel_size)


def build_targets(scene: Scene) -> Targets:
    """All target regions of the scene, in the order of ``scene.spec.targets``, then one
    region per non-privacy zone (camplace.targets.zones: zones replace the volume targets
    inside their polygons, later zones win). A building: every storey's, stacked
    (stack_targets)."""
    if scene.storeys:
        return stack_targets([build_targets(st.scene) for st in scene.storeys], scene.storeys)
    pos, nrm, gam, wts, rid = [], [], [], [], []
    zones = scene.spec.zones
    regions = list(scene.spec.targets) + [zone_region(z, scene.spec) for z in zones if not z.privacy]
    for r, region in enumerate(regions):
        if region.kind == "volume":
            p = volume_targets(scene, region)
            n = np.zeros_like(p)
        elif region.box is not None:
            from camplace.scene.from_scan import scan_surface_targets

            p, n = scan_surface_targets(scene, region.box.min, region.box.max)
        else:
            p, n = surface_targets(scene, region)
        if zones:
            keep = keep_mask(scene, r, p)
            p, n = p[keep], n[keep]
        pos.append(p)
        nrm.append(n)
        gam.append(np.full(len(p), region.coverage, dtype=np.int64))
        wts.append(np.full(len(p), region.weight, dtype=np.float64))
        rid.append(np.full(len(p), r, dtype=np.int32))
    t = Targets(
        np.concatenate(pos), np.concatenate(nrm), np.concatenate(gam), np.concatenate(wts), np.concatenate(rid),
        tuple(r.name for r in regions), tuple(r.kind for r in regions),
        np.array([r.max_incidence_deg for r in regions], dtype=np.float64),
        np.array([r.min_px_per_m_value for r in regions], dtype=np.float64), float(scene.spec.voxel_size),
    )
    if len(t) == 0:
        raise InputError(f"scene '{scene.name}': targets: no target point lies in free space inside the room")
    return t


def privacy_targets(scene: Scene) -> Targets | None:
    """The points of the privacy zones (one region per zone; at the zone's heights, default
    every voxel centre from floor to ceiling; free space only), or None without privacy
    zones. Never part of the cost: the visibility step removes every candidate that sees one."""
    if scene.storeys:
        parts = [(privacy_targets(st.scene), st) for st in scene.storeys]
        parts = [(t, st) for t, st in parts if t is not None]
        return stack_targets([t for t, _ in parts], [st for _, st in parts]) if parts else None
    zones = [z for z in scene.spec.zones if z.privacy]
    if not zones:
        return None
    pos = []
    for z in zones:
        p = layer_points(scene, privacy_heights(scene, z))
        pos.append(p[in_polygon(z.polygon, p[:, :2])])
    p = np.concatenate(pos)
    n = len(p)
    return Targets(p, np.zeros_like(p), np.ones(n, np.int64), np.ones(n), np.repeat(
        np.arange(len(zones), dtype=np.int32), [len(q) for q in pos]), tuple(z.name for z in zones),
        ("volume",) * len(zones), np.full(len(zones), 90.0), np.zeros(len(zones)), float(scene.spec.voxel_size))
