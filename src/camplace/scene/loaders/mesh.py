"""Triangle meshes (OBJ, PLY, STL, OFF, GLB/glTF via trimesh): read, voxelize into an
occupancy grid, and write boxes as a mesh (for round trips of box scenes).

Surfaces are voxelized conservatively (a barycentric lattice of quarter-cell steps,
each point marking the cells within a quarter cell), so no cell the surface crosses is
missed; ``solid=True`` also fills the
cells enclosed by the surface (closed meshes).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numba
import numpy as np
from scipy import ndimage

from camplace.core.errors import InputError
from camplace.core.files import atomic_write_bytes
from camplace.scene.loaders.guards import check_glb, check_ply


@dataclass(frozen=True)
class Mesh:
    """vertices: (V, 3) float64 m; faces: (F, 3) int64 vertex indices."""

    vertices: np.ndarray
    faces: np.ndarray
    info: dict = field(default_factory=dict)


def load_mesh(path: str | Path) -> Mesh:
    """Read a mesh file (all its geometry merged into one triangle mesh)."""
    import trimesh

    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: mesh file not found")
    if p.stat().st_size == 0:
        raise InputError(f"{p}: the file is empty")
    if p.suffix.lower() == ".glb":
        check_glb(p)
    elif p.suffix.lower() == ".ply":
        check_ply(p)
    try:
        m = trimesh.load(str(p), force="mesh")
    except Exception as err:  # trimesh raises many kinds for bad files
        msg = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise InputError(f"{p}: not a readable mesh ({msg[:120]})") from None
    faces = np.asarray(getattr(m, "faces", np.zeros((0, 3))), dtype=np.int64)
    verts = np.asarray(getattr(m, "vertices", np.zeros((0, 3))), dtype=np.float64)
    if any(a.size and (a.ndim != 2 or a.shape[1] != 3) for a in (faces, verts)):
        raise InputError(f"{p}: the mesh's vertex or face lists are not rows of 3 (a broken line?)")
    faces, verts = faces.reshape(-1, 3), verts.reshape(-1, 3)
    if len(faces) == 0:
        raise InputError(f"{p}: the mesh has no triangles")
    if faces.min() < 0 or faces.max() >= len(verts) or not np.all(np.isfinite(verts)):
        raise InputError(f"{p}: the mesh has bad vertex indices or non-finite vertices")
    return Mesh(verts, faces, {"path": str(p), "vertices": len(verts), "faces": len(faces),
                               "watertight": bool(m.is_watertight)})


@numba.njit(cache=True)
def _mark_triangles(tri, occ, ox, oy, oz, res):
    """Mark (in place) every cell of occ that a triangle of ``tri`` (T, 3, 3) may touch.

    Each triangle is sampled on a barycentric lattice with steps <= res / 4; every point
    of the triangle is then within res / 4 of a lattice point, so marking, for each lattice
    point, all cells within res / 4 (L-inf) of it is conservative: no crossed cell is missed
    (cells up to a quarter cell away may be marked too)."""
    nx, ny, nz = occ.shape
    marked = 0
    d = 0.25 + 1e-6
    for t in range(tri.shape[0]):
        a, b, c = tri[t, 0], tri[t, 1], tri[t, 2]
        e1 = b - a
        e2 = c - a
        lmax = max(np.sqrt((e1 ** 2).sum()), np.sqrt((e2 ** 2).sum()), np.sqrt(((c - b) ** 2).sum()))
        n = max(int(np.ceil(lmax / (0.25 * res))), 1)
        for i in range(n + 1):
            for j in range(n + 1 - i):
                u = i / n
                v = j / n
                fx = (a[0] + u * e1[0] + v * e2[0] - ox) / res
                fy = (a[1] + u * e1[1] + v * e2[1] - oy) / res
                fz = (a[2] + u * e1[2] + v * e2[2] - oz) / res
                x0 = int(np.floor(fx - d))
                x1 = int(np.floor(fx + d))
                y0 = int(np.floor(fy - d))
                y1 = int(np.floor(fy + d))
                z0 = int(np.floor(fz - d))
                z1 = int(np.floor(fz + d))
                for ix in range(max(x0, 0), min(x1, nx - 1) + 1):
                    for iy in range(max(y0, 0), min(y1, ny - 1) + 1):
                        for iz in range(max(z0, 0), min(z1, nz - 1) + 1):
                            if not occ[ix, iy, iz]:
                                occ[ix, iy, iz] = True
                                marked += 1
    return marked


def voxelize_mesh(mesh: Mesh, occupied: np.ndarray, origin: np.ndarray, resolution: float,
                  solid: bool = False) -> int:
    """Mark the cells of ``occupied`` (nx, ny, nz bool, in place) that the mesh surface
    crosses; with ``solid`` also the cells it encloses. Returns the cells marked."""
    tri = mesh.vertices[mesh.faces].astype(np.float64)
    if not solid:
        return int(_mark_triangles(tri, occupied, float(origin[0]), float(origin[1]), float(origin[2]),
                                   float(resolution)))
    # solid: voxelize into a local box one cell larger than the mesh, fill, then merge
    lo = np.floor((tri.reshape(-1, 3).min(0) - origin) / resolution).astype(int) - 1
    hi = np.ceil((tri.reshape(-1, 3).max(0) - origin) / resolution).astype(int) + 2
    local = np.zeros(tuple(hi - lo), dtype=bool)
    o = origin + lo * resolution
    _mark_triangles(tri, local, float(o[0]), float(o[1]), float(o[2]), float(resolution))
    filled = ndimage.binary_fill_holes(local)
    glo, ghi = np.maximum(lo, 0), np.minimum(hi, occupied.shape)
    if np.any(ghi <= glo):
        return 0
    part = filled[glo[0] - lo[0]:ghi[0] - lo[0], glo[1] - lo[1]:ghi[1] - lo[1], glo[2] - lo[2]:ghi[2] - lo[2]]
    view = occupied[glo[0]:ghi[0], glo[1]:ghi[1], glo[2]:ghi[2]]
    before = int(view.sum())
    view |= part
    return int(view.sum()) - before


def boxes_to_mesh(boxes: list[tuple[np.ndarray, np.ndarray]]) -> Mesh:
    """Axis-aligned boxes (min (3,), max (3,)) -> one closed triangle mesh (12 triangles each,
    outward winding)."""
    corners = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]])
    quads = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (2, 3, 7, 6), (1, 2, 6, 5), (0, 4, 7, 3)]
    tri = np.array([[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads])
    verts, faces = [], []
    for k, (bmin, bmax) in enumerate(boxes):
        verts.append(np.asarray(bmin, float) + corners * (np.asarray(bmax, float) - np.asarray(bmin, float)))
        faces.append(tri + 8 * k)
    if not verts:
        return Mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64))
    return Mesh(np.concatenate(verts), np.concatenate(faces).astype(np.int64))


def write_mesh(path: str | Path, mesh: Mesh) -> Path:
    """Write a mesh in the format named by the suffix (.obj .ply .stl .glb .off), atomically."""
    import trimesh

    p = Path(path)
    suf = p.suffix.lower().lstrip(".")
    if suf not in ("obj", "ply", "stl", "glb", "off"):
        raise InputError(f"{p}: cannot write meshes as '.{suf}'; expected .obj, .ply, .stl, .glb or .off")
    tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    data = tm.export(file_type=suf)
    return atomic_write_bytes(p, data if isinstance(data, bytes) else data.encode())
