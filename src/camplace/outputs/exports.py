"""Exports of the mount list for calibration and reconstruction tools, and their readers.

Two formats, both written from the camera objects of placement.json (``position`` in
metres, ``rotation`` world-from-camera with OpenCV camera axes, ``intrinsics``):

- **OpenCV camera YAML**, one file per camera (``opencv/camera_<id>.yaml``), in the
  ``%YAML:1.0`` FileStorage format that ``cv2.FileStorage`` reads:
  ``camera_matrix`` K (3x3), ``distortion_coefficients`` (1xN, OpenCV order
  k1 k2 p1 p2 k3 ...), ``rotation_matrix`` R and ``translation_vector`` t (3x1) of the
  OpenCV **world-to-camera** transform x_cam = R x_world + t (so R = rotationᵀ and
  t = −R·position), ``rvec`` (Rodrigues of R), ``image_width``/``image_height``.
  Pixel convention: OpenCV's (centre of the top-left pixel at (0, 0)), as camplace.
- **COLMAP text model** (``colmap/cameras.txt``, ``images.txt``, empty
  ``points3D.txt``): one COLMAP camera per mounted camera; images.txt holds
  QW QX QY QZ TX TY TZ of world-to-camera (Hamilton quaternion, QW >= 0). COLMAP puts
  the centre of the top-left pixel at (0.5, 0.5), so cx, cy are written +0.5 and the
  reader subtracts it again.

The readers (``read_opencv_yaml``, ``read_colmap_text``) return the same fields back,
including ``position`` and world-from-camera ``rotation``; numbers are written with
Python's shortest round-trip repr, so a round trip is exact up to float rounding.
A lens as sold (issue 27) also carries the focal length it is set to: ``focal_length_mm``
in the OpenCV YAML, a ``# CAMERA_ID k FOCAL_MM f`` comment line in cameras.txt (COLMAP
skips comments); K holds the intrinsics that follow from it.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import yaml

from camplace.core.errors import InputError
from camplace.core.files import atomic_write_text, atomic_write_texts

COLMAP_MODELS = {  # name -> number of distortion coefficients after fx fy cx cy
    "PINHOLE": 0, "OPENCV": 4, "FULL_OPENCV": 8, "OPENCV_FISHEYE": 4,
}


# ----------------------------------------------------------------------------- poses
def world_to_camera(rotation: np.ndarray, position: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World-from-camera rotation (3, 3) and camera centre (3,) m -> OpenCV extrinsics
    (R (3, 3), t (3,)) with x_cam = R x_world + t."""
    Rwc = np.asarray(rotation, float).reshape(3, 3)
    R = Rwc.T.copy()
    t = -R @ np.asarray(position, float).reshape(3)
    return R, t


