"""Shared HiGHS plumbing: a MILP given as arrays -> highspy.Highs, callbacks, results.

Every MILP here is   min c·z  s.t.  row_lower <= A z <= row_upper,
col_lower <= z <= col_upper, z_k integer where integrality[k] = 1.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import highspy
import numpy as np
import scipy.sparse as sp

from camplace.solvers.base import OnIncumbent, ShouldStop, stopped

INF = highspy.kHighsInf


@dataclass
class MilpArrays:
    """A MILP as arrays. A: (m, n) sparse; c, col_lower, col_upper: (n,) float64;
    row_lower, row_upper: (m,) float64; integrality: (n,) int32 (0 continuous, 1 integer);
    sense: +1 minimize, −1 maximize. n_x: the first n_x columns are the camera
    variables x_i (rows of V)."""

    c: np.ndarray
    A: sp.spmatrix
    row_lower: np.ndarray
    row_upper: np.ndarray
    col_lower: np.ndarray
    col_upper: np.ndarray
    integrality: np.ndarray
    n_x: int
    sense: int = 1
    offset: float = 0.0

    @property
    def shape(self) -> tuple[int, int]:
        return self.A.shape


_BANNER_DONE = False


def new_highs() -> highspy.Highs:
    """A silent highspy.Highs. HiGHS prints a banner on stdout the first time one is
    made in a process; library code must not print, so that first one is made with
    file descriptor 1 pointed at /dev/null."""
    global _BANNER_DONE
    if _BANNER_DONE:
        h = highspy.Highs()
    else:
        import os
        import sys

        sys.stdout.flush()
        saved = os.dup(1)
        try:
            with open(os.devnull, "w") as null:
                os.dup2(null.fileno(), 1)
                h = highspy.Highs()
        finally:
            os.dup2(saved, 1)
            os.close(saved)
        _BANNER_DONE = True
    h.setOptionValue("output_flag", False)
    return h


def highs_from_arrays(m: MilpArrays, *, integer: bool = True) -> highspy.Highs:
    """A silent highspy.Highs holding the model (integer=False: its LP relaxation)."""
    h = new_highs()
    A = sp.csc_matrix(m.A, dtype=np.float64)
    A.sort_indices()
    n_row, n_col = A.shape
    sense = highspy.ObjSense.kMinimize if m.sense > 0 else highspy.ObjSense.kMaximize
    integ = np.asarray(m.integrality, np.int32) if integer else np.zeros(n_col, np.int32)
    status = h.passModel(int(n_col), int(n_row), int(A.nnz), int(highspy.MatrixFormat.kColwise), int(sense),
                         float(m.offset), np.asarray(m.c, np.float64), np.asarray(m.col_lower, np.float64),
                         np.asarray(m.col_upper, np.float64), np.asarray(m.row_lower, np.float64),
                         np.asarray(m.row_upper, np.float64), A.indptr.astype(np.int32),
                         A.indices.astype(np.int32), A.data.astype(np.float64), integ)
    if status == highspy.HighsStatus.kError:
        raise RuntimeError("HiGHS rejected the model")
    return h


def location_rows(location_ids: np.ndarray) -> sp.csr_matrix:
    """(N_l, N_g) 0/1 matrix L̃ of the paper: one row per location with >= 2 candidates
    (a location with one candidate needs no row)."""
    _, inv, counts = np.unique(location_ids, return_inverse=True, return_counts=True)
    keep = counts[inv] >= 2
    cols = np.nonzero(keep)[0]
    if len(cols) == 0:
        return sp.csr_matrix((0, len(location_ids)))
    _, rows = np.unique(inv[cols], return_inverse=True)
    return sp.csr_matrix((np.ones(len(cols)), (rows, cols)), shape=(int(rows.max()) + 1, len(location_ids)))


@dataclass
class HighsOutcome:
    status: str  # 'optimal' | 'time_limit' | 'interrupted' | 'infeasible' | 'other:<HiGHS status>'
    values: np.ndarray | None  # (n,) best solution or None
    objective: float | None
    bound: float | None
    gap: float | None
    seconds: float
    nodes: int
    model_status: str


def subscribe_stop(h: highspy.Highs, should_stop: ShouldStop | None) -> dict:
    """Poll should_stop from HiGHS' MIP, simplex and IPM interrupt callbacks. Returns a
    dict whose "stop" turns True once HiGHS was interrupted."""
    flag = {"stop": False}

    def interrupt(e) -> None:
        if stopped(should_stop):
            flag["stop"] = True
            e.interrupt()

    if should_stop is not None:
        h.cbMipInterrupt.subscribe(interrupt)
        h.cbSimplexInterrupt.subscribe(interrupt)
        h.cbIpmInterrupt.subscribe(interrupt)
    return flag


def set_start(h: highspy.Highs, values: np.ndarray) -> None:
    """Hand HiGHS a full column vector as its starting solution."""
    sol = highspy.HighsSolution()
    sol.col_value = list(map(float, values))
    sol.value_valid = True
    h.setSolution(sol)


def run_highs(h: highspy.Highs, *, time_limit_s: float | None = None, threads: int | None = None, seed: int = 0,
              should_stop: ShouldStop | None = None, on_incumbent: OnIncumbent | None = None,
              start: np.ndarray | None = None, mip_rel_gap: float | None = None,
              verbose: bool = False, options: dict | None = None) -> HighsOutcome:
    """Solve with HiGHS; should_stop is polled from the MIP / simplex / IPM interrupt
    callbacks; on_incumbent(objective, dual bound) fires on every improving solution."""
    if time_limit_s is not None:
        h.setOptionValue("time_limit", float(max(time_limit_s, 0.01)))
    if threads is not None:
        h.setOptionValue("threads", int(threads))
    h.setOptionValue("random_seed", int(seed))
    if mip_rel_gap is not None:
        h.setOptionValue("mip_rel_gap", float(mip_rel_gap))
    for key, value in (options or {}).items():
        h.setOptionValue(key, value)
    if verbose:
        h.setOptionValue("output_flag", True)
    flag = subscribe_stop(h, should_stop)
    if on_incumbent is not None:
        def improving(e) -> None:
            out = e.data_out
            on_incumbent(float(out.objective_function_value), float(out.mip_dual_bound))

        h.cbMipImprovingSolution.subscribe(improving)
    if start is not None:
        set_start(h, start)
    t0 = time.perf_counter()
    h.run()
    seconds = time.perf_counter() - t0
    ms = h.getModelStatus()
    info = h.getInfo()
    has_sol = info.primal_solution_status >= 1 if hasattr(info, "primal_solution_status") else True
    values = np.asarray(h.getSolution().col_value, np.float64) if has_sol else None
    if values is not None and len(values) == 0:
        values = None
    MS = highspy.HighsModelStatus
    if ms in (MS.kOptimal, MS.kModelEmpty):
        status = "optimal"
    elif ms == MS.kTimeLimit:
        status = "time_limit"
    elif ms in (MS.kInterrupt, MS.kHighsInterrupt) or flag["stop"]:
        status = "interrupted"
    elif ms in (MS.kInfeasible,):
        status = "infeasible"
    else:
        status = f"other:{h.modelStatusToString(ms)}"
    is_mip = h.getLp().integrality_ is not None and len(h.getLp().integrality_) > 0
    if is_mip:
        bound = float(info.mip_dual_bound)
        objective = float(info.objective_function_value) if values is not None else None
        gap = float(info.mip_gap) if values is not None else None
        nodes = int(info.mip_node_count)
    else:
        objective = float(info.objective_function_value) if ms == MS.kOptimal else None
        bound = objective
        gap = 0.0 if objective is not None else None
        nodes = 0
    if bound is not None and not np.isfinite(bound):
        bound = None
    return HighsOutcome(status, values, objective, bound, gap, seconds, nodes, h.modelStatusToString(ms))
