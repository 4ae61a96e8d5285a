"""The scene file (YAML) schema: the user's contract, validated with pydantic.

Every error names the file, the key path (e.g. ``mounts[0].yaw_deg.step``) and what
was expected. See docs/scene-file.md for the reference.
"""

from __future__ import annotations

import difflib
import math
from pathlib import Path
from typing import Annotated, Any, Literal, Union

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from camplace.errors import InputError

PositiveFloat = Annotated[float, Field(gt=0, allow_inf_nan=False)]
Finite = Annotated[float, Field(allow_inf_nan=False)]
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

    def values(self) -> list[float]:
        n = int(math.floor((self.stop - self.start) / self.step + 1e-9)) + 1
        return [self.start + k * self.step for k in range(max(n, 0))]


Angles = Union[AngleRange, list[Finite], Finite]


def angle_values(a: Angles) -> list[float]:
    if isinstance(a, AngleRange):
        return a.values()
    if isinstance(a, list):
        return [float(v) for v in a]
    return [float(a)]


class Room(_Strict):
    footprint: list[Point2] = Field(min_length=3)
    height: PositiveFloat


class Box(_Strict):
    min: Point3
    max: Point3

    @model_validator(mode="after")
    def _ordered(self) -> "Box":
        for k, (lo, hi) in enumerate(zip(self.min, self.max)):
            if not hi > lo:
                raise ValueError(f"box max must exceed min on every axis (axis {'xyz'[k]}: min {lo}, max {hi})")
        return self


