"""Stage 8 - outputs: placement.json, metrics.json, visibility.npz, placement.csv.

Keys follow the output contract (docs/output-contract.md). Every file is written
atomically (temporary file + rename).
"""

from __future__ import annotations

import csv
import io
import time
from pathlib import Path
from typing import Callable

import numpy as np

from camplace.cameras.candidates import Candidates, ypr_from_rotation
from camplace.core.errors import InputError, Interrupted
from camplace.core.files import AtomicBatch, atomic_write_json
from camplace.metrics.coverage import Metrics
from camplace.outputs.storeys import mark_storeys
from camplace.outputs.bom import recording_load, selected_models
from camplace.outputs.writers import OutputResult, write_registered
from camplace.scene.frames import map_poses
from camplace.solvers.base import Placement
from camplace.visibility.voxel import Visibility


def _round(x: float, nd: int = 9) -> float:
    return float(round(float(x), nd))


def camera_entries(candidates: Candidates, selected: np.ndarray) -> list[dict]:
    """One placement.json camera object per selected candidate (in id order)."""
    out = []
    for i in np.sort(np.asarray(selected, np.int64)):
        cam = candidates.cameras[int(candidates.camera_ids[i])]
        yaw, pitch, roll = (float(a) for a in candidates.angles_deg[i])
        out.append({
            "candidate_id": int(i),
            "location_id": int(candidates.location_ids[i]),
            "position": [float(v) for v in candidates.positions[i]],  # exact: evaluate re-raycasts it
            "yaw_deg": _round(yaw), "pitch_deg": _round(pitch), "roll_deg": _round(roll),
            "rotation": [[float(v) for v in row] for row in candidates.rotations[i]],
            "camera": cam.name,
            "intrinsics": cam.intrinsics(),
            **({} if cam.lens is None else {"focal_mm": _round(cam.focal_mm)}),  # a lens as sold (issue 27)
        })
    return out


FRAMES = ("scene", "input")


def check_frame(frame: str) -> None:
    """InputError(option='frame') unless ``frame`` is 'scene' or 'input'."""
    if frame not in FRAMES:
        raise InputError(f"frame: expected 'scene' or 'input', got {frame!r}", option="frame")


def cameras_in_frame(cameras: list[dict], T: np.ndarray) -> list[dict]:
    """placement.json camera objects moved by the 4x4 ``T`` (camplace.scene.frames: e.g.
    input_from_scene): position, rotation and yaw/pitch/roll recomputed from the moved
    rotation (camplace.cameras.candidates.ypr_from_rotation, the same formulas in the new
    frame). New dicts; the rest of each object is kept."""
    if not cameras:
        return []
    pos, rot = map_poses(T, [c["position"] for c in cameras], [c["rotation"] for c in cameras])
    ang = ypr_from_rotation(rot)
    return [dict(c, position=[float(v) for v in p], rotation=[[float(v) for v in row] for row in R],
                 yaw_deg=_round(a[0]), pitch_deg=_round(a[1]), roll_deg=_round(a[2]))
            for c, p, R, a in zip(cameras, pos, rot, ang)]


