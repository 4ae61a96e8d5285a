"""Reading scene files: YAML (a key given twice is refused), validation into a SceneSpec,
and the files a scene names (meshes, point clouds, ...) checked to exist."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ValidationError

from camplace.core.errors import InputError
from camplace.spec.schema import SceneSpec
from camplace.spec.wording import format_validation_error

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
