"""`paper-mip`: the paper's own piecewise-linear MILP (eq. 6–7), generalized to any Γ.

For every target j with Γ_j >= 1 and every piece k = 0..Γ_j: a binary selector
pl^k_j and an integer f^k_j with

    min  Σ_j w_j Σ_k k · f^k_j
    s.t. Σ_k f^k_j + Σ_i V_ij x_i >= Γ_j                 (Q_j = Σ_k f^k_j >= shortfall)
         lb_j pl^0_j <= f^0_j <= 0.5 pl^0_j
         (k − 0.5) pl^k_j <= f^k_j <= (k + 0.5) pl^k_j    (0 < k < Γ_j)
         (Γ_j − 0.5) pl^Γ_j <= f^Γ_j <= Γ_j pl^Γ_j
         Σ_k pl^k_j = 1
         Σ_i x_i <= N_s, [Σ_i cost_i x_i <= money_budget], Σ_{i at l} x_i <= 1,
         [Σ_{i of type t} x_i <= limit_t per limited camera type]

(the paper's strict "<" become "<=": f^k is integer, so f^k_j = k · pl^k_j and the
objective is Σ_j w_j Q_j², as eq. 6–7 intend; lb_j = min(0, Γ_j − #candidates seeing j)).
Solved with CBC through Python-MIP as in the paper (engine='cbc', default), or with
HiGHS on the same model (engine='highs', also the fallback when CBC cannot load, with
the reason in info['fallback']). Warm start from greedy. Much weaker LP relaxation than
`mip`; kept for faithful reproduction and as a speed baseline.
"""

from __future__ import annotations

import os
import tempfile
import time
import warnings

import numpy as np
import scipy.sparse as sp

from camplace.problem.model import PlacementProblem
from camplace.solvers.base import (OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, limit_left, out_of_time,
                                   stopped, trivial_placement)
from camplace.solvers.contract import Tags, make_solver
from camplace.solvers.highs_util import INF, MilpArrays, build_seconds, highs_from_arrays, location_rows, model_fits
from camplace.solvers.mip import better_selection, skipped_placement, solve_highs_model

# Measured on store-a (3.5 M nonzeros, 2 shared cores): HiGHS writes the MPS file in 4 s,
# Python-MIP reads it in 4.3 s, CBC takes 12 s before it stops at a 1 s max_seconds.
CBC_IO_S_PER_NNZ = 2.5e-6  # seconds per nonzero to hand the model to CBC (MPS write + read)
CBC_SETUP_S_PER_NNZ = 3.0e-6  # seconds per nonzero CBC runs before it polls max_seconds


def paper_model_nnz(problem: PlacementProblem) -> int:
    """Nonzeros of the paper's model (an estimate known before building it)."""
    pieces = int(np.sum(problem.gamma[problem.gamma > 0])) + int(np.count_nonzero(problem.gamma))
    return int(problem.V.nnz + 6 * pieces + 2 * problem.n_candidates)


def cbc_seconds(nnz: int) -> float:
    """Estimated seconds to hand a model of ``nnz`` nonzeros to CBC and for CBC to stop."""
    return (CBC_IO_S_PER_NNZ + CBC_SETUP_S_PER_NNZ) * float(nnz)


