"""Scene-file obstacles backed by files (``point_cloud``, ``mesh``, ``octomap``) into an
occupancy grid: read the file (path relative to the scene file), apply the obstacle's
clean-up keys, and mark the occupied cells. Each loader reports what it did.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numba
import numpy as np

from camplace.core.errors import InputError
from camplace.scene.loaders import Progress
from camplace.scene.loaders.cleanup import apply_matrix, clean_cloud, crop_mask, rigid_matrix
from camplace.scene.loaders.pointcloud import PointCloud, load_point_cloud

_CACHE: dict[tuple, tuple] = {}  # the last few cleaned clouds (scene built twice, e.g. --cloud)


@dataclass
class LoadedObstacle:
    """What an obstacle file contributed. points: (N, 3) cleaned scan points (scene frame)
    or None; viewpoints: (K, 3); free_lo / free_size: observed-free boxes (OctoMap free
    leaves) or None; report: what was read and done."""

    points: np.ndarray | None = None
    viewpoints: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    free_lo: np.ndarray | None = None
    free_size: np.ndarray | None = None
    report: dict = field(default_factory=dict)


def resolve_path(rel: str, base_dir: Path | None) -> Path:
    p = Path(rel).expanduser()
    return p if p.is_absolute() or base_dir is None else Path(base_dir) / p


def _where(source: str, i: int, ob, key: str) -> str:
    return f"{source}: obstacles[{i}].{key} ('{ob.name}')"


def load_cloud_obstacle(ob, base_dir: Path | None, where: str = "", progress: Progress | None = None
                        ) -> tuple[PointCloud, list[dict]]:
    """Read and clean the point cloud of a ``point_cloud`` obstacle (scene frame)."""
    path = resolve_path(ob.point_cloud, base_dir)
    if not path.is_file():
        raise InputError(f"{where}: point cloud file not found: {path}")
    st = path.stat()
    key = (str(path.resolve()), st.st_mtime_ns, st.st_size,
           ob.model_dump_json(include={"transform", "crop", "downsample", "remove_outliers", "viewpoints"}))
    if key in _CACHE:
        return _CACHE[key]
    t = ob.transform
    # thin while reading (in file units, chunk by chunk), so memory follows the output;
    # the exact downsampling then runs again in the scene frame below
    pre = ob.downsample / (t.scale if t else 1.0) if ob.downsample else None
    try:
        cloud = load_point_cloud(path, downsample=pre, progress=progress)
    except InputError as err:
        raise InputError(f"{where}: {err}") from None
    if ob.viewpoints is not None:
        cloud = PointCloud(cloud.points, np.asarray(ob.viewpoints, float).reshape(-1, 3), cloud.info)
    out = clean_cloud(
        cloud,
        scale=t.scale if t else 1.0, rotate_deg=t.rotate_deg if t else (0, 0, 0),
        translate=t.translate if t else (0, 0, 0), level_floor=bool(t and t.level_floor), up=t.up if t else "+z",
        crop=(ob.crop.min, ob.crop.max) if ob.crop else None, downsample=ob.downsample,
        outliers=(ob.remove_outliers.neighbors, ob.remove_outliers.std_ratio) if ob.remove_outliers else None)
    if len(out[0].points) == 0:
        raise InputError(f"{where}: no point is left after clean-up (check crop / transform)")
    _CACHE.clear()
    _CACHE[key] = out
    return out


@numba.njit(cache=True)
def _mark_boxes(occ, ox, oy, oz, res, lo, size):
    """Mark cells whose centres lie in [lo, lo + size) of any box; returns cells newly marked."""
    nx, ny, nz = occ.shape
    n = 0
    for b in range(lo.shape[0]):
        i0 = max(int(np.ceil((lo[b, 0] - ox) / res - 0.5)), 0)
        j0 = max(int(np.ceil((lo[b, 1] - oy) / res - 0.5)), 0)
        k0 = max(int(np.ceil((lo[b, 2] - oz) / res - 0.5)), 0)
        i1 = min(int(np.ceil((lo[b, 0] + size[b] - ox) / res - 0.5)), nx)
        j1 = min(int(np.ceil((lo[b, 1] + size[b] - oy) / res - 0.5)), ny)
        k1 = min(int(np.ceil((lo[b, 2] + size[b] - oz) / res - 0.5)), nz)
        for i in range(i0, i1):
            for j in range(j0, j1):
                for k in range(k0, k1):
                    if not occ[i, j, k]:
                        occ[i, j, k] = True
                        n += 1
    return n


def mark_boxes(grid_occ: np.ndarray, origin: np.ndarray, res: float, lo: np.ndarray, size: np.ndarray) -> int:
    """Mark (in place) the cells of ``grid_occ`` whose centres lie in the cubes
    lo (N, 3) + [0, size (N,)) m. Returns the cells newly marked."""
    return int(_mark_boxes(grid_occ, float(origin[0]), float(origin[1]), float(origin[2]), float(res),
                           np.ascontiguousarray(lo, dtype=np.float64), np.ascontiguousarray(size, dtype=np.float64)))


def mark_points(grid_occ: np.ndarray, origin: np.ndarray, res: float, points: np.ndarray) -> int:
    """Mark (in place) the cells holding points (N, 3) m; points outside are ignored.
    Returns the number of points inside the grid."""
    c = np.floor((points - origin) / res).astype(np.int64)
    ok = np.all((c >= 0) & (c < np.array(grid_occ.shape)), axis=1)
    c = c[ok]
    grid_occ[c[:, 0], c[:, 1], c[:, 2]] = True
    return int(ok.sum())


def add_obstacle(grid_occ: np.ndarray, origin: np.ndarray, res: float, ob, i: int, base_dir: Path | None,
                 source: str, progress: Progress | None = None) -> LoadedObstacle:
    """Mark a file-backed obstacle's occupied cells into ``grid_occ`` (in place)."""
    before = int(grid_occ.sum())
    if ob.point_cloud is not None:
        where = _where(source, i, ob, "point_cloud")
        cloud, steps = load_cloud_obstacle(ob, base_dir, where, progress)
        inside = mark_points(grid_occ, origin, res, cloud.points) if ob.occludes else 0
        rep = {"kind": "point_cloud", **{k: v for k, v in cloud.info.items() if k != "path"}, "cleanup": steps,
               "points_in_grid": inside, "viewpoints": len(cloud.viewpoints)}
        out = LoadedObstacle(cloud.points, cloud.viewpoints, report=rep)
    elif ob.mesh is not None:
        from camplace.scene.loaders.mesh import Mesh, load_mesh, voxelize_mesh

        where = _where(source, i, ob, "mesh")
        path = resolve_path(ob.mesh, base_dir)
        try:
            mesh = load_mesh(path)
        except InputError as err:
            raise InputError(f"{where}: {err}") from None
        v = mesh.vertices
        t = ob.transform
        if t is not None:
            if t.level_floor:
                raise InputError(f"{where}: transform.level_floor belongs to point clouds; give rotate_deg instead")
            v = apply_matrix(v, rigid_matrix(t.scale, t.rotate_deg, t.translate))
        faces = mesh.faces
        if ob.crop is not None:
            faces = faces[crop_mask(v[faces].mean(axis=1), ob.crop.min, ob.crop.max)]
        mesh = Mesh(v, faces, mesh.info)
        if ob.occludes:
            voxelize_mesh(mesh, grid_occ, origin, res, solid=ob.solid)
        rep = {"kind": "mesh", **{k: v for k, v in mesh.info.items() if k != "path"}, "solid": ob.solid}
        if ob.solid and not mesh.info.get("watertight", False):
            rep["warning"] = "solid: true on a mesh that is not closed; only enclosed voxels were filled"
        out = LoadedObstacle(report=rep)
    elif ob.octomap is not None:
        from camplace.scene.loaders.octomap import load_octomap

        where = _where(source, i, ob, "octomap")
        try:
            om = load_octomap(resolve_path(ob.octomap, base_dir))
        except InputError as err:
            raise InputError(f"{where}: {err}") from None
        occ_lo, occ_s, free_lo, free_s = om.occupied_lo, om.occupied_size, om.free_lo, om.free_size
        t = ob.transform
        if t is not None:
            if t.level_floor or any(t.rotate_deg):
                raise InputError(f"{where}: an OctoMap takes only transform.scale and transform.translate "
                                 "(its leaves are axis-aligned cubes)")
            occ_lo, free_lo = occ_lo * t.scale + np.asarray(t.translate), free_lo * t.scale + np.asarray(t.translate)
            occ_s, free_s = occ_s * t.scale, free_s * t.scale
        if ob.crop is not None:
            k = crop_mask(occ_lo + occ_s[:, None] / 2, ob.crop.min, ob.crop.max)
            occ_lo, occ_s = occ_lo[k], occ_s[k]
            k = crop_mask(free_lo + free_s[:, None] / 2, ob.crop.min, ob.crop.max)
            free_lo, free_s = free_lo[k], free_s[k]
        if ob.occludes:
            mark_boxes(grid_occ, origin, res, occ_lo, occ_s)
        rep = {"kind": "octomap", **{k: v for k, v in om.info.items() if k != "path"}}
        centres = occ_lo + occ_s[:, None] / 2
        out = LoadedObstacle(points=centres, free_lo=free_lo, free_size=free_s, report=rep)
    else:  # pragma: no cover - the schema allows only these
        raise InputError(f"{source}: obstacles[{i}]: unknown obstacle kind")
    out.report["cells_marked"] = int(grid_occ.sum()) - before
    return out


