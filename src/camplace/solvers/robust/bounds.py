"""Lower bounds on the optimal worst case W* = min_S max_i cost(S minus i) (proofs in
docs/beyond-the-grid.md): one camera fewer (Lagrangian) and the mean failure (LP)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from camplace.problem.model import PlacementProblem
from camplace.solvers.bounds import lagrangian_bound
from camplace.solvers.highs_util import convex_model_nnz, highs_from_arrays, model_fits, run_highs
from camplace.solvers.mip import tight_model_arrays


def robust_bound(problem: PlacementProblem, coverage_hint: np.ndarray | None = None,
                 time_limit_s: float = 10.0, incumbent_cost: float | None = None) -> float | None:
    """Lower bound on min_S max_i cost(S minus i): a Lagrangian lower bound of the nominal
    problem with one camera fewer (None when N_s < 1)."""
    if problem.budget < 1:
        return None
    fewer = replace(problem, budget=problem.budget - 1)
    res = lagrangian_bound(fewer, time_limit_s=time_limit_s, coverage=coverage_hint, incumbent_cost=incumbent_cost)
    return max(0.0, float(res.bound))


def mean_failure_bound(problem: PlacementProblem, *, time_limit_s: float | None = 60.0,
                       threads: int | None = None, end: float = float("inf")) -> float | None:
    """Lower bound on min_S W(S) from the mean failure: for 1 <= |S| <= N_s,
    W(S) >= mean_s cost(S minus s) >= cost(S) + (1/N_s) Σ_s loss_s(S) = Σ_j w_j g_j(c_j) with
    g(c) = (Γ − c)+² + (c / N_s) ((Γ − c + 1)+² − (Γ − c)+²), a convex function of the coverage
    c (for N_s >= 2; proof in docs/beyond-the-grid.md), so min Σ_j w_j g_j(c_j) is a placement
    problem of the tight convex form with Γ_j + 1 units per target; its LP relaxation
    (HiGHS interior point + crossover) is the bound. None if the LP does not finish in
    time or N_s < 2, or when the LP cannot be built and started before the perf_counter()
    deadline ``end``."""
    n = problem.budget
    if n < 2 or not model_fits(end, convex_model_nnz(problem) + int(np.count_nonzero(problem.gamma))):
        return None
    g = np.asarray(problem.gamma, np.int64)
    arrays, lay = tight_model_arrays(replace(problem, gamma=np.where(g > 0, g + 1, 0)))
    G = g[lay.u_target].astype(np.float64)
    k = lay.u_k
    c = G + 1 - k  # unit k is the step from coverage c + 1 down to c
    d = G - c
    slope = np.where(k == 1, G / n, (2 * d - 1) + (2 * c - 2 * d + 1) / n)
    arrays.c[lay.n_x:] = problem.weights[lay.u_target] * slope
    h = highs_from_arrays(arrays, integer=False)
    out = run_highs(h, time_limit_s=time_limit_s, threads=threads, options={"solver": "ipm"}, end=end)
    if out.status != "optimal" or out.objective is None:
        return None
    val = float(out.objective)
    val -= 1e-7 * max(1.0, abs(val))  # the dual objective equals it up to HiGHS's tolerances
    return _round_up(problem, max(val, 0.0))


def _round_up(problem: PlacementProblem, bound: float) -> float:
    """Integer weights make every cost an integer: a bound may then be rounded up."""
    w = np.asarray(problem.weights)
    if np.all(w == np.round(w)):
        return float(np.ceil(bound - 1e-6))
    return bound



__all__ = ["mean_failure_bound", "robust_bound"]
