"""The ``cameras`` entries of the scene file: camera types given by their field of view,
intrinsics or a calibration file, or described as sold (issue 27): sensor (pixel pitch
or sensor width), focal length fixed or varifocal ``[min, max]``, price, recording
bitrate and IR range. ``cameras: {catalogue: FILE}`` reads them from a catalogue
(camplace.spec.catalogue). See docs/scene-file.md#cameras and docs/lenses.md.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, model_validator

from camplace.spec.basics import Finite, PositiveFloat, PositiveInt, _no_bool, _Strict, scene_error

Angle360 = Annotated[float, BeforeValidator(_no_bool), Field(gt=0, le=360)]
NonNegative = Annotated[float, BeforeValidator(_no_bool), Field(ge=0, allow_inf_nan=False)]
LENS_SOURCES = ("fov_deg", "intrinsics", "calibration", "focal_mm")
DEFAULT_FOCAL_STEPS = 4  # focal settings of a varifocal lens on the candidate grid
SOLD_ONLY = ("pixel_um", "sensor_width_mm", "focal_steps")  # keys that belong to a lens given by focal_mm


class Intrinsics(_Strict):
    """Calibrated pinhole intrinsics (pixels)."""

    fx: PositiveFloat
    fy: PositiveFloat
    cx: Finite
    cy: Finite


def _price_alias(data: Any) -> Any:
    """``price`` is ``cost`` by another name (issue 27); giving both is refused."""
    if isinstance(data, dict) and "price" in data:
        if "cost" in data:
            raise scene_error("price", "give either 'price' or 'cost' (the same thing), not both")
        data = {k: v for k, v in data.items() if k != "price"} | {"cost": data["price"]}
    return data


class Camera(_Strict):
    """A camera type: give exactly one of ``fov_deg``, ``intrinsics``, ``calibration`` (an
    OpenCV calibration YAML/JSON file, path relative to the scene file) or ``focal_mm``
    (a lens as sold, with ``pixel_um`` or ``sensor_width_mm``)."""

    name: str = Field(min_length=1)
    model: Literal["pinhole", "opencv", "fisheye"] = "pinhole"
    resolution: tuple[PositiveInt, PositiveInt] | None = None
    fov_deg: tuple[Angle360, Angle360] | None = None
    intrinsics: Intrinsics | None = None
    distortion: list[Finite] | None = None
    calibration: str | None = None
    focal_mm: PositiveFloat | tuple[PositiveFloat, PositiveFloat] | None = None  # fixed, or [min, max] varifocal
    pixel_um: PositiveFloat | None = None  # pixel pitch (µm)
    sensor_width_mm: PositiveFloat | None = None  # or the sensor's active width (mm): pitch = width / pixels
    focal_steps: PositiveInt | None = None  # varifocal: focal settings on the candidate grid (default 4)
    max_fov_deg: Angle360 | None = None
    max_range: PositiveFloat | None = None  # m; default 5, or from the targets' pixel density for focal_mm lenses
    cost: NonNegative = 1.0  # price of one camera (alias: price)
    bitrate_mbps: NonNegative | None = None  # recording stream (Mbit/s)
    ir_range_m: PositiveFloat | None = None  # infrared illuminator reach (m), informational

    @model_validator(mode="before")
    @classmethod
    def _alias(cls, data: Any) -> Any:
        return _price_alias(data)

    @model_validator(mode="after")
    def _lens(self) -> "Camera":
        given = [k for k in LENS_SOURCES if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of {', '.join(repr(k) for k in LENS_SOURCES)}"
                             + (f" (got {', '.join(given)})" if given else ""))
        if self.resolution is None and self.calibration is None:
            raise scene_error("resolution", "required key is missing ([width, height] in pixels)")
        if self.fov_deg is not None and self.model != "fisheye" and max(self.fov_deg) >= 180:
            raise scene_error("fov_deg", f"a {self.model} lens sees less than 180 degrees; got {list(self.fov_deg)} "
                                         "(use model: fisheye for wider lenses)")
        n = len(self.distortion or [])
        allowed = {"pinhole": (0,), "opencv": (0, 4, 5, 8), "fisheye": (0, 4)}[self.model]
        if n not in allowed:
            what = "no distortion (use model: opencv)" if self.model == "pinhole" else \
                f"{' or '.join(str(a) for a in allowed if a)} coefficients"
            raise scene_error("distortion", f"model '{self.model}' takes {what}, got {n}")
        if self.max_fov_deg is not None and self.model != "fisheye":
            raise scene_error("max_fov_deg", "belongs to fisheye cameras")
        self._sold()
        return self

    def _sold(self) -> None:
        """The keys of a lens as sold: a pixel pitch with focal_mm, a range in order."""
        if self.focal_mm is None:
            extra = [k for k in SOLD_ONLY if getattr(self, k) is not None]
            if extra:
                raise scene_error(extra[0], "belongs to a lens given by 'focal_mm'")
            return
        if (self.pixel_um is None) == (self.sensor_width_mm is None):
            raise scene_error("pixel_um", "a lens given by 'focal_mm' needs exactly one of 'pixel_um' (pixel pitch, "
                                          "µm) or 'sensor_width_mm'")
        lo, hi = self.focal_range_mm
        if hi < lo:
            raise scene_error("focal_mm", f"expected [min, max] with min <= max (mm), got [{lo}, {hi}]")
        if self.focal_steps is not None and hi == lo:
            raise scene_error("focal_steps", "belongs to a varifocal lens (focal_mm: [min, max])")

    @property
    def focal_range_mm(self) -> tuple[float, float]:
        """(min, max) focal length (mm); equal for a fixed lens."""
        f = self.focal_mm
        return (float(f[0]), float(f[1])) if isinstance(f, tuple) else (float(f), float(f))

    @property
    def n_settings(self) -> int:
        """Camera models one pose of this type becomes: focal_steps for a varifocal lens, else 1."""
        lo, hi = self.focal_range_mm if self.focal_mm is not None else (0.0, 0.0)
        return (self.focal_steps or DEFAULT_FOCAL_STEPS) if hi > lo else 1

    @property
    def pixel_pitch_um(self) -> float:
        """Pixel pitch (µm): ``pixel_um``, or ``sensor_width_mm`` / horizontal pixels."""
        if self.pixel_um is not None:
            return float(self.pixel_um)
        return float(self.sensor_width_mm) * 1000.0 / float(self.resolution[0])


class Recording(_Strict):
    """``recording``: how long the recorder keeps video (the storage figure of the bill of materials)."""

    retention_days: PositiveFloat
