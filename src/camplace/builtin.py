"""Built-in scenes, usable by name with no file (``camplace run standard-store``).

They ship as YAML files in ``camplace/scenes/`` so they double as scene-file examples
(``camplace scenes --show NAME`` prints one).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import yaml

from camplace.config import SceneSpec, load_scene_file, parse_scene
from camplace.errors import InputError

BUILTIN_SCENES = ("demo", "standard-store", "store-a")


def builtin_yaml(name: str) -> str:
    """The YAML text of a built-in scene."""
    if name not in BUILTIN_SCENES:
        raise InputError(f"unknown built-in scene '{name}'; expected one of {', '.join(BUILTIN_SCENES)} or a .yaml file")
    return resources.files("camplace").joinpath("scenes", f"{name}.yaml").read_text()


def resolve_scene(scene: str | Path | SceneSpec) -> tuple[SceneSpec, Path | None, str]:
    """A scene given as a built-in name, a YAML path or a spec -> (spec, base_dir, source)."""
    if isinstance(scene, SceneSpec):
        return scene, None, f"<scene {scene.name}>"
    text = str(scene)
    if text in BUILTIN_SCENES:
        return parse_scene(yaml.safe_load(builtin_yaml(text)), f"<built-in {text}>"), None, f"<built-in {text}>"
    p = Path(text)
    if p.suffix.lower() in (".yaml", ".yml") or p.exists():
        return load_scene_file(p), p.resolve().parent, str(p)
    raise InputError(f"scene '{text}': not a built-in scene ({', '.join(BUILTIN_SCENES)}) nor an existing .yaml file")