def camera_pose(R: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of world_to_camera: (R, t) -> (world-from-camera rotation, centre (3,) m)."""
    R = np.asarray(R, float).reshape(3, 3)
    return R.T.copy(), -R.T @ np.asarray(t, float).reshape(3)


def rotmat_to_qvec(R: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) -> unit quaternion (qw, qx, qy, qz), qw >= 0 (Shepperd)."""
    R = np.asarray(R, float).reshape(3, 3)
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr > 0:
        s = 2.0 * math.sqrt(tr + 1.0)
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = 2.0 * math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = [(R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s]
    elif R[1, 1] > R[2, 2]:
        s = 2.0 * math.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = [(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = [(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s]
    q = np.asarray(q, float)
    q /= np.linalg.norm(q)
    return -q if q[0] < 0 else q


def qvec_to_rotmat(q: np.ndarray) -> np.ndarray:
    """Quaternion (qw, qx, qy, qz) (normalized here) -> rotation matrix (3, 3)."""
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def rodrigues(R: np.ndarray) -> np.ndarray:
    """Rotation matrix -> axis * angle (3,) (OpenCV rvec)."""
    q = rotmat_to_qvec(R)
    s = np.linalg.norm(q[1:])
    if s < 1e-15:
        return np.zeros(3)
    angle = 2.0 * math.atan2(s, q[0])
    return q[1:] / s * angle


def intrinsic_matrix(intr: dict) -> np.ndarray:
    """K (3, 3) from a placement.json ``intrinsics`` object."""
    return np.array([[intr["fx"], 0.0, intr["cx"]], [0.0, intr["fy"], intr["cy"]], [0.0, 0.0, 1.0]], float)


# ----------------------------------------------------------------------------- OpenCV YAML
def _num(v: float) -> str:
    """Shortest round-trip float text that YAML 1.1 and OpenCV both read as a float."""
    r = repr(float(v))
    if "e" in r and "." not in r.split("e")[0]:
        m, e = r.split("e")
        r = f"{m}.0e{e}"
    return r


def _cv_matrix(name: str, M: np.ndarray) -> str:
    M = np.atleast_2d(np.asarray(M, float))
    data = ", ".join(_num(v) for v in M.ravel())
    return (f"{name}: !!opencv-matrix\n   rows: {M.shape[0]}\n   cols: {M.shape[1]}\n   dt: d\n"
            f"   data: [ {data} ]\n")


def _distortion_model(intr: dict) -> str:
    if intr.get("model") == "fisheye":
        return "fisheye"
    return "rational_polynomial" if len(intr.get("distortion", ())) > 5 else "plumb_bob"


def opencv_yaml_text(cam: dict) -> str:
    """The ``%YAML:1.0`` OpenCV FileStorage text of one placement.json camera object."""
    intr = cam["intrinsics"]
    R, t = world_to_camera(cam["rotation"], cam["position"])
    dist = list(intr.get("distortion", ()))
    if not dist and intr.get("model", "pinhole") != "fisheye":
        dist = [0.0] * 5
    elif not dist:
        dist = [0.0] * 4
    lines = ["%YAML:1.0", "---",
             f"camera_id: {int(cam['candidate_id']) if cam.get('candidate_id') is not None else -1}",
             f"camera_name: \"{cam.get('camera', '')}\"",
             f"model: \"{intr.get('model', 'pinhole')}\"",
             f"distortion_model: \"{_distortion_model(intr)}\"",
             f"image_width: {int(intr['width'])}",
             f"image_height: {int(intr['height'])}"]
    if cam.get("focal_mm") is not None:  # a lens as sold (issue 27): the focal length it is set to
        lines.append(f"focal_length_mm: {_num(cam['focal_mm'])}")
    text = "\n".join(lines) + "\n"
    text += _cv_matrix("camera_matrix", intrinsic_matrix(intr))
    text += _cv_matrix("distortion_coefficients", np.asarray(dist, float).reshape(1, -1))
    text += _cv_matrix("rotation_matrix", R)
    text += _cv_matrix("rvec", rodrigues(R).reshape(3, 1))
    text += _cv_matrix("translation_vector", t.reshape(3, 1))
    text += ("# x_cam = rotation_matrix * x_world + translation_vector (OpenCV world-to-camera);\n"
             f"# camera centre (world, m): [{', '.join(_num(v) for v in cam['position'])}]\n")
    return text


class _CvLoader(yaml.SafeLoader):
    pass


def _construct_cv_matrix(loader: yaml.SafeLoader, node: yaml.Node) -> np.ndarray:
    m = loader.construct_mapping(node, deep=True)
    return np.asarray([float(v) for v in m["data"]], float).reshape(int(m["rows"]), int(m["cols"]))


_CvLoader.add_constructor("tag:yaml.org,2002:opencv-matrix", _construct_cv_matrix)


def read_opencv_yaml(path: str | Path) -> dict:
    """Read an OpenCV camera YAML written by ``opencv_yaml_text`` (or by cv2.FileStorage
    with the same keys). Returns K, dist, R, t, width, height, rotation (world-from-
    camera), position (m), camera_id, camera_name, model, focal_mm (None unless written)."""
    p = Path(path)
    text = p.read_text()
    if text.startswith("%YAML"):
        text = text.split("\n", 1)[1]
    try:
        d = yaml.load(text, Loader=_CvLoader)  # noqa: S506 - SafeLoader subclass
    except yaml.YAMLError as err:
        raise InputError(f"{p}: not an OpenCV YAML file: {str(err).splitlines()[0]}") from None
    for key in ("camera_matrix", "rotation_matrix", "translation_vector", "image_width", "image_height"):
        if not isinstance(d, dict) or key not in d:
            raise InputError(f"{p}: key '{key}' missing; expected an OpenCV camera YAML")
    K = d["camera_matrix"]
    R, t = d["rotation_matrix"], d["translation_vector"].reshape(3)
    rot, pos = camera_pose(R, t)
    dist = d.get("distortion_coefficients", np.zeros((1, 0))).ravel()
    return {"camera_id": d.get("camera_id"), "camera_name": d.get("camera_name"), "model": d.get("model", "pinhole"),
            "focal_mm": None if d.get("focal_length_mm") is None else float(d["focal_length_mm"]),
            "width": int(d["image_width"]), "height": int(d["image_height"]), "K": K, "dist": dist,
            "fx": float(K[0, 0]), "fy": float(K[1, 1]), "cx": float(K[0, 2]), "cy": float(K[1, 2]),
            "R": R, "t": t, "rotation": rot, "position": pos}


# ----------------------------------------------------------------------------- COLMAP
def _colmap_model(intr: dict) -> tuple[str, list[float]]:
    dist = [float(v) for v in intr.get("distortion", ())]
    if intr.get("model") == "fisheye":
        return "OPENCV_FISHEYE", (dist + [0.0] * 4)[:4]
    if not any(dist):
        return "PINHOLE", []
    if len(dist) <= 4:
        return "OPENCV", (dist + [0.0] * 4)[:4]
    return "FULL_OPENCV", (dist + [0.0] * 8)[:8]


def colmap_texts(cameras: list[dict]) -> tuple[str, str, str]:
    """(cameras.txt, images.txt, points3D.txt) of a COLMAP text model, one COLMAP camera
    and one image per placement.json camera object (ids 1..k in the given order)."""
    cam_lines = ["# Camera list with one line of data per camera:",
                 "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]",
                 f"# Number of cameras: {len(cameras)}"]
    img_lines = ["# Image list with two lines of data per image:",
                 "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME",
                 "#   POINTS2D[] as (X, Y, POINT3D_ID)",
                 f"# Number of images: {len(cameras)}, mean observations per image: 0"]
    for k, cam in enumerate(cameras, start=1):
        intr = cam["intrinsics"]
        model, dist = _colmap_model(intr)
        params = [intr["fx"], intr["fy"], intr["cx"] + 0.5, intr["cy"] + 0.5, *dist]
        if cam.get("focal_mm") is not None:  # a comment COLMAP skips; read_colmap_text reads it back
            cam_lines.append(f"# CAMERA_ID {k} FOCAL_MM {_num(cam['focal_mm'])}")
        cam_lines.append(f"{k} {model} {int(intr['width'])} {int(intr['height'])} " + " ".join(_num(v) for v in params))
        R, t = world_to_camera(cam["rotation"], cam["position"])
        q = rotmat_to_qvec(R)
        cid = cam.get("candidate_id")
        name = f"camera_{cid if cid is not None else k}_{cam.get('camera', 'cam')}.png"
        img_lines.append(f"{k} " + " ".join(_num(v) for v in (*q, *t)) + f" {k} {name}")
        img_lines.append("")
    pts = "# 3D point list with one line of data per point:\n#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[]\n" \
          "# Number of points: 0, mean track length: 0\n"
    return "\n".join(cam_lines) + "\n", "\n".join(img_lines) + "\n", pts


def read_colmap_text(folder: str | Path) -> list[dict]:
    """Read cameras.txt + images.txt of a COLMAP text model. One dict per image (file
    order): image_id, name, camera_id, model, width, height, params (COLMAP's), fx, fy,
    cx, cy (OpenCV pixel convention), dist, focal_mm (None unless written), qvec, R, t, rotation, position."""
    folder = Path(folder)
    cams: dict[int, dict] = {}
    focal: dict[int, float] = {}
    for n, line in enumerate((folder / "cameras.txt").read_text().splitlines(), start=1):
        f = line.split()
        if line.startswith("# CAMERA_ID ") and len(f) == 5 and f[3] == "FOCAL_MM":
            focal[int(f[2])] = float(f[4])
        if not line.strip() or line.startswith("#"):
            continue
        f = line.split()
        if len(f) < 8 or f[1] not in COLMAP_MODELS or len(f) != 8 + COLMAP_MODELS[f[1]]:
            raise InputError(f"{folder / 'cameras.txt'}:{n}: expected 'ID MODEL W H fx fy cx cy [dist]' "
                             f"with a model of {', '.join(COLMAP_MODELS)}")
        p = [float(v) for v in f[4:]]
        cams[int(f[0])] = {"model": f[1], "width": int(f[2]), "height": int(f[3]), "params": p,
                           "fx": p[0], "fy": p[1], "cx": p[2] - 0.5, "cy": p[3] - 0.5, "dist": np.asarray(p[4:]),
                           "focal_mm": focal.get(int(f[0]))}
    out = []
    lines = (folder / "images.txt").read_text().splitlines()
    data = [(n, ln) for n, ln in enumerate(lines, start=1) if not ln.startswith("#")]
    k = 0
    while k < len(data):
        n, line = data[k]
        if not line.strip():
            k += 1
            continue
        f = line.split()
        if len(f) < 10 or int(f[8]) not in cams:
            raise InputError(f"{folder / 'images.txt'}:{n}: expected 'ID QW QX QY QZ TX TY TZ CAMERA_ID NAME' "
                             "with a camera id of cameras.txt")
        q = np.asarray([float(v) for v in f[1:5]])
        t = np.asarray([float(v) for v in f[5:8]])
        R = qvec_to_rotmat(q)
        rot, pos = camera_pose(R, t)
        out.append({"image_id": int(f[0]), "name": " ".join(f[9:]), "camera_id": int(f[8]), **cams[int(f[8])],
                    "qvec": q, "R": R, "t": t, "rotation": rot, "position": pos})
        k += 2  # the POINTS2D line follows (possibly empty)
    return out


# ----------------------------------------------------------------------------- all
def write_exports(out_dir: str | Path, cameras: list[dict]) -> dict[str, Path]:
    """Write opencv/camera_<id>.yaml per camera and colmap/{cameras,images,points3D}.txt;
    returns relative name -> path. ``cameras``: placement.json camera objects."""
    out = Path(out_dir)
    paths: dict[str, Path] = {}
    names = {f"camera_{c.get('candidate_id') if c.get('candidate_id') is not None else k}.yaml"
             for k, c in enumerate(cameras)}
    for stale in (out / "opencv").glob("camera_*.yaml"):  # from an earlier run into the same folder
        if stale.name not in names:
            stale.unlink()
    yamls = {}
    for k, cam in enumerate(cameras):
        cid = cam.get("candidate_id")
        yamls[f"opencv/camera_{cid if cid is not None else k}.yaml"] = opencv_yaml_text(cam)
    paths.update(zip(yamls, atomic_write_texts({out / n: t for n, t in yamls.items()})))  # fsyncs overlap (issue 37)
    for name, text in zip(("cameras.txt", "images.txt", "points3D.txt"), colmap_texts(cameras)):
        paths[f"colmap/{name}"] = atomic_write_text(out / "colmap" / name, text)
    return paths
