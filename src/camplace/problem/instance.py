"""Saved instances: a PlacementProblem from a visibility.npz (no geometry needed).

Only the CSR arrays (`data`, `indices`, `indptr`, `shape`), `gamma` and
`location_ids` of the visibility.npz contract are required; `weights` defaults to 1
and every other array is optional (see the output contract).
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from camplace.core.errors import InputError
from camplace.problem.model import PlacementProblem

REQUIRED = ("data", "indices", "indptr", "shape", "gamma", "location_ids")


def load_arrays(path: str | Path) -> dict[str, np.ndarray]:
    """All arrays of an .npz file (no pickles); InputError when unreadable."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: file not found (expected a visibility.npz)")
    try:
        with np.load(p, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except (OSError, ValueError, zipfile.BadZipFile) as err:
        raise InputError(f"{p}: not a readable .npz file ({err.__class__.__name__})") from None


def load_problem_npz(path: str | Path, budget: int) -> tuple[PlacementProblem, dict[str, np.ndarray]]:
    """(problem, arrays) from a visibility.npz: V (N_g × N_p CSR), gamma (N_p,),
    weights (N_p,, default 1), location_ids (N_g,), with the given budget."""
    arrays = load_arrays(path)
    for key in REQUIRED:
        if key not in arrays:
            raise InputError(f"{path}: array '{key}' missing (needs {', '.join(REQUIRED)})")
    shape = np.asarray(arrays["shape"]).ravel()
    if shape.shape != (2,) or np.any(shape < 0):
        raise InputError(f"{path}: 'shape' must be 2 non-negative integers, got {shape.tolist()}")
    n_g, n_p = (int(v) for v in shape)
    indptr = np.asarray(arrays["indptr"], np.int64).ravel()
    indices = np.asarray(arrays["indices"], np.int64).ravel()
    data = np.asarray(arrays["data"]).ravel()
    if indptr.shape != (n_g + 1,) or indptr[0] != 0 or np.any(np.diff(indptr) < 0) or indptr[-1] != len(indices):
        raise InputError(f"{path}: 'indptr' must be non-decreasing, length {n_g + 1}, from 0 to len(indices)")
    if len(data) != len(indices):
        raise InputError(f"{path}: 'data' and 'indices' must have the same length")
    if len(indices) and (indices.min() < 0 or indices.max() >= n_p):
        raise InputError(f"{path}: 'indices' must lie in [0, {n_p})")
    if len(data) and not np.all(np.isin(data, (0, 1))):
        raise InputError(f"{path}: 'data' must be 0/1")
    V = sp.csr_matrix((data.astype(np.uint8), indices, indptr), shape=(n_g, n_p))
    V.eliminate_zeros()
    V.sum_duplicates()
    V.data[:] = 1
    gamma = np.asarray(arrays["gamma"]).ravel()
    if gamma.shape != (n_p,) or not np.issubdtype(gamma.dtype, np.number) or np.any(gamma < 0) \
            or np.any(gamma != np.round(gamma)):
        raise InputError(f"{path}: 'gamma' must be {n_p} non-negative integers")
    weights = np.asarray(arrays.get("weights", np.ones(n_p)), np.float64).ravel()
    if weights.shape != (n_p,) or np.any(~np.isfinite(weights)) or np.any(weights < 0):
        raise InputError(f"{path}: 'weights' must be {n_p} finite non-negative numbers")
    loc = np.asarray(arrays["location_ids"]).ravel()
    if loc.shape != (n_g,) or not np.issubdtype(loc.dtype, np.integer):
        raise InputError(f"{path}: 'location_ids' must be {n_g} integers")
    if budget < 0:
        raise InputError(f"--budget: expected a non-negative integer, got {budget}")
    prob = PlacementProblem(V, gamma.astype(np.int64), weights, int(budget), loc.astype(np.int64))
    return prob, arrays


def save_problem_npz(path: str | Path, problem: PlacementProblem) -> Path:
    """Write the minimal visibility.npz arrays of a problem (atomically)."""
    from camplace.core.files import atomic_savez

    V = problem.V
    return atomic_savez(Path(path), data=V.data.astype(np.uint8), indices=V.indices.astype(np.int32),
                        indptr=V.indptr.astype(np.int64), shape=np.array(V.shape, np.int64),
                        gamma=problem.gamma.astype(np.int64), weights=problem.weights.astype(np.float64),
                        location_ids=problem.location_ids.astype(np.int64))


# ------------------------------------------------------ solve a saved instance --

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
    import time

    from camplace.metrics.coverage import compute_metrics
    from camplace.solvers import solve

    timings: dict[str, float] = {}
    t = time.perf_counter()
    problem, arrays = load_problem_npz(path, budget)
    timings["load"] = time.perf_counter() - t
    t = time.perf_counter()
    placement = solve(problem, solver, **solver_options)
    timings["solve"] = time.perf_counter() - t
    t = time.perf_counter()
    region_ids = arrays.get("target_region_ids")
    names = arrays.get("region_names")
    ok = region_ids is not None and names is not None and region_ids.shape == (problem.n_targets,)
    metrics = compute_metrics(problem, placement.selected, region_ids if ok else None,
                              [str(n) for n in names] if ok else ())
    timings["metrics"] = time.perf_counter() - t
    return problem, placement, metrics, arrays, timings


def certificate_keys(placement) -> dict:
    """The certification keys added to placement.json (when the solver reports them)."""
    out = {}
    for key in ("incumbent_method", "bound_method"):
        if key in placement.info:
            out[key] = str(placement.info[key])
    return out


def write_instance_outputs(out_dir: str | Path, name: str, problem: PlacementProblem, placement, metrics,
                           arrays: dict[str, np.ndarray], timings: dict[str, float]) -> dict[str, Path]:
    """placement.json and metrics.json of a solved saved instance (contract keys; pose
    fields null where the file has no geometry)."""
    from camplace.core.files import atomic_write_json

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    pdict = {
        "scene": name, "solver": placement.solver, "budget": int(problem.budget), "status": placement.status,
        "objective": float(placement.objective),
        "bound": None if placement.bound is None else float(placement.bound),
        "gap": placement.gap, **certificate_keys(placement),
        "n_cameras": int(len(placement.selected)),
        "cameras": camera_entries_from_arrays(arrays, placement.selected, problem.location_ids),
    }
    m = metrics.to_dict()
    m["timings_s"] = {k: round(float(v), 4) for k, v in timings.items()}
    return {"placement.json": atomic_write_json(out / "placement.json", pdict),
            "metrics.json": atomic_write_json(out / "metrics.json", m)}
