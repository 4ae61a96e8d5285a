"""Placement files: the poses of placement.json / placement.csv (or hand-written, or
another tool's) read into camplace.cameras.candidates.Candidates. Used by
camplace.workflows.evaluate (score a file) and by existing cameras (``existing:`` as a
CSV path, ``keep``). Formats: see camplace.workflows.evaluate."""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from camplace.cameras.candidates import (Candidates, location_ids_of, merge_cameras, rotation_from_ypr,
                                         ypr_from_rotation)
from camplace.cameras.models import CameraModel
from camplace.core.errors import InputError

CSV_COLUMNS = ("id", "x", "y", "z", "yaw", "pitch", "roll", "lens")


@dataclass(frozen=True)
class Poses:
    """Camera poses read from a file. ids: source ids (str); positions: (k, 3) m;
    rotations: (k, 3, 3) world-from-camera; angles_deg: (k, 3) yaw, pitch, roll;
    lenses: camera type names (None: the scene's only camera); intrinsics: per pose the
    JSON ``intrinsics`` object (+ ``max_range``) or None, used for a lens the scene lacks;
    focal_mm: per pose the focal length a varifocal type is set to (None: its widest)."""

    ids: tuple[str, ...]
    positions: np.ndarray
    rotations: np.ndarray
    angles_deg: np.ndarray
    lenses: tuple[str | None, ...]
    source: str = "<poses>"
    intrinsics: tuple[dict | None, ...] = ()
    focal_mm: tuple[float | None, ...] = ()

    def __len__(self) -> int:
        return len(self.positions)


