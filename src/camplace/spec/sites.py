"""The scene keys of real sites (issue 17): ``zones``, ``mount_rules`` and ``existing``.

Zones are requirements by area (or on faces) that replace the volume targets of
``targets:`` inside their polygon; privacy zones must never be seen; mount rules say
where cameras may hang; existing cameras are fixed and count toward coverage only.
See docs/scene-file.md (zones, mount_rules, existing).
"""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BeforeValidator, Field, StrictBool, model_validator

from camplace.spec.basics import (Box, Face, Finite, Incidence, Point2, Point3, PositiveFloat, PxPerM, _Strict,
                                  polygon_problem, scene_error)
from camplace.spec.wording import did_you_mean, name_list

Polygon2 = Annotated[list[Point2], Field(min_length=3)]
ZONE_LIMIT_KEYS = ("coverage", "weight", "min_px_per_m", "max_incidence_deg")


def _polygons_ok(polygons: list, key: str) -> None:
    """scene_error naming ``key[i]`` for the first polygon that is not simple."""
    for i, poly in enumerate(polygons):
        why = polygon_problem(poly)
        if why:
            raise scene_error(f"{key}[{i}]", why)


class Zone(_Strict):
    """A requirement by area: volume targets inside ``polygon`` at ``heights`` (default: the
    heights of the volume regions of ``targets``), replacing those regions' targets there;
    or, with ``of`` / ``box``, surface targets as a surface region. ``privacy``: no selected
    camera may see any point of the polygon (hard rule; the zone gets no targets)."""

    name: str = Field(min_length=1)
    polygon: Polygon2 | None = None
    heights: list[Finite] | None = None
    of: list[str] | None = None
    box: Box | None = None
    faces: list[Face] | None = None
    coverage: Annotated[int, Field(ge=0, strict=True)] = 1
    weight: PositiveFloat = 1.0
    min_px_per_m: PxPerM = None
    max_incidence_deg: Incidence = 90.0
    privacy: StrictBool = False

    @model_validator(mode="after")
    def _shape(self) -> "Zone":
        surface = self.of is not None or self.box is not None
        if surface == (self.polygon is not None):
            raise ValueError("give either 'polygon' (a volume zone) or 'of' / 'box' (a surface zone), not both")
        if self.of is not None and self.box is not None:
            raise scene_error("box", "give either 'of' or 'box' for a surface zone, not both")
        if self.polygon is not None:
            _polygons_ok([self.polygon], "polygon")
            if self.faces is not None:
                raise scene_error("faces", "belongs to surface zones (with 'of')")
        elif self.heights is not None:
            raise scene_error("heights", "belongs to volume zones (with 'polygon')")
        if self.privacy:
            if surface:
                raise scene_error("privacy", "belongs to volume zones (with 'polygon')")
            extra = [k for k in ZONE_LIMIT_KEYS if k in self.model_fields_set]
            if extra:
                raise scene_error(extra[0], "a privacy zone has no targets; remove this key")
        return self

    @property
    def is_surface(self) -> bool:
        return self.polygon is None


Polygons = list[Polygon2]


class MountRules(_Strict):
    """Where cameras may hang: never inside ``forbid`` polygons, only inside ``allow``
    polygons (if given), only at the CSV ``points`` (x,y,z per line; if given);
    ``max_per_type``: at most this many new cameras of a camera type; ``clearance``: the
    metres a camera keeps from every wall and obstacle (occupied cell) other than the
    surface it hangs from (camplace.cameras.mount_rules.clear_of_occupied)."""

    forbid: Polygons = []
    allow: Polygons | None = None
    points: str | None = None
    max_per_type: dict[str, Annotated[int, Field(ge=0, strict=True)]] = {}
    clearance: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 0.1  # m: room for the camera body

    @model_validator(mode="after")
    def _simple(self) -> "MountRules":
        _polygons_ok(self.forbid, "forbid")
        _polygons_ok(self.allow or [], "allow")
        return self

    @property
    def active(self) -> bool:
        """True when any rule restricts the mount positions."""
        return bool(self.forbid) or self.allow is not None or self.points is not None


