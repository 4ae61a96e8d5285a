"""Camera lens models, in the OpenCV camera frame (x right, y down, z forward).

Models (``model``):

- ``pinhole``: u = fx x/z + cx, v = fy y/z + cy.
- ``opencv``: pinhole with OpenCV radial-tangential distortion, coefficients in OpenCV
  order (k1, k2, p1, p2[, k3[, k4, k5, k6]]) (the rational model when k4..k6 are given).
- ``fisheye``: OpenCV fisheye / Kannala-Brandt equidistant model, coefficients
  (k1, k2, k3, k4): theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8),
  u = fx theta_d x / r + cx with r = sqrt(x^2 + y^2), theta = atan2(r, z). It sees
  behind the image plane (z <= 0) when its field of view exceeds 180 degrees.

Pixel convention (OpenCV): pixel (i, j) has its centre at (u, v) = (i, j); the image
spans u in [-0.5, W - 0.5], v in [-0.5, H - 0.5]. ``fov_deg`` is the full angle
between the outer edges of the outer pixels (pinhole: tangent law; fisheye:
equidistant, fx = (W / 2) / (fov_x / 2 in radians)).

Distorted models are valid only where the distortion is monotonic in the radius: the
largest valid undistorted radius (``opencv``: r = |(x/z, y/z)|; ``fisheye``: the angle
theta) is computed once and stored in the parameter vector; points beyond it project
to "invalid", so folded-back distortion never puts a point into the image.

Each model also packs into a flat float64 parameter vector (``params``) that the
compiled visibility kernels read; ``project_nb`` is the kernel-side projection and
``px_per_m_nb`` the kernel-side pixel density. Layout:
``[model code, W, H, fx, fy, cx, cy, max_range, d0..d7, limit, 0]`` (``N_PARAMS`` = 18;
``limit`` = largest valid radius / angle, see above).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numba
import numpy as np

from camplace.cameras.calibration import load_calibration
from camplace.cameras.distortion import (fisheye_theta_d, fisheye_undistort_theta, monotonic_limit,
                                         opencv_distort, opencv_undistort)
from camplace.cameras.lenses import Lens
from camplace.core.errors import InputError
from camplace.spec.lenses import DEFAULT_FOCAL_STEPS
from camplace.spec.quality import DORI_PX_PER_M, range_density

MODEL_CODES = {"pinhole": 0, "opencv": 1, "fisheye": 2}
N_PARAMS = 18  # [model, W, H, fx, fy, cx, cy, max_range, d0..d7, limit, reserved]
LIMIT_INDEX = 16
N_DISTORTION = {"pinhole": (0,), "opencv": (4, 5, 8), "fisheye": (4,)}


@dataclass(frozen=True)
class CameraModel:
    """A lens + sensor. width/height: pixels; fx, fy, cx, cy: pixels; max_range: m;
    distortion: OpenCV-order coefficients (see module doc); max_fov_deg: full cone
    angle beyond which a fisheye lens sees nothing (None = no limit but the model's). A lens
    as sold (issue 27): ``lens`` (cameras.lenses.Lens) set to ``focal_mm``; stream Mbit/s; IR m."""

    name: str
    model: str
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    max_range: float = 5.0
    distortion: tuple[float, ...] = field(default_factory=tuple)
    cost: float = 1.0
    max_fov_deg: float | None = None
    focal_mm: float | None = None
    lens: Lens | None = None
    bitrate_mbps: float | None = None
    ir_range_m: float | None = None

    def __post_init__(self) -> None:
        if self.model not in MODEL_CODES:
            raise InputError(f"camera '{self.name}': model: expected one of {', '.join(MODEL_CODES)}, got {self.model!r}")
        if len(self.distortion) not in N_DISTORTION[self.model] and not (self.model == "pinhole" and not any(self.distortion)):
            raise InputError(f"camera '{self.name}': distortion: model '{self.model}' takes "
                             f"{' or '.join(str(n) for n in N_DISTORTION[self.model])} coefficients, got {len(self.distortion)}")
        if not (self.fx > 0 and self.fy > 0 and self.width > 0 and self.height > 0):
            raise InputError(f"camera '{self.name}': intrinsics: fx, fy, width and height must be positive")

    # ------------------------------------------------------------------ constructors
    @classmethod
    def pinhole_from_fov(cls, name: str, resolution: tuple[int, int], fov_deg: tuple[float, float],
                         max_range: float = 5.0, cost: float = 1.0) -> "CameraModel":
        return cls.from_fov(name, "pinhole", resolution, fov_deg, max_range=max_range, cost=cost)

    @classmethod
    def from_fov(cls, name: str, model: str, resolution: tuple[int, int], fov_deg: tuple[float, float],
                 distortion: tuple[float, ...] = (), max_range: float = 5.0, cost: float = 1.0,
                 max_fov_deg: float | None = None) -> "CameraModel":
        """Focal lengths from the full fields of view (degrees) and the resolution (pixels),
        principal point at the image centre: the image edges on the axes sit at the
        (distorted) half angles. Fisheye without distortion: f = half-size / half-angle."""
        w, h = int(resolution[0]), int(resolution[1])
        d = np.zeros(8)
        d[:len(distortion)] = distortion
        hx, hy = math.radians(fov_deg[0]) / 2.0, math.radians(fov_deg[1]) / 2.0
        if model == "fisheye":
            # the image edge on each axis sits at the distorted angle of the half field of view
            fx = (w / 2.0) / float(fisheye_theta_d(np.array(hx), d))
            fy = (h / 2.0) / float(fisheye_theta_d(np.array(hy), d))
            if not distortion:
                distortion = (0.0, 0.0, 0.0, 0.0)
        else:
            rx, ry = math.tan(hx), math.tan(hy)
            fx = (w / 2.0) / float(opencv_distort(np.array(rx), np.array(0.0), d)[0])
            fy = (h / 2.0) / float(opencv_distort(np.array(0.0), np.array(ry), d)[1])
            if model == "opencv" and not distortion:
                distortion = (0.0, 0.0, 0.0, 0.0, 0.0)
        return cls(name, model, w, h, fx, fy, (w - 1) / 2.0, (h - 1) / 2.0, float(max_range),
                   tuple(float(v) for v in distortion), float(cost), max_fov_deg)

    @classmethod
    def from_intrinsics(cls, name: str, model: str, resolution: tuple[int, int], fx: float, fy: float,
                        cx: float, cy: float, distortion: tuple[float, ...] = (), max_range: float = 5.0,
                        cost: float = 1.0, max_fov_deg: float | None = None) -> "CameraModel":
        """From a calibration: focal lengths and principal point in pixels."""
        if model == "fisheye" and not distortion:
            distortion = (0.0,) * 4
        if model == "opencv" and not distortion:
            distortion = (0.0,) * 5
        return cls(name, model, int(resolution[0]), int(resolution[1]), float(fx), float(fy), float(cx), float(cy),
                   float(max_range), tuple(float(v) for v in distortion), float(cost), max_fov_deg)

    # ------------------------------------------------------------------ lens settings (issue 27)
    def at_focal(self, focal_mm: float) -> "CameraModel":
        """This type set to ``focal_mm`` (clamped to its lens's range): fx = fy = f_mm / pitch,
        the range recomputed from the lens's density (when the type gives none)."""
        if self.lens is None:
            raise InputError(f"camera '{self.name}': focal_mm: this camera type has no lens given as focal_mm "
                             f"and a pixel pitch")
        f = self.lens.clamp(focal_mm)
        fp = self.lens.f_px(f)
        return replace(self, fx=fp, fy=fp, focal_mm=f, max_range=self.lens.range_at(f, self.max_range))

    def settings(self) -> tuple["CameraModel", ...]:
        """The focal settings on the candidate grid: one per step of a varifocal lens, else self."""
        if self.lens is None or not self.lens.varifocal:
            return (self,)
        return tuple(self.at_focal(float(f)) for f in self.lens.settings_mm())

    # ------------------------------------------------------------------ derived
    @property
    def dist8(self) -> np.ndarray:
        """(8,) distortion coefficients padded with zeros."""
        d = np.zeros(8)
        d[:len(self.distortion)] = self.distortion
        return d

    @property
    def limit(self) -> float:
        """Largest valid undistorted radius (opencv: of (x/z, y/z); fisheye: angle theta, rad;
        pinhole: inf)."""
        return _limit_of(self.model, tuple(self.distortion), self.max_fov_deg,
                         self.width, self.height, self.fx, self.fy, self.cx, self.cy)

    @property
    def fov_deg(self) -> tuple[float, float]:
        """Full horizontal and vertical field of view (degrees) through the principal point."""
        uv = np.array([[-0.5, self.cy], [self.width - 0.5, self.cy], [self.cx, -0.5], [self.cx, self.height - 0.5]])
        r = self.unproject(uv)
        ang = np.degrees(np.arccos(np.clip(r[:, 2], -1, 1)))
        return float(ang[0] + ang[1]), float(ang[2] + ang[3])

    @property
    def params(self) -> np.ndarray:
        """(N_PARAMS,) float64 parameter vector read by the compiled kernels."""
        p = np.zeros(N_PARAMS, dtype=np.float64)
        p[:8] = [MODEL_CODES[self.model], self.width, self.height, self.fx, self.fy, self.cx, self.cy, self.max_range]
        p[8:16] = self.dist8
        p[LIMIT_INDEX] = min(self.limit, 1e30)
        return p

    def intrinsics(self) -> dict:
        """The ``intrinsics`` object of placement.json."""
        out = {"model": self.model, "width": self.width, "height": self.height,
               "fx": self.fx, "fy": self.fy, "cx": self.cx, "cy": self.cy}
        if self.distortion:
            out["distortion"] = list(self.distortion)
        return out

    # ------------------------------------------------------------------ projection
    def project(self, points_cam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """points_cam: (N, 3) camera-frame metres -> (uv (N, 2) pixels, valid (N,) bool).

        valid = inside the model's domain (in front for pinhole/opencv, within the lens
        angle for fisheye) and inside the image; range is not checked here. uv of invalid
        points is undefined."""
        p = np.asarray(points_cam, float).reshape(-1, 3)
        x, y, z = p[:, 0], p[:, 1], p[:, 2]
        lim = self.limit
        if self.model == "fisheye":
            r = np.hypot(x, y)
            theta = np.arctan2(r, z)
            td = fisheye_theta_d(theta, self.dist8)
            scale = np.where(r > 1e-300, td / np.where(r > 1e-300, r, 1.0), 1.0 / np.where(z > 0, z, 1.0))
            xd, yd = x * scale, y * scale
            ok = (theta <= lim) & (np.abs(p).sum(axis=1) > 0)
        else:
            front = z > 1e-12
            zs = np.where(front, z, 1.0)
            xn, yn = x / zs, y / zs
            if self.model == "opencv":
                xd, yd = opencv_distort(xn, yn, self.dist8)
                ok = front & (xn * xn + yn * yn <= lim * lim)
            else:
                xd, yd, ok = xn, yn, front
        u = self.fx * xd + self.cx
        v = self.fy * yd + self.cy
        valid = ok & (u >= -0.5) & (u <= self.width - 0.5) & (v >= -0.5) & (v <= self.height - 0.5)
        return np.c_[u, v], valid

    def unproject(self, uv: np.ndarray) -> np.ndarray:
        """uv: (N, 2) pixels -> (N, 3) unit rays in the camera frame (distortion inverted by
        Newton iteration). Pixels outside the model's valid domain give the ray of the
        nearest valid radius."""
        uv = np.asarray(uv, float).reshape(-1, 2)
        xd = (uv[:, 0] - self.cx) / self.fx
        yd = (uv[:, 1] - self.cy) / self.fy
        if self.model == "pinhole":
            d = np.c_[xd, yd, np.ones(len(uv))]
        elif self.model == "opencv":
            x, y = opencv_undistort(xd, yd, self.dist8, self.limit)
            d = np.c_[x, y, np.ones(len(uv))]
        else:
            rd = np.hypot(xd, yd)
            theta = fisheye_undistort_theta(rd, self.dist8, self.limit)
            s = np.sin(theta)
            with np.errstate(invalid="ignore", divide="ignore"):
                cx = np.where(rd > 0, xd / np.where(rd > 0, rd, 1.0), 0.0)
                cy = np.where(rd > 0, yd / np.where(rd > 0, rd, 1.0), 0.0)
            d = np.c_[s * cx, s * cy, np.cos(theta)]
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    def pixel_rays(self, stride: int = 1) -> np.ndarray:
        """Unit rays (M, 3) through the centres of pixel blocks of ``stride`` x ``stride``
        pixels, row-major (v outer, u inner): M = (W // stride) * (H // stride)."""
        s = max(1, int(stride))
        us = (np.arange(max(1, self.width // s)) + 0.5) * s - 0.5
        vs = (np.arange(max(1, self.height // s)) + 0.5) * s - 0.5
        gu, gv = np.meshgrid(us, vs)
        return self.unproject(np.c_[gu.ravel(), gv.ravel()])

    def px_per_m(self, points_cam: np.ndarray, normals_cam: np.ndarray | None = None) -> np.ndarray:
        """Pixel density (px/m) at camera-frame points: the smallest singular value of the
        projection Jacobian restricted to the plane perpendicular to the viewing ray, or to
        the surface plane when a normal (N, 3) is given (rows of zeros = perpendicular)."""
        p = np.asarray(points_cam, float).reshape(-1, 3)
        n = np.zeros_like(p) if normals_cam is None else np.asarray(normals_cam, float).reshape(-1, 3)
        par = self.params
        return np.array([px_per_m_nb(par, *p[i], *n[i]) for i in range(len(p))])


@functools.lru_cache(maxsize=256)
def _limit_of(model: str, dist: tuple[float, ...], max_fov_deg: float | None, w: int, h: int,
              fx: float, fy: float, cx: float, cy: float) -> float:
    d = np.zeros(8)
    d[:len(dist)] = dist
    if model == "pinhole":
        return math.inf
    if model == "fisheye":
        lim = monotonic_limit(lambda t: fisheye_theta_d(t, d), math.pi - 1e-9)
        if max_fov_deg is not None:
            lim = min(lim, math.radians(max_fov_deg) / 2.0)
        return lim
    # opencv: radial mapping r -> r * radial(r) along the worst axis must increase
    corner = max(math.hypot(max(cx + 0.5, w - 0.5 - cx) / fx, max(cy + 0.5, h - 0.5 - cy) / fy), 1e-6)
    hi = 4.0 * corner + 1.0

    def radial_r(r):
        r2 = r * r
        return r * (1 + r2 * (d[0] + r2 * (d[1] + r2 * d[4]))) / (1 + r2 * (d[5] + r2 * (d[6] + r2 * d[7])))
    return monotonic_limit(radial_r, hi)


# ----------------------------------------------------------------------------- kernel side
@numba.njit(cache=True, inline="always")
def _image_plane_nb(params: np.ndarray, x: float, y: float, z: float) -> tuple[float, float, bool]:
    """(u, v, defined): pixel coordinates of a camera-frame point, without the image bounds
    test; defined = inside the model's valid domain."""
    code = params[0]
    lim = params[16]
    if code == 2.0:
        r = math.sqrt(x * x + y * y)
        if r == 0.0 and z <= 0.0:
            return 0.0, 0.0, False
        theta = math.atan2(r, z)
        if theta > lim:
            return 0.0, 0.0, False
        t2 = theta * theta
        td = theta * (1.0 + t2 * (params[8] + t2 * (params[9] + t2 * (params[10] + t2 * params[11]))))
        if r > 1e-300:
            s = td / r
        else:
            s = 1.0 / z
        xd = x * s
        yd = y * s
    else:
        if z <= 1e-12:
            return 0.0, 0.0, False
        xd = x / z
        yd = y / z
        if code == 1.0:
            r2 = xd * xd + yd * yd
            if r2 > lim * lim:
                return 0.0, 0.0, False
            radial = (1.0 + r2 * (params[8] + r2 * (params[9] + r2 * params[12]))) / \
                (1.0 + r2 * (params[13] + r2 * (params[14] + r2 * params[15])))
            p1 = params[10]
            p2 = params[11]
            x2 = xd * radial + 2.0 * p1 * xd * yd + p2 * (r2 + 2.0 * xd * xd)
            y2 = yd * radial + p1 * (r2 + 2.0 * yd * yd) + 2.0 * p2 * xd * yd
            xd = x2
            yd = y2
    return params[3] * xd + params[5], params[4] * yd + params[6], True


@numba.njit(cache=True, inline="always")
def project_nb(params: np.ndarray, x: float, y: float, z: float) -> tuple[float, float, bool]:
    """Kernel-side projection of one camera-frame point: (u, v, inside-image and valid).

    Same result as ``CameraModel.project`` for every model (``params`` from
    ``CameraModel.params``). Fisheye accepts z <= 0 when its angle limit exceeds 90 deg."""
    u, v, ok = _image_plane_nb(params, x, y, z)
    if not ok:
        return u, v, False
    ok = (u >= -0.5) and (u <= params[1] - 0.5) and (v >= -0.5) and (v <= params[2] - 0.5)
    return u, v, ok


@numba.njit(cache=True)  # a call, not inlined: px_per_m_nb evaluates it four times (compiles in 1/4 the time)
def _image_plane_call(params: np.ndarray, x: float, y: float, z: float) -> tuple[float, float, bool]:
    """``_image_plane_nb`` as a function call."""
    return _image_plane_nb(params, x, y, z)


@numba.njit(cache=True)
def px_per_m_nb(params: np.ndarray, x: float, y: float, z: float, nx: float, ny: float, nz: float) -> float:
    """Pixel density (px/m) at a camera-frame point: the smallest singular value of the
    2x3 projection Jacobian restricted to a plane: the surface plane with camera-frame
    normal n, or (n = 0) the plane perpendicular to the viewing ray. Pinhole on a
    fronto-parallel patch: min(fx, fy) / z. 0 where the projection is undefined."""
    d = math.sqrt(x * x + y * y + z * z)
    if d <= 0.0:
        return 0.0
    if nx == 0.0 and ny == 0.0 and nz == 0.0:
        nx, ny, nz = x / d, y / d, z / d
    else:
        nn = math.sqrt(nx * nx + ny * ny + nz * nz)
        nx, ny, nz = nx / nn, ny / nn, nz / nn
    # e1 = n x a (a = a coordinate axis not parallel to n), e2 = n x e1
    ax, ay, az = 1.0, 0.0, 0.0
    if abs(nx) > 0.6:
        ax, ay = 0.0, 1.0
    e1x, e1y, e1z = ny * az - nz * ay, nz * ax - nx * az, nx * ay - ny * ax
    l1 = math.sqrt(e1x * e1x + e1y * e1y + e1z * e1z)
    e1x, e1y, e1z = e1x / l1, e1y / l1, e1z / l1
    e2x, e2y, e2z = ny * e1z - nz * e1y, nz * e1x - nx * e1z, nx * e1y - ny * e1x
    h = 1e-5 * d
    ua, va, oka = _image_plane_call(params, x + h * e1x, y + h * e1y, z + h * e1z)
    ub, vb, okb = _image_plane_call(params, x - h * e1x, y - h * e1y, z - h * e1z)
    uc, vc, okc = _image_plane_call(params, x + h * e2x, y + h * e2y, z + h * e2z)
    ud, vd, okd = _image_plane_call(params, x - h * e2x, y - h * e2y, z - h * e2z)
    if not (oka and okb and okc and okd):
        return 0.0
    m11 = (ua - ub) / (2 * h)
    m21 = (va - vb) / (2 * h)
    m12 = (uc - ud) / (2 * h)
    m22 = (vc - vd) / (2 * h)
    a = m11 * m11 + m21 * m21
    b = m11 * m12 + m21 * m22
    c = m12 * m12 + m22 * m22
    lam = 0.5 * (a + c) - math.sqrt(max(0.25 * (a - c) * (a - c) + b * b, 0.0))
    return math.sqrt(max(lam, 0.0))


# ----------------------------------------------------------------------------- scene file side
DEFAULT_MAX_RANGE = 5.0  # m: a camera type's range when it gives neither max_range nor a lens (focal_mm)


def cameras_from_spec(spec, base_dir: Path | None = None) -> dict[str, CameraModel]:
    """The camera types of a SceneSpec by name (lens ranges from spec.quality.range_density)."""
    return {c.name: camera_from_spec(c, base_dir, range_density(spec)) for c in spec.cameras}


def camera_from_spec(spec, base_dir: Path | None = None, range_px_per_m: float | None = None) -> CameraModel:
    """Build a CameraModel from a validated ``cameras[i]`` entry of the scene file
    (``calibration`` paths are relative to ``base_dir``, the scene file's folder). A lens
    given as sold (``focal_mm`` + pixel pitch) is set to its widest focal length; without
    ``max_range`` its range ends where the axis density falls to ``range_px_per_m``
    (default: the DORI detect level)."""
    cam = _camera_model(spec, base_dir, range_px_per_m)
    return replace(cam, bitrate_mbps=spec.bitrate_mbps, ir_range_m=spec.ir_range_m)


def _camera_model(spec, base_dir: Path | None, range_px_per_m: float | None) -> CameraModel:
    where = f"cameras '{spec.name}'"
    model = spec.model
    dist = tuple(spec.distortion or ())
    res = spec.resolution
    rng = DEFAULT_MAX_RANGE if spec.max_range is None else spec.max_range
    if spec.focal_mm is not None:
        lo, hi = spec.focal_range_mm
        density = None if spec.max_range is not None else (range_px_per_m or DORI_PX_PER_M["detect"])
        lens = Lens(spec.pixel_pitch_um, lo, hi, spec.focal_steps or DEFAULT_FOCAL_STEPS, density)
        f = lens.f_px(lo)
        cam = CameraModel.from_intrinsics(spec.name, model, res, f, f, (res[0] - 1) / 2.0, (res[1] - 1) / 2.0, dist,
                                          lens.range_at(lo, rng), spec.cost, spec.max_fov_deg)
        return replace(cam, focal_mm=lo, lens=lens)
    if spec.calibration is not None:
        path = Path(spec.calibration)
        if not path.is_absolute() and base_dir is not None:
            path = Path(base_dir) / path
        cal = load_calibration(path)
        if "model" in cal and "model" not in spec.model_fields_set:
            model = cal["model"]
        if not dist:
            dist = tuple(cal["distortion"])
        if model == "pinhole" and any(dist):
            model = "opencv"
        if model == "opencv" and len(dist) not in N_DISTORTION["opencv"]:
            if len(dist) > 8 or len(dist) < 4:
                raise InputError(f"{path}: distortion_coefficients: the opencv model takes 4, 5 or 8 values, got {len(dist)}")
            dist = tuple(dist) + (0.0,) * (8 - len(dist)) if len(dist) > 5 else tuple(dist) + (0.0,) * (5 - len(dist))
        if model == "pinhole":
            dist = ()
        res = res or cal.get("resolution")
        if res is None:
            raise InputError(f"{where}: resolution: missing (the calibration file {path} gives no image size)")
        return CameraModel.from_intrinsics(spec.name, model, res, cal["fx"], cal["fy"], cal["cx"], cal["cy"], dist,
                                           rng, spec.cost, spec.max_fov_deg)
    if spec.intrinsics is not None:
        k = spec.intrinsics
        return CameraModel.from_intrinsics(spec.name, model, res, k.fx, k.fy, k.cx, k.cy, dist,
                                           rng, spec.cost, spec.max_fov_deg)
    return CameraModel.from_fov(spec.name, model, res, spec.fov_deg, dist, rng, spec.cost, spec.max_fov_deg)