def placement_dict(scene_name: str, placement: Placement, budget: int, candidates: Candidates,
                   input_from_scene: np.ndarray | None = None, frame: str = "scene",
                   retention_days: float | None = None) -> dict:
    """placement.json (docs/output-contract.md). ``input_from_scene`` (4x4, default
    identity) is written as is; with ``frame='input'`` the cameras' poses are mapped by it.
    ``recording`` (issue 27) is added when a camera type gives a bitrate or ``retention_days``
    (the scene's recording.retention_days) is given (camplace.outputs.bom.recording_load)."""
    check_frame(frame)
    T = np.eye(4) if input_from_scene is None else np.asarray(input_from_scene, np.float64)
    cameras = camera_entries(candidates, placement.selected)
    out = {
        "scene": scene_name,
        "solver": placement.solver,
        "budget": int(budget),
        "status": placement.status,
        "objective": float(placement.objective),
        "bound": None if placement.bound is None else float(placement.bound),
        "gap": placement.gap,
        **{k: str(placement.info[k]) for k in ("incumbent_method", "bound_method") if k in placement.info},
        # issue 10; their wall-clock seconds go to metrics.json timings_s only (run_timings)
        **{k: _timeless(placement.info[k]) for k in ("refine", "adaptive", "robust", "quality") if k in placement.info},
        "n_cameras": int(len(placement.selected)),
        "frame": frame,
        "input_from_scene": [[float(v) for v in row] for row in T],
        "cameras": cameras_in_frame(cameras, T) if frame == "input" else cameras,
    }
    info = solver_info(placement.info)
    if info:
        out["solver_info"] = info
    src = placement.info.get("source_ids")
    if src is not None:  # an evaluated placement (camplace.workflows.evaluate): the ids its file gave the cameras
        for c in out["cameras"]:
            c["source_id"] = str(src[c["candidate_id"]])
    mark_existing(out, placement.info)
    rec = recording_load(out["cameras"], [m.bitrate_mbps for m in selected_models(candidates, placement.selected)],
                         retention_days)
    if rec is not None:
        out["recording"] = rec
    return out


def mark_existing(pdict: dict, info: dict) -> None:
    """Existing cameras (issue 17; ``info['existing_ids']``: V row -> id as in the scene, from
    camplace.workflows.sites): every camera gets ``existing`` (bool), existing ones their
    ``id``; ``n_existing`` is added and ``budget`` is the new cameras' (``info['new_budget']``).
    Nothing changes without existing cameras."""
    existing_ids = info.get("existing_ids")
    if not existing_ids:
        return
    pdict["budget"] = int(info.get("new_budget", pdict["budget"] - len(existing_ids)))
    for c in pdict["cameras"]:
        c["existing"] = c["candidate_id"] in existing_ids
        if c["existing"]:
            c["id"] = str(existing_ids[c["candidate_id"]])
    pdict["n_existing"] = len(existing_ids)


