"""scene.glb (trimesh, binary glTF 2.0): the scene, the cameras and the coverage in 3D.

Nodes: ``room`` (the floor polygon and the walls along the footprint, from 0 to the
room's height), ``obstacles`` (the box obstacles merged into one mesh) or, for scans and
meshes, ``occupancy`` (the exposed faces of the occupied cells inside the room: a voxel
surface), one ``camera <mark> id <id>`` frustum per camera (a pyramid from the camera
centre to its image corners, FRUSTUM_DEPTH m deep, kept inside the room's box), and
``coverage`` (the targets as points coloured by coverage class, the Fig. 2 colours).
Scene frame, metres, z up (glTF viewers that expect y up show it lying on its side
unless told z is up; Blender's importer converts it).
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from camplace.core.files import atomic_write_bytes
from camplace.outputs.figures import COVERAGE_CLASSES, coverage_class
from camplace.outputs.plan_data import PlanData

FRUSTUM_DEPTH = 0.4  # m
MAX_FACES = 2_000_000  # voxel surfaces larger than this are built from a coarser copy of the grid


def _rgba(hex_colour: str) -> list[int]:
    return [int(hex_colour[1:3], 16), int(hex_colour[3:5], 16), int(hex_colour[5:7], 16), 255]


def room_mesh(footprint: np.ndarray, height: float, floor=None):
    """The floor (constrained Delaunay triangles of the footprint, or of the shapely polygon
    ``floor``: a storey's slab with its openings) and the wall quads."""
    import shapely
    import trimesh
    from shapely.geometry import Polygon

    fp = np.asarray(footprint, float)
    tris = shapely.constrained_delaunay_triangles(Polygon(fp) if floor is None else floor)
    floor = [np.asarray(t.exterior.coords)[:3] for t in tris.geoms]
    v, f = [], []
    for t in floor:
        f.append([len(v), len(v) + 1, len(v) + 2])
        v.extend([[x, y, 0.0] for x, y in t])
    for a, b in zip(fp, np.roll(fp, -1, axis=0)):
        k = len(v)
        v.extend([[a[0], a[1], 0.0], [b[0], b[1], 0.0], [b[0], b[1], height], [a[0], a[1], height]])
        f.extend([[k, k + 1, k + 2], [k, k + 2, k + 3]])
    return trimesh.Trimesh(np.array(v), np.array(f), process=False)


def boxes_mesh(boxes: dict):
    """The box obstacles (name -> (min, max) m) merged into one mesh; None without boxes."""
    import trimesh

    parts = [trimesh.creation.box(bounds=np.array([b0, b1], float)) for b0, b1 in boxes.values()]
    return trimesh.util.concatenate(parts) if parts else None


def voxel_surface(mask: np.ndarray, origin: np.ndarray, res: float):
    """The exposed faces of the True cells of ``mask`` (nx, ny, nz) from ``origin`` (3,) in
    cells of ``res`` m, as one mesh (two triangles a face); None when there are none."""
    import trimesh

    while mask.sum() * 6 > MAX_FACES and min(mask.shape) > 2:
        s = [n - n % 2 for n in mask.shape]
        mask = mask[:s[0], :s[1], :s[2]].reshape(s[0] // 2, 2, s[1] // 2, 2, s[2] // 2, 2).any(axis=(1, 3, 5))
        res *= 2
    padded = np.pad(mask, 1)
    verts, faces = [], []
    unit = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    quads = {(0, 1): (1, 2, 6, 5), (0, -1): (0, 4, 7, 3), (1, 1): (2, 3, 7, 6), (1, -1): (0, 1, 5, 4),
             (2, 1): (4, 5, 6, 7), (2, -1): (0, 3, 2, 1)}
    n = 0
    for (axis, sign), q in quads.items():
        nb = np.roll(padded, -sign, axis=axis)[1:-1, 1:-1, 1:-1]
        cells = np.argwhere(mask & ~nb).astype(float)
        if not len(cells):
            continue
        corners = origin + (cells[:, None, :] + unit[list(q)][None]) * res  # (M, 4, 3)
        verts.append(corners.reshape(-1, 3))
        base = n + 4 * np.arange(len(cells))[:, None]
        faces.append(np.vstack([np.c_[base, base + 1, base + 2], np.c_[base, base + 2, base + 3]]))
        n += 4 * len(cells)
    if not verts:
        return None
    return trimesh.Trimesh(np.vstack(verts), np.vstack(faces), process=False)


def frustum_mesh(camera: dict, lo: np.ndarray, hi: np.ndarray, depth: float = FRUSTUM_DEPTH):
    """A pyramid from the camera centre to its four image corners at ``depth`` m (pinhole
    approximation of the intrinsics), clipped into the box [lo, hi]."""
    import trimesh

    k = camera["intrinsics"]
    uv = np.array([[-0.5, -0.5], [k["width"] - 0.5, -0.5], [k["width"] - 0.5, k["height"] - 0.5],
                   [-0.5, k["height"] - 0.5]])
    rays = np.c_[(uv[:, 0] - k["cx"]) / k["fx"], (uv[:, 1] - k["cy"]) / k["fy"], np.ones(4)]
    rays /= np.linalg.norm(rays, axis=1, keepdims=True)
    p = np.asarray(camera["position"], float)
    corners = p + depth * rays @ np.asarray(camera["rotation"], float).T
    v = np.clip(np.vstack([p, corners]), lo, hi)
    f = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1], [1, 3, 2], [1, 4, 3]])
    return trimesh.Trimesh(v, f, process=False)


