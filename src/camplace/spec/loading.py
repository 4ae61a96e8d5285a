"""Reading scene files: YAML (a key given twice is refused), validation into a SceneSpec,
and the files a scene names (meshes, point clouds, ...) checked to exist."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from camplace.core.errors import InputError
from camplace.spec.catalogue import expand_catalogue
from camplace.spec.schema import SceneSpec
from camplace.spec.wording import format_validation_error
from camplace.spec.yamltext import load_yaml_text  # noqa: F401 - re-exported (scene files read it from here)

FILE_KEYS = ("mesh", "point_cloud", "octomap", "calibration", "file", "path", "points",  # scene keys that name a file
             "existing")


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


def parse_scene(data: Any, source: str = "<scene>", base_dir: Path | None = None) -> SceneSpec:
    """Validate a scene mapping; raise InputError with a one-line message. ``cameras:
    {catalogue: FILE}`` is read first (camplace.spec.catalogue; FILE relative to ``base_dir``,
    default the working directory)."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: expected a YAML mapping of scene keys, got {type(data).__name__}")
    data = expand_catalogue(data, base_dir, source)
    try:
        return SceneSpec.model_validate(data)
    except ValidationError as err:
        raise InputError(format_validation_error(err, source, SceneSpec)) from None


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
    spec = parse_scene(data, str(p), p.resolve().parent)
    check_referenced_files(spec, p.resolve().parent, str(p))
    return spec