class Obstacle(_Strict):
    name: str = Field(min_length=1)
    box: Box | None = None
    mesh: str | None = None
    point_cloud: str | None = None
    solid: bool = False

    @model_validator(mode="after")
    def _one_source(self) -> "Obstacle":
        given = [k for k in ("box", "mesh", "point_cloud") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of 'box', 'mesh', 'point_cloud'")
        return self


class TargetRegion(_Strict):
    name: str = Field(min_length=1)
    kind: Literal["volume", "surface"]
    coverage: Annotated[int, Field(ge=0, strict=True)]
    weight: PositiveFloat = 1.0
    heights: list[Finite] | None = None  # volume: target layer heights (m)
    of: list[str] | None = None  # surface: obstacle names
    faces: list[Literal["+x", "-x", "+y", "-y", "+z", "-z"]] | None = None
    max_incidence_deg: Annotated[float, Field(gt=0, le=90, allow_inf_nan=False)] = 90.0

    @model_validator(mode="after")
    def _kind_keys(self) -> "TargetRegion":
        if self.kind == "volume":
            if not self.heights:
                raise ValueError("a volume region needs 'heights' (a non-empty list of metres)")
            if self.of is not None or self.faces is not None:
                raise ValueError("'of' and 'faces' belong to surface regions")
        else:
            if not self.of:
                raise ValueError("a surface region needs 'of' (a list of obstacle names)")
            if self.heights is not None:
                raise ValueError("'heights' belongs to volume regions")
        return self


class Camera(_Strict):
    name: str = Field(min_length=1)
    model: Literal["pinhole"] = "pinhole"
    resolution: tuple[Annotated[int, Field(gt=0)], Annotated[int, Field(gt=0)]]
    fov_deg: tuple[Annotated[float, Field(gt=0, lt=180)], Annotated[float, Field(gt=0, lt=180)]]
    max_range: PositiveFloat = 5.0
    cost: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 1.0


class Mount(_Strict):
    kind: Literal["ceiling_grid"]
    camera: str
    spacing: PositiveFloat = 1.0
    offset_below_ceiling: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 0.1
    wall_clearance: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 0.05
    yaw_deg: Angles = AngleRange(start=0, stop=330, step=30)
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

    @model_validator(mode="after")
    def _references(self) -> "SceneSpec":
        for key, items in (("obstacles", self.obstacles), ("targets", self.targets), ("cameras", self.cameras)):
            seen: set[str] = set()
            for i, it in enumerate(items):
                if it.name in seen:
                    raise ValueError(f"{key}[{i}].name: duplicate name '{it.name}'")
                seen.add(it.name)
        obstacle_names = [o.name for o in self.obstacles]
        for i, t in enumerate(self.targets):
            for name in t.of or []:
                if name not in obstacle_names:
                    raise ValueError(f"targets[{i}].of: unknown obstacle '{name}'{_did_you_mean(name, obstacle_names)}")
            for h in t.heights or []:
                if not 0 < h < self.room.height:
                    raise ValueError(f"targets[{i}].heights: {h} m is outside the room (0, {self.room.height}) m")
        camera_names = [c.name for c in self.cameras]
        for i, m in enumerate(self.mounts):
            if m.camera not in camera_names:
                raise ValueError(f"mounts[{i}].camera: unknown camera '{m.camera}'{_did_you_mean(m.camera, camera_names)}")
            if m.offset_below_ceiling >= self.room.height:
                raise ValueError(f"mounts[{i}].offset_below_ceiling: {m.offset_below_ceiling} m is not below the ceiling")
        return self


def _did_you_mean(word: str, choices: list[str]) -> str:
    close = difflib.get_close_matches(word, choices, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def _loc_to_path(loc: tuple[Any, ...]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif part in ("AngleRange", "list[float]", "float", "list[constrained-float]", "constrained-float"):
            continue  # union branch names are noise for the user
        else:
            out += ("." if out else "") + str(part)
    return out


def _fields_of(model: type[BaseModel], loc: tuple[Any, ...]) -> list[str]:
    """Field names valid at the parent of ``loc`` (for 'did you mean')."""
    cur: Any = model
    for part in loc[:-1]:
        if isinstance(part, int):
            continue
        field = getattr(cur, "model_fields", {}).get(part)
        if field is None:
            return []
        ann = field.annotation
        args = getattr(ann, "__args__", ()) or ()
        nxt = [a for a in (ann, *args) if isinstance(a, type) and issubclass(a, BaseModel)]
        for a in args:
            for b in getattr(a, "__args__", ()) or ():
                if isinstance(b, type) and issubclass(b, BaseModel):
                    nxt.append(b)
        if not nxt:
            return []
        cur = nxt[0]
    return list(getattr(cur, "model_fields", {}).keys())


def format_validation_error(err: ValidationError, source: str, model: type[BaseModel] = None) -> str:
    """One line: ``source: key.path: what is wrong`` (the first error; count of the rest)."""
    e = err.errors()[0]
    path = _loc_to_path(tuple(e["loc"]))
    msg = e["msg"]
    if e["type"] == "extra_forbidden":
        key = str(e["loc"][-1])
        hint = _did_you_mean(key, _fields_of(model, tuple(e["loc"]))) if model else ""
        msg = f"unknown key '{key}'{hint}"
    elif msg.startswith("Value error, "):
        msg = msg[len("Value error, "):]
    if e["type"] not in ("extra_forbidden", "missing") and "input" in e and not isinstance(e["input"], (dict, list)):
        msg += f" (got {e['input']!r})"
    more = len(err.errors()) - 1
    tail = f" [+{more} more error(s)]" if more else ""
    return f"{source}: {path or '<top>'}: {msg}{tail}"


def parse_scene(data: Any, source: str = "<scene>") -> SceneSpec:
    """Validate a scene mapping; raise InputError with a one-line message."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: expected a YAML mapping of scene keys, got {type(data).__name__}")
    try:
        return SceneSpec.model_validate(data)
    except ValidationError as err:
        raise InputError(format_validation_error(err, source, SceneSpec)) from None


def load_scene_file(path: str | Path) -> SceneSpec:
    """Read and validate a YAML scene file."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: scene file not found")
    try:
        data = yaml.safe_load(p.read_text())
    except (yaml.YAMLError, UnicodeDecodeError) as err:
        first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise InputError(f"{p}: not valid YAML: {first}") from None
    if data is None:
        raise InputError(f"{p}: the file is empty; expected a YAML mapping of scene keys")
    return parse_scene(data, str(p))
