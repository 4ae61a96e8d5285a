"""Mount rules (issue 17): where cameras may hang.

``mount_rules.forbid`` polygons (floor plan, m) hold no camera (their boundary included);
with ``allow`` cameras hang only inside those polygons (boundary included); ``points``
(a CSV of x,y,z, metres, header optional) replaces the grid positions of every mount;
``clearance`` (m) keeps every camera that far from walls and obstacles (occupied cells),
except on the side of the surface it hangs from (clear_of_occupied). The same rules bound
refined and adaptive poses (camplace.improve.refine.pose_box) and the planner.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import Polygon
from shapely.ops import unary_union

from camplace.core.errors import InputError
from camplace.scene.build import OccupancyGrid, Scene

CEILING_BACK = np.array([0.0, 0.0, 1.0])  # a ceiling-mounted camera hangs from the surface above it
CHUNK = 1024  # points per block of occupied_distance (about 250 neighbour cells each)


def _union(polygons) -> object:
    return unary_union([Polygon(p) for p in polygons])


def allowed_xy(scene: Scene, xy: np.ndarray) -> np.ndarray:
    """(M,) bool: mount positions (M, 2) m that the rules allow (all True without rules)."""
    rules = scene.spec.mount_rules
    xy = np.asarray(xy, float).reshape(-1, 2)
    ok = np.ones(len(xy), bool)
    if rules.allow is not None:
        ok &= shapely.intersects_xy(_union(rules.allow), xy[:, 0], xy[:, 1])
    if rules.forbid:
        ok &= ~shapely.intersects_xy(_union(rules.forbid), xy[:, 0], xy[:, 1])
    return ok


def restrict_region(scene: Scene, region) -> object:
    """``region`` (shapely geometry) cut to the allowed mount area: inside ``allow`` (if
    given), outside every ``forbid`` polygon (its boundary too, for contains_xy tests)."""
    rules = scene.spec.mount_rules
    if rules.allow is not None:
        region = region.intersection(_union(rules.allow))
    if rules.forbid:
        region = region.difference(_union(rules.forbid))
    return region


def points_path(scene: Scene) -> Path | None:
    """The ``mount_rules.points`` file, resolved against the scene file's folder (None if not given)."""
    name = scene.spec.mount_rules.points
    if name is None:
        return None
    p = Path(name).expanduser()
    return p if p.is_absolute() or scene.base_dir is None else Path(scene.base_dir) / p


def explicit_points(scene: Scene) -> np.ndarray | None:
    """(K, 3) m: the mount points of ``mount_rules.points`` (rows x,y,z; a first row that is
    not numbers is a header; blank and '#' lines skipped), or None when not given."""
    path = points_path(scene)
    if path is None:
        return None
    key = f"{scene.spec.name}: mount_rules.points"
    try:
        rows = list(csv.reader(path.read_text(encoding="utf-8-sig").splitlines()))
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"{key}: cannot read '{path}' ({err})") from None
    rows = [r for r in rows if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    out = []
    for n, row in enumerate(rows):
        try:
            xyz = [float(c) for c in row[:3]]
        except ValueError:
            if n == 0:
                continue  # header
            raise InputError(f"{key}: line {n + 1} of '{path.name}': expected x,y,z numbers, got {row}") from None
        if len(xyz) != 3 or not all(math.isfinite(v) for v in xyz):
            raise InputError(f"{key}: line {n + 1} of '{path.name}': expected x,y,z finite numbers, got {row}")
        out.append(xyz)
    if not out:
        raise InputError(f"{key}: '{path.name}' holds no x,y,z row; expected one mount point per line")
    return np.asarray(out, float)


def _neighbour_offsets(reach_cells: float) -> np.ndarray:
    """(M, 3) int64 cell offsets whose boxes can lie within ``reach_cells`` cells of a point
    in cell (0, 0, 0)."""
    k = int(math.ceil(reach_cells))
    r = np.arange(-k, k + 1)
    off = np.stack(np.meshgrid(r, r, r, indexing="ij"), axis=-1).reshape(-1, 3)
    gap = np.maximum(np.abs(off) - 1, 0)  # whole cells between the point's cell and the offset cell
    return off[(gap**2).sum(1) < reach_cells**2].astype(np.int64)


def occupied_distance(grid: OccupancyGrid, points: np.ndarray, backs: np.ndarray, reach: float) -> np.ndarray:
    """(N,) m: distance from each point (N, 3) m to the nearest occupied cell (its box),
    ignoring the cells wholly behind the plane through the point with normal ``backs``
    ((N, 3) or (3,): towards the surface the camera hangs from, e.g. +z under a ceiling,
    into the wall for a wall mount; a zero vector ignores none); inf when no occupied cell
    lies within ``reach`` m. Cells outside the grid count as occupied."""
    pts = np.asarray(points, float).reshape(-1, 3)
    backs = np.broadcast_to(np.asarray(backs, float), pts.shape)
    out = np.full(len(pts), np.inf)
    if not len(pts) or reach <= 0:
        return out
    res = float(grid.resolution)
    off = _neighbour_offsets(reach / res)
    shape = np.array(grid.shape)
    for a in range(0, len(pts), CHUNK):
        p, b = pts[a:a + CHUNK, None, :], backs[a:a + CHUNK, None, :]
        cells = grid.cell_of(pts[a:a + CHUNK])[:, None, :] + off[None]  # (n, M, 3)
        lo = grid.origin + cells * res
        hi = lo + res
        dist = np.linalg.norm(np.maximum(np.maximum(lo - p, p - hi), 0.0), axis=2)
        nearest_along_back = np.where(b > 0, lo - p, hi - p) * b  # the box's nearest point towards the surface
        behind = (nearest_along_back.sum(2) > -1e-9) & np.any(b != 0, axis=2)
        inside = np.all((cells >= 0) & (cells < shape), axis=2)
        occ = np.ones(cells.shape[:2], bool)
        ci = cells[inside]
        occ[inside] = grid.occupied[ci[:, 0], ci[:, 1], ci[:, 2]]
        d = np.where(occ & ~behind & (dist < reach), dist, np.inf)
        out[a:a + CHUNK] = d.min(1)
    return out


def clear_of_occupied(scene: Scene, points: np.ndarray, backs: np.ndarray) -> np.ndarray:
    """(N,) bool: the points (N, 3) m that keep ``mount_rules.clearance`` from every
    occupied cell not behind their mount surface (``backs`` as occupied_distance); all
    True when the clearance is 0."""
    c = float(scene.spec.mount_rules.clearance)
    pts = np.asarray(points, float).reshape(-1, 3)
    if c <= 0:
        return np.ones(len(pts), bool)
    return occupied_distance(scene.occupancy, pts, backs, c) >= c - 1e-6
