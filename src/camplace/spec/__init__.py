"""camplace.spec (layer 1): the scene file, the user's contract.

schema (the pydantic models), wording (one-line errors, "did you mean"), loading (YAML
and scene files), resources (sizes estimated from the spec, checked against the memory
limit), builtin (the built-in scenes), quality (pixel density levels). The public names
are re-exported here; modules inside spec/ import the submodules, never this package.
"""

from camplace.spec.builtin import BUILTIN_SCENES, builtin_yaml, resolve_scene
from camplace.spec.loading import check_referenced_files, load_scene_file, load_yaml_text, parse_scene
from camplace.spec.resources import ResourceEstimate, check_resources, estimate_resources
from camplace.spec.schema import Camera, Mount, Obstacle, SceneSpec, TargetRegion, angle_values
from camplace.spec.wording import did_you_mean, format_validation_error

__all__ = ["BUILTIN_SCENES", "Camera", "Mount", "Obstacle", "ResourceEstimate", "SceneSpec", "TargetRegion",
           "angle_values", "builtin_yaml", "check_referenced_files", "check_resources", "did_you_mean",
           "estimate_resources", "format_validation_error", "load_scene_file", "load_yaml_text", "parse_scene",
           "resolve_scene"]