def paper_model_arrays(problem: PlacementProblem) -> tuple[MilpArrays, np.ndarray, np.ndarray]:
    """The paper's MILP as arrays. Columns: x (N_g), then per target with Γ_j >= 1 its
    pieces k = 0..Γ_j as [pl^k_j, f^k_j] pairs. Returns (arrays, piece_target (n_pc,),
    piece_k (n_pc,)) where piece columns are n_x + 2·p (pl) and n_x + 2·p + 1 (f)."""
    V = problem.V
    n_g = problem.n_candidates
    targets = np.nonzero(problem.gamma > 0)[0]
    g = problem.gamma[targets].astype(np.int64)
    n_t = len(targets)
    pieces = g + 1
    pt = np.repeat(np.arange(n_t), pieces)  # local target index of each piece
    starts = np.cumsum(pieces) - pieces
    pk = np.arange(int(pieces.sum())) - np.repeat(starts, pieces)
    n_pc = len(pt)
    pl_col = n_g + 2 * np.arange(n_pc)
    f_col = pl_col + 1
    n = n_g + 2 * n_pc
    deg = np.bincount(V.indices, minlength=problem.n_targets)[targets]
    lb = np.minimum(0, g - deg).astype(np.float64)
    gk = g[pt]
    rows, cols, vals, lo, hi = [], [], [], [], []
    r = 0
    # shortfall rows: Σ_k f^k_j + Σ_i V_ij x_i >= Γ_j
    cover = sp.coo_matrix(V[:, targets].T)
    rows.append(cover.row)
    cols.append(cover.col)
    vals.append(np.ones(cover.nnz))
    rows.append(pt)
    cols.append(f_col)
    vals.append(np.ones(n_pc))
    lo.append(g.astype(np.float64))
    hi.append(np.full(n_t, INF))
    r += n_t
    # f^k − a_k pl^k >= 0  and  f^k − b_k pl^k <= 0
    a = np.where(pk == 0, lb[pt], pk - 0.5)
    b = np.where(pk == 0, 0.5, np.where(pk == gk, gk.astype(np.float64), pk + 0.5))
    idx = np.arange(n_pc)
    for coef, low, up in ((a, 0.0, INF), (b, -INF, 0.0)):
        rows += [r + idx, r + idx]
        cols += [f_col, pl_col]
        vals += [np.ones(n_pc), -coef]
        lo.append(np.full(n_pc, low))
        hi.append(np.full(n_pc, up))
        r += n_pc
    # Σ_k pl^k_j = 1
    rows.append(r + pt)
    cols.append(pl_col)
    vals.append(np.ones(n_pc))
    lo.append(np.ones(n_t))
    hi.append(np.ones(n_t))
    r += n_t
    # budget, money, locations
    rows.append(np.full(n_g, r))
    cols.append(np.arange(n_g))
    vals.append(np.ones(n_g))
    lo.append([-INF])
    hi.append([float(problem.budget)])
    r += 1
    if problem.money_budget is not None:
        rows.append(np.full(n_g, r))
        cols.append(np.arange(n_g))
        vals.append(problem.costs)
        lo.append([-INF])
        hi.append([float(problem.money_budget)])
        r += 1
    L = location_rows(problem.location_ids).tocoo()
    rows.append(r + L.row)
    cols.append(L.col)
    vals.append(L.data)
    lo.append(np.full(L.shape[0], -INF))
    hi.append(np.ones(L.shape[0]))
    r += L.shape[0]
    if problem.has_type_limits:
        T, limits = problem.type_rows()
        T = T.tocoo()
        rows.append(r + T.row)
        cols.append(T.col)
        vals.append(T.data)
        lo.append(np.full(len(limits), -INF))
        hi.append(limits)
        r += len(limits)
    A = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(r, n))
    c = np.zeros(n)
    c[f_col] = problem.weights[targets][pt] * pk
    col_lower = np.zeros(n)
    col_upper = np.ones(n)
    col_lower[f_col] = np.minimum(lb[pt], 0.0)
    col_upper[f_col] = gk
    arrays = MilpArrays(c, A, np.concatenate([np.asarray(x, float) for x in lo]),
                        np.concatenate([np.asarray(x, float) for x in hi]), col_lower, col_upper,
                        np.ones(n, np.int32), n_g)
    return arrays, targets[pt], pk


def paper_start(problem: PlacementProblem, selected: np.ndarray, piece_target: np.ndarray,
                piece_k: np.ndarray) -> np.ndarray:
    """Full column vector of the paper model for a selection."""
    short = np.maximum(problem.gamma - problem.coverage(selected), 0)
    on = (piece_k == short[piece_target]).astype(np.float64)
    x = np.zeros(problem.n_candidates)
    x[np.asarray(selected, np.int64)] = 1
    inter = np.empty(2 * len(on))
    inter[0::2] = on
    inter[1::2] = on * piece_k
    return np.concatenate([x, inter])


def load_cbc():
    """(mip module, None) when Python-MIP's CBC loads here, else (None, reason)."""
    try:
        import mip

        m = mip.Model(solver_name=mip.CBC)
        m.verbose = 0
        return mip, None
    except Exception as err:  # noqa: BLE001 - any load failure means "no CBC here"
        return None, f"{type(err).__name__}: {err}"