def _id_text(v: Any) -> Any:
    return str(v) if isinstance(v, int) and not isinstance(v, bool) else v


class ExistingCamera(_Strict):
    """A camera already installed: fixed, counted toward coverage, not budget (degrees as mounts)."""

    id: Annotated[str, BeforeValidator(_id_text), Field(min_length=1)]
    camera: str
    position: Point3
    yaw_deg: Finite
    pitch_deg: Finite
    roll_deg: Finite = 0.0
    focal_mm: PositiveFloat | None = None  # a varifocal type's setting (default: its widest); issue 27


def walkable_heights(spec) -> list[float]:
    """The heights (m) of the volume regions of ``spec.targets``, in order, without repeats."""
    out: list[float] = []
    for t in spec.targets:
        out += [h for h in t.heights or [] if h not in out]
    return out


def _unknown(key: str, what: str, name: str, names: list[str]):
    return scene_error(key, f"unknown {what} '{name}'{did_you_mean(name, names)}; expected one of {name_list(names)}")


def site_references(spec, obstacle_names: list[str], camera_names: list[str]) -> None:
    """Zones, mount rules and existing cameras of ``spec`` (a SceneSpec) name things that
    exist and fit the room; scene_error naming the key path otherwise."""
    H, taken = spec.room.height, {t.name: f"targets[{i}]" for i, t in enumerate(spec.targets)}
    for i, z in enumerate(spec.zones):
        if z.name in taken:
            raise scene_error(f"zones[{i}].name", f"duplicate name '{z.name}' (already used by {taken[z.name]}); "
                                                  "zone and region names must be unique")
        taken[z.name] = f"zones[{i}]"
        for k, name in enumerate(z.of or []):
            if name not in obstacle_names:
                raise _unknown(f"zones[{i}].of[{k}]", "obstacle", name, obstacle_names)
        for k, h in enumerate(z.heights or []):
            if not 0 < h < H or h in (z.heights or [])[:k]:
                raise scene_error(f"zones[{i}].heights[{k}]", f"{h} m: expected a height in (0, {H}) m, each once")
        if not z.is_surface and not z.privacy and not z.heights and not walkable_heights(spec):
            raise scene_error(f"zones[{i}].heights", "required: targets has no volume region whose heights a zone "
                                                     "could take (a non-empty list of metres)")
    for name in spec.mount_rules.max_per_type:
        if name not in camera_names:
            raise _unknown(f"mount_rules.max_per_type.{name}", "camera", name, camera_names)
    seen: dict[str, int] = {}
    for i, e in enumerate(spec.existing if isinstance(spec.existing, list) else []):
        if e.id in seen:
            raise scene_error(f"existing[{i}].id", f"duplicate id '{e.id}' (already used by existing[{seen[e.id]}])")
        seen[e.id] = i
        if e.camera not in camera_names:
            raise _unknown(f"existing[{i}].camera", "camera", e.camera, camera_names)
        _focal_in_range(e.focal_mm, next(c for c in spec.cameras if c.name == e.camera), f"existing[{i}].focal_mm")


def _focal_in_range(focal_mm: float | None, camera, key: str) -> None:
    """scene_error naming ``key`` unless ``focal_mm`` (None: nothing to check) lies in the
    focal range of ``camera`` (a cameras entry given by focal_mm)."""
    if focal_mm is None:
        return
    if camera.focal_mm is None:
        raise scene_error(key, f"camera '{camera.name}' has no lens given by focal_mm; remove this key")
    lo, hi = camera.focal_range_mm
    if not lo - 1e-9 <= focal_mm <= hi + 1e-9:
        raise scene_error(key, f"{focal_mm} mm is outside the lens's range; expected {lo:g}..{hi:g} mm")
