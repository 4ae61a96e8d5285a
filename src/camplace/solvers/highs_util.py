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

from camplace.solvers.base import OnIncumbent, ShouldStop, out_of_time, time_left
from camplace.solvers.highs_process import (FINISH_S_PER_NNZ, remember_model, remember_start, run_model)

INF = highspy.kHighsInf

# Measured on store-a (3.1 M nonzeros, 2 shared cores): building the arrays 0.6-2.3 s,
# passModel 0.5 s, HiGHS presolve / MIP set-up before its first callback 1-2.5 s, reading
# the solution back 0.2-0.4 s, up to 2 s from an interrupt to its return. HiGHS checks its
# time limit only after presolve, so a model whose set-up cannot end before the deadline
# is not started at all.
BUILD_S_PER_NNZ = 0.4e-6  # seconds per nonzero to build the arrays and pass them to HiGHS
SETUP_S_PER_NNZ = 0.6e-6  # seconds per nonzero HiGHS spends before it polls its time limit


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


def build_seconds(nnz: int) -> float:
    """Estimated seconds to build and pass a model with ``nnz`` nonzeros."""
    return BUILD_S_PER_NNZ * float(nnz)


def setup_seconds(nnz: int) -> float:
    """Estimated seconds HiGHS needs (presolve, set-up, read-back) before a model with
    ``nnz`` nonzeros can return anything."""
    return (SETUP_S_PER_NNZ + FINISH_S_PER_NNZ) * float(nnz)


def model_fits(end: float, nnz: int) -> bool:
    """True when building a model of ``nnz`` nonzeros and starting HiGHS on it can end
    before the perf_counter() deadline ``end`` (always True without a deadline)."""
    return not out_of_time(end, build_seconds(nnz) + setup_seconds(nnz))


def convex_model_nnz(problem) -> int:
    """Nonzeros of the tight convex model of a PlacementProblem, known before building it:
    V, the u columns (Σ Γ_j), the budget and location rows (2 per candidate)."""
    return int(problem.V.nnz + int(np.sum(problem.gamma)) + 2 * problem.n_candidates)


def deadline_room(h: highspy.Highs, end: float) -> float | None:
    """Seconds HiGHS ``h`` may run before the perf_counter() deadline ``end``, less the
    read-back of its solution; None without a deadline; 0.0 when the time left is less
    than HiGHS needs to start on the model (setup_seconds)."""
    left = time_left(end)
    if left is None:
        return None
    nnz = int(h.getNumNz())
    if left < setup_seconds(nnz):
        return 0.0
    return max(0.01, left - FINISH_S_PER_NNZ * nnz)


def limit_to_deadline(h: highspy.Highs, end: float) -> bool:
    """Set HiGHS' time_limit to the room before ``end`` (deadline_room); False when there
    is too little room to start."""
    room = deadline_room(h, end)
    if room is not None and room > 0:
        h.setOptionValue("time_limit", room)
    return room is None or room > 0


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
    remember_model(h, n_col, n_row, A, m.c, m.col_lower, m.col_upper, m.row_lower, m.row_upper, integ, m.sense,
                   m.offset)
    return h


def target_rows(V: sp.spmatrix, targets: np.ndarray) -> sp.csr_matrix:
    """(len(targets), N_g) float64 csr: V[:, targets].T, without the (slow) column indexing
    when ``targets`` are all the columns in order."""
    if len(targets) == V.shape[1] and np.array_equal(targets, np.arange(V.shape[1])):
        return sp.csr_matrix(V.T, dtype=np.float64)
    return sp.csr_matrix(V[:, targets].T, dtype=np.float64)


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


def skipped_outcome(reason: str) -> HighsOutcome:
    """The outcome of a HiGHS run not started because the deadline would not allow it."""
    return HighsOutcome("time_limit", None, None, None, None, 0.0, 0, f"skipped: {reason}")


def set_start(h: highspy.Highs, values: np.ndarray) -> None:
    """Hand HiGHS a full column vector as its starting solution."""
    sol = highspy.HighsSolution()
    sol.col_value = list(map(float, values))
    sol.value_valid = True
    h.setSolution(sol)
    remember_start(h, values)


def run_highs(h: highspy.Highs, *, time_limit_s: float | None = None, threads: int | None = None, seed: int = 0,
              should_stop: ShouldStop | None = None, on_incumbent: OnIncumbent | None = None,
              start: np.ndarray | None = None, mip_rel_gap: float | None = None,
              verbose: bool = False, options: dict | None = None, end: float = float("inf")) -> HighsOutcome:
    """Solve with HiGHS; should_stop is polled from the MIP / simplex / IPM interrupt
    callbacks; on_incumbent(objective, dual bound) fires on every improving solution.
    ``end``: perf_counter() deadline; HiGHS gets only the time left before it (less the
    read-back), is interrupted at it, and is not started when its set-up alone would pass
    it (status 'time_limit', no values)."""
    room = deadline_room(h, end)
    if room == 0.0:
        return skipped_outcome(f"HiGHS needs about {setup_seconds(h.getNumNz()):.2f} s to start")
    if room is not None:
        time_limit_s = room if time_limit_s is None else min(float(time_limit_s), room)
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
    if start is not None:
        set_start(h, start)
    is_mip = h.getLp().integrality_ is not None and len(h.getLp().integrality_) > 0
    t0 = time.perf_counter()
    run = run_model(h, should_stop=should_stop, end=end, on_improving=on_incumbent)
    seconds = time.perf_counter() - t0
    ms, info = run.model_status, run.info
    has_sol = info.primal_solution_status >= 1
    values = run.col_value if has_sol else None
    MS = highspy.HighsModelStatus
    if ms in (MS.kOptimal, MS.kModelEmpty):
        status = "optimal"
    elif ms == MS.kTimeLimit:
        status = "time_limit"
    elif run.deadline and not run.stopped:
        status = "time_limit"
    elif ms in (MS.kInterrupt, MS.kHighsInterrupt) or run.stopped:
        status = "interrupted"
    elif ms in (MS.kInfeasible,):
        status = "infeasible"
    else:
        status = f"other:{run.status_text}"
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
    return HighsOutcome(status, values, objective, bound, gap, seconds, nodes, run.status_text)
