"""The building blocks of the scene schema (camplace.spec.schema, camplace.spec.sites):
number and point types that refuse YAML booleans and NaN, the strict base model, boxes,
polygons and the error that names its own key path."""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, model_validator
from pydantic_core import PydanticCustomError


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
Face = Literal["+x", "-x", "+y", "-y", "+z", "-z"]
# image quality: px/m on the target, or a DORI level (detect, observe, recognise, identify)
PxPerM = Union[Annotated[float, BeforeValidator(_no_bool), Field(ge=0, allow_inf_nan=False)],
               Literal["detect", "observe", "recognise", "recognize", "identify"], None]
Incidence = Annotated[float, Field(gt=0, le=90, allow_inf_nan=False)]


def polygon_problem(points: list) -> str | None:
    """Why ``points`` (floor-plan corners, m) is not a simple polygon of non-zero area, or None."""
    import shapely
    from shapely.geometry import Polygon

    poly = Polygon(points)
    if not poly.is_valid:
        return f"expected a simple polygon (edges must not cross or touch), got {shapely.is_valid_reason(poly)}"
    if poly.area <= 1e-9:
        return "the polygon has zero area (all corners on one line?)"
    return None


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


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