def _number(value, where: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{where}: expected a number, got {value!r}") from None
    if not math.isfinite(v):
        raise InputError(f"{where}: expected a finite number, got {value!r}")
    return v


def read_placement_csv(path: str | Path) -> Poses:
    """Poses from a mount list CSV (header id,x,y,z,yaw,pitch,roll[,lens])."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"{p}: cannot read the placement CSV ({err})") from None
    rows = list(csv.reader(text.splitlines()))
    rows = [r for r in rows if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    if not rows:
        raise InputError(f"{p}: empty; expected a header {','.join(CSV_COLUMNS)} and one row per camera")
    header = [h.strip().lower() for h in rows[0]]
    missing = [c for c in CSV_COLUMNS[1:7] if c not in header]
    if missing:
        raise InputError(f"{p}: header lacks column(s) {', '.join(missing)}; expected {','.join(CSV_COLUMNS)}")
    col = {h: k for k, h in enumerate(header)}
    ids, pos, ang, lenses, focal = [], [], [], [], []
    for n, row in enumerate(rows[1:], start=2):
        if len(row) < len(header):
            raise InputError(f"{p}: line {n}: {len(row)} fields, expected {len(header)} ({','.join(header)})")
        get = {h: row[k].strip() for h, k in col.items()}
        pos.append([_number(get[c], f"{p}: line {n}: column '{c}'") for c in ("x", "y", "z")])
        ang.append([_number(get[c], f"{p}: line {n}: column '{c}'") for c in ("yaw", "pitch", "roll")])
        ids.append(get.get("id", str(n - 2)) or str(n - 2))
        lenses.append(get.get("lens") or None)
        focal.append(_focal(get.get("focal_mm"), f"{p}: line {n}: column 'focal_mm'"))
    if not pos:
        raise InputError(f"{p}: no camera rows after the header")
    a = np.asarray(ang, float)
    return Poses(tuple(ids), np.asarray(pos, float), rotation_from_ypr(a[:, 0], a[:, 1], a[:, 2]), a,
                 tuple(lenses), str(p), focal_mm=tuple(focal))


def _focal(value, where: str) -> float | None:
    """A focal length (mm, > 0) from a file, or None for an empty / missing value."""
    if value is None or value == "":
        return None
    f = _number(value, where)
    if f <= 0:
        raise InputError(f"{where}: expected a focal length > 0 (mm), got {value!r}")
    return f


def _rotation_of(cam: dict, where: str) -> tuple[np.ndarray, np.ndarray]:
    """(rotation (3, 3), angles (3,)) of one JSON camera object."""
    names = next((k for k in (("yaw_deg", "pitch_deg", "roll_deg"), ("yaw", "pitch", "roll"))
                  if any(x in cam for x in k)), None)
    ang = None
    if names is not None:
        if names[0] not in cam or names[1] not in cam:
            raise InputError(f"{where}: give both '{names[0]}' and '{names[1]}' ('{names[2]}' defaults to 0)")
        ang = np.array([_number(cam[names[0]], f"{where}.{names[0]}"), _number(cam[names[1]], f"{where}.{names[1]}"),
                        _number(cam.get(names[2], 0.0), f"{where}.{names[2]}")])
    if "rotation" in cam and cam["rotation"] is not None:
        try:
            R = np.asarray(cam["rotation"], float)
        except (TypeError, ValueError):
            raise InputError(f"{where}.rotation: expected a 3x3 list of numbers") from None
        if R.shape != (3, 3) or not np.all(np.isfinite(R)):
            raise InputError(f"{where}.rotation: expected a 3x3 list of numbers, got shape {R.shape}")
        if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or abs(np.linalg.det(R) - 1.0) > 1e-6:
            raise InputError(f"{where}.rotation: not a rotation matrix (orthonormal, det +1)")
        if ang is not None and not np.allclose(rotation_from_ypr(*ang)[0], R, atol=1e-6):
            raise InputError(f"{where}: 'rotation' and the yaw/pitch/roll angles disagree; edit both or give one")
        return R, (ang if ang is not None else ypr_from_rotation(R)[0])
    if ang is None:
        raise InputError(f"{where}: give 'rotation' (3x3 world-from-camera) or 'yaw_deg' and 'pitch_deg'")
    return rotation_from_ypr(*ang)[0], ang


def read_placement_json(path: str | Path) -> Poses:
    """Poses from placement.json (or a bare JSON list of camera objects)."""
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"{p}: cannot read the placement JSON ({err})") from None
    except json.JSONDecodeError as err:
        raise InputError(f"{p}: not valid JSON: {err}") from None
    cams = data.get("cameras") if isinstance(data, dict) else data
    if not isinstance(cams, list):
        raise InputError(f"{p}: cameras: expected a list of camera objects (placement.json format)")
    ids, pos, rot, ang, lenses, intrinsics, focal = [], [], [], [], [], [], []
    for k, cam in enumerate(cams):
        where = f"{p}: cameras[{k}]"
        if not isinstance(cam, dict):
            raise InputError(f"{where}: expected an object with 'position' and 'rotation' or angles")
        xyz = cam.get("position")
        if not isinstance(xyz, (list, tuple)) or len(xyz) != 3:
            raise InputError(f"{where}.position: expected [x, y, z] in metres")
        pos.append([_number(v, f"{where}.position") for v in xyz])
        R, a = _rotation_of(cam, where)
        rot.append(R)
        ang.append(a)
        cid = cam.get("candidate_id", cam.get("id"))
        ids.append(str(k if cid is None else cid))
        lens = cam.get("camera", cam.get("lens"))
        lenses.append(None if lens is None else str(lens))
        focal.append(_focal(cam.get("focal_mm"), f"{where}.focal_mm"))
        intr = cam.get("intrinsics")
        if intr is not None and not isinstance(intr, dict):
            raise InputError(f"{where}.intrinsics: expected an object (model, width, height, fx, fy, cx, cy)")
        intrinsics.append(None if intr is None else dict(intr, **({"max_range": cam["max_range"]}
                                                                     if "max_range" in cam else {})))
    if not cams:
        raise InputError(f"{p}: cameras: the list is empty")
    return Poses(tuple(ids), np.asarray(pos, float), np.asarray(rot, float), np.asarray(ang, float),
                 tuple(lenses), str(p), tuple(intrinsics), tuple(focal))


def read_placement(path: str | Path) -> Poses:
    """Poses from a .json or .csv placement file."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: placement file not found")
    suffix = p.suffix.lower()
    if suffix == ".json":
        return read_placement_json(p)
    if suffix in (".csv", ".txt"):
        return read_placement_csv(p)
    raise InputError(f"{p}: expected a .json (placement.json) or .csv (id,x,y,z,yaw,pitch,roll,lens) file")