def placement_csv(cameras: list[dict]) -> str:
    """The mount list: header id,x,y,z,yaw,pitch,roll,lens (metres, degrees), and a
    focal_mm column when some camera's lens is given as sold (issue 27; empty for the others)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    focal = any("focal_mm" in c for c in cameras)
    w.writerow(["id", "x", "y", "z", "yaw", "pitch", "roll", "lens"] + (["focal_mm"] if focal else []))
    for c in cameras:
        w.writerow([c.get("id", c["candidate_id"]), *c["position"], c["yaw_deg"], c["pitch_deg"], c["roll_deg"],
                    c["camera"]] + ([c.get("focal_mm", "")] if focal else []))
    return buf.getvalue()


SITE_NPZ_PAIRS = 20_000_000  # from this many visible pairs on, visibility.npz is written at zlib level 1
SITE_NPZ_LEVEL = 1  # 2.7x faster than numpy's level 6 on a warehouse's V, files ~1.5x larger (issue 37)


def npz_level(nnz: int) -> int | None:
    """The zlib level of visibility.npz for a V of ``nnz`` pairs: SITE_NPZ_LEVEL at site
    scale (≥ SITE_NPZ_PAIRS, e.g. warehouse:2500 and up), else None (numpy's own)."""
    return SITE_NPZ_LEVEL if nnz >= SITE_NPZ_PAIRS else None


def visibility_arrays(vis: Visibility) -> dict[str, np.ndarray]:
    """The arrays of visibility.npz (no pickles)."""
    V, t, c = vis.V, vis.targets, vis.candidates
    return {
        "data": V.data.astype(np.uint8, copy=False), "indices": V.indices.astype(np.int32, copy=False),
        "indptr": V.indptr.astype(np.int64, copy=False), "shape": np.array(V.shape, dtype=np.int64),
        "gamma": t.gamma.astype(np.int64), "weights": t.weights.astype(np.float64),
        "target_positions": t.positions.astype(np.float64), "target_normals": t.normals.astype(np.float64),
        "target_region_ids": t.region_ids.astype(np.int32), "region_names": np.array(t.region_names, dtype=str),
        "candidate_positions": c.positions.astype(np.float64), "rotations": c.rotations.astype(np.float64),
        "candidate_angles_deg": c.angles_deg.astype(np.float64), "camera_ids": c.camera_ids.astype(np.int32),
        "camera_names": np.array([cam.name for cam in c.cameras], dtype=str),
        "location_ids": c.location_ids.astype(np.int64),
    }


def write_outputs(out_dir: str | Path, scene_name: str, vis: Visibility, placement: Placement, budget: int,
                  metrics: Metrics, timings: dict[str, float], scene=None, report: bool = True,
                  repeatable: bool = False, frame: str = "scene", plan: bool = True,
                  paper: str = "A3", compressed: bool = True, on_contract: Callable[[], None] | None = None,
                  deadline: Callable[[], float | None] | None = None,
                  skipped: list[str] | None = None, problem=None) -> dict[str, Path]:
    """Write the contract files into out_dir and, with ``report``, the report set
    (report.html, PNG figures, opencv/ and colmap/ exports; camplace.outputs.report_html);
    ``scene`` (camplace.scene.build.Scene) adds the room and obstacles to the pictures;
    ``repeatable`` writes every timing as 0.0 (byte-identical metrics.json for
    identical runs). Returns name -> path. ``problem``: the PlacementProblem solved, handed
    to the output writers.

    The order (the structure every command shares): the contract files; then every
    registered output writer (``camplace.outputs`` entry points, camplace's own ``bom``
    first: camplace.outputs.writers.write_registered, given an OutputResult); then the
    report set, whose report.html links every file written before it.

    ``frame``: 'scene' (default) writes the poses of placement.json / .csv and the exports
    in the scene frame; 'input' in the input file's frame (``scene.input_from_scene``,
    camplace.scene.frames; identity without a scene). visibility.npz, metrics and the
    report's pictures stay in the scene frame.

    ``plan`` (with ``report`` and a ``scene``): the hand-over plan set too (plan.pdf on
    ``paper`` 'A4' | 'A3' | 'letter', plan.svg, plan.dxf, scene.glb; camplace.outputs.handover)
    and report.html's plan view.

    The contract files (visibility.npz, placement.json, placement.csv, metrics.json) land
    first, together (camplace.core.files.AtomicBatch: all new or all old); the report comes
    after them, so a report that fails or is interrupted cannot cost the new placement.
    Then a report.html left from an earlier run (it would show another placement) is
    removed, and a KeyboardInterrupt comes out as camplace.core.errors.Interrupted saying so;
    metrics.json is rewritten at the end with the report's time in ``timings_s.report``.

    After an interrupt (the caller's choice): ``compressed`` False writes visibility.npz
    uncompressed (ten times faster); ``on_contract()`` is called once the contract files
    are in place; ``deadline()`` (a perf_counter() time or None) ends the report set: a
    part (exports, figures, plan set, report.html) starts only before it, and with a
    ``deadline`` a KeyboardInterrupt during the report set only ends it. The parts not
    written are appended to ``skipped``."""
    t0 = time.perf_counter()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    T = getattr(scene, "input_from_scene", None)
    days = getattr(getattr(getattr(scene, "spec", None), "recording", None), "retention_days", None)
    pdict = placement_dict(scene_name, placement, budget, vis.candidates, T, frame, days)
    mark_storeys(pdict, scene)  # a building: each camera's storey (issue 33)
    builtin = (getattr(scene, "info", None) or {}).get("builtin")
    if builtin:  # the built-in scene as named ('warehouse:1000'): camplace serve reopens the run with it
        pdict = {**dict(list(pdict.items())[:1]), "builtin_scene": str(builtin), **pdict}
    timings = dict(timings)
    # shown in report.html (no "report"); repeatable: 0.0 as in metrics.json, so the page is byte-identical
    report_timings = {k: 0.0 if repeatable else round(float(v), 4) for k, v in timings.items()}
    with AtomicBatch() as batch:  # the contract files replace the old ones together, once all are written
        paths = {
            "visibility.npz": batch.stage_savez(out / "visibility.npz", compressed=compressed,
                                                level=npz_level(vis.V.nnz), **visibility_arrays(vis)),
            "placement.json": batch.stage_json(out / "placement.json", pdict),
            "placement.csv": batch.stage_text(out / "placement.csv", placement_csv(pdict["cameras"])),
        }
        timings["report"] = time.perf_counter() - t0
        paths["metrics.json"] = batch.stage_json(out / "metrics.json", _metrics_dict(metrics, timings, repeatable))
    result = OutputResult(pdict, _metrics_dict(metrics, timings, repeatable), scene_name, placement, metrics,
                          problem, vis, scene, None, timings, frame, repeatable, dict(paths))
    paths.update(write_registered(out, result))
    if not report:
        return paths
    if plan:
        from camplace.outputs.plan_data import check_paper

        paper = check_paper(paper)
    skipped = [] if skipped is None else skipped
    parts = ReportParts(deadline, skipped, [p for p in REPORT_PARTS if p != PLAN_SET or (plan and scene is not None)])
    try:
        if on_contract is not None:
            on_contract()
        # the report's pictures and mount table are drawn in the scene frame; exports follow ``frame``
        shown = pdict if frame == "scene" else placement_dict(scene_name, placement, budget, vis.candidates, T,
                                                              retention_days=days)
        mark_storeys(shown, scene)
        _write_report_set(out, vis, placement, shown, metrics, report_timings, scene, repeatable,
                          paper if plan else None, T if frame == "input" else None, parts, tuple(paths))
        paths.update(parts.paths)
        if frame != "scene" and "colmap/images.txt" in paths:
            from camplace.outputs.exports import write_exports

            paths.update(write_exports(out, pdict["cameras"]))
    except BaseException as err:
        paths.update(parts.paths)
        if "report.html" not in paths:  # an earlier run's page would contradict the new contract files
            _unlink_quietly(out / "report.html")
        if isinstance(err, KeyboardInterrupt) and deadline is not None:
            parts.cut()
            return paths
        if isinstance(err, KeyboardInterrupt):
            raise Interrupted(f"stopped during the report: the contract files (placement.json, metrics.json, "
                              f"visibility.npz, placement.csv) are written to {out}; the report set is "
                              f"incomplete") from err
        raise
    if not repeatable and not skipped:  # repeatable: every timing is 0.0, metrics.json is already final
        timings["report"] = time.perf_counter() - t0
        atomic_write_json(out / "metrics.json", _metrics_dict(metrics, timings, repeatable))
    return paths


EXPORTS, FIGURES, HTML = "exports (opencv/, colmap/)", "figures (PNG)", "report.html"
PLAN_SET = "plan set (plan.pdf, plan.svg, plan.dxf, scene.glb)"
REPORT_PARTS = (EXPORTS, FIGURES, PLAN_SET, HTML)  # in the order they are written


class ReportParts:
    """The parts of the report set (``planned``, REPORT_PARTS names), written in order while
    they fit the deadline (``deadline()``: a perf_counter() time or None); ``skipped``
    collects the names of the parts not written, ``paths`` what was."""

    def __init__(self, deadline: Callable[[], float | None] | None, skipped: list[str],
                 planned: tuple[str, ...] | list[str] = REPORT_PARTS) -> None:
        self.deadline = deadline
        self.skipped = skipped
        self.planned = list(planned)
        self.done: list[str] = []
        self.paths: dict[str, Path] = {}

    def fits(self) -> bool:
        end = None if self.deadline is None else self.deadline()
        return end is None or time.perf_counter() < end

    def run(self, name: str, write: Callable[[], dict[str, Path]]) -> bool:
        """Write the part ``name`` (``write()`` returns its paths) if it fits; True when written."""
        if not self.fits():
            self.skipped.append(name)
            return False
        self.paths.update(write())
        self.done.append(name)
        return True

    def cut(self) -> None:
        """The report set was stopped: the part in progress and those after it are skipped."""
        self.skipped.extend(n for n in self.planned if n not in self.done and n not in self.skipped)


OWN_INFO_KEYS = ("incumbent_method", "bound_method", "refine", "adaptive", "robust", "quality",  # own keys
                 "source_ids", "existing_ids", "new_budget")  # written into the camera objects and budget
MAX_INFO_ARRAY = 1000  # a longer array in Placement.info is written as its shape and dtype only


def json_safe(value):
    """``value`` as plain JSON (dict with str keys, list, str, int, float, bool, None):
    numpy scalars as numbers, arrays up to MAX_INFO_ARRAY elements as lists (longer ones as
    {"shape", "dtype"}), tuples and sets as lists, non-finite floats as None, anything else
    as its str()."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        if value.size > MAX_INFO_ARRAY:
            return {"shape": list(value.shape), "dtype": str(value.dtype)}
        return json_safe(value.tolist())
    if isinstance(value, (list, tuple, set, frozenset)):
        return [json_safe(v) for v in (sorted(value, key=str) if isinstance(value, (set, frozenset)) else value)]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return value if np.isfinite(value) else None
    if value is None or isinstance(value, (str, int, bool)):
        return value
    return str(value)


def solver_info(info: dict) -> dict:
    """placement.json ``solver_info``: the solver's Placement.info, JSON-safe (json_safe),
    without wall-clock entries (_timeless) and without the keys placement.json writes on
    its own (OWN_INFO_KEYS)."""
    return _timeless(json_safe({k: v for k, v in info.items() if k not in OWN_INFO_KEYS}))


def _timeless(value):
    """``value`` without the wall-clock entries of its dicts (nested too): keys ``seconds``
    and ``*_seconds``; placement.json must be byte-identical between identical runs."""
    if isinstance(value, dict):
        return {k: _timeless(v) for k, v in value.items() if not (k == "seconds" or k.endswith("_seconds"))}
    if isinstance(value, list):
        return [_timeless(v) for v in value]
    return value


def _metrics_dict(metrics: Metrics, timings: dict[str, float], repeatable: bool) -> dict:
    m = metrics.to_dict()
    # repeatable: timings written as 0.0 so that metrics.json is byte-identical between runs
    m["timings_s"] = {k: 0.0 if repeatable else round(float(v), 4) for k, v in timings.items()}
    return m


def _write_report_set(out: Path, vis: Visibility, placement: Placement, pdict: dict, metrics: Metrics,
                      timings: dict[str, float], scene, repeatable: bool = False,
                      paper: str | None = None, input_T: np.ndarray | None = None,
                      parts: ReportParts | None = None, written: tuple[str, ...] = ()) -> dict[str, Path]:
    """report.html, PNG figures and exports (camplace.outputs.report_html.write_report); with
    ``repeatable`` every camera view is rendered (no time budget), so the page depends only on
    the inputs. ``paper`` (with a scene): the hand-over plan set on that paper (plan.dxf
    in the frame of ``input_T``, 4x4, when given). Written part by part through ``parts``
    (ReportParts: exports, figures, the plan set, report.html, each while it fits its deadline).
    ``written``: names of the files written before the report set (linked from report.html)."""
    from camplace.outputs.figures import SceneView
    from camplace.outputs.report_html import write_report

    parts = ReportParts(None, []) if parts is None else parts
    sel = np.asarray(placement.selected, np.int64)
    cov = np.bincount(vis.V[sel].indices, minlength=vis.V.shape[1]).astype(np.int64)
    m = dict(metrics.to_dict(), timings_s=timings)
    view = SceneView.from_scene(scene) if scene else None

    def report(**what) -> dict[str, Path]:
        opts = dict(html_report=False, figures=False, exports=False) | what
        return write_report(out, vis.targets, cov, pdict, m, view, n_candidates=int(vis.V.shape[0]), scene=scene,
                            vis=vis, selected=sel, repeatable=repeatable, written=(*written, *parts.paths), **opts)

    plan: dict = {"extra": "", "views": None}
    early = _start_plan_set(scene, vis, pdict, metrics, m, sel, paper, repeatable, input_T, parts)
    try:
        parts.run(EXPORTS, lambda: report(exports=True))
        parts.run(FIGURES, lambda: report(figures=True))
        if paper is not None and scene is not None:  # the hand-over set renders the camera views once for both
            from camplace.outputs.handover import write_plan_set

            def plan_set() -> dict[str, Path]:
                kw = _plan_set_args(metrics, paper, repeatable, input_T)
                paths, plan["extra"], plan["views"] = write_plan_set(out, scene, vis, pdict, m, sel, **kw, **early)
                return paths

            parts.run(PLAN_SET, plan_set)
    finally:
        for job in early.get("made", ()):
            job.cancel()

    def html() -> dict[str, Path]:
        extra, figs, traces = plan["extra"], None, None
        if getattr(metrics, "crowd", None) is not None:  # issue 28: the placement in held-out crowds
            from camplace.outputs.report_crowd import crowd_report

            shown = view or SceneView.from_targets(str(pdict.get("scene", "scene")), vis.targets.positions,
                                                   pdict.get("cameras", []))
            cr = crowd_report(shown, vis.targets, metrics.crowd, m, pdict.get("cameras", []))
            extra, figs, traces = cr.section + extra, cr.figures, cr.traces
        return report(html_report=True, extra_html=extra, rendered_views=plan["views"], extra_figures=figs,
                      extra_traces=traces)

    parts.run(HTML, html)
    return parts.paths


def _plan_set_args(metrics: Metrics, paper: str, repeatable: bool, input_T) -> dict:
    """write_plan_set's keywords: paper, repeatable, input frame and the test people (issue 36: one
    held-out crowd's people in the camera views)."""
    cm = getattr(metrics, "crowd", None)
    people = (cm.shown, cm.radius, cm.height) if cm is not None and len(cm.shown) else None
    return {"paper": paper, "repeatable": repeatable, "input_from_scene": input_T, "people": people}


def _start_plan_set(scene, vis, pdict: dict, metrics: Metrics, m: dict, sel: np.ndarray, paper: str | None,
                    repeatable: bool, input_T, parts: ReportParts) -> dict:
    """The plan set started before the rest of the report set (when it is planned and fits the
    deadline): the camera views and viewsheds computed now (numba kernels on every core; the
    children's imports beside the viewsheds), then plan.pdf, plan.dxf and scene.glb made in forked
    children (camplace.outputs.handover.start_plan_files) while this process writes the exports,
    the figures and plan.svg. Returns write_plan_set's ``prepared`` and ``made`` keywords ({} when not started; an error here is raised again by the plan set part,
    in its turn)."""
    if paper is None or scene is None or PLAN_SET not in parts.planned or not parts.fits():
        return {}
    from camplace.outputs.handover import prepare_plan_set, start_plan_files

    try:
        ps = prepare_plan_set(scene, vis, pdict, m, sel, **_plan_set_args(metrics, paper, repeatable, input_T),
                              preload=True)
    except Exception:  # noqa: BLE001 - the plan set part meets it again in its turn, after exports and figures
        return {}
    return {"prepared": ps, "made": start_plan_files(ps)}


def _unlink_quietly(path: Path) -> None:
    try:
        path.unlink()
    except OSError:
        pass
