"""A scene from a scan: floor and ceiling levels, the room footprint, surface targets
and normals on the scanned points, and a whole scene mapping from just a cloud.

- ``detect_floor_ceiling``: the floor and ceiling heights of a z-up cloud, from the
  peaks of its height histogram (horizontal planes hold many points at one z).
- ``auto_footprint``: a room polygon from the wall band of a scan.
- ``scan_surface_targets``: surface targets (positions, PCA normals) inside a box.
- ``scene_from_cloud``: a scene-file mapping with defaults from a scan alone.

Errors name the parameter to change (``up``, ``level_floor``, ``footprint``, ...) with
``InputError.option``; the CLI words them as its flags.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from camplace.core.errors import InputError


# ------------------------------------------------------------------ floor / ceiling


def detect_floor_ceiling(points: np.ndarray, bin_m: float = 0.02, min_share: float = 0.2) -> dict:
    """Heights of the floor and ceiling of a z-up cloud (N, 3).

    A horizontal plane is a peak of the z histogram (of the cloud thinned to one point
    per 5 cm voxel, so that counts follow area, not nearness to the scanner). The floor is the lowest peak holding
    at least ``min_share`` of the largest peak's points (in the lower half of the z
    range), the ceiling the highest such peak in the upper half (None if no peak there).
    Returns {"floor_z", "ceiling_z", "z_range"} in metres."""
    from camplace.scene.loaders.pointcloud import voxel_downsample

    z = voxel_downsample(np.asarray(points, float), 0.05)[:, 2]  # even density: counts ~ plane area
    lo, hi = np.quantile(z, 0.001), np.quantile(z, 0.999)
    if hi - lo < 4 * bin_m:
        return {"floor_z": float(lo), "ceiling_z": None, "z_range": [float(lo), float(hi)]}
    edges = np.arange(lo - bin_m, hi + 2 * bin_m, bin_m)
    h, _ = np.histogram(z, edges)
    hs = np.convolve(h, [1, 1, 1], mode="same")  # tolerate a plane split across two bins
    mid = 0.5 * (lo + hi)
    centres = 0.5 * (edges[:-1] + edges[1:])
    strong = hs >= min_share * hs.max()
    peaks = strong & (hs >= np.r_[0, hs[:-1]]) & (hs >= np.r_[hs[1:], 0])
    low = np.nonzero(peaks & (centres <= mid))[0]
    high = np.nonzero(peaks & (centres > mid))[0]
    floor = float(centres[low[0]]) if len(low) else float(lo)
    ceiling = float(centres[high[-1]]) if len(high) else None
    return {"floor_z": round(floor, 4), "ceiling_z": None if ceiling is None else round(ceiling, 4),
            "z_range": [round(float(lo), 4), round(float(hi), 4)]}


# ------------------------------------------------------------------ footprint


def auto_footprint(points: np.ndarray, floor_z: float = 0.0, ceiling_z: float | None = None,
                   trim: float = 0.005, cell: float = 0.1) -> np.ndarray:
    """A room polygon (K, 2) from a z-up scan's wall band (0.15 to 0.6 m below the ceiling,
    where only walls remain; without a ceiling 0.3 m above the floor to 0.3 m below the
    top), 0.5 % of extreme x and y trimmed (stray points through openings).

    When the walls close a loop (rasterized at ``cell`` m and closed over 2-cell gaps),
    the polygon is the filled inside of that loop (non-convex rooms keep their shape);
    otherwise (open walls, no ceiling) the convex hull of the points 0.3 m above the floor
    to 0.3 m below the ceiling."""
    from shapely.geometry import MultiPoint, box
    from shapely.ops import unary_union

    p = np.asarray(points, float)

    def _trimmed(b: np.ndarray) -> np.ndarray:
        if len(b) < 10:
            b = p
        lo_, hi_ = np.quantile(b[:, :2], trim, axis=0), np.quantile(b[:, :2], 1 - trim, axis=0)
        return b[np.all((b[:, :2] >= lo_) & (b[:, :2] <= hi_), axis=1)]

    top = ceiling_z if ceiling_z is not None else float(np.quantile(p[:, 2], 0.99))
    wide = _trimmed(p[(p[:, 2] > floor_z + 0.3) & (p[:, 2] < top - 0.3)])
    hull = MultiPoint(wide[:, :2]).convex_hull.simplify(0.05)
    if hull.geom_type != "Polygon" or hull.area < 0.5:
        raise InputError("scan: cannot find a room footprint (the wall band of the scan has no area); "
                         "give footprint= or a scene file", option="footprint")
    if ceiling_z is None:
        return np.asarray(hull.exterior.coords)[:-1]
    # just below the ceiling only walls remain (shelves and people end lower)
    band = _trimmed(p[(p[:, 2] > max(floor_z + 0.3, ceiling_z - 0.6)) & (p[:, 2] < ceiling_z - 0.15)])
    lo, hi = band[:, :2].min(0), band[:, :2].max(0)
    # the walls as a 2D image; their filled inside, if they close
    o = lo - 2 * cell
    ij = np.floor((band[:, :2] - o) / cell).astype(int)
    shape = tuple(np.floor((hi - o) / cell).astype(int) + 3)
    img = np.zeros(shape, bool)
    img[ij[:, 0], ij[:, 1]] = True
    walls = ndimage.binary_closing(img, structure=np.ones((3, 3), bool), iterations=2) | img
    inside = ndimage.binary_fill_holes(walls) & ~walls
    if inside.sum() * cell * cell < 0.5 * hull.area:
        return np.asarray(hull.exterior.coords)[:-1]  # the walls do not close: convex hull
    labels, n = ndimage.label(inside)
    biggest = np.argmax(np.bincount(labels.ravel())[1:]) + 1
    room = ndimage.binary_fill_holes(labels == biggest)  # furniture columns inside belong to the room
    room = ndimage.binary_dilation(room, iterations=1) & (room | walls)  # out to the wall surface
    cells = np.argwhere(room)
    poly = unary_union([box(o[0] + i * cell, o[1] + j * cell, o[0] + (i + 1) * cell, o[1] + (j + 1) * cell)
                        for i, j in cells])
    if poly.geom_type != "Polygon":
        poly = max(poly.geoms, key=lambda g: g.area)
    poly = poly.simplify(cell * 1.5)
    if poly.geom_type != "Polygon" or not poly.is_valid or poly.area < 0.5:
        return np.asarray(hull.exterior.coords)[:-1]
    return np.asarray(poly.exterior.coords)[:-1]


# ------------------------------------------------------------------ surface normals


def pca_normals(points: np.ndarray, at: np.ndarray, k: int = 20) -> np.ndarray:
    """Unit normals (M, 3) at ``at`` (M, 3): the direction of least spread of the ``k``
    nearest ``points`` (N, 3) (PCA). Sign not oriented."""
    from scipy.spatial import cKDTree

    k = int(min(k, len(points)))
    _, idx = cKDTree(points).query(at, k=k, workers=-1)
    nb = points[idx.reshape(len(at), k)]
    c = nb - nb.mean(axis=1, keepdims=True)
    cov = np.einsum("mki,mkj->mij", c, c)
    _, vec = np.linalg.eigh(cov)
    return vec[:, :, 0]


# ------------------------------------------------------------------ surface targets on scans


def snap_outward(occupancy, positions: np.ndarray, normals: np.ndarray, max_shift: float = 0.15,
                 offset_cells: float = 0.75) -> tuple[np.ndarray, np.ndarray]:
    """Move each surface point (M, 3) out along its normal (M, 3) by whole occupancy cells
    until the point ``offset_cells`` outside it is free (a scanned face is a noisy shell of
    occupied cells, so the labelled box face may lie inside it). Returns (positions, kept
    mask (M,)); points still blocked after ``max_shift`` m are not kept."""
    res = occupancy.resolution
    out = positions.copy()
    done = np.zeros(len(positions), dtype=bool)
    for k in range(int(math.ceil(max_shift / res)) + 1):
        cand = positions + normals * (k * res)
        ok = ~done & ~occupancy.is_occupied(cand + normals * (offset_cells * res))
        out[ok] = cand[ok]
        done |= ok
    return out, done


def scan_surface_targets(scene, lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """Surface targets from the scan inside the box [lo, hi] (m): one per target voxel
    (``voxel_size``) holding scan points (their centroid; occupied cell centres when the
    scene has no points), normal by PCA of the 20 nearest points, turned toward free space
    (then toward the scanners), snapped outward. Returns (positions (M, 3), normals (M, 3))."""
    from camplace.scene.loaders.pointcloud import voxel_downsample

    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    g = scene.occupancy
    if scene.points is not None:
        src = scene.points
    else:
        src = g.origin + (np.argwhere(g.occupied) + 0.5) * g.resolution
    margin = 2 * g.resolution
    near = src[np.all((src >= lo - margin) & (src <= hi + margin), axis=1)]
    inside = near[np.all((near >= lo) & (near <= hi), axis=1)]
    if len(inside) < 3:
        return np.zeros((0, 3)), np.zeros((0, 3))
    pos = voxel_downsample(inside, float(scene.spec.voxel_size))
    nrm = pca_normals(near, pos)
    score = np.zeros(len(pos))
    for k in (1, 2, 3):
        d = nrm * (k * g.resolution)
        score += (~g.is_occupied(pos + d)).astype(float) - (~g.is_occupied(pos - d)).astype(float)
    if scene.viewpoints is not None and len(scene.viewpoints):
        to_vp = scene.viewpoints[np.argmin(np.linalg.norm(pos[:, None, :] - scene.viewpoints[None], axis=2), axis=1)] - pos
        score = np.where(score == 0, np.sign(np.einsum("ij,ij->i", to_vp, nrm)), score)
    nrm = np.where((score < 0)[:, None], -nrm, nrm)
    pos, keep = snap_outward(g, pos, nrm)
    return pos[keep], nrm[keep]


# ------------------------------------------------------------------ a scene from just a scan

DEFAULT_CAMERA = {"name": "wide", "model": "pinhole", "resolution": [1780, 720], "fov_deg": [71, 36],
                  "max_range": 5.0}


def scene_from_cloud(cloud: str, *, name: str | None = None, level_floor: bool = True, up: str = "+z",
                     scale: float = 1.0, rotate_deg=(0.0, 0.0, 0.0), translate=(0.0, 0.0, 0.0),
                     crop: tuple | None = None, downsample: float | None = 0.02,
                     remove_outliers: bool = True, viewpoints: list | None = None,
                     footprint: list | None = None, heights=(0.5, 1.0, 1.5), coverage: int = 2,
                     budget: int = 20, wall_mount_height: float | None = None,
                     progress=None) -> tuple[dict, dict]:
    """A scene (as a scene-file mapping) from just a scan, with defaults: the scan levelled
    (floor plane -> z = 0), floor and ceiling detected, footprint from the scan's wall band
    (or given), walkable ``kind: volume`` targets at ``heights`` with ``coverage``, a 1 m
    ceiling grid 0.1 m below the detected ceiling (wall mounts too with
    ``wall_mount_height``), the default 71°x36° camera.

    Returns (scene mapping, report: what was detected). The cloud path is stored
    absolute, so the mapping can be used as is or saved next to anything. Errors name
    the parameter to change (``InputError.option``: cloud, up, heights)."""
    from pathlib import Path

    from camplace.spec.loading import parse_scene
    from camplace.scene.loaders.obstacles import load_cloud_obstacle

    p = Path(cloud).expanduser().resolve()
    entry: dict = {"name": "scan", "point_cloud": str(p)}
    tf: dict = {}
    if downsample:
        entry["downsample"] = float(downsample)
    if remove_outliers:
        entry["remove_outliers"] = {"neighbors": 16, "std_ratio": 2.0}
    if viewpoints:
        entry["viewpoints"] = [[float(v) for v in vp] for vp in viewpoints]

    def _obstacle():
        from camplace.spec.schema import Obstacle

        e = dict(entry)
        if tf:
            e["transform"] = dict(tf)
        if crop is not None:
            e["crop"] = {"min": list(crop[0]), "max": list(crop[1])}
        return Obstacle.model_validate(e)

    # 1. the frame: user transform, then (optionally) the floor plane levelled, then the
    # floor moved to z = 0 - folded into one explicit transform, so the scene is reproducible
    from scipy.spatial.transform import Rotation

    from camplace.scene.loaders.cleanup import apply_matrix, level_floor_matrix, rigid_matrix
    from camplace.scene.loaders.pointcloud import load_point_cloud

    try:
        raw = load_point_cloud(p, downsample=0.05, progress=progress)
    except InputError as err:
        raise InputError(f"cloud: {err}", option="cloud") from None
    m = rigid_matrix(scale, rotate_deg, translate)
    q = apply_matrix(raw.points, m)
    level_info: dict = {}
    if level_floor:
        try:
            ml, level_info = level_floor_matrix(q, up)
        except ValueError:
            raise InputError(f"scan {p}: no floor plane within 30° of '{up}' up; give another up= or "
                             "level_floor=False", option="up") from None
        m = ml @ m
        q = apply_matrix(raw.points, m)
    floor = detect_floor_ceiling(q)["floor_z"]
    m[2, 3] -= floor
    tf = {}
    if scale != 1.0:
        tf["scale"] = float(scale)
    rot = m[:3, :3] / float(scale)
    eul = Rotation.from_matrix(rot).as_euler("xyz", degrees=True)
    if np.any(np.abs(eul) > 1e-6):
        tf["rotate_deg"] = [round(float(v), 6) for v in eul]
    if np.any(np.abs(m[:3, 3]) > 1e-9):
        tf["translate"] = [round(float(v), 6) for v in m[:3, 3]]
    # 2. the cleaned cloud in that frame (cached: building the scene reuses it)
    loaded, steps = load_cloud_obstacle(_obstacle(), None, f"scan {p}", progress)
    if level_info:
        steps = [{"step": "level_floor", **level_info}, *steps]
    levels = detect_floor_ceiling(loaded.points)
    pts = loaded.points
    ceiling = levels["ceiling_z"]
    height = float(ceiling) if ceiling is not None else float(np.quantile(pts[:, 2], 0.999)) + 0.05
    height = round(height, 3)
    if height <= 0.5:
        raise InputError(f"scan {p}: the scan is only {height:.2f} m high above its floor; is it z-up? "
                         "(try up='+y' for phone scans, or level_floor=False)", option="up")
    fp = np.asarray(footprint, float) if footprint is not None else auto_footprint(pts, 0.0, ceiling)
    hs = [float(h) for h in heights if 0 < h < height - 0.1]
    if not hs:
        raise InputError(f"scan {p}: no target height below the detected ceiling ({height} m)", option="heights")
    mounts = [{"kind": "ceiling_grid", "camera": "wide", "spacing": 1.0, "offset_below_ceiling": 0.1,
               "yaw_deg": {"start": 0, "stop": 330, "step": 30}, "pitch_deg": [30, 45, 60]}]
    if wall_mount_height is not None:
        mounts.append({"kind": "wall", "camera": "wide", "height": float(wall_mount_height), "spacing": 1.0,
                       "pitch_deg": [20, 35, 50]})
    e = dict(entry)
    if tf:
        e["transform"] = tf
    if crop is not None:
        e["crop"] = {"min": [float(v) for v in crop[0]], "max": [float(v) for v in crop[1]]}
    data = {
        "name": name or p.stem,
        "voxel_size": 0.25,
        "occupancy_resolution": 0.05,
        "room": {"footprint": [[round(float(x), 3), round(float(y), 3)] for x, y in fp], "height": height},
        "obstacles": [e],
        "targets": [{"name": "walkable", "kind": "volume", "heights": hs, "coverage": int(coverage)}],
        "cameras": [dict(DEFAULT_CAMERA)],
        "mounts": mounts,
        "placement": {"budget": int(budget), "solver": "greedy"},
    }
    parse_scene(data, f"scan {p}")  # validate now: errors name the scan, not a YAML file
    area = float(abs(np.dot(fp[:, 0], np.roll(fp[:, 1], 1)) - np.dot(fp[:, 1], np.roll(fp[:, 0], 1))) / 2)
    report = {"points": len(pts), "cleanup": steps, "floor_z_in_file_frame": floor, "transform": tf, "ceiling_z": ceiling, "height_m": height,
              "footprint_vertices": len(fp), "floor_area_m2": round(area, 2), "viewpoints": len(loaded.viewpoints)}
    return data, report


def describe_free_space(info: dict) -> str:
    """One log line for scene.info['free_space']."""
    out = (f"free space: {info.get('free_volume_m3', 0)} m3 walkable (clearance {info.get('clearance_m')} m, "
           f"grid {info.get('grid_bytes_planned', 0) / 1024**2:.0f} MiB planned)")
    if info.get("carved_from_viewpoints"):
        out += f"; carved from {info['carved_from_viewpoints']} viewpoint(s)"
    if info.get("octomap_free_leaves"):
        out += f"; {info['octomap_free_leaves']:,} OctoMap free leaves"
    if info.get("viewpoints_ignored"):
        out += f"; {info['viewpoints_ignored']} viewpoint(s) ignored ({info.get('carving_dropped', 'outside the room or inside an obstacle')})"
    if "observed" in info:
        out += "; observed space unknown: free = not occupied (give obstacle viewpoints for ray carving)"
    return out
