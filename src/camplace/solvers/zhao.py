"""Baseline `zhao`: the fixed-budget model of Zhao, Cheung & Nguyen (2008), as a MILP.

A target counts only when fully covered (binary y_j = 1 only if c_j >= Γ_j):

    max  Σ_j w_j y_j
    s.t. Γ_j y_j − Σ_i V_ij x_i <= 0          (one row per target with Γ_j >= 1)
         Σ_i x_i <= N_s,  [Σ_i cost_i x_i <= money_budget],  Σ_{i at l} x_i <= 1,
         [Σ_{i of type t} x_i <= limit_t per limited camera type]
         x ∈ {0,1}^{N_g},  y ∈ {0,1}^{N_p}

solved by HiGHS, warm-started from the Hörster greedy. Partially covered targets
earn nothing, so the model has no reason to help them (the paper's point). The
Placement's objective is the squared-shortfall cost of the chosen cameras (so all
methods are compared on the same measure); bound is None because Zhao's bound is on
its own objective; info holds zhao_covered (Σ w_j y_j), zhao_bound and the MILP status.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from camplace.problem.model import PlacementProblem
from camplace.solvers.base import OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, trivial_placement
from camplace.solvers.contract import make_solver
from camplace.solvers.highs_util import (INF, MilpArrays, highs_from_arrays, location_rows, model_fits,
                                        target_rows, run_highs,
                                        skipped_outcome)


def zhao_arrays(problem: PlacementProblem) -> MilpArrays:
    """Zhao's fixed-budget MILP (module docstring) as arrays; columns x then y."""
    n_g = problem.n_candidates
    targets = np.nonzero(problem.gamma > 0)[0]
    n_t = len(targets)
    cover_x = -target_rows(problem.V, targets)
    cover_y = sp.diags(problem.gamma[targets].astype(np.float64), format="csr")
    blocks = [[cover_x, cover_y], [sp.csr_matrix(np.ones((1, n_g))), sp.csr_matrix((1, n_t))]]
    upper = [np.zeros(n_t), [float(problem.budget)]]
    if problem.money_budget is not None:
        blocks.append([sp.csr_matrix(problem.costs.reshape(1, -1)), sp.csr_matrix((1, n_t))])
        upper.append([float(problem.money_budget)])
    L = location_rows(problem.location_ids)
    if L.shape[0]:
        blocks.append([L, sp.csr_matrix((L.shape[0], n_t))])
        upper.append(np.ones(L.shape[0]))
    if problem.has_type_limits:
        T, limits = problem.type_rows()
        blocks.append([T, sp.csr_matrix((T.shape[0], n_t))])
        upper.append(limits)
    A = sp.bmat(blocks, format="csc")
    ub = np.concatenate([np.asarray(u, np.float64) for u in upper])
    n = n_g + n_t
    c = np.concatenate([np.zeros(n_g), problem.weights[targets]])
    return MilpArrays(c, A, np.full(len(ub), -INF), ub, np.zeros(n), np.ones(n), np.ones(n, np.int32), n_g, sense=-1)


def solve_zhao(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
               seed: int = 0, should_stop: ShouldStop | None = None, progress: ProgressFn | None = None,
               on_incumbent: OnIncumbent | None = None, mip_rel_gap: float | None = None, verbose: bool = False) -> Placement:
    """Zhao et al. fixed-budget MILP on HiGHS (module docstring)."""
    from camplace.solvers.horster import solve_horster

    t0 = time.perf_counter()
    if (easy := trivial_placement(problem, "zhao", t0)) is not None:
        return Placement(easy.selected, easy.objective, None, easy.status, "zhao", easy.seconds, {})
    start = solve_horster(problem, should_stop=should_stop).selected
    targets = np.nonzero(problem.gamma > 0)[0]
    full = problem.coverage(start)[targets] >= problem.gamma[targets]
    x0 = np.zeros(problem.n_candidates)
    x0[start] = 1
    end = deadline(time_limit_s, t0)
    if model_fits(end, problem.V.nnz + 2 * problem.n_candidates + len(targets)):
        arrays = zhao_arrays(problem)
        h = highs_from_arrays(arrays)
        out = run_highs(h, threads=threads, seed=seed, should_stop=should_stop, end=end, mip_rel_gap=mip_rel_gap,
                        start=np.concatenate([x0, full.astype(np.float64)]), verbose=verbose)
    else:
        out = skipped_outcome("no time left to build Zhao's model")
    sel = np.sort(start)
    covered0 = float(problem.weights[targets][full].sum())
    covered = covered0
    if out.values is not None:
        cand = np.nonzero(out.values[:problem.n_candidates] > 0.5)[0].astype(np.int64)
        try:
            problem.check_feasible(cand)
            cov = problem.coverage(cand)[targets] >= problem.gamma[targets]
            c = float(problem.weights[targets][cov].sum())
            if c >= covered0:
                sel, covered = cand, c
        except ValueError:
            pass
    status = out.status if out.status in ("optimal", "time_limit", "interrupted") else "feasible"
    cost = problem.cost(sel)
    if on_incumbent:
        on_incumbent(cost, None)
    info = {"zhao_covered": covered, "zhao_bound": out.bound, "zhao_gap": out.gap, "nodes": out.nodes,
            "highs_status": out.model_status, "warm_start_covered": covered0}
    return Placement(sel, cost, None, status, "zhao", time.perf_counter() - t0, info)


ZHAO = make_solver("zhao", solve_zhao, summary="Zhao et al. baseline")
