"""A synthetic scanner and exports of box scenes, so loaders and round trips need no
outside data.

``scan_scene`` casts rays from a few viewpoints (a spherical lattice of directions, like
a tripod LiDAR) against the exact geometry of a box scene - floor z = 0, ceiling
z = height, the footprint's walls and every occluding box - and keeps the first hit,
with Gaussian range noise. What a viewpoint cannot see (the back of a shelf, the inside
of a gondola) gets no points: occlusion as in a real scan.

``export_mesh`` / ``export_octomap`` write the same scene as a triangle mesh (the boxes)
or an OctoMap (its occupancy grid), for the mesh and OctoMap round trips.
"""

from __future__ import annotations

from pathlib import Path

import numba
import numpy as np
import shapely

from camplace.core.errors import InputError
from camplace.scene.loaders import Progress
from camplace.scene.loaders.pointcloud import PointCloud
from camplace.scene.build import Scene
from camplace.visibility.voxel import segment_clear


@numba.njit(cache=True, parallel=True)
def _cast(origin, dirs, height, edges, boxes, t_max):
    """First-hit distance of each ray (inf if none within t_max)."""
    n = dirs.shape[0]
    out = np.full(n, np.inf)
    for r in numba.prange(n):
        dx, dy, dz = dirs[r, 0], dirs[r, 1], dirs[r, 2]
        best = t_max
        if dz < 0:
            best = min(best, -origin[2] / dz)
        elif dz > 0:
            best = min(best, (height - origin[2]) / dz)
        for e in range(edges.shape[0]):  # vertical walls: o.xy + t d.xy = a + s (b - a)
            ax, ay, bx, by = edges[e, 0], edges[e, 1], edges[e, 2], edges[e, 3]
            ex, ey = bx - ax, by - ay
            den = dx * ey - dy * ex
            if abs(den) < 1e-12:
                continue
            wx, wy = ax - origin[0], ay - origin[1]
            t = (wx * ey - wy * ex) / den
            s = (wx * dy - wy * dx) / den
            if t > 1e-9 and 0.0 <= s <= 1.0 and t < best:
                best = t
        for b in range(boxes.shape[0]):  # slab test
            t0, t1 = 0.0, best
            hit = True
            for a in range(3):
                o, d = origin[a], dirs[r, a]
                lo, hi = boxes[b, a], boxes[b, 3 + a]
                if abs(d) < 1e-12:
                    if o < lo or o > hi:
                        hit = False
                        break
                else:
                    ta, tb = (lo - o) / d, (hi - o) / d
                    if ta > tb:
                        ta, tb = tb, ta
                    t0 = max(t0, ta)
                    t1 = min(t1, tb)
                    if t0 > t1:
                        hit = False
                        break
            if hit and t0 > 1e-9 and t0 < best:
                best = t0
        if best < t_max:
            out[r] = best
    return out


