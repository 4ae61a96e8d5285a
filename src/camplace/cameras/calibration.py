"""Camera calibration files: OpenCV FileStorage YAML (``%YAML:1.0``, ``!!opencv-matrix``),
ROS camera_info YAML, or JSON -> intrinsics, distortion, image size and lens model.
Errors name the file and the key (``camera_matrix``, ``distortion_coefficients``, ...)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from camplace.core.errors import InputError


def _matrix(value, where: str) -> np.ndarray:
    """A calibration matrix given as nested lists, a flat list, or {rows, cols, data}."""
    if isinstance(value, dict):
        data = value.get("data")
        if data is None:
            raise InputError(f"{where}: expected 'data' in the matrix mapping")
        arr = np.asarray(data, float)
        rows, cols = value.get("rows"), value.get("cols")
        if rows is not None and cols is not None:
            arr = arr.reshape(int(rows), int(cols))
        return arr
    return np.asarray(value, float)


_K_KEYS = ("camera_matrix", "cameramatrix", "k", "intrinsic_matrix", "intrinsics", "mtx", "matrix")
_D_KEYS = ("distortion_coefficients", "distortioncoefficients", "dist_coeffs", "distcoeffs", "distortion",
           "dist", "d", "distortion_coeffs")


def _find(data: dict, keys: tuple[str, ...]):
    low = {str(k).lower().replace(" ", "_"): v for k, v in data.items()}
    for k in keys:
        if k in low:
            return low[k]
    return None


def _read_calibration_mapping(path: Path) -> dict:
    text = path.read_text()
    if path.suffix.lower() == ".json":
        try:
            data = json.loads(text)
        except json.JSONDecodeError as err:
            raise InputError(f"{path}: not valid JSON: {err}") from None
    else:
        import yaml

        class _Loader(yaml.SafeLoader):
            pass

        def _cv_matrix(loader, node):
            return loader.construct_mapping(node, deep=True)

        _Loader.add_constructor("tag:yaml.org,2002:opencv-matrix", _cv_matrix)
        _Loader.add_constructor("!opencv-matrix", _cv_matrix)
        lines = text.splitlines()
        if lines and lines[0].startswith("%YAML:"):
            lines = lines[1:]  # OpenCV's FileStorage header is not a valid YAML directive
        lines = [ln for ln in lines if ln.strip() != "---"]
        try:
            data = yaml.load("\n".join(lines), Loader=_Loader)  # noqa: S506 - SafeLoader subclass
        except yaml.YAMLError as err:
            first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
            raise InputError(f"{path}: not valid YAML: {first}") from None
    if not isinstance(data, dict):
        raise InputError(f"{path}: expected a mapping with camera_matrix and distortion_coefficients")
    return data


def load_calibration(path: str | Path) -> dict:
    """Read an OpenCV calibration file (YAML FileStorage ``%YAML:1.0`` with
    ``!!opencv-matrix``, ROS camera_info YAML, or JSON) -> dict with fx, fy, cx, cy,
    distortion (list), and when present resolution [W, H] and model
    ('opencv' / 'fisheye' from ``distortion_model``)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: calibration file not found")
    data = _read_calibration_mapping(p)
    if "fx" in {str(k).lower() for k in data} and _find(data, _K_KEYS) is None:
        low = {str(k).lower(): v for k, v in data.items()}
        try:
            K = np.array([[low["fx"], 0, low["cx"]], [0, low["fy"], low["cy"]], [0, 0, 1]], float)
        except KeyError as err:
            raise InputError(f"{p}: missing key {err.args[0]!r} (expected fx, fy, cx, cy)") from None
    else:
        kv = _find(data, _K_KEYS)
        if kv is None:
            raise InputError(f"{p}: camera_matrix: missing (expected a 3x3 matrix: camera_matrix / K)")
        K = _matrix(kv, f"{p}: camera_matrix")
        if K.size != 9:
            raise InputError(f"{p}: camera_matrix: expected 9 values (3x3), got {K.size}")
        K = K.reshape(3, 3)
    dv = _find(data, _D_KEYS)
    dist = [] if dv is None else [float(v) for v in _matrix(dv, f"{p}: distortion_coefficients").ravel()]
    out: dict = {"fx": float(K[0, 0]), "fy": float(K[1, 1]), "cx": float(K[0, 2]), "cy": float(K[1, 2]),
                 "distortion": dist}
    w = _find(data, ("image_width", "width", "imagewidth"))
    h = _find(data, ("image_height", "height", "imageheight"))
    size = _find(data, ("image_size", "resolution", "imagesize", "size"))
    if w is not None and h is not None:
        out["resolution"] = [int(w), int(h)]
    elif size is not None:
        s = _matrix(size, f"{p}: image_size").ravel()
        if len(s) == 2:
            out["resolution"] = [int(s[0]), int(s[1])]
    dm = _find(data, ("distortion_model", "model", "camera_model"))
    if isinstance(dm, str):
        dm = dm.lower()
        if dm in ("equidistant", "fisheye", "kannala_brandt", "kb4", "opencv_fisheye"):
            out["model"] = "fisheye"
        elif dm in ("plumb_bob", "radtan", "rational_polynomial", "opencv", "radial-tangential"):
            out["model"] = "opencv"
        elif dm == "pinhole":
            out["model"] = "pinhole"
    return out