def scene_glb(data: PlanData) -> bytes:
    """The binary glTF of the scene, cameras and coverage."""
    import trimesh

    sc = data.scene
    fp = np.asarray(sc.footprint, float)
    lo, hi = np.r_[fp.min(0), 0.0], np.r_[fp.max(0), sc.height]
    out = trimesh.Scene()
    room = room_mesh(fp, sc.height)
    room.visual.face_colors = [205, 205, 200, 255]
    out.add_geometry(room, node_name="room", geom_name="room")
    occ = sc.occupancy
    if sc.boxes:
        mesh = boxes_mesh({k: v for k, v in sc.boxes.items()})
        mesh.visual.face_colors = [150, 150, 150, 255]
        out.add_geometry(mesh, node_name="obstacles", geom_name="obstacles")
    elif occ.occupied.any():
        from shapely import contains_xy

        gx, gy = np.meshgrid(occ.cell_centres(0), occ.cell_centres(1), indexing="ij")
        zs = occ.cell_centres(2)
        inner = occ.occupied & contains_xy(sc.polygon, gx, gy)[:, :, None] & ((zs >= 0) & (zs <= sc.height))
        mesh = voxel_surface(inner, np.asarray(occ.origin, float), float(occ.resolution))
        if mesh is not None:
            mesh.visual.face_colors = [150, 150, 150, 255]
            out.add_geometry(mesh, node_name="occupancy", geom_name="occupancy")
    for c, mark in zip(data.cameras, data.marks):
        fr = frustum_mesh(c, lo, hi)
        fr.visual.face_colors = [31, 79, 209, 160]
        name = f"camera {mark} id {c.get('source_id', c['candidate_id'])}"
        out.add_geometry(fr, node_name=name, geom_name=name)
    pos = np.asarray(data.targets.positions, float)
    if len(pos):
        colours = np.array([_rgba(c) for _, c in COVERAGE_CLASSES], np.uint8)[coverage_class(data.coverage)]
        out.add_geometry(trimesh.PointCloud(pos, colors=colours), node_name="coverage", geom_name="coverage")
    buf = io.BytesIO()
    out.export(buf, file_type="glb")
    return buf.getvalue()


def write_scene_glb(path: str | Path, data: PlanData) -> Path:
    return atomic_write_bytes(Path(path), scene_glb(data))


def building_glb(scene, storeys: list[PlanData]) -> bytes:
    """The binary glTF of a building (camplace.scene.build.Scene with storeys), stacked: per
    storey (PlanData of camplace.outputs.plan_storeys, local z) the nodes '<storey>/room'
    (its slab, open where its floor is, and its outer walls from its floor to its ceiling),
    '<storey>/obstacles' (boxes), '<storey>/walls' (prism obstacles), '<storey>/camera <mark>
    id <id>' and '<storey>/coverage', all raised to the storey's elevation (building z)."""
    import shapely
    import trimesh

    from camplace.outputs.walls import prism_mesh, scene_walls

    out = trimesh.Scene()

    def add(mesh, name: str, e: float, colour) -> None:
        mesh.apply_translation([0.0, 0.0, e])
        if colour is not None:
            mesh.visual.face_colors = colour
        out.add_geometry(mesh, node_name=name, geom_name=name)

    for st, data in zip(scene.storeys, storeys):
        sc, e, n = st.scene, float(st.elevation), st.name
        fp = np.asarray(sc.footprint, float)
        slab = sc.polygon.difference(shapely.union_all(st.openings)) if st.openings else None
        add(room_mesh(fp, sc.height, slab), f"{n}/room", e, [205, 205, 200, 255])
        if sc.boxes:
            add(boxes_mesh(sc.boxes), f"{n}/obstacles", e, [150, 150, 150, 255])
        walls = [trimesh.Trimesh(v, t, process=False) for v, t in (prism_mesh(w, sc.height) for w in scene_walls(sc))
                 if len(t)]
        if walls:
            add(trimesh.util.concatenate(walls), f"{n}/walls", e, [120, 120, 120, 255])
        lo, hi = np.r_[fp.min(0), 0.0], np.r_[fp.max(0), sc.height]
        for c, mark in zip(data.cameras, data.marks):
            add(frustum_mesh(c, lo, hi), f"{n}/camera {mark} id {c.get('source_id', c['candidate_id'])}", e,
                [31, 79, 209, 160])
        pos = np.asarray(data.targets.positions, float)
        if len(pos):
            colours = np.array([_rgba(c) for _, c in COVERAGE_CLASSES], np.uint8)[coverage_class(data.coverage)]
            out.add_geometry(trimesh.PointCloud(pos + [0.0, 0.0, e], colors=colours), node_name=f"{n}/coverage",
                             geom_name=f"{n}/coverage")
    buf = io.BytesIO()
    out.export(buf, file_type="glb")
    return buf.getvalue()


def write_building_glb(path: str | Path, scene, storeys: list[PlanData]) -> Path:
    return atomic_write_bytes(Path(path), building_glb(scene, storeys))
