"""``camplace render`` as one call: rebuild a scene's camera (a candidate, or a camera of
a placement file), raycast what it covers and draw its view (camplace.outputs.render)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from camplace.cameras.candidates import build_candidates
from camplace.core.errors import InputError
from camplace.core.files import atomic_write_bytes
from camplace.outputs.render import RenderedView, render_view, view_figure_png
from camplace.visibility.engine import compute_visibility
from camplace.visibility.voxel import VoxelEngine
from camplace.workflows.evaluate import candidates_from_poses, read_placement
from camplace.workflows.run import scene_inputs


def render_camera(scene, camera_id: int, placement: str | Path | None = None, out: str | Path | None = None,
                  width: int = 480, progress=None) -> tuple[Path | None, RenderedView, dict]:
    """The view of one camera as PNG (written atomically to ``out`` when given).

    Without ``placement``, camera_id is a candidate id (row of V over every candidate
    of the scene); with a placement file (placement.json / .csv, see camplace.workflows.evaluate)
    it is the index of the camera in that file. The covered targets are raycast
    afresh (voxel engine). Returns (png path or None, the view, info)."""
    sc, targets, cameras, _ = scene_inputs(scene, progress)
    if placement is not None:
        cands = candidates_from_poses(read_placement(placement), cameras)
        what = f"camera index in {placement}"
    else:
        cands = build_candidates(sc, cameras)
        what = "candidate id"
    if not 0 <= int(camera_id) < len(cands):
        raise InputError(f"camera_id: {what} {camera_id} is out of range (0..{len(cands) - 1})", option="camera_id")
    one = cands.subset(np.array([int(camera_id)]))
    cam = one.cameras[int(one.camera_ids[0])]
    vis = compute_visibility(VoxelEngine(), sc.occupancy, targets, one)
    covered = vis.V.indices[vis.V.indptr[0]:vis.V.indptr[1]]
    pos, rot = one.positions[0], one.rotations[0]
    view = render_view(sc, cam, pos, rot, width)
    yaw, pitch, roll = (float(a) for a in one.angles_deg[0])
    title = (f"{sc.name}: {what} {camera_id} ({cam.name}, {cam.model}) at ({pos[0]:.2f}, {pos[1]:.2f}, {pos[2]:.2f}) m, "
             f"yaw {yaw:.0f}, pitch {pitch:.0f}, roll {roll:.0f} deg; covers {len(covered)} targets")
    info = {"covered": int(len(covered)), "camera": cam.name, "position": [float(v) for v in pos],
            "yaw_deg": yaw, "pitch_deg": pitch, "roll_deg": roll}
    path = None
    if out is not None:
        png = view_figure_png(sc, view, cam, pos, rot, targets, covered, title)
        path = atomic_write_bytes(Path(out), png)
    return path, view, info
