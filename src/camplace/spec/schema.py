"""The scene file (YAML) schema: the user's contract, as pydantic models.

Every error names the file, the key path (e.g. ``mounts[0].yaw_deg.step``) and what
was expected (worded by camplace.spec.wording; files read by camplace.spec.loading).
See docs/scene-file.md for the reference.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal, Union

from pydantic import BaseModel, Discriminator, Field, Tag, ValidationError, model_validator

from camplace.spec.basics import (FACES, Box, Face, Finite, Incidence, Point2, Point3, PositiveFloat,  # noqa: F401
                                  PositiveInt, PxPerM, _no_bool, _Strict, polygon_problem, scene_error)
from camplace.spec.crowd import CrowdSpec, crowd_references
from camplace.spec.lenses import Camera, Intrinsics, Recording  # noqa: F401 - the cameras entries
from camplace.spec.sites import ExistingCamera, MountRules, Polygon2, Zone, site_references
from camplace.spec.wording import did_you_mean, name_list

MAX_ANGLES_PER_AXIS = 3600  # an angle list/range longer than this is a typo (e.g. step 0.001)


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
        why = polygon_problem(self.footprint)
        if why:
            raise scene_error("footprint", why)
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


class Prism(_Strict):
    """A polygon in plan (m; any orientation, convex or not, optional ``holes``) extruded
    from ``z[0]`` to ``z[1]`` (m): walls and furniture drawn in plan (camplace.scene.importers)."""

    polygon: Polygon2
    holes: list[Polygon2] = []
    z: tuple[Finite, Finite]

    @model_validator(mode="after")
    def _shape(self) -> "Prism":
        if not self.z[1] > self.z[0]:
            raise scene_error("z", f"expected [zmin, zmax] with zmax > zmin, got {list(self.z)}")
        from shapely.geometry import Polygon

        poly = Polygon(self.polygon, self.holes)
        why = polygon_problem(self.polygon) or (None if poly.is_valid else
                                                "the holes must lie inside the polygon without crossing it")
        if why:
            raise scene_error("polygon", why)
        return self


class Obstacle(_Strict):
    name: str = Field(min_length=1)
    box: Box | None = None
    prism: Prism | None = None  # a polygon extruded between two heights (walls in plan)
    source: dict[str, str] | None = None  # provenance of imported obstacles: file, layer/entity, handle
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
        given = [k for k in ("box", "prism", "mesh", "point_cloud", "octomap") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of 'box', 'prism', 'mesh', 'point_cloud', 'octomap'")
        if self.point_cloud is None:
            for k in ("downsample", "remove_outliers", "viewpoints"):
                if getattr(self, k) is not None:
                    raise scene_error(k, "belongs to 'point_cloud' obstacles")
        if not self.is_file and (self.transform is not None or self.crop is not None):
            raise scene_error("transform" if self.transform is not None else "crop",
                              "belongs to point_cloud, mesh and octomap obstacles")
        if self.solid and self.mesh is None:
            raise scene_error("solid", "belongs to 'mesh' obstacles")
        return self

    @property
    def is_file(self) -> bool:
        """True for obstacles read from a file (mesh, point cloud, OctoMap)."""
        return self.box is None and self.prism is None


class TargetRegion(_Strict):
    name: str = Field(min_length=1)
    kind: Literal["volume", "surface"]
    coverage: Annotated[int, Field(ge=0, strict=True)]
    weight: PositiveFloat = 1.0
    heights: list[Finite] | None = None  # volume: target layer heights (m)
    of: list[str] | None = None  # surface: obstacle names
    box: Box | None = None  # surface on scans: the occupied cells inside this box (normals by PCA)
    faces: list[Face] | None = None
    max_incidence_deg: Incidence = 90.0
    min_px_per_m: PxPerM = None  # image quality: px/m on the target, or a DORI level

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


class Mount(_Strict):
    """``ceiling_grid``: a grid below the ceiling, yaw absolute. ``wall``: along the walls
    (the footprint's edges, or the given ``walls`` segments) at ``height``, facing inward;
    yaw is relative to the inward normal (default -60..60 step 30)."""

    kind: Literal["ceiling_grid", "wall"]
    camera: str | Annotated[list[str], Field(min_length=1)]  # a camera type, or several (each at every pose)
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

    @property
    def camera_names(self) -> list[str]:
        """The camera types this mount carries (``camera``: one name or a list)."""
        return [self.camera] if isinstance(self.camera, str) else list(self.camera)

    def yaw_values(self) -> list[float]:
        """Yaw angles (degrees); relative to the inward wall normal for wall mounts."""
        return angle_values(self.yaw_deg)
    pitch_deg: Angles = [30.0, 45.0, 60.0]
    roll_deg: Angles = [0.0]


class PlacementSettings(_Strict):
    budget: Annotated[int, Field(ge=0, strict=True)] = 20
    solver: str = "greedy"
    time_limit_s: PositiveFloat = 600.0
    quality: Literal["default", "high"] = "default"  # high: the whole run's quality_time_s on the placement (issue 37)
    money_budget: Annotated[float, Field(ge=0, allow_inf_nan=False)] | None = None  # Σ camera cost limit
    # the solver's own options (and seed / threads), checked against the solver's declared
    # types before any heavy stage (camplace.workflows.run); they go with ``solver`` only
    options: dict[str, Any] = {}


class Storey(_Strict):
    """One storey of a building (``storeys:``, issue 33): its floor ``elevation`` (m, building
    z), its room (footprint, floor-to-ceiling height), walls and furniture, zones, where its
    floor opens to the storey below (``floor_openings``: plan polygons, m), an optional camera
    limit (``budget``) and, optionally, its own targets / mounts / mount rules (default: the
    building's). Coordinates in plan are the building's; heights are above this storey's floor."""

    elevation: Finite = 0.0
    room: Room
    obstacles: list[Obstacle] = []
    zones: list[Zone] = []
    targets: list[TargetRegion] | None = None
    mounts: list[Mount] | None = None
    mount_rules: MountRules | None = None
    floor_openings: list[Polygon2] = []
    budget: Annotated[int, Field(ge=0, strict=True)] | None = None


STOREY_SHARED = ("voxel_size", "occupancy_resolution", "targets", "cameras", "mounts", "placement", "free_space",
                 "mount_rules", "recording")  # building keys a storey takes unless it gives its own


class SceneSpec(_Strict):
    name: str = Field(min_length=1)
    voxel_size: PositiveFloat = 0.25
    occupancy_resolution: PositiveFloat = 0.05
    room: Room
    obstacles: list[Obstacle] = []
    targets: list[TargetRegion] = Field(min_length=1)
    cameras: list[Camera] = Field(min_length=1)
    mounts: list[Mount] = Field(min_length=1)
    placement: PlacementSettings = PlacementSettings()
    free_space: FreeSpaceSpec = FreeSpaceSpec()
    zones: list[Zone] = []  # later zones win where they overlap (docs/scene-file.md#zones)
    mount_rules: MountRules = MountRules()
    existing: list[ExistingCamera] | str | None = None  # or a placement.csv path (relative to the scene file)
    crowd: CrowdSpec | None = None  # people who may block sight lines (issue 28; camplace.spec.crowd)
    recording: Recording | None = None  # retention for the recording load (issue 27)
    # a building: storey name -> Storey, stacked at their elevations in one scene (issue 33);
    # ``room`` is then the building's envelope (filled in when not given)
    storeys: dict[Annotated[str, Field(min_length=1)], Storey] | None = None

    @model_validator(mode="before")
    @classmethod
    def _envelope(cls, data: Any) -> Any:
        """A building without ``room``: the bounding rectangle of its storeys' footprints,
        as high as floor of the lowest to ceiling of the highest storey."""
        if not (isinstance(data, dict) and isinstance(data.get("storeys"), dict) and data["storeys"]
                and "room" not in data):
            return data
        try:
            rooms = [(float((st.get("elevation") if isinstance(st, dict) else st.elevation) or 0.0),
                      st["room"] if isinstance(st, dict) else st.room.model_dump()) for st in data["storeys"].values()]
            pts = [p for _, r in rooms for p in r["footprint"]]
            x0, y0 = min(float(p[0]) for p in pts), min(float(p[1]) for p in pts)
            x1, y1 = max(float(p[0]) for p in pts), max(float(p[1]) for p in pts)
            top = max(e + float(r["height"]) for e, r in rooms) - min(e for e, _ in rooms)
        except (KeyError, TypeError, ValueError, IndexError, AttributeError):
            return data  # the storeys' own errors say what is wrong
        return {**data, "room": {"footprint": [[x0, y0], [x1, y0], [x1, y1], [x0, y1]], "height": top}}

    def storey_spec(self, name: str) -> "SceneSpec":
        """The single-storey scene of storey ``name`` (floor at z = 0, plan in building x, y):
        its own room, obstacles, zones and limits with the building's shared keys
        (STOREY_SHARED) where it gives none; the building budget unless it has its own."""
        st = (self.storeys or {})[name]
        data = {k: getattr(self, k) for k in STOREY_SHARED if getattr(self, k) is not None}
        data.update(name=f"{self.name}/{name}", room=st.room, obstacles=st.obstacles, zones=st.zones)
        for k in ("targets", "mounts", "mount_rules"):
            if getattr(st, k) is not None:
                data[k] = getattr(st, k)
        if st.budget is not None:
            data["placement"] = self.placement.model_copy(update={"budget": st.budget})
        return SceneSpec.model_validate({k: (v.model_dump() if isinstance(v, BaseModel) else
                                             [x.model_dump() if isinstance(x, BaseModel) else x for x in v]
                                             if isinstance(v, list) else v) for k, v in data.items()})

    @property
    def storey_names(self) -> list[str]:
        """The storeys of a building, lowest floor first ([] for a single room)."""
        return sorted(self.storeys or {}, key=lambda n: self.storeys[n].elevation)

    @model_validator(mode="after")
    def _building(self) -> "SceneSpec":
        if not self.storeys:
            return self
        for key in ("obstacles", "zones", "existing", "crowd"):
            if getattr(self, key):
                raise scene_error(key, "a building gives these per storey (storeys.NAME.%s)" % key
                                  if key in ("obstacles", "zones") else "not available for buildings (storeys) yet")
        names = self.storey_names
        for name in names:
            try:
                self.storey_spec(name)
            except ValidationError as err:
                e = err.errors()[0]
                loc = ".".join(str(p) for p in e["loc"] if not str(p).startswith("function-"))
                path = (e.get("ctx") or {}).get("path") or loc
                raise scene_error(f"storeys.{name}.{path}" if path else f"storeys.{name}",
                                  (e.get("ctx") or {}).get("message") or e["msg"]) from None
        for lo, hi in zip(names, names[1:]):
            a, b = self.storeys[lo], self.storeys[hi]
            if b.elevation <= a.elevation:
                raise scene_error(f"storeys.{hi}.elevation", f"{b.elevation} m is the floor of '{lo}' too; "
                                                             f"expected every storey at its own elevation")
        return self

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
                                      f"{did_you_mean(name, obstacle_names)}; expected one of "
                                      f"{name_list(obstacle_names)}")
            for k, h in enumerate(t.heights or []):
                if not 0 < h < H:
                    raise scene_error(f"targets[{i}].heights[{k}]",
                                      f"{h} m is outside the room; expected a height in (0, {H}) m")
                if h in (t.heights or [])[:k]:
                    raise scene_error(f"targets[{i}].heights[{k}]", f"duplicate height {h} m")
        if self.targets and all(t.coverage == 0 for t in self.targets) and not any(
                z.coverage > 0 and not z.privacy for z in self.zones):
            raise scene_error("targets", "every region has coverage 0, so there is nothing to place cameras for; "
                                         "expected at least one region with coverage >= 1")
        camera_names = [c.name for c in self.cameras]
        for i, m in enumerate(self.mounts):
            for k, name in enumerate(m.camera_names):
                if name not in camera_names:
                    key = f"mounts[{i}].camera" + ("" if isinstance(m.camera, str) else f"[{k}]")
                    raise scene_error(key, f"unknown camera '{name}'{did_you_mean(name, camera_names)}; "
                                           f"expected one of {name_list(camera_names)}")
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
        site_references(self, obstacle_names, camera_names)
        crowd_references(self)
        return self
