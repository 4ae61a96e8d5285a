"""Built-in scenes, usable by name with no file (``camplace run standard-store``).

They ship as YAML files in ``camplace/scenes/`` so they double as scene-file examples
(``camplace scenes --show NAME`` prints one).
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import yaml

from camplace.core.errors import InputError
from camplace.spec.loading import load_scene_file, parse_scene
from camplace.spec.schema import SceneSpec
from camplace.spec.wording import did_you_mean

BUILTIN_SCENES = ("demo", "standard-store", "store-a", "warehouse", "catalogue-store", "retail-site", "lens-store")
PROCEDURAL_SCENES = ("warehouse",)  # generated in code; ``warehouse:AREA`` picks the size

# --- procedural warehouse (issue 7: site scale) -------------------------------------
WAREHOUSE_DEFAULT_AREA = 10_000.0  # m2 of floor for plain ``warehouse``
WAREHOUSE_MIN_AREA = 200.0
WAREHOUSE = {
    "aspect": 1.25,  # length (x) / width (y)
    "ceiling": 7.0,  # m
    "rack_depth": 1.2,  # m (y)
    "aisle": 3.0,  # m between rack rows
    "rack_heights": (4.0, 3.0, 3.5, 2.5),  # m, cycled over rows and segments
    "segment": 24.0,  # m of rack between cross aisles
    "cross_aisle": 3.0,  # m
    "dock": 5.0,  # m of open staging floor at x = 0
    "margin": 3.0,  # m of perimeter aisle on the other three walls
    "voxel_size": 0.5,  # m target grid (a store uses 0.25)
    "occupancy_resolution": 0.1,  # m occlusion grid (a store uses 0.05)
    "heights": (0.5, 1.0, 1.5),  # m, walkable target layers
    "max_range": 10.0,  # m: ~1.4 x ceiling so a 30-degree camera reaches the floor
    "m2_per_camera": 25.0,  # default budget = area / this
}


def warehouse_spec(area_m2: float = WAREHOUSE_DEFAULT_AREA) -> SceneSpec:
    """A procedural warehouse of ``area_m2`` m2 floor (a 1.25:1 rectangle, 7 m ceiling).

    Racking rows run along x (1.2 m deep, 2.5-4 m high, 3 m aisles), broken every ~24 m
    by 3 m cross aisles, with a 5 m open dock zone at x = 0 and 3 m perimeter aisles.
    Targets: walkable aisle volume at 0.5 / 1.0 / 1.5 m with coverage 3 and the aisle
    faces of the racks with coverage 1 (0.5 m voxels). Mounts: 1 m ceiling grid 0.1 m
    below the ceiling, 12 yaws x 3 pitches, the stores' 1780x720 71x36 deg pinhole but
    with a 10 m range (from 6.9 m up, a 5 m range would not reach the floor)."""
    w = WAREHOUSE
    a = float(area_m2)
    if not a >= WAREHOUSE_MIN_AREA or not math.isfinite(a):
        raise InputError(f"scene 'warehouse:{area_m2}': expected a floor area in m2 >= {WAREHOUSE_MIN_AREA:g}")
    length = round(math.sqrt(a * w["aspect"]), 2)
    width = round(a / length, 3)
    x0, x1 = w["dock"], length - w["margin"]
    usable = x1 - x0
    n_seg = max(1, int(round((usable + w["cross_aisle"]) / (w["segment"] + w["cross_aisle"]))))
    seg_len = (usable - w["cross_aisle"] * (n_seg - 1)) / n_seg
    obstacles, names = [], []
    row = 0
    y = w["margin"]
    while y + w["rack_depth"] <= width - w["margin"] + 1e-9:
        for s in range(n_seg):
            xa = x0 + s * (seg_len + w["cross_aisle"])
            h = w["rack_heights"][(row + s) % len(w["rack_heights"])]
            name = f"rack-{row + 1:02d}-{s + 1}"
            names.append(name)
            obstacles.append({"name": name, "box": {"min": [round(xa, 3), round(y, 3), 0.0],
                                                    "max": [round(xa + seg_len, 3), round(y + w["rack_depth"], 3), h]}})
        row += 1
        y += w["rack_depth"] + w["aisle"]
    targets = [{"name": "walkable", "kind": "volume", "heights": list(w["heights"]), "coverage": 3}]
    if names:
        targets.append({"name": "rack-faces", "kind": "surface", "of": names, "faces": ["+y", "-y"],
                        "coverage": 1, "max_incidence_deg": 60})
    data = {
        "name": f"warehouse-{a:g}",
        "voxel_size": w["voxel_size"],
        "occupancy_resolution": w["occupancy_resolution"],
        "room": {"footprint": [[0, 0], [length, 0], [length, width], [0, width]], "height": w["ceiling"]},
        "obstacles": obstacles,
        "targets": targets,
        "cameras": [{"name": "wide", "model": "pinhole", "resolution": [1780, 720], "fov_deg": [71, 36],
                     "max_range": w["max_range"]}],
        "mounts": [{"kind": "ceiling_grid", "spacing": 1.0, "offset_below_ceiling": 0.1,
                    "yaw_deg": {"start": 0, "stop": 330, "step": 30}, "pitch_deg": [30, 45, 60], "roll_deg": [0],
                    "camera": "wide"}],
        "placement": {"budget": max(1, int(round(a / w["m2_per_camera"]))), "solver": "greedy-fast"},
    }
    return parse_scene(data, f"<built-in warehouse:{a:g}>")


def parse_procedural(name: str) -> SceneSpec | None:
    """``warehouse`` or ``warehouse:AREA`` -> its spec; None for any other name."""
    base, sep, arg = name.partition(":")
    if base != "warehouse":
        return None
    if not sep:
        return warehouse_spec()
    try:
        area = float(arg)
    except ValueError:
        raise InputError(f"scene '{name}': expected warehouse:AREA with AREA the floor area in m2 (e.g. warehouse:10000)") from None
    return warehouse_spec(area)


def builtin_yaml(name: str) -> str:
    """The YAML text of a built-in scene."""
    spec = parse_procedural(name)
    if spec is not None:
        head = f"# camplace built-in scene \"{name}\": generated by camplace.spec.builtin.warehouse_spec\n"
        return head + yaml.safe_dump(spec.model_dump(mode="json", exclude_none=True), sort_keys=False, default_flow_style=None, width=110)
    if name not in BUILTIN_SCENES:
        raise InputError(f"unknown built-in scene '{name}'; expected one of {', '.join(BUILTIN_SCENES)} or a .yaml file")
    return resources.files("camplace.spec").joinpath("scenes", f"{name}.yaml").read_text()


def resolve_scene(scene: str | Path | SceneSpec) -> tuple[SceneSpec, Path | None, str]:
    """A scene given as a built-in name, a YAML path or a spec -> (spec, base_dir, source)."""
    if isinstance(scene, SceneSpec):
        return scene, None, f"<scene {scene.name}>"
    text = str(scene)
    spec = parse_procedural(text)
    if spec is not None:
        return spec, None, f"<built-in {text}>"
    if text in BUILTIN_SCENES:
        with resources.as_file(resources.files("camplace.spec").joinpath("scenes")) as folder:  # catalogues beside it
            spec = parse_scene(yaml.safe_load(builtin_yaml(text)), f"<built-in {text}>", folder)
        return spec, None, f"<built-in {text}>"
    p = Path(text)
    if p.suffix.lower() in (".yaml", ".yml") or p.exists():
        return load_scene_file(p), p.resolve().parent, str(p)
    raise InputError(f"scene '{text}': not a built-in scene{did_you_mean(text, list(BUILTIN_SCENES))} "
                     f"({', '.join(BUILTIN_SCENES)}) nor an existing .yaml file")
