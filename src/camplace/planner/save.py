"""Save: the session's cameras scored and written exactly as ``camplace evaluate`` of the
saved placement writes them (camplace.workflows.evaluate + camplace.outputs.write.write_outputs),
into a folder that must stay inside the start folder."""

from __future__ import annotations

import os
import time
from pathlib import Path, PurePosixPath, PureWindowsPath

import numpy as np

from camplace.cameras.placement_files import Poses
from camplace.planner.errors import ApiError


def safe_dir(root: Path, name: str | None, default: Path) -> Path:
    """The save folder: ``default`` when ``name`` is None, else ``root/name``; refused
    (ApiError 'dir') when ``name`` is absolute, holds a '..' part, or resolves (symlinks
    followed) outside ``root``."""
    root = Path(root).resolve()
    if name is None:
        target = Path(default)
    else:
        if "\x00" in name or PurePosixPath(name).is_absolute() or PureWindowsPath(name).is_absolute() \
                or PureWindowsPath(name).drive or name.startswith("~"):
            raise ApiError(f"dir: expected a folder relative to {root.name}/, got an absolute path {name!r}", "dir")
        parts = PurePosixPath(name.replace("\\", "/")).parts
        if ".." in parts:
            raise ApiError(f"dir: '..' is not allowed (the folder must stay inside {root.name}/), got {name!r}", "dir")
        target = root / Path(*parts)
    resolved = Path(os.path.realpath(target))
    if resolved != root and root not in resolved.parents:
        raise ApiError(f"dir: {name or str(default)!r} resolves outside the start folder {root}", "dir")
    if resolved.exists() and not resolved.is_dir():
        raise ApiError(f"dir: {name!r} exists and is not a folder", "dir")
    return resolved


def session_poses(session) -> Poses:
    """The session's cameras as Poses (ids = the session's camera ids)."""
    vis, _ = session.visibility()
    c = vis.candidates
    models = [session.lenses[k] for k in c.camera_ids]
    return Poses(tuple(cam.id for cam in session.cams), c.positions.copy(), c.rotations.copy(), c.angles_deg.copy(),
                 tuple(m.name for m in models), "planner",
                 focal_mm=tuple(None if m.lens is None else m.focal_mm for m in models))  # a lens as sold (issue 27)


def save_session(session, name: str | None, *, repeatable: bool = False) -> dict:
    """POST /api/save: evaluate the cameras (camplace.workflows.evaluate) and write every
    output (contract files, report.html, hand-over set) -> {"path", "metrics", "files"}."""
    from camplace.outputs.write import write_outputs
    from camplace.workflows.evaluate import evaluate

    with session.lock:
        out = safe_dir(session.opened.root, name, session.opened.save_dir)
        if not session.cams:
            raise ApiError("cameras: there is no camera to save; add one first", "cameras", 409)
        poses = session_poses(session)
    result = evaluate(session.opened.scene_ref, poses)
    t0 = time.perf_counter()
    paths = write_outputs(out, result.scene.name, result.visibility, result.placement, result.problem.budget,
                          result.metrics, result.timings_s, scene=result.scene, repeatable=repeatable,
                          problem=result.problem)
    result.timings_s["report"] = time.perf_counter() - t0
    metrics = result.metrics.to_dict()
    metrics["timings_s"] = {k: round(float(v), 4) for k, v in result.timings_s.items()}
    return {"path": str(out), "metrics": metrics, "files": sorted(paths),
            "cost_matches": bool(np.isclose(metrics["cost"], session.metrics.cost, rtol=1e-9, atol=1e-9))}
