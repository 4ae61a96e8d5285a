"""What ``camplace serve`` opens: a run folder (placement.json + the scene it names) or a
scene (run first by camplace.workflows.run, on the grid), as the planner's start point.

Either way the result is the scene (built), the grid visibility (every admitted grid
candidate, blind ones dropped; the existing cameras not folded in) and the start
cameras as placement.json camera objects (existing ones marked ``existing`` with their
``id``), in the scene frame.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from camplace.core.errors import InputError
from camplace.scene.build import Scene
from camplace.visibility.engine import Visibility


@dataclass
class Opened:
    """The planner's start: ``scene_ref`` (what camplace.workflows.evaluate is given: a
    built-in name or a YAML path), the built ``scene``, the grid ``vis``, the start
    ``cameras`` (placement.json objects, scene frame), the ``budget`` (total cameras,
    existing included), ``root`` (the folder no path may leave), ``save_dir`` (default
    save folder, inside root) and ``source`` (for messages)."""

    scene_ref: str | Path
    scene: Scene
    vis: Visibility
    cameras: list[dict]
    budget: int
    root: Path
    save_dir: Path
    source: str


def scene_of_run(run_dir: Path, placement: dict, scene: str | Path | None) -> str | Path:
    """The scene a run folder was made from: ``scene`` when given, else the placement's
    ``builtin_scene`` (a built-in as the run named it, parameters included:
    'warehouse:1000'), else its ``scene`` name if it is a built-in, else a *.yaml / *.yml
    beside the folder (in it or its parent) whose ``name`` is that name."""
    from camplace.spec.builtin import resolve_scene

    if scene is not None:
        return scene
    if isinstance(placement.get("builtin_scene"), str):
        return placement["builtin_scene"]
    name = str(placement.get("scene", ""))
    try:
        spec, base, _ = resolve_scene(name)
        if base is None:
            return name
    except InputError:
        pass
    for folder in (run_dir, run_dir.parent):
        for p in sorted(list(folder.glob("*.yaml")) + list(folder.glob("*.yml"))):
            try:
                spec, _, _ = resolve_scene(p)
            except InputError:
                continue
            if spec.name == name:
                return p
    raise InputError(f"{run_dir / 'placement.json'}: scene '{name}' is not a built-in scene and no scene YAML "
                     f"named '{name}' lies in {run_dir} or its parent; give the scene file", option="scene")


def run_cameras(run_dir: Path, sc: Scene) -> tuple[list[dict], int]:
    """The cameras of a run folder's placement.json (scene frame) and its total budget."""
    from camplace.outputs.write import cameras_in_frame
    from camplace.scene.frames import invert

    path = run_dir / "placement.json"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise InputError(f"{path}: cannot read the placement ({err})") from None
    cams = data.get("cameras") if isinstance(data, dict) else None
    if not isinstance(cams, list):
        raise InputError(f"{path}: cameras: expected a list of camera objects (placement.json format)")
    from camplace.cameras.placement_files import read_placement_json

    poses = read_placement_json(path) if cams else None  # checks every camera object (one-line errors)
    out = []
    for k, c in enumerate(cams):
        obj = dict(c, position=[float(v) for v in poses.positions[k]], yaw_deg=float(poses.angles_deg[k, 0]),
                   pitch_deg=float(poses.angles_deg[k, 1]), roll_deg=float(poses.angles_deg[k, 2]),
                   rotation=poses.rotations[k].tolist())
        out.append(obj)
    if data.get("frame") == "input" and out:
        out = cameras_in_frame(out, invert(sc.input_from_scene))
    n_existing = sum(bool(c.get("existing")) for c in out)
    budget = int(data.get("budget", len(out) - n_existing)) + n_existing
    return out, max(budget, len(out))


def open_start(target, scene: str | Path | None = None, root: str | Path | None = None,
               progress=None, cache_dir: str | Path | None = None) -> Opened:
    """Open a run folder (with placement.json) or a scene (built-in name, YAML path or
    SceneSpec; run first, grid placement).
    ``root``: the folder no path may leave (default: the run folder, or the current folder
    for a scene); ``cache_dir``: the visibility block cache (camplace.visibility.cache), so
    a run folder made with the same cache opens without raycasting V again."""
    from camplace.workflows.run import prepare_site, run

    from camplace.spec.schema import SceneSpec

    p = None if isinstance(target, SceneSpec) else Path(target)
    if p is not None and p.is_dir():
        if not (p / "placement.json").is_file():
            raise InputError(f"{p}: not a run folder (no placement.json); give a run folder or a scene",
                             option="target")
        run_dir = p.resolve()
        with (run_dir / "placement.json").open(encoding="utf-8") as fh:
            try:
                placement = json.load(fh)
            except json.JSONDecodeError as err:
                raise InputError(f"{run_dir / 'placement.json'}: not valid JSON: {err}") from None
        ref = scene_of_run(run_dir, placement if isinstance(placement, dict) else {}, scene)
        sc, vis, _ = prepare_site(ref, progress, cache_dir=cache_dir)
        cameras, budget = run_cameras(run_dir, sc)
        base = Path(root).resolve() if root is not None else run_dir
        return Opened(ref, sc, vis, cameras, budget, base, run_dir, str(run_dir))
    from camplace.outputs.write import placement_dict

    result = run(target, progress=progress, cache_dir=cache_dir)
    vis = result.visibility
    n = vis.V.shape[0] - int(vis.info.get("existing", 0))
    grid = Visibility(vis.V[:n], vis.candidates.subset(np.arange(n)), vis.targets, vis.mode, dict(vis.info), vis.engine)
    pdict = placement_dict(result.scene.name, result.placement, int(result.problem.budget), vis.candidates)
    base = Path(root or ".").resolve()
    return Opened(target, result.scene, grid, pdict["cameras"], int(result.problem.budget), base,
                  base / "camplace-out" / f"{result.scene.name}-planned", result.scene.name)
