"""Zones (issue 17): which floor-plan points a zone claims, its target region, and the
grid points of a layer set.

Overlap rule: a point (x, y) inside several zone polygons belongs to the LAST of them in
``zones:`` order (later entries win); the volume regions of ``targets:`` keep only the
points no zone polygon claims; a privacy zone always wins (its points are never
targets, whatever the order). A polygon contains its boundary (points on a shared edge
go to the later zone).
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import Polygon

from camplace.scene.build import Scene
from camplace.spec.schema import SceneSpec, TargetRegion
from camplace.spec.sites import Zone, walkable_heights


def layer_points(scene: Scene, heights) -> np.ndarray:
    """Free-space voxel centres inside the footprint at each height: (M, 3) metres."""
    v = float(scene.spec.voxel_size)
    lo, hi = scene.footprint.min(0), scene.footprint.max(0)
    nx, ny = (int(np.floor((hi[a] - lo[a]) / v + 1e-9)) for a in range(2))
    xs = lo[0] + (np.arange(nx) + 0.5) * v
    ys = lo[1] + (np.arange(ny) + 0.5) * v
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    inside = shapely.contains_xy(scene.polygon, gx, gy)
    xy = np.c_[gx[inside], gy[inside]]
    layers = [np.c_[xy, np.full(len(xy), float(h))] for h in heights or []]
    pts = np.concatenate(layers) if layers else np.zeros((0, 3))
    pts = pts[~scene.occupancy.is_occupied(pts)]
    if getattr(scene, "free_space", None) is not None:  # scans / OctoMaps: observed walkable space only
        pts = pts[scene.free_space.contains(pts)]
    return pts


def in_polygon(polygon, xy: np.ndarray) -> np.ndarray:
    """(M,) bool: points (M, 2) m inside or on the boundary of ``polygon`` (corner list)."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    return shapely.intersects_xy(Polygon(polygon), xy[:, 0], xy[:, 1])


def zone_owner(zones: list[Zone], xy: np.ndarray) -> np.ndarray:
    """(M,) int: index into ``zones`` of the last polygon zone containing each point (M, 2), -1: none."""
    owner = np.full(len(xy), -1, np.int64)
    for k, z in enumerate(zones):
        if z.polygon is not None:
            owner[in_polygon(z.polygon, xy)] = k
    return owner


def in_privacy(zones: list[Zone], xy: np.ndarray) -> np.ndarray:
    """(M,) bool: points (M, 2) inside any privacy zone."""
    out = np.zeros(len(xy), bool)
    for z in zones:
        if z.privacy:
            out |= in_polygon(z.polygon, xy)
    return out


def zone_region(zone: Zone, spec: SceneSpec) -> TargetRegion:
    """The target region of a non-privacy zone: volume at its heights (default: the walkable
    heights of ``spec.targets``) or surface on its ``of`` / ``box``."""
    common = dict(name=zone.name, coverage=zone.coverage, weight=zone.weight, min_px_per_m=zone.min_px_per_m,
                  max_incidence_deg=zone.max_incidence_deg)
    if zone.is_surface:
        return TargetRegion(kind="surface", of=zone.of, box=zone.box, faces=zone.faces, **common)
    return TargetRegion(kind="volume", heights=zone.heights or walkable_heights(spec), **common)


def privacy_heights(scene: Scene, zone: Zone) -> list[float]:
    """A privacy zone's heights (m): its own, else every voxel centre from floor to ceiling."""
    if zone.heights:
        return list(zone.heights)
    v = float(scene.spec.voxel_size)
    return [(k + 0.5) * v for k in range(int(np.floor(scene.height / v + 1e-9)))]


def keep_mask(scene: Scene, region_index: int, points: np.ndarray) -> np.ndarray:
    """(M,) bool: which of region ``region_index``'s points stay (regions: ``targets:`` then the
    non-privacy zones in order). Volume regions of ``targets:`` keep what no zone claims;
    a zone keeps what it owns outside every privacy zone (nothing when its coverage is 0);
    surface regions of ``targets:`` keep everything."""
    spec = scene.spec
    zones = list(spec.zones)
    n_t = len(spec.targets)
    xy = points[:, :2]
    if region_index < n_t:
        if spec.targets[region_index].kind != "volume":
            return np.ones(len(points), bool)
        return zone_owner(zones, xy) == -1
    k = [i for i, z in enumerate(zones) if not z.privacy][region_index - n_t]
    z = zones[k]
    if z.coverage == 0:
        return np.zeros(len(points), bool)
    if z.is_surface:
        return np.ones(len(points), bool)
    return (zone_owner(zones, xy) == k) & ~in_privacy(zones, xy)
