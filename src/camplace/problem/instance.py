"""Saved instances: a PlacementProblem from a visibility.npz (no geometry needed), and back.
Solving a saved instance and writing its outputs is camplace.workflows.solve.

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
        raise InputError(f"budget: expected a non-negative integer, got {budget}", option="budget")
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