def camera_from_intrinsics(name: str, intr: dict, scene_cameras: list[CameraModel], where: str) -> CameraModel:
    """A lens the scene does not name, from a placement.json-style ``intrinsics`` object;
    ``max_range`` from the object, else the scene's cameras' common range."""
    try:
        vals = {k: intr[k] for k in ("width", "height", "fx", "fy", "cx", "cy")}
    except KeyError as err:
        raise InputError(f"{where}.intrinsics: '{err.args[0]}' missing; expected model, width, height, fx, fy, "
                         f"cx, cy (pixels) and optional distortion, max_range") from None
    ranges = {c.max_range for c in scene_cameras}
    if "max_range" in intr:
        rng = _number(intr["max_range"], f"{where}.max_range")
    elif len(ranges) == 1:
        rng = ranges.pop()
    else:
        raise InputError(f"{where}: lens '{name}' is not in the scene and the scene's cameras differ in "
                         f"max_range; give 'max_range' (m)")
    return CameraModel(name, str(intr.get("model", "pinhole")), int(vals["width"]), int(vals["height"]),
                       *(_number(vals[k], f"{where}.intrinsics.{k}") for k in ("fx", "fy", "cx", "cy")),
                       max_range=rng, distortion=tuple(_number(v, f"{where}.intrinsics.distortion")
                                                       for v in intr.get("distortion") or ()))


def candidates_from_poses(poses: Poses, cameras: dict[str, CameraModel]) -> Candidates:
    """One candidate per pose, in file order. A lens is a scene camera by name (set to the
    pose's ``focal_mm`` when given: a lens as sold, camplace.cameras.models.CameraModel.at_focal);
    a name the scene lacks needs the pose's ``intrinsics`` (JSON), which then define that lens."""
    cam_list = list(cameras.values())
    index = {c.name: k for k, c in enumerate(cam_list)}
    scene_names = list(index)
    ids = np.empty(len(poses), np.int32)
    for k, lens in enumerate(poses.lenses):
        intr = poses.intrinsics[k] if k < len(poses.intrinsics) else None
        if lens is None:
            if len(scene_names) != 1:
                raise InputError(f"{poses.source}: camera {poses.ids[k]}: no lens given and the scene has "
                                 f"{len(scene_names)} cameras ({', '.join(scene_names)}); add a 'lens' column / "
                                 f"'camera' key")
            ids[k] = 0
        elif lens not in index:
            if intr is None:
                raise InputError(f"{poses.source}: camera {poses.ids[k]}: lens '{lens}' is not a camera of the "
                                 f"scene (expected one of {', '.join(scene_names)}, or give its 'intrinsics')")
            index[lens] = len(cam_list)
            cam_list.append(camera_from_intrinsics(lens, intr, list(cameras.values()),
                                                   f"{poses.source}: cameras[{k}]"))
            ids[k] = index[lens]
        else:
            ids[k] = index[lens]
        f = poses.focal_mm[k] if k < len(poses.focal_mm) else None
        if f is not None:
            ids[k] = _at_focal(cam_list, int(ids[k]), f, f"{poses.source}: camera {poses.ids[k]}: focal_mm")
    cam_list = tuple(cam_list)
    return Candidates(np.ascontiguousarray(poses.positions, float), np.ascontiguousarray(poses.rotations, float),
                      np.asarray(poses.angles_deg, float), ids, location_ids_of(poses.positions), cam_list,
                      {"generated": len(poses), "dropped_inside_obstacle": 0, "source": poses.source})


def _at_focal(cam_list: list[CameraModel], k: int, focal_mm: float, where: str) -> int:
    """Index in ``cam_list`` of camera k set to ``focal_mm`` (appended unless already there)."""
    cam = cam_list[k]
    if cam.lens is None:
        raise InputError(f"{where}: lens '{cam.name}' is not given by focal_mm in the scene; remove the focal length")
    if not cam.lens.focal_min_mm - 1e-6 <= focal_mm <= cam.lens.focal_max_mm + 1e-6:
        raise InputError(f"{where}: {focal_mm:g} mm is outside lens '{cam.name}' "
                         f"({cam.lens.focal_min_mm:g}..{cam.lens.focal_max_mm:g} mm)")
    merged, idx = merge_cameras(tuple(cam_list), (cam.at_focal(focal_mm),))
    cam_list[:] = merged
    return int(idx[0])
