"""Score a given placement on a scene: ``camplace evaluate SCENE PLACEMENT.json|.csv``.

The placement may come from camplace (placement.json / placement.csv of a run), be
written by hand, or come from another tool. Its poses need not be grid candidates:
they are turned into candidates and raycast afresh with camplace.visibility.voxel on the
scene's targets, then scored with camplace.metrics.coverage (the same figures as a run).
The result is a RunResult whose placement has solver ``file`` and selects every pose
(candidate_id = row of V = the pose's index in the file).

Accepted files:

- ``.csv`` with header ``id,x,y,z,yaw,pitch,roll[,lens]`` (metres, degrees as in
  camplace.cameras.candidates: yaw about +z from +x, pitch = downward tilt, roll about the
  optical axis); ``lens`` names a scene camera (may be omitted when the scene has
  one camera type).
- ``.json``: placement.json (``{"cameras": [...]}``) or a bare list of camera objects,
  each with ``position`` [x, y, z] and either ``rotation`` (3x3 world-from-camera,
  OpenCV camera axes) or ``yaw_deg``/``pitch_deg``/``roll_deg`` (or ``yaw``/``pitch``/
  ``roll``), and ``camera`` (or ``lens``). When both rotation and angles are given they
  must agree (1e-6), so a hand edit of one without the other is caught. A camera whose
  lens the scene does not define is evaluated with its own ``intrinsics`` (model, width,
  height, fx, fy, cx, cy, optional distortion) and ``max_range`` (default: the scene
  cameras' common range).
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from camplace.cameras.placement_files import (CSV_COLUMNS, Poses, camera_from_intrinsics,  # noqa: F401 - re-exported
                                              candidates_from_poses, read_placement, read_placement_csv,
                                              read_placement_json)
from camplace.cameras.candidates import ypr_from_rotation
from camplace.spec.schema import SceneSpec


def poses_in_frame(poses: Poses, T: np.ndarray) -> Poses:
    """``poses`` moved by the 4x4 T (camplace.scene.frames.map_poses), angles recomputed
    from the moved rotations."""
    from dataclasses import replace

    from camplace.scene.frames import map_poses

    pos, rot = map_poses(T, poses.positions, poses.rotations)
    return replace(poses, positions=pos, rotations=rot, angles_deg=ypr_from_rotation(rot))


def evaluate(scene: str | Path | SceneSpec, placement: str | Path | Poses, progress=None, *,
             max_memory_bytes: int | None = None, workers: int = 1, scheduler: str | None = None,
             frame: str = "scene", crowd: dict | None = None):
    """Score a placement file (or Poses) on a scene -> camplace.workflows.run.RunResult.

    Every pose is raycast afresh (no cache) and selected; the Placement has solver
    'file', status 'feasible', budget = number of poses, bound None. ``frame``: the
    poses' frame, 'scene' (default) or 'input' (the scene's input file: they are mapped
    into the scene frame by the inverse of Scene.input_from_scene, camplace.scene.frames).
    With a crowd (the scene's ``crowd:``, ``crowd`` overrides its keys) metrics.json gets
    ``crowd``: the placement in held-out crowds (camplace.workflows.crowd)."""
    from camplace.outputs.write import check_frame
    from camplace.scene.frames import invert
    from camplace.core.executors import make_executor
    from camplace.workflows.run import RunResult, placement_metrics, problem_from_visibility, scene_inputs
    from camplace.solvers.base import Placement
    from camplace.visibility.engine import compute_visibility
    from camplace.visibility.privacy import privacy_report
    from camplace.visibility.voxel import VoxelEngine
    from camplace.spec.crowd import crowd_with
    from camplace.workflows.crowd import crowd_scores
    from camplace.workflows.sites import privacy_guard

    timings: dict[str, float] = {}
    check_frame(frame)
    poses = placement if isinstance(placement, Poses) else read_placement(placement)
    sc, targets, cameras, _ = scene_inputs(scene, progress, timings, max_memory_bytes)
    crowd_spec = crowd_with(sc.spec.crowd, crowd)
    if frame == "input":
        poses = poses_in_frame(poses, invert(sc.input_from_scene))
    t = time.perf_counter()
    if progress:
        progress("candidates", 0, 1)
    cands = candidates_from_poses(poses, cameras)
    timings["candidates"] = time.perf_counter() - t
    t = time.perf_counter()
    with make_executor(workers, scheduler) as executor:
        vis = compute_visibility(VoxelEngine(), sc.occupancy, targets, cands, executor=executor, progress=progress)
    timings["visibility"] = time.perf_counter() - t
    problem = problem_from_visibility(vis, len(cands))
    selected = np.arange(len(cands), dtype=np.int64)
    timings["solve"] = 0.0
    t = time.perf_counter()
    cost = problem.cost(selected)
    metrics = placement_metrics(vis, problem, selected, scene=sc)
    timings["metrics"] = time.perf_counter() - t
    seen = np.diff(vis.V.indptr)
    inside = sc.occupancy.is_occupied(cands.positions)
    log = [f"placement: {len(cands)} cameras from {poses.source}",
           f"targets: {len(targets)} ({', '.join(f'{n}: {int((targets.region_ids == r).sum())}' for r, n in enumerate(targets.region_names))})",
           f"visibility: V {vis.V.shape[0]} x {vis.V.shape[1]}, nnz {vis.V.nnz}"]
    for k in np.nonzero(inside)[0]:
        log.append(f"warning: camera {poses.ids[k]} at {np.round(cands.positions[k], 3).tolist()} lies inside an "
                   f"obstacle or outside the room")
    for k in np.nonzero((seen == 0) & ~inside)[0]:
        log.append(f"warning: camera {poses.ids[k]} sees no target")
    guard = privacy_guard(sc, cands.cameras, VoxelEngine())
    if guard is not None:  # issue 17: which cameras see a privacy zone (reported; --strict fails on them)
        metrics = replace(metrics, privacy=privacy_report(guard, cands, selected, list(poses.ids)))
        if metrics.privacy["violations"]:
            log.append(f"warning: privacy: {metrics.privacy['violations']} camera(s) see a privacy zone: "
                       f"{', '.join(metrics.privacy['camera_ids'])}")
    pl = Placement(selected, cost, None, "feasible", "file", 0.0,
                   {"source": poses.source, "source_ids": list(poses.ids)})
    if crowd_spec is not None:  # issue 28: the placement in held-out crowds
        metrics = replace(metrics, crowd=crowd_scores(sc, vis, pl, crowd_spec, log=log))
    return RunResult(sc, vis, problem, pl, metrics, timings, log)
