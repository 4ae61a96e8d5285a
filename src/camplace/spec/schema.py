"""The scene file (YAML) schema: the user's contract, validated with pydantic.

Every error names the file, the key path (e.g. ``mounts[0].yaw_deg.step``) and what
was expected. See docs/scene-file.md for the reference.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal, Union

import yaml
from pydantic import (BaseModel, BeforeValidator, ConfigDict, Discriminator, Field, Tag, ValidationError,
                      field_validator, model_validator)
from pydantic_core import PydanticCustomError

from camplace.core.errors import InputError

MAX_ANGLES_PER_AXIS = 3600  # an angle list/range longer than this is a typo (e.g. step 0.001)


def _no_bool(v: Any) -> Any:
    """YAML turns yes/no/true/false into booleans; never accept them as numbers."""
    if isinstance(v, bool):
        raise PydanticCustomError("bool_not_number", "expected a number, not a boolean")
    return v


def scene_error(path: str, message: str) -> PydanticCustomError:
    """A validation error raised by a model validator that names its own key path
    (relative to the scene's top level), e.g. ``scene_error("mounts[0].camera", "...")``."""
    return PydanticCustomError("scene", "{message}", {"path": path, "message": message})


PositiveFloat = Annotated[float, BeforeValidator(_no_bool), Field(gt=0, allow_inf_nan=False)]
Finite = Annotated[float, BeforeValidator(_no_bool), Field(allow_inf_nan=False)]
PositiveInt = Annotated[int, BeforeValidator(_no_bool), Field(gt=0)]
Point2 = tuple[Finite, Finite]
Point3 = tuple[Finite, Finite, Finite]
FACES = ("+x", "-x", "+y", "-y", "+z", "-z")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class AngleRange(_Strict):
    """Angles start, start+step, ... up to and including stop (degrees)."""

    start: Finite
    stop: Finite
    step: PositiveFloat

    @model_validator(mode="after")
    def _sane(self) -> "AngleRange":
        if self.stop < self.start:
            raise scene_error("stop", f"must be >= start ({self.start}), got {self.stop}")
        n = self.count()
        if n > MAX_ANGLES_PER_AXIS:
            raise scene_error("step", f"{self.step} gives {n} angles from {self.start} to {self.stop}; "
                                      f"expected at most {MAX_ANGLES_PER_AXIS} (use a larger step)")
        return self

    def count(self) -> int:
        """Number of angles, computed without building the list."""
        return max(int(math.floor((self.stop - self.start) / self.step + 1e-9)) + 1, 0)

    def values(self) -> list[float]:
        return [self.start + k * self.step for k in range(self.count())]


def _angles_kind(v: Any) -> str:
    if isinstance(v, (dict, AngleRange)):
        return "range"
    if isinstance(v, (list, tuple)):
        return "list"
    return "value"


AngleList = Annotated[list[Finite], Field(min_length=1, max_length=MAX_ANGLES_PER_AXIS)]
Angles = Annotated[Union[Annotated[AngleRange, Tag("range")], Annotated[AngleList, Tag("list")],
                         Annotated[Finite, Tag("value")]], Discriminator(_angles_kind)]
_UNION_TAGS = ("range", "list", "value")


def angle_values(a: Angles) -> list[float]:
    if isinstance(a, AngleRange):
        return a.values()
    if isinstance(a, list):
        return [float(v) for v in a]
    return [float(a)]


class Room(_Strict):
    footprint: list[Point2] = Field(min_length=3)
    height: PositiveFloat

    @model_validator(mode="after")
    def _simple_polygon(self) -> "Room":
        import shapely
        from shapely.geometry import Polygon

        poly = Polygon(self.footprint)
        if not poly.is_valid:
            raise scene_error("footprint", f"expected a simple polygon (edges must not cross or touch), "
                                           f"got {shapely.is_valid_reason(poly)}")
        if poly.area <= 1e-9:
            raise scene_error("footprint", "the polygon has zero area (all corners on one line?)")
        return self


class Box(_Strict):
    min: Point3
    max: Point3

    @model_validator(mode="after")
    def _ordered(self) -> "Box":
        for k, (lo, hi) in enumerate(zip(self.min, self.max)):
            if not hi > lo:
                raise scene_error(f"max[{k}]", f"box max must exceed min on every axis (axis {'xyz'[k]}: "
                                               f"min {lo}, max {hi})")
        return self


class CloudTransform(_Strict):
    """p -> R(rotate_deg: about x, then y, then z) · (scale · p) + translate; then, with
    ``level_floor``, the dominant floor plane (RANSAC, normal within 30° of ``up``) is
    made z = 0 with +z up."""

    scale: PositiveFloat = 1.0
    rotate_deg: Point3 = (0.0, 0.0, 0.0)
    translate: Point3 = (0.0, 0.0, 0.0)
    level_floor: bool = False
    up: Literal["+x", "-x", "+y", "-y", "+z", "-z"] = "+z"


class OutlierRemoval(_Strict):
    """Statistical outlier removal: drop points whose mean distance to ``neighbors``
    nearest points is above the cloud mean by ``std_ratio`` standard deviations."""

    neighbors: Annotated[int, Field(ge=1, le=256, strict=True)] = 16
    std_ratio: PositiveFloat = 2.0


class FreeSpaceSpec(_Strict):
    """How free space is derived from scans / OctoMaps (volume targets come from it)."""

    clearance: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 0.05  # m from any occupied cell
    connected_to_floor: bool = True  # keep only free space connected to the main floor area
    unobserved_occludes: bool = True  # space no scanner saw blocks sight lines (like an obstacle)


class Obstacle(_Strict):
    name: str = Field(min_length=1)
    box: Box | None = None
    mesh: str | None = None
    point_cloud: str | None = None
    octomap: str | None = None  # an OctoMap .bt / .ot file (path relative to the scene file)
    solid: bool = False  # mesh: also fill the cells a closed mesh encloses
    occludes: bool = True  # false: a labelled box for surface targets only (a scan gives the occlusion)
    # point-cloud clean-up (issue 5), each optional and reported: see docs/scan-to-mount-list.md
    transform: CloudTransform | None = None
    crop: Box | None = None  # keep points inside this box (scene frame, after transform)
    downsample: PositiveFloat | None = None  # voxel edge (m)
    remove_outliers: OutlierRemoval | None = None
    viewpoints: list[Point3] | None = None  # scanner positions (file frame), for free-space carving

    @model_validator(mode="after")
    def _one_source(self) -> "Obstacle":
        given = [k for k in ("box", "mesh", "point_cloud", "octomap") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of 'box', 'mesh', 'point_cloud', 'octomap'")
        if self.point_cloud is None:
            for k in ("downsample", "remove_outliers", "viewpoints"):
                if getattr(self, k) is not None:
                    raise scene_error(k, "belongs to 'point_cloud' obstacles")
        if self.box is not None and (self.transform is not None or self.crop is not None):
            raise scene_error("transform" if self.transform is not None else "crop",
                              "belongs to point_cloud, mesh and octomap obstacles")
        if self.solid and self.mesh is None:
            raise scene_error("solid", "belongs to 'mesh' obstacles")
        return self


class TargetRegion(_Strict):
    name: str = Field(min_length=1)
    kind: Literal["volume", "surface"]
    coverage: Annotated[int, Field(ge=0, strict=True)]
    weight: PositiveFloat = 1.0
    heights: list[Finite] | None = None  # volume: target layer heights (m)
    of: list[str] | None = None  # surface: obstacle names
    box: Box | None = None  # surface on scans: the occupied cells inside this box (normals by PCA)
    faces: list[Literal["+x", "-x", "+y", "-y", "+z", "-z"]] | None = None
    max_incidence_deg: Annotated[float, Field(gt=0, le=90, allow_inf_nan=False)] = 90.0
    # image quality: px/m on the target, or a DORI level (detect, observe, recognise, identify)
    min_px_per_m: Union[Annotated[float, BeforeValidator(_no_bool), Field(ge=0, allow_inf_nan=False)],
                        Literal["detect", "observe", "recognise", "recognize", "identify"], None] = None

    @property
    def min_px_per_m_value(self) -> float:
        """Minimum pixel density in px/m (DORI names resolved; 0 = no limit)."""
        from camplace.spec.quality import px_per_m_value

        return px_per_m_value(self.min_px_per_m)

    @model_validator(mode="after")
    def _kind_keys(self) -> "TargetRegion":
        if self.kind == "volume":
            if not self.heights:
                raise ValueError("a volume region needs 'heights' (a non-empty list of metres)")
            if self.of is not None or self.faces is not None or self.box is not None:
                raise ValueError("'of', 'faces' and 'box' belong to surface regions")
        else:
            if not self.of and self.box is None:
                raise ValueError("a surface region needs 'of' (a list of obstacle names) or 'box'")
            if self.of and self.box is not None:
                raise ValueError("give either 'of' or 'box' for a surface region, not both")
            if self.heights is not None:
                raise ValueError("'heights' belongs to volume regions")
        return self


class Intrinsics(_Strict):
    """Calibrated pinhole intrinsics (pixels)."""

    fx: PositiveFloat
    fy: PositiveFloat
    cx: Finite
    cy: Finite


class Camera(_Strict):
    """A camera type: give exactly one of ``fov_deg``, ``intrinsics`` or ``calibration``
    (an OpenCV calibration YAML/JSON file, path relative to the scene file)."""

    name: str = Field(min_length=1)
    model: Literal["pinhole", "opencv", "fisheye"] = "pinhole"
    resolution: tuple[PositiveInt, PositiveInt] | None = None
    fov_deg: tuple[Annotated[float, BeforeValidator(_no_bool), Field(gt=0, le=360)],
                   Annotated[float, BeforeValidator(_no_bool), Field(gt=0, le=360)]] | None = None
    intrinsics: Intrinsics | None = None
    distortion: list[Finite] | None = None
    calibration: str | None = None
    max_fov_deg: Annotated[float, BeforeValidator(_no_bool), Field(gt=0, le=360)] | None = None
    max_range: PositiveFloat = 5.0
    cost: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 1.0

    @model_validator(mode="after")
    def _lens(self) -> "Camera":
        given = [k for k in ("fov_deg", "intrinsics", "calibration") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of 'fov_deg', 'intrinsics', 'calibration'"
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
        return self


class Mount(_Strict):
    """``ceiling_grid``: a grid below the ceiling, yaw absolute. ``wall``: along the walls
    (the footprint's edges, or the given ``walls`` segments) at ``height``, facing inward;
    yaw is relative to the inward normal (default -60..60 step 30)."""

    kind: Literal["ceiling_grid", "wall"]
    camera: str
    spacing: PositiveFloat = 1.0
    offset_below_ceiling: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 0.1
    wall_clearance: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 0.05
    height: Finite | None = None  # wall: mount height above the floor (m)
    walls: list[tuple[Point2, Point2]] | None = None  # wall: segments [[x0, y0], [x1, y1]] (default: footprint edges)
    yaw_deg: Angles = AngleRange(start=0, stop=330, step=30)  # wall default: -60..60 step 30 (relative)

    @model_validator(mode="before")
    @classmethod
    def _wall_yaw_default(cls, data: Any) -> Any:
        if isinstance(data, dict) and data.get("kind") == "wall" and "yaw_deg" not in data:
            data = {**data, "yaw_deg": [-60.0, -30.0, 0.0, 30.0, 60.0]}
        return data

    @model_validator(mode="after")
    def _kind_keys(self) -> "Mount":
        if self.kind == "wall" and self.height is None:
            raise scene_error("height", "a wall mount needs 'height' (metres above the floor)")
        if self.kind == "ceiling_grid" and (self.height is not None or self.walls is not None):
            raise scene_error("height" if self.height is not None else "walls", "belongs to wall mounts")
        return self

    def yaw_values(self) -> list[float]:
        """Yaw angles (degrees); relative to the inward wall normal for wall mounts."""
        return angle_values(self.yaw_deg)
    pitch_deg: Angles = [30.0, 45.0, 60.0]
    roll_deg: Angles = [0.0]


class Placement(_Strict):
    budget: Annotated[int, Field(ge=0, strict=True)] = 20
    solver: str = "greedy"
    time_limit_s: PositiveFloat = 600.0
    money_budget: Annotated[float, Field(ge=0, allow_inf_nan=False)] | None = None  # Σ camera cost limit


class SceneSpec(_Strict):
    name: str = Field(min_length=1)
    voxel_size: PositiveFloat = 0.25
    occupancy_resolution: PositiveFloat = 0.05
    room: Room
    obstacles: list[Obstacle] = []
    targets: list[TargetRegion] = Field(min_length=1)
    cameras: list[Camera] = Field(min_length=1)
    mounts: list[Mount] = Field(min_length=1)
    placement: Placement = Placement()
    free_space: FreeSpaceSpec = FreeSpaceSpec()

    @model_validator(mode="after")
    def _references(self) -> "SceneSpec":
        for key, items in (("obstacles", self.obstacles), ("targets", self.targets), ("cameras", self.cameras)):
            seen: dict[str, int] = {}
            for i, it in enumerate(items):
                if it.name in seen:
                    raise scene_error(f"{key}[{i}].name", f"duplicate name '{it.name}' (already used by "
                                                          f"{key}[{seen[it.name]}]); names must be unique")
                seen[it.name] = i
        H = self.room.height
        fp = [p for p in self.room.footprint]
        xlo, ylo = min(p[0] for p in fp), min(p[1] for p in fp)
        xhi, yhi = max(p[0] for p in fp), max(p[1] for p in fp)
        for i, ob in enumerate(self.obstacles):
            b = ob.box
            if b is not None and (b.max[0] <= xlo or b.min[0] >= xhi or b.max[1] <= ylo or b.min[1] >= yhi
                                  or b.max[2] <= 0 or b.min[2] >= H):
                raise scene_error(f"obstacles[{i}].box", f"lies entirely outside the room (x {xlo}..{xhi}, "
                                                         f"y {ylo}..{yhi}, z 0..{H} m)")
        obstacle_names = [o.name for o in self.obstacles]
        for i, t in enumerate(self.targets):
            for k, name in enumerate(t.of or []):
                if name not in obstacle_names:
                    raise scene_error(f"targets[{i}].of[{k}]", f"unknown obstacle '{name}'"
                                      f"{_did_you_mean(name, obstacle_names)}; expected one of "
                                      f"{_names(obstacle_names)}")
            for k, h in enumerate(t.heights or []):
                if not 0 < h < H:
                    raise scene_error(f"targets[{i}].heights[{k}]",
                                      f"{h} m is outside the room; expected a height in (0, {H}) m")
                if h in (t.heights or [])[:k]:
                    raise scene_error(f"targets[{i}].heights[{k}]", f"duplicate height {h} m")
        if self.targets and all(t.coverage == 0 for t in self.targets):
            raise scene_error("targets", "every region has coverage 0, so there is nothing to place cameras for; "
                                         "expected at least one region with coverage >= 1")
        camera_names = [c.name for c in self.cameras]
        for i, m in enumerate(self.mounts):
            if m.camera not in camera_names:
                raise scene_error(f"mounts[{i}].camera", f"unknown camera '{m.camera}'"
                                  f"{_did_you_mean(m.camera, camera_names)}; expected one of {_names(camera_names)}")
            if m.kind == "wall" and not 0 < (m.height or 0) < H:
                raise scene_error(f"mounts[{i}].height", f"{m.height} m is outside the room; expected (0, {H}) m")
            off = getattr(m, "offset_below_ceiling", None)
            if off is not None and off >= H:
                raise scene_error(f"mounts[{i}].offset_below_ceiling",
                                  f"{off} m is not below the ceiling; expected a value in [0, {H}) m")
            h = getattr(m, "height", None)
            if getattr(m, "kind", "") == "wall" and h is not None and not 0 < h < H:
                raise scene_error(f"mounts[{i}].height", f"{h} m is outside the room; expected a height in (0, {H}) m")
            for k, seg in enumerate(getattr(m, "walls", None) or []):
                if math.dist(seg[0], seg[1]) <= 1e-9:
                    raise scene_error(f"mounts[{i}].walls[{k}]", "zero-length wall segment (both ends equal)")
        return self


def _names(names: list[str]) -> str:
    return ", ".join(f"'{n}'" for n in names[:8]) + (", ..." if len(names) > 8 else "") if names else "(none defined)"


def _did_you_mean(word: str, choices: list[str]) -> str:
    close = difflib.get_close_matches(word, choices, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def _loc_to_path(loc: tuple[Any, ...]) -> str:
    """pydantic's error location -> ``mounts[0].yaw_deg.step`` (union tags dropped)."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif part in _UNION_TAGS or _is_branch_name(str(part)):
            continue  # union branch names are noise for the user
        else:
            out += ("." if out else "") + str(part)
    return out


def _is_branch_name(part: str) -> bool:
    """pydantic names the branch of an untagged union by its type ('float', 'list[...]', 'Box', ...)."""
    return part in ("float", "int", "str", "bool", "constrained-float", "constrained-int", "constrained-str") or (
        part.endswith("]") and "[" in part) or part.startswith("function-") or (
        part[:1].isupper() and part in _model_names())


def _model_names() -> set[str]:
    if not _MODEL_NAMES:
        seen: set[type[BaseModel]] = set()
        todo: list[type[BaseModel]] = [SceneSpec]
        while todo:
            m = todo.pop()
            if m not in seen:
                seen.add(m)
                for f in m.model_fields.values():
                    todo += _models_in(f.annotation)
        _MODEL_NAMES.update(m.__name__ for m in seen)
    return _MODEL_NAMES


_MODEL_NAMES: set[str] = set()


def _models_in(tp: Any) -> list[type[BaseModel]]:
    """Every pydantic model a type annotation may hold (through Annotated, Union, list, tuple, dict)."""
    import typing

    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return [tp]
    if typing.get_origin(tp) is typing.Annotated:
        return _models_in(typing.get_args(tp)[0])
    out: list[type[BaseModel]] = []
    for a in typing.get_args(tp) or ():
        for m in _models_in(a):
            if m not in out:
                out.append(m)
    return out


def _fields_of(model: type[BaseModel], loc: tuple[Any, ...]) -> list[str]:
    """Field names valid at the parent of ``loc`` (for 'did you mean')."""
    cur = [model]
    for part in loc[:-1]:
        if isinstance(part, int) or part in _UNION_TAGS:
            continue
        nxt: list[type[BaseModel]] = []
        for m in cur:
            f = m.model_fields.get(str(part))
            if f is not None:
                nxt += [x for x in _models_in(f.annotation) if x not in nxt]
        if not nxt:
            if any(m.__name__ == part for m in cur):  # union branch named by its model
                continue
            return []
        cur = nxt
    names: list[str] = []
    for m in cur:
        names += [k for k in m.model_fields if k not in names]
    return names


_ERROR_ORDER = {"extra_forbidden": 0}  # a mistyped key also shows up as a missing one: name the typo


def format_error_entry(e: dict, model: type[BaseModel] | None = None, missing: tuple[str, ...] = ()) -> tuple[str, str]:
    """One pydantic error -> (key path, message); ``missing``: required keys missing beside it."""
    import re

    loc = tuple(e["loc"])
    path = _loc_to_path(loc)
    msg = e["msg"]
    t = e["type"]
    ctx = e.get("ctx") or {}
    if t == "scene":
        sub = ctx.get("path", "")
        path = (path + ("." if path and not sub.startswith("[") else "") + sub) if sub else path
        return path, ctx.get("message", msg)
    if t == "extra_forbidden":
        key = str(loc[-1])
        hint = _did_you_mean(key, list(missing)) or (_did_you_mean(key, _fields_of(model, loc)) if model else "")
        return path, f"unknown key '{key}'{hint}"
    if t == "missing":
        return path, "required key is missing"
    if msg.startswith("Value error, "):
        msg = msg[len("Value error, "):]
    msg = re.sub(r"^Input should be ", "expected ", msg)
    msg = re.sub(r"^Input should have ", "expected ", msg)
    inp = e.get("input")
    if isinstance(inp, float) and not math.isfinite(inp):
        msg = "expected a finite number"
    if t == "literal_error" and isinstance(inp, str):
        msg += _did_you_mean(inp, re.findall(r"'([^']*)'", str(ctx.get("expected", ""))))
    if "input" in e and not isinstance(inp, (dict, list, tuple, BaseModel)):
        r = repr(inp)
        msg += f" (got {r if len(r) <= 60 else r[:57] + '...'})"
    return path, msg


def format_validation_error(err: ValidationError, source: str, model: type[BaseModel] | None = None) -> str:
    """One line: ``source: key.path: what is wrong`` (the first error; count of the rest)."""
    errors = sorted(err.errors(), key=lambda e: _ERROR_ORDER.get(e["type"], 1))
    first = errors[0]
    missing = tuple(str(e["loc"][-1]) for e in errors
                    if e["type"] == "missing" and tuple(e["loc"][:-1]) == tuple(first["loc"][:-1]))
    path, msg = format_error_entry(first, model, missing)
    more = len(errors) - 1
    tail = f" (and {more} more error{'s' if more > 1 else ''})" if more else ""
    return f"{source}: {path or '<top>'}: {msg}{tail}".replace("\n", " ")


# --- checks that need more than one key: referenced files, memory -------------------------------

FILE_KEYS = ("mesh", "point_cloud", "octomap", "calibration", "file", "path")  # scene keys that name a file


def _walk_files(obj: Any, path: str):
    """Yield (key path, file name) for every FILE_KEYS string anywhere in a spec."""
    if isinstance(obj, BaseModel):
        for k in type(obj).model_fields:
            v = getattr(obj, k, None)
            sub = f"{path}.{k}" if path else k
            if k in FILE_KEYS and isinstance(v, (str, Path)):
                yield sub, str(v)
            else:
                yield from _walk_files(v, sub)
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            yield from _walk_files(v, f"{path}[{i}]")


def check_referenced_files(spec: BaseModel, base_dir: Path | None, source: str) -> None:
    """Every file the scene names (meshes, point clouds, ...) must exist, relative to the scene file."""
    for path, name in _walk_files(spec, ""):
        f = Path(name).expanduser()
        if not f.is_absolute() and base_dir is not None:
            f = base_dir / f
        if not f.is_file():
            where = f" (looked in {f.parent})" if not Path(name).is_absolute() else ""
            raise InputError(f"{source}: {path}: file '{name}' not found{where}")


GIB = 1024**3


def memory_limit_bytes() -> int:
    """The memory a run may plan to use: ``CAMPLACE_MAX_MEMORY_GB`` if set, else 80 % of physical RAM."""
    import os

    env = os.environ.get("CAMPLACE_MAX_MEMORY_GB")
    if env:
        try:
            v = float(env)
        except ValueError:
            raise InputError(f"CAMPLACE_MAX_MEMORY_GB: expected a number of GiB, got '{env}'") from None
        if not (v > 0 and math.isfinite(v)):
            raise InputError(f"CAMPLACE_MAX_MEMORY_GB: expected a positive number of GiB, got '{env}'")
        return int(v * GIB)
    try:
        return int(0.8 * os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-POSIX
        return 8 * GIB


# bytes per item, measured roughly on the stage code (arrays + temporaries)
BYTES_PER_OCC_CELL = 1.0  # bool grid
BYTES_PER_OCC_COLUMN = 40.0  # 2D meshgrid + inside test over x, y
BYTES_PER_TARGET = 160.0  # positions, normals, gamma, weights, region ids, masks, visibility inputs
BYTES_PER_TARGET_GRID_CELL = 40.0  # xy meshgrid of the volume grid
BYTES_PER_CANDIDATE = 500.0  # positions, angles, rotations (+ temporaries), ids, visibility counts


@dataclass(frozen=True)
class ResourceEstimate:
    """Sizes a scene will allocate, computed from the spec alone (nothing allocated).
    Each ``items`` entry: (key path to blame, what, count, bytes)."""

    items: tuple[tuple[str, str, float, float], ...]

    @property
    def total_bytes(self) -> float:
        return float(sum(it[3] for it in self.items))

    def count(self, what: str) -> float:
        return float(sum(it[2] for it in self.items if it[1] == what))


def _n_angles(a: Any) -> int:
    if isinstance(a, AngleRange):
        return a.count()
    if isinstance(a, (list, tuple)):
        return len(a)
    return 1


def estimate_resources(spec: "SceneSpec") -> ResourceEstimate:
    """Upper estimates of the occupancy grid, target and candidate sizes of a scene."""
    fp = [tuple(map(float, p)) for p in spec.room.footprint]
    w = max(p[0] for p in fp) - min(p[0] for p in fp)
    d = max(p[1] for p in fp) - min(p[1] for p in fp)
    H = float(spec.room.height)
    items: list[tuple[str, str, float, float]] = []
    r = float(spec.occupancy_resolution)
    nx, ny, nz = (math.ceil(e / r) + 2 for e in (w, d, H))
    cells = float(nx) * ny * nz
    items.append(("occupancy_resolution", "occupancy cells", cells,
                  cells * BYTES_PER_OCC_CELL + float(nx) * ny * BYTES_PER_OCC_COLUMN))
    v = float(spec.voxel_size)
    grid_xy = float(math.floor(w / v) + 1) * float(math.floor(d / v) + 1)
    boxes = {o.name: o.box for o in spec.obstacles if getattr(o, "box", None) is not None}
    for i, t in enumerate(spec.targets):
        if t.kind == "volume":
            n = grid_xy * len(t.heights or [])
            items.append((f"targets[{i}]", "targets", n, n * BYTES_PER_TARGET + grid_xy * BYTES_PER_TARGET_GRID_CELL))
        else:
            n = 0.0
            for name in t.of or []:
                b = boxes.get(name)
                if b is None:
                    continue
                ext = [hi - lo for lo, hi in zip(b.min, b.max)]
                for a in range(3):
                    u, q = [k for k in range(3) if k != a]
                    n += 2 * (math.ceil(ext[u] / v) + 1) * (math.ceil(ext[q] / v) + 1)
            items.append((f"targets[{i}]", "targets", n, n * BYTES_PER_TARGET))
    for i, m in enumerate(spec.mounts):
        spacing = getattr(m, "spacing", None)
        if not spacing:
            continue
        if getattr(m, "kind", "") == "ceiling_grid":
            pts = float(math.floor(w / spacing) + 1) * float(math.floor(d / spacing) + 1)
        else:  # wall or other mounts: along the walls (given segments or the footprint's edges)
            segs = getattr(m, "walls", None) or [(fp[k], fp[(k + 1) % len(fp)]) for k in range(len(fp))]
            pts = sum(math.dist(a, b) / spacing + 1 for a, b in segs)
        n = pts * _n_angles(getattr(m, "yaw_deg", 1)) * _n_angles(getattr(m, "pitch_deg", 1)) * \
            _n_angles(getattr(m, "roll_deg", 1))
        items.append((f"mounts[{i}]", "candidates", n, n * BYTES_PER_CANDIDATE))
    return ResourceEstimate(tuple(items))


def _gib(b: float) -> str:
    return f"{b / GIB:.1f} GiB" if b >= 0.1 * GIB else f"{b / 1024**2:.0f} MiB"


def check_resources(spec: "SceneSpec", source: str, limit_bytes: int | None = None) -> ResourceEstimate:
    """Refuse (InputError, with the numbers) a scene whose grids would not fit in memory,
    before anything is allocated."""
    limit = memory_limit_bytes() if limit_bytes is None else int(limit_bytes)
    est = estimate_resources(spec)
    hint = "set the limit with --max-memory-gb or CAMPLACE_MAX_MEMORY_GB"
    fix = {"occupancy_resolution": "use a coarser occupancy_resolution",
           "targets": "use a coarser voxel_size or fewer heights", "mounts": "use a larger spacing or fewer angles"}
    for path, what, n, b in sorted(est.items, key=lambda it: -it[3]):
        if b > limit:
            key = path if path == "occupancy_resolution" else (
                "voxel_size" if path.startswith("targets") else path + ".spacing")
            value = {"occupancy_resolution": spec.occupancy_resolution, "voxel_size": spec.voxel_size}.get(key)
            shown = f" {value} m" if value is not None else ""
            raise InputError(f"{source}: {key}:{shown} would need {n:.3g} {what} ({_gib(b)} of memory, limit "
                             f"{_gib(limit)}); {fix[path.split('[')[0]]} ({hint})")
    if est.total_bytes > limit:
        parts = ", ".join(f"{p}: {_gib(b)}" for p, _, _, b in sorted(est.items, key=lambda it: -it[3])[:3])
        raise InputError(f"{source}: the scene would need about {_gib(est.total_bytes)} of memory ({parts}), "
                         f"limit {_gib(limit)}; use coarser grids ({hint})")
    return est


def parse_scene(data: Any, source: str = "<scene>") -> SceneSpec:
    """Validate a scene mapping; raise InputError with a one-line message."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: expected a YAML mapping of scene keys, got {type(data).__name__}")
    try:
        return SceneSpec.model_validate(data)
    except ValidationError as err:
        raise InputError(format_validation_error(err, source, SceneSpec)) from None


class _UniqueKeyLoader(yaml.SafeLoader):
    """yaml.SafeLoader that refuses a key given twice in one mapping (PyYAML keeps the last)."""


def _construct_unique_mapping(loader: _UniqueKeyLoader, node: yaml.MappingNode, deep: bool = False) -> dict:
    seen: dict[Any, int] = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        try:
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"key '{key}' appears twice in one mapping (first on line {seen[key] + 1})",
                    key_node.start_mark)
            seen[key] = key_node.start_mark.line
        except TypeError:  # unhashable key: let the default constructor complain
            pass
    return loader.construct_mapping(node, deep=deep)


_UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_unique_mapping)


def load_yaml_text(text: str, source: str) -> Any:
    """Parse YAML (duplicate keys refused); errors are one line with line and column."""
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        problem = getattr(err, "problem", None) or str(err).strip().splitlines()[0]
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        raise InputError(f"{source}: not valid YAML{where}: {problem}") from None


def load_scene_file(path: str | Path) -> SceneSpec:
    """Read and validate a YAML scene file."""
    p = Path(path)
    if p.is_dir():
        raise InputError(f"{p}: is a folder; expected a YAML scene file")
    if not p.is_file():
        raise InputError(f"{p}: scene file not found")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{p}: not a text file (not UTF-8); expected a YAML scene file") from None
    except OSError as err:
        raise InputError(f"{p}: cannot read the scene file ({err.strerror})") from None
    data = load_yaml_text(text, str(p))
    if data is None:
        raise InputError(f"{p}: the file is empty; expected a YAML mapping of scene keys")
    spec = parse_scene(data, str(p))
    check_referenced_files(spec, p.resolve().parent, str(p))
    return spec
