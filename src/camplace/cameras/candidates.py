"""Stage 3 - candidate poses: where a camera may be mounted and how it may point.

Angles (degrees): yaw about world z, 0 = +x, counter-clockwise; pitch = downward tilt
below the horizon; roll about the optical axis (positive turns the image x axis
toward the image y axis). Rotations are world-from-camera (columns = camera x, y, z
axes in world), OpenCV camera frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import shapely

from camplace.cameras.models import CameraModel
from camplace.cameras.mount_rules import CEILING_BACK, allowed_xy, clear_of_occupied, explicit_points
from camplace.spec.schema import Mount, angle_values
from camplace.core.errors import InputError
from camplace.scene.build import Scene


def rotation_from_ypr(yaw_deg, pitch_deg, roll_deg) -> np.ndarray:
    """Vectorized world-from-camera rotations: inputs broadcast to (N,) -> (N, 3, 3)."""
    y, p, r = (np.radians(np.atleast_1d(np.asarray(a, float))) for a in (yaw_deg, pitch_deg, roll_deg))
    y, p, r = np.broadcast_arrays(y, p, r)
    fwd = np.stack([np.cos(p) * np.cos(y), np.cos(p) * np.sin(y), -np.sin(p)], axis=-1)
    right0 = np.stack([np.sin(y), -np.cos(y), np.zeros_like(y)], axis=-1)
    down0 = np.cross(fwd, right0)
    cr, sr = np.cos(r)[..., None], np.sin(r)[..., None]
    right = cr * right0 + sr * down0
    down = -sr * right0 + cr * down0
    return np.stack([right, down, fwd], axis=-1)


def ypr_from_rotation(R: np.ndarray) -> np.ndarray:
    """Inverse of rotation_from_ypr: (N, 3, 3) -> (N, 3) yaw, pitch, roll in degrees."""
    R = np.asarray(R, float).reshape(-1, 3, 3)
    fwd = R[:, :, 2]
    pitch = np.degrees(np.arcsin(np.clip(-fwd[:, 2], -1, 1)))
    yaw = np.degrees(np.arctan2(fwd[:, 1], fwd[:, 0]))
    R0 = rotation_from_ypr(yaw, pitch, 0.0)
    right = R[:, :, 0]
    roll = np.degrees(np.arctan2(np.einsum("ij,ij->i", right, R0[:, :, 1]), np.einsum("ij,ij->i", right, R0[:, :, 0])))
    return np.c_[yaw % 360.0, pitch, roll]


@dataclass(frozen=True)
class Candidates:
    """N_g candidate poses. positions: (N, 3) m; rotations: (N, 3, 3) world-from-camera;
    angles_deg: (N, 3) yaw, pitch, roll; camera_ids: (N,) int32 index into ``cameras``;
    location_ids: (N,) int64 (same position = same location)."""

    positions: np.ndarray
    rotations: np.ndarray
    angles_deg: np.ndarray
    camera_ids: np.ndarray
    location_ids: np.ndarray
    cameras: tuple[CameraModel, ...]
    info: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.positions)

    def subset(self, keep: np.ndarray) -> "Candidates":
        """Rows ``keep`` (bool mask or index array), location ids unchanged."""
        return replace(self, positions=self.positions[keep], rotations=self.rotations[keep],
                       angles_deg=self.angles_deg[keep], camera_ids=self.camera_ids[keep],
                       location_ids=self.location_ids[keep])


def location_ids_of(positions: np.ndarray) -> np.ndarray:
    """(N, 3) metres -> (N,) int64: equal (to 1 mm) positions share an id, ids in first-seen order."""
    key = np.round(np.asarray(positions, float) * 1000.0).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(np.argsort(first, kind="stable"), kind="stable")  # rank by first appearance
    return order[inv.ravel()].astype(np.int64)


def ceiling_grid_positions(scene: Scene, mount: Mount) -> np.ndarray:
    """Grid points (multiples of ``spacing`` from the footprint's min corner) inside the
    footprint at least ``wall_clearance`` from its boundary: (M, 3) metres."""
    s = float(mount.spacing)
    lo, hi = scene.footprint.min(0), scene.footprint.max(0)
    xs = lo[0] + s * np.arange(int(np.floor((hi[0] - lo[0]) / s + 1e-9)) + 1)
    ys = lo[1] + s * np.arange(int(np.floor((hi[1] - lo[1]) / s + 1e-9)) + 1)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    region = scene.polygon.buffer(-mount.wall_clearance) if mount.wall_clearance > 0 else scene.polygon
    inside = shapely.contains_xy(region, gx, gy)
    z = scene.height - mount.offset_below_ceiling
    return np.c_[gx[inside], gy[inside], np.full(int(inside.sum()), z)]


def wall_positions(scene: Scene, mount: Mount) -> tuple[np.ndarray, np.ndarray]:
    """Mount points along walls: every ``spacing`` m (the first half a spacing from a
    wall's end) on each wall segment - ``mount.walls`` or, by default, the footprint's
    edges - moved ``wall_clearance`` m inward, at z = ``height``.

    Returns (positions (M, 3) m, inward-facing yaw (M,) degrees). Points outside the
    footprint are dropped. The inward side of a given segment is the one whose offset
    midpoint lies inside the footprint."""
    poly = scene.polygon
    s = float(mount.spacing)
    out_p, out_yaw = [], []
    for a, b in wall_segments(scene, mount):
        d = b - a
        length = float(np.hypot(*d))
        if length < 1e-9:
            continue
        u = d / length
        n = inward_normal(poly, a, b, mount.wall_clearance)
        k = max(int(np.floor(length / s + 1e-9)), 1)
        t = (np.arange(k) + 0.5) * (length / k)
        xy = a + np.outer(t, u) + n * mount.wall_clearance
        out_p.append(np.c_[xy, np.full(k, float(mount.height))])
        out_yaw.append(np.full(k, np.degrees(np.arctan2(n[1], n[0]))))
    if not out_p:
        return np.zeros((0, 3)), np.zeros(0)
    p, yaw = np.concatenate(out_p), np.concatenate(out_yaw)
    keep = shapely.contains_xy(poly, p[:, 0], p[:, 1])
    return p[keep], yaw[keep]


def wall_segments(scene: Scene, mount: Mount) -> np.ndarray:
    """(S, 2, 2) m: the mount's ``walls`` segments, or the footprint's edges."""
    if mount.walls is not None:
        return np.asarray(mount.walls, float).reshape(-1, 2, 2)
    fp = scene.footprint
    return np.stack([fp, np.roll(fp, -1, axis=0)], axis=1)


def inward_normal(poly, a: np.ndarray, b: np.ndarray, clearance: float) -> np.ndarray:
    """(2,) unit normal of segment a-b pointing into the room (the left one unless its probe
    point, ``clearance`` (>= 5 cm) from the midpoint, lies outside while the right one's lies inside)."""
    d = (b - a) / float(np.hypot(*(b - a)))
    n = np.array([-d[1], d[0]])
    mid = (a + b) / 2
    probe = max(clearance, 0.05)
    if not shapely.contains_xy(poly, *(mid + n * probe)) and shapely.contains_xy(poly, *(mid - n * probe)):
        n = -n
    return n


def nearest_wall_yaw(scene: Scene, mount: Mount, xy: np.ndarray) -> np.ndarray:
    """(M,) degrees: the inward-normal yaw of the wall segment nearest each point (M, 2)."""
    segs = [(a, b) for a, b in wall_segments(scene, mount) if np.hypot(*(b - a)) > 1e-9]
    dist = np.stack([shapely.distance(shapely.LineString([a, b]), shapely.points(xy)) for a, b in segs], axis=1)
    normals = np.array([inward_normal(scene.polygon, a, b, mount.wall_clearance) for a, b in segs])
    n = normals[np.argmin(dist, axis=1)]
    return np.degrees(np.arctan2(n[:, 1], n[:, 0]))


def mount_positions(scene: Scene, mount: Mount, points: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None]:
    """(positions (M, 3) m, base yaw (M,) degrees or None): the mount's grid / wall points,
    or the explicit ``points`` (mount_rules.points) with the nearest wall's yaw for wall mounts."""
    if points is not None:
        return points, nearest_wall_yaw(scene, mount, points[:, :2]) if mount.kind == "wall" else None
    if mount.kind == "wall":  # yaw relative to the inward normal of each wall
        return wall_positions(scene, mount)
    return ceiling_grid_positions(scene, mount), None


def mount_backs(mount: Mount, base_yaw: np.ndarray | None, n: int) -> np.ndarray:
    """(n, 3): the direction of the surface each of a mount's n positions hangs from: up
    (+z) for a ceiling grid, into the wall (minus the inward normal, ``base_yaw`` degrees)
    for a wall mount (camplace.cameras.mount_rules.occupied_distance ignores what lies behind)."""
    if mount.kind == "wall" and base_yaw is not None:
        yaw = np.radians(np.asarray(base_yaw, float))
        return -np.c_[np.cos(yaw), np.sin(yaw), np.zeros(len(yaw))]
    return np.tile(CEILING_BACK, (n, 1))


def surface_back(scene: Scene, position: np.ndarray) -> np.ndarray:
    """(3,): the direction of the surface a camera at ``position`` (3,) m hangs from, by the
    mount at its height (a ceiling grid: up; a wall mount: into the nearest wall); zero when
    no mount has that height (then every side keeps the clearance)."""
    z = float(position[2])
    for m in scene.spec.mounts:
        if m.kind == "ceiling_grid" and abs(scene.height - m.offset_below_ceiling - z) < 1e-6:
            return CEILING_BACK.copy()
        if m.kind == "wall" and abs(float(m.height) - z) < 1e-6:
            return mount_backs(m, nearest_wall_yaw(scene, m, np.asarray(position, float)[None, :2]), 1)[0]
    return np.zeros(3)


def mount_points(scene: Scene, mount: Mount, points: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None, dict]:
    """The positions (M, 3) m of one mount where a camera may hang, their base yaw (M,)
    degrees or None, and the counts of positions removed: by the mount rules' areas
    (``ruled_out``), inside an obstacle or, on scans, unobserved space (``inside``),
    closer than ``mount_rules.clearance`` to a wall or obstacle (``clearance``)."""
    p, base_yaw = mount_positions(scene, mount, points)
    counts = {"ruled_out": 0, "inside": 0, "clearance": 0}
    if scene.spec.mount_rules.active:  # forbid / allow polygons (camplace.cameras.mount_rules)
        keep = allowed_xy(scene, p[:, :2])
        counts["ruled_out"] = int((~keep).sum())
        p, base_yaw = p[keep], None if base_yaw is None else base_yaw[keep]
    inside = scene.occupancy.is_occupied(p)
    if getattr(scene, "free_space", None) is not None:  # scans: not in space no scanner saw (inside things)
        inside |= ~scene.free_space.observed_at(p)
    keep = ~inside
    keep[keep] = clear_of_occupied(scene, p[keep], mount_backs(mount, None if base_yaw is None else base_yaw[keep],
                                                                int(keep.sum())))
    counts.update(inside=int(inside.sum()), clearance=int((~inside & ~keep).sum()))
    return p[keep], None if base_yaw is None else base_yaw[keep], counts


def lens_settings(cameras: dict[str, CameraModel]) -> tuple[tuple[CameraModel, ...], dict[str, list[int]]]:
    """(every camera model a candidate may carry: each type's focal settings in type order
    (camplace.cameras.models.CameraModel.settings); type name -> its indices in that tuple).
    Without varifocal lenses the tuple is ``cameras.values()``."""
    cam_list: list[CameraModel] = []
    index: dict[str, list[int]] = {}
    for name, cam in cameras.items():
        settings = cam.settings()
        index[name] = list(range(len(cam_list), len(cam_list) + len(settings)))
        cam_list += settings
    return tuple(cam_list), index


def merge_cameras(first: tuple[CameraModel, ...],
                  second: tuple[CameraModel, ...]) -> tuple[tuple[CameraModel, ...], np.ndarray]:
    """(``first`` + the models of ``second`` it lacks, (len(second),) int32 index of each of
    ``second``'s models in that tuple): camera ids of two candidate sets in one tuple."""
    out = list(first)
    idx = np.empty(len(second), np.int32)
    for k, cam in enumerate(second):
        if cam not in out:
            out.append(cam)
        idx[k] = out.index(cam)
    return tuple(out), idx


def focal_models(cameras: tuple[CameraModel, ...], camera_ids: np.ndarray,
                 focal_mm: np.ndarray) -> tuple[tuple[CameraModel, ...], np.ndarray]:
    """(``cameras`` + the focal settings it lacks, (K,) int32 ids): each pose's camera
    ``camera_ids[k]`` set to ``focal_mm[k]`` (CameraModel.at_focal; a camera without a
    lens as sold, or already at that focal length, keeps its id)."""
    ids = np.asarray(camera_ids, np.int32).copy()
    todo = [k for k, (c, f) in enumerate(zip(ids, np.asarray(focal_mm, float)))
            if cameras[c].lens is not None and f != cameras[c].focal_mm]
    if not todo:
        return tuple(cameras), ids
    cams, idx = merge_cameras(tuple(cameras), tuple(cameras[ids[k]].at_focal(float(focal_mm[k])) for k in todo))
    ids[todo] = idx
    return cams, ids


def stack_candidates(scene: Scene, cameras: dict[str, CameraModel],
                     extra_pitches: tuple[float, ...] = ()) -> Candidates:
    """A building's candidates: each storey's (its own mounts and rules, floor at z = 0)
    raised to its elevation, as one set in building z; poses that would hang in the open
    slab under the next storey's floor openings (within OPENING_REACH_M of that storey's
    ceiling) are dropped. A storey with no pose in free space is left out (counted in
    ``info['storeys_without_mounts']``); none at all is an InputError."""
    parts, empty, dropped = [], [], 0
    for k, st in enumerate(scene.storeys):
        try:
            c = build_candidates(st.scene, cameras, extra_pitches)
        except InputError:
            empty.append(st.name)
            continue
        keep = np.ones(len(c), bool)
        above = scene.storeys[k + 1].openings if k + 1 < len(scene.storeys) else ()
        near_ceiling = c.positions[:, 2] > st.top - st.elevation - OPENING_REACH_M
        for hole in above:
            keep &= ~(near_ceiling & shapely.contains_xy(hole, c.positions[:, 0], c.positions[:, 1]))
        dropped += int((~keep).sum())
        c = c.subset(keep)
        parts.append((c, st.elevation))
    if not parts:
        raise InputError(f"scene '{scene.name}': mounts: no candidate pose lies in free space on any storey")
    first = parts[0][0]
    positions = np.concatenate([c.positions + [0.0, 0.0, e] for c, e in parts])
    info = {key: sum(int(c.info.get(key) or 0) for c, _ in parts) for key in
            ("generated", "dropped_inside_obstacle", "dropped_clearance")}
    info.update(clearance_m=first.info.get("clearance_m", 0.0), dropped_under_openings=dropped,
                storeys_without_mounts=empty)
    return Candidates(positions, np.concatenate([c.rotations for c, _ in parts]),
                      np.concatenate([c.angles_deg for c, _ in parts]),
                      np.concatenate([c.camera_ids for c, _ in parts]), location_ids_of(positions), first.cameras,
                      info)


OPENING_REACH_M = 0.5  # a ceiling pose this close below an opening in the floor above has nothing to hang from


def build_candidates(scene: Scene, cameras: dict[str, CameraModel],
                     extra_pitches: tuple[float, ...] = ()) -> Candidates:
    """Every mount of the scene expanded into poses, each pose with every focal setting of
    each camera type the mount carries; poses inside an obstacle or closer than
    ``mount_rules.clearance`` to one are dropped (counted per pose in ``info``). A building:
    every storey's (stack_candidates). ``extra_pitches`` (degrees down) join every mount's
    own pitches (a crowd-aware run's steep views, camplace.spec.crowd.CrowdSpec.steep_pitches)."""
    if scene.storeys:
        return stack_candidates(scene, cameras, extra_pitches)
    cam_list, cam_index = lens_settings(cameras)
    pos, ang, cid = [], [], []
    rules = scene.spec.mount_rules
    points = explicit_points(scene)
    ruled_out = n_all = n_inside = n_close = 0
    for mount in scene.spec.mounts:
        yaws, pitches, rolls = (angle_values(a) for a in (mount.yaw_deg, mount.pitch_deg, mount.roll_deg))
        if extra_pitches:
            pitches = sorted(set(pitches) | {float(v) for v in extra_pitches})
        yy, pp, rr = np.meshgrid(yaws, pitches, rolls, indexing="ij")
        a = np.c_[yy.ravel(), pp.ravel(), rr.ravel()]
        ks = [k for name in mount.camera_names for k in cam_index[name]]  # camera types x focal settings
        p, base_yaw, counts = mount_points(scene, mount, points)
        ruled_out += counts["ruled_out"]
        n_inside += counts["inside"] * len(a) * len(ks)
        n_close += counts["clearance"] * len(a) * len(ks)
        n_all += (len(p) + counts["inside"] + counts["clearance"]) * len(a) * len(ks)
        a_all = np.tile(a, (len(p), 1))
        if base_yaw is not None:
            a_all[:, 0] = (a_all[:, 0] + np.repeat(base_yaw, len(a))) % 360.0
        for k in ks:
            pos.append(np.repeat(p, len(a), axis=0))
            ang.append(a_all)
            cid.append(np.full(len(p) * len(a), k, dtype=np.int32))
    positions = np.concatenate(pos) if pos else np.zeros((0, 3))
    angles = np.concatenate(ang) if ang else np.zeros((0, 3))
    camera_ids = np.concatenate(cid) if cid else np.zeros(0, np.int32)
    if len(positions) == 0:
        raise InputError(f"scene '{scene.name}': mounts: no candidate pose lies in free space "
                         f"({n_all} generated, {n_inside} inside obstacles or walls, {n_close} closer than "
                         f"mount_rules.clearance ({rules.clearance:g} m) to a wall or obstacle)")
    rot = rotation_from_ypr(angles[:, 0], angles[:, 1], angles[:, 2])
    info = {"generated": n_all, "dropped_inside_obstacle": n_inside, "dropped_clearance": n_close,
            "clearance_m": float(rules.clearance)}
    if extra_pitches:  # the refinement's pitch steps count them too (camplace.improve.refine.pose_box)
        info["extra_pitches"] = [float(v) for v in extra_pitches]
    if rules.active:
        info.update(mount_positions_ruled_out=ruled_out, explicit_points=None if points is None else len(points))
    return Candidates(positions, rot, angles, camera_ids, location_ids_of(positions), cam_list, info)
