"""Camera calibration files: OpenCV FileStorage YAML (``%YAML:1.0``, ``!!opencv-matrix``),
ROS camera_info YAML, or JSON -> intrinsics, distortion, image size and lens model.
Errors name the file and the key (``camera_matrix``, ``distortion_coefficients``, ...)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from camplace.core.errors import InputError


def _matrix(value, where: str) -> np.ndarray:
    """A calibration matrix given as nested lists, a flat list, or {rows, cols, data};
    InputError naming ``where`` unless every entry is a finite number."""
    try:
        if isinstance(value, dict):
            data = value.get("data")
            if data is None:
                raise InputError(f"{where}: expected 'data' in the matrix mapping")
            arr = np.asarray(data, float)
            rows, cols = value.get("rows"), value.get("cols")
            if rows is not None and cols is not None:
                arr = arr.reshape(int(rows), int(cols))
        else:
            arr = np.asarray(value, float)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{where}: expected a matrix of numbers") from None
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{where}: expected finite numbers, got {arr.ravel().tolist()[:9]}")
    return arr


def _reject_constant(name: str):
    raise ValueError(f"{name} is not a number JSON allows here")


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
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as err:
        raise InputError(f"{path}: not UTF-8 text (byte 0x{err.object[err.start]:02x} at offset {err.start})") from None
    except OSError as err:
        raise InputError(f"{path}: cannot read the calibration file ({err.strerror or err})") from None
    if path.suffix.lower() == ".json":
        try:
            data = json.loads(text, parse_constant=_reject_constant)
        except (json.JSONDecodeError, ValueError, RecursionError) as err:
            raise InputError(f"{path}: not valid JSON: {str(err).splitlines()[0] if str(err) else 'empty'}") from None
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
        except (yaml.YAMLError, RecursionError, ValueError, TypeError) as err:
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
    try:
        return _calibration_values(p, data)
    except (TypeError, ValueError, OverflowError, AttributeError) as err:
        raise InputError(f"{p}: expected numbers for the intrinsics and image size ({err})") from None


def _calibration_values(p: Path, data: dict) -> dict:
    """fx, fy, cx, cy, distortion, resolution and model from a calibration mapping (finite numbers)."""
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
    K = _matrix(K, f"{p}: camera_matrix")
    out: dict = {"fx": float(K[0, 0]), "fy": float(K[1, 1]), "cx": float(K[0, 2]), "cy": float(K[1, 2]),
                 "distortion": dist}
    w = _find(data, ("image_width", "width", "imagewidth"))
    h = _find(data, ("image_height", "height", "imageheight"))
    size = _find(data, ("image_size", "resolution", "imagesize", "size"))
    if w is not None and h is not None:
        wh = _matrix([w, h], f"{p}: image_width, image_height")
        out["resolution"] = [int(wh[0]), int(wh[1])]
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