def solve_paper_mip(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                    seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
                    on_incumbent: OnIncumbent | None = None, engine: str = "cbc", warm_start: bool = True,
                    local_search: bool = False, mip_rel_gap: float | None = None, verbose: bool = False) -> Placement:
    """The paper's MILP (module docstring) on CBC (engine='cbc') or HiGHS ('highs').
    Warm start: greedy (local_search=False by default, as the paper's greedy). CBC
    cannot be interrupted mid-solve: should_stop is checked before it starts."""
    from camplace.solvers.greedy import solve_greedy

    t0 = time.perf_counter()
    if (easy := trivial_placement(problem, "paper-mip", t0)) is not None:
        return easy
    end = deadline(time_limit_s, t0)
    info: dict = {"engine": engine}
    start = np.zeros(0, np.int64)
    if warm_start:
        g = solve_greedy(problem, time_limit_s=limit_left(end), should_stop=should_stop, local_search=local_search)
        start = g.selected
        info["warm_start_objective"] = g.objective
    if stopped(should_stop):
        return Placement(start, problem.cost(start), None, "interrupted", "paper-mip", time.perf_counter() - t0, info)
    nnz = paper_model_nnz(problem)
    if not model_fits(end, nnz) or (engine == "cbc" and out_of_time(end, build_seconds(nnz) + cbc_seconds(nnz))):
        return skipped_placement(problem, start, "paper-mip", t0, info, "no time left to build and solve the model")
    tb = time.perf_counter()
    arrays, piece_target, piece_k = paper_model_arrays(problem)
    info.update(columns=arrays.shape[1], rows=arrays.shape[0], nonzeros=int(arrays.A.nnz))
    start_cols = paper_start(problem, start, piece_target, piece_k) if warm_start else None
    h = highs_from_arrays(arrays)
    if engine == "cbc":
        mip, reason = load_cbc()
        if mip is None:
            info["fallback"] = f"Python-MIP's CBC could not load ({reason}); solved the same model with HiGHS"
            warnings.warn(info["fallback"], RuntimeWarning, stacklevel=2)
            info["engine"] = "highs"
        else:
            if out_of_time(end, cbc_seconds(arrays.A.nnz)):
                return skipped_placement(problem, start, "paper-mip", t0, info, "no time left to hand the model to CBC")
            return _solve_cbc(mip, problem, h, arrays, start_cols, start, end=end,
                              threads=threads, seed=seed, on_incumbent=on_incumbent, mip_rel_gap=mip_rel_gap,
                              verbose=verbose, t0=t0, tb=tb, info=info)
    info["build_seconds"] = time.perf_counter() - tb
    left = None if time_limit_s is None else max(0.01, time_limit_s - (time.perf_counter() - t0))
    p = solve_highs_model(problem, h, start_cols, start, arrays.n_x, "paper-mip", time_limit_s=left,
                          threads=threads, seed=seed, should_stop=should_stop, on_incumbent=on_incumbent,
                          mip_rel_gap=mip_rel_gap, verbose=verbose, t0=time.perf_counter(), info=info, end=end)
    return Placement(p.selected, p.objective, p.bound, p.status, "paper-mip", time.perf_counter() - t0, p.info)


def _solve_cbc(mip, problem: PlacementProblem, h, arrays: MilpArrays, start_cols, start_sel, *, end: float,
               threads, seed, on_incumbent, mip_rel_gap, verbose, t0, tb, info) -> Placement:
    """Hand the model to CBC through an MPS file written by HiGHS (fast, exact columns);
    CBC's max_seconds is the time left before ``end`` less what CBC runs before polling it."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "paper.mps")
        h.writeModel(path)
        m = mip.Model(solver_name=mip.CBC)
        m.verbose = 1 if verbose else 0
        m.read(path)
    m.seed = int(seed)
    if threads is not None:
        m.threads = int(threads)
    if mip_rel_gap is not None:
        m.max_mip_gap = float(mip_rel_gap)
    cols = m.vars
    if start_cols is not None:
        m.start = [(cols[k], float(v)) for k, v in enumerate(start_cols) if v != 0.0]
    info["build_seconds"] = time.perf_counter() - tb
    left = limit_left(end)
    left = None if left is None else max(0.1, left - CBC_SETUP_S_PER_NNZ * arrays.A.nnz)
    ts = time.perf_counter()
    st = m.optimize(max_seconds=left if left is not None else float("inf"))
    info["cbc_seconds"] = time.perf_counter() - ts
    info["cbc_status"] = st.name
    found = None
    if st in (mip.OptimizationStatus.OPTIMAL, mip.OptimizationStatus.FEASIBLE) and m.num_solutions:
        x = np.array([cols[k].x or 0.0 for k in range(arrays.n_x)])
        found = np.nonzero(x > 0.5)[0].astype(np.int64)
    best, best_cost = better_selection(problem, start_sel, found, info, "cbc_solution_rejected")
    bound = m.objective_bound
    bound = None if bound is None or not np.isfinite(bound) else min(max(float(bound), 0.0), best_cost)
    if st != mip.OptimizationStatus.OPTIMAL and bound is not None and bound >= best_cost - 1e-9 * max(1.0, best_cost):
        # CBC stopped by its time limit (often before its root LP) reports the incumbent as
        # its bound: that proves nothing, so no bound is claimed.
        info["cbc_reported_bound"] = m.objective_bound
        bound = None
    if st == mip.OptimizationStatus.OPTIMAL:
        status = "optimal"
    elif left is not None and info["cbc_seconds"] >= 0.95 * left:
        status = "time_limit"
    else:
        status = "feasible"
    if status == "optimal" and bound is not None and best_cost - bound > 1e-4 * max(1.0, best_cost) + 1e-6:
        status = "feasible"
    if on_incumbent:
        on_incumbent(best_cost, bound)
    return Placement(best, best_cost, bound, status, "paper-mip", time.perf_counter() - t0, info)


PAPER_MIP = make_solver("paper-mip", solve_paper_mip, Tags(exact=True, gives_bound=True),
                        summary="The paper's MIP model (CBC or HiGHS), exact")