def _box_scene_parts(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    for ob in scene.spec.obstacles:
        if ob.box is None:
            raise InputError(f"scene '{scene.name}': obstacle '{ob.name}': the synthetic scanner needs box obstacles")
    boxes = np.array([np.r_[scene.boxes[ob.name][0], scene.boxes[ob.name][1]]
                      for ob in scene.spec.obstacles if ob.occludes], float).reshape(-1, 6)
    fp = scene.footprint
    edges = np.c_[fp, np.roll(fp, -1, axis=0)]
    return edges, boxes


def scan_directions(step_deg: float) -> np.ndarray:
    """Unit ray directions (N, 3) on an azimuth x elevation lattice of ``step_deg``."""
    az = np.radians(np.arange(0.0, 360.0, step_deg))
    el = np.radians(np.arange(-90.0 + step_deg / 2, 90.0, step_deg))
    A, E = np.meshgrid(az, el, indexing="ij")
    return np.c_[(np.cos(E) * np.cos(A)).ravel(), (np.cos(E) * np.sin(A)).ravel(), np.sin(E).ravel()]


@numba.njit(cache=True, parallel=True)
def _seen_matrix(occ, origin, res, a, b):
    """(len(a), len(b)) bool: segment a_i -> b_j meets no occupied cell."""
    out = np.zeros((a.shape[0], b.shape[0]), np.bool_)
    for i in numba.prange(a.shape[0]):
        for j in range(b.shape[0]):
            out[i, j] = segment_clear(occ, origin[0], origin[1], origin[2], res,
                                      a[i, 0], a[i, 1], a[i, 2], b[j, 0], b[j, 1], b[j, 2])
    return out


def default_viewpoints(scene: Scene, count: int | None = None, height: float = 1.6, clearance: float = 0.4,
                       floor_share: float = 0.99, max_count: int = 40) -> np.ndarray:
    """Scanner positions (K, 3) at ``height`` on free floor, as a survey crew would place
    them: greedily, each one seeing the most still-unseen floor (a 0.5 m lattice of points
    0.5 m above the floor), until ``floor_share`` of it is seen (or ``count`` / ``max_count``
    positions)."""
    poly = scene.polygon.buffer(-clearance)
    lo, hi = scene.footprint.min(0), scene.footprint.max(0)
    gx, gy = np.meshgrid(np.arange(lo[0] + 0.25, hi[0], 0.5), np.arange(lo[1] + 0.25, hi[1], 0.5), indexing="ij")
    xy = np.c_[gx.ravel(), gy.ravel()]
    g = scene.occupancy
    floor = np.c_[xy, np.full(len(xy), 0.5)]
    floor = floor[~g.is_occupied(floor) & shapely.contains_xy(scene.polygon, floor[:, 0], floor[:, 1])]
    xy = xy[shapely.contains_xy(poly, xy[:, 0], xy[:, 1])]
    for bmin, bmax in scene.boxes.values():
        inside = np.all((xy >= bmin[:2] - clearance) & (xy <= bmax[:2] + clearance), axis=1)
        xy = xy[~inside]
    cand = np.c_[xy, np.full(len(xy), float(height))]
    cand = cand[~g.is_occupied(cand)]
    if len(cand) == 0 or len(floor) == 0:
        raise InputError(f"scene '{scene.name}': no free floor spot for a scanner viewpoint")
    seen = _seen_matrix(g.occupied.view(np.uint8), g.origin.astype(np.float64), float(g.resolution),
                        np.ascontiguousarray(cand), np.ascontiguousarray(floor))
    covered = np.zeros(len(floor), dtype=bool)
    chosen: list[int] = []
    limit = count if count is not None else max_count
    while len(chosen) < limit:
        gain = (seen & ~covered).sum(axis=1)
        k = int(np.argmax(gain))
        if gain[k] == 0 and count is None:
            break
        chosen.append(k)
        covered |= seen[k]
        if count is None and covered.mean() >= floor_share:
            break
    return cand[chosen]


def scan_scene(scene: Scene, viewpoints: np.ndarray | None = None, n_viewpoints: int | None = None,
               height: float = 1.6, step_deg: float = 0.4, noise: float = 0.01, max_range: float = 30.0, seed: int = 0,
               progress: Progress | None = None) -> PointCloud:
    """Scan a box scene: points (N, 3) m of the first hits of every viewpoint's rays,
    range noise ~ N(0, noise) m along each ray. Viewpoints: given (K, 3), else
    ``n_viewpoints`` chosen by default_viewpoints (None: enough to see 99 % of the floor)."""
    edges, boxes = _box_scene_parts(scene)
    vps = default_viewpoints(scene, n_viewpoints, height) if viewpoints is None else np.asarray(viewpoints, float)
    dirs = scan_directions(step_deg)
    rng = np.random.default_rng(seed)
    pts = []
    for k, vp in enumerate(vps):
        t = _cast(np.asarray(vp, float), dirs, float(scene.height), edges, boxes, float(max_range))
        ok = np.isfinite(t)
        tt = t[ok] + (rng.normal(0.0, noise, int(ok.sum())) if noise > 0 else 0.0)
        pts.append(vp + dirs[ok] * tt[:, None])
        if progress:
            progress("scan", k + 1, len(vps))
    p = np.concatenate(pts)
    return PointCloud(p, vps, {"format": "synthetic", "viewpoints": len(vps), "rays_per_viewpoint": len(dirs),
                               "step_deg": step_deg, "noise_m": noise, "points": len(p)})


# ------------------------------------------------------------------ exports for round trips


def export_mesh(scene: Scene, path: str | Path) -> Path:
    """Write the scene's occluding boxes as one closed triangle mesh (.obj .ply .stl .glb .off)."""
    from camplace.scene.loaders.mesh import boxes_to_mesh, write_mesh

    _box_scene_parts(scene)
    boxes = [scene.boxes[ob.name] for ob in scene.spec.obstacles if ob.occludes]
    if not boxes:
        raise InputError(f"scene '{scene.name}': no box obstacle to export")
    return write_mesh(path, boxes_to_mesh(boxes))


def export_octomap(scene: Scene, path: str | Path) -> Path:
    """Write the scene's occupancy grid as an OctoMap (.bt / .ot): occupied cells as occupied
    leaves, the free cells inside the room as free leaves."""
    from camplace.scene.loaders.octomap import write_octomap

    g = scene.occupancy
    return write_octomap(path, g.occupied, ~g.occupied, g.origin, g.resolution)


def scan_cli_summary(cloud: PointCloud) -> str:
    """One line describing a synthetic scan (for the CLI)."""
    i = cloud.info
    return (f"{i['points']:,} points from {i['viewpoints']} viewpoints ({i['rays_per_viewpoint']:,} rays each, "
            f"{i['step_deg']}° step, noise {i['noise_m']} m)")


# ------------------------------------------------------------------ round trips


def roundtrip_spec(spec, kind: str, path: str | Path, downsample: float | None = 0.02):
    """The box scene ``spec`` with its occlusion replaced by a file: kind ``point_cloud``,
    ``mesh`` (solid) or ``octomap``. The boxes stay as labels (``occludes: false``) so
    surface targets keep their faces, as the paper labels shelves on its scan."""
    from camplace.spec.loading import parse_scene

    data = spec.model_dump(mode="json", exclude_defaults=True)
    obs = [dict(o, occludes=False) for o in data.get("obstacles", [])]
    entry: dict = {"name": f"roundtrip-{kind}", kind: str(path)}
    if kind == "point_cloud" and downsample:
        entry["downsample"] = downsample
    if kind == "mesh":
        entry["solid"] = True
    data["obstacles"] = obs + [entry]
    data["name"] = f"{spec.name}-via-{kind}"
    return parse_scene(data, f"<round trip {kind} of {spec.name}>")


def evaluate_selection(scene: Scene, candidates, selected) -> "object":
    """Score chosen poses on another scene: raycast ``candidates.subset(selected)`` on
    ``scene`` (its occupancy and targets) and return camplace.metrics.coverage.Metrics."""
    from camplace.metrics.coverage import compute_metrics
    from camplace.problem.model import PlacementProblem
    from camplace.targets.build import build_targets
    from camplace.visibility.voxel import compute_visibility

    sel = np.asarray(selected, dtype=np.int64)
    tg = build_targets(scene)
    vis = compute_visibility(scene.occupancy, tg, candidates.subset(sel))
    prob = PlacementProblem(vis.V, tg.gamma, tg.weights, len(sel), np.arange(len(sel), dtype=np.int64))
    return compute_metrics(prob, np.arange(len(sel)), tg.region_ids, tg.region_names)