def describe(name: str, rep: dict) -> str:
    """One log line for an obstacle file's report: what was read and each clean-up step."""
    kind = rep.get("kind", "?")
    if kind == "point_cloud":
        steps = ", ".join(f"{s['step']} -> {s.get('points', '?'):,}" for s in rep.get("cleanup", []))
        return (f"obstacle '{name}': point cloud ({rep.get('format')}) {rep.get('points_read', 0):,} points read"
                + (f"; {rep['non_finite_dropped']:,} non-finite points dropped" if rep.get("non_finite_dropped") else "")
                + (f"; {steps}" if steps else "") + f"; {rep.get('viewpoints', 0)} viewpoint(s); "
                f"{rep.get('cells_marked', 0):,} cells marked")
    if kind == "mesh":
        return (f"obstacle '{name}': mesh {rep.get('faces', 0):,} triangles"
                f"{' (solid)' if rep.get('solid') else ''}; {rep.get('cells_marked', 0):,} cells marked"
                + (f"; {rep['warning']}" if rep.get("warning") else ""))
    return (f"obstacle '{name}': OctoMap ({rep.get('format')}, {rep.get('resolution')} m) "
            f"{rep.get('occupied_leaves', 0):,} occupied / {rep.get('free_leaves', 0):,} free leaves; "
            f"{rep.get('cells_marked', 0):,} cells marked")
