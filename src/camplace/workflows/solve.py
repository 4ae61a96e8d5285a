"""Solve a saved instance (a visibility.npz, no geometry needed) and write its
placement.json and metrics.json (the output contract; pose fields null where the file
has no geometry)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from camplace.core.files import atomic_copy, atomic_write_json, atomic_write_text
from camplace.metrics.coverage import compute_metrics
from camplace.problem.instance import load_problem_npz
from camplace.problem.model import PlacementProblem
from camplace.workflows.run import solve_stoppable


def instance_name(path: str | Path) -> str:
    """A name for a saved instance: the folder of a `visibility.npz`, else the file stem."""
    p = Path(path)
    return (p.parent.name or "instance") if p.stem == "visibility" else p.stem


def camera_entries_from_arrays(arrays: dict[str, np.ndarray], selected: np.ndarray, location_ids: np.ndarray) -> list[dict]:
    """placement.json camera objects from the optional pose arrays of a visibility.npz
    (`candidate_positions`, `rotations`, `candidate_angles_deg`, `camera_ids`,
    `camera_names`); a field the file lacks is null."""
    def arr(key, n_dims):
        a = arrays.get(key)
        return None if a is None or a.ndim != n_dims or len(a) != len(location_ids) else a

    pos, rot, ang = arr("candidate_positions", 2), arr("rotations", 3), arr("candidate_angles_deg", 2)
    cam_ids, names = arr("camera_ids", 1), arrays.get("camera_names")
    out = []
    for i in np.sort(np.asarray(selected, np.int64)):
        cam = None
        if cam_ids is not None and names is not None and 0 <= int(cam_ids[i]) < len(names):
            cam = str(names[int(cam_ids[i])])
        out.append({
            "candidate_id": int(i),
            "location_id": int(location_ids[i]),
            "position": None if pos is None else [float(v) for v in pos[i]],
            "yaw_deg": None if ang is None else float(ang[i][0]),
            "pitch_deg": None if ang is None else float(ang[i][1]),
            "roll_deg": None if ang is None else float(ang[i][2]),
            "rotation": None if rot is None else [[float(v) for v in row] for row in rot[i]],
            "camera": cam,
            "intrinsics": None,
        })
    return out


def solve_instance(path: str | Path, budget: int, solver: str = "greedy", **solver_options):
    """Load a saved visibility.npz and solve it: returns (problem, placement, metrics, arrays, timings)."""
    timings: dict[str, float] = {}
    t = time.perf_counter()
    problem, arrays = load_problem_npz(path, budget)
    timings["load"] = time.perf_counter() - t
    t = time.perf_counter()
    placement = solve_stoppable(problem, solver, **solver_options)  # comes back soon after should_stop()
    timings["solve"] = time.perf_counter() - t
    t = time.perf_counter()
    region_ids = arrays.get("target_region_ids")
    names = arrays.get("region_names")
    ok = region_ids is not None and names is not None and region_ids.shape == (problem.n_targets,)
    metrics = compute_metrics(problem, placement.selected, region_ids if ok else None,
                              [str(n) for n in names] if ok else ())
    timings["metrics"] = time.perf_counter() - t
    return problem, placement, metrics, arrays, timings


def write_instance_outputs(out_dir: str | Path, name: str, problem: PlacementProblem, placement, metrics,
                           arrays: dict[str, np.ndarray], timings: dict[str, float],
                           source: str | Path | None = None) -> dict[str, Path]:
    """The contract files of a solved saved instance (docs/output-contract.md: placement.json,
    metrics.json, placement.csv, and visibility.npz: a copy of ``source``, the instance file,
    unless it is already that file; pose fields null, CSV cells empty, where the file has no
    geometry), then every registered output writer (camplace.outputs.writers.write_registered;
    no scene nor candidates: ``visibility`` and ``scene`` are None)."""
    from camplace.outputs.write import placement_csv, solver_info
    from camplace.outputs.writers import OutputResult, write_registered

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    pdict = {
        "scene": name, "solver": placement.solver, "budget": int(problem.budget), "status": placement.status,
        "objective": float(placement.objective),
        "bound": None if placement.bound is None else float(placement.bound),
        "gap": placement.gap, **{k: str(placement.info[k]) for k in ("incumbent_method", "bound_method")
                                 if k in placement.info},
        **({"solver_info": info} if (info := solver_info(placement.info)) else {}),
        "n_cameras": int(len(placement.selected)),
        "cameras": camera_entries_from_arrays(arrays, placement.selected, problem.location_ids),
    }
    m = metrics.to_dict()
    m["timings_s"] = {k: round(float(v), 4) for k, v in timings.items()}
    paths: dict[str, Path] = {}
    npz = out / "visibility.npz"
    if source is not None and not (npz.exists() and npz.samefile(source)):
        paths["visibility.npz"] = atomic_copy(source, npz)
    elif npz.exists():
        paths["visibility.npz"] = npz
    rows = [dict(c, position=c["position"] or ["", "", ""], camera=c["camera"] or "") for c in pdict["cameras"]]
    paths["placement.json"] = atomic_write_json(out / "placement.json", pdict)
    paths["placement.csv"] = atomic_write_text(out / "placement.csv", placement_csv(rows))
    paths["metrics.json"] = atomic_write_json(out / "metrics.json", m)
    result = OutputResult(pdict, m, name, placement, metrics, problem, None, None, arrays, timings,
                          written=dict(paths))
    paths.update(write_registered(out, result))
    return paths
