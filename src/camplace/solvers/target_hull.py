"""The per-target decomposition bound: each target's shortfall over its own integer
copy of the placement (proof and why it stops at the LP: docs/certify.md §10).

Give every target j its own copy y^j of the candidates C_j that see it, with the same
rules (≤ N cameras, ≤ 1 per location), and price the copy constraints y^j = x|C_j with
μ (one price per non-zero (i, j) of V, any sign). For every μ,

    OPT ≥ Σ_j h_j(μ_j) − max_{x∈X} Σ_i r_i x_i,   r_i = Σ_j μ_ij,
    h_j(μ_j) = min over y ∈ X_j of w_j (Γ_j − |y|)₊² + μ_j·y,

and h_j is exact in O(|C_j| log |C_j|): for c cameras the cheapest copy takes the c
smallest per-location minima of μ_j. This is the Lagrangian dual of the *per-target
convex hull* of the shortfall (the hull of {(y, w_j(Γ_j − |y|)₊²) : y ∈ X_j}); its
maximum over μ equals the LP bound exactly (§10), so it is a certificate that no per-target
strengthening of the shortfall's piecewise-linear model can pass the LP.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numba
import numpy as np
import scipy.sparse as sp

from camplace.problem.model import PlacementProblem
from camplace.solvers.bounds import BoundResult, StopFn
from camplace.solvers.region_bound import max_over_x

METHOD = "per-target decomposition (exact target subproblems)"


@numba.njit(cache=True, nogil=True)
def _target_parts(col_ptr, ent_loc, mu, gamma, weights, budget, y):
    """Σ_j h_j(μ_j) (see the module docstring) and, in y (nnz,) bool, the entries of
    each target's minimizing copy. Entries of column j are col_ptr[j]:col_ptr[j+1],
    grouped by location (ent_loc non-decreasing inside a column)."""
    n_p = col_ptr.shape[0] - 1
    width = 0
    for j in range(n_p):
        width = max(width, col_ptr[j + 1] - col_ptr[j])
    gmin = np.empty(width)
    garg = np.empty(width, np.int64)
    total = 0.0
    for j in range(n_p):
        a = col_ptr[j]
        b = col_ptr[j + 1]
        m = 0
        p = a
        while p < b:
            loc = ent_loc[p]
            best = mu[p]
            arg = p
            p += 1
            while p < b and ent_loc[p] == loc:
                if mu[p] < best:
                    best = mu[p]
                    arg = p
                p += 1
            gmin[m] = best
            garg[m] = arg
            m += 1
        order = np.argsort(gmin[:m])
        g = gamma[j]
        w = weights[j]
        best_val = w * g * g
        best_c = 0
        s = 0.0
        for c in range(1, min(m, budget) + 1):
            s += gmin[order[c - 1]]
            d = g - c
            f = w * d * d if d > 0 else 0.0
            if f + s < best_val:
                best_val = f + s
                best_c = c
        for c in range(best_c):
            y[garg[order[c]]] = True
        total += best_val
    return total


@dataclass
class TargetDecomposition:
    """The per-target decomposition of a problem: entries of V in column (target) order,
    grouped by location inside each column. `evaluate(mu)` is a valid lower bound on the
    optimal cost for any mu (nnz,) indexed like `ent_cand` / `ent_target`."""

    problem: PlacementProblem
    col_ptr: np.ndarray  # (N_p + 1,) int64
    ent_cand: np.ndarray  # (nnz,) int64 candidate of each entry
    ent_target: np.ndarray  # (nnz,) int64 target of each entry
    ent_loc: np.ndarray  # (nnz,) int64 dense location of each entry's candidate
    loc: np.ndarray  # (N_g,) int64 dense location of each candidate
    n_loc: int

    @classmethod
    def of(cls, problem: PlacementProblem) -> TargetDecomposition:
        coo = sp.coo_matrix(problem.V)
        rows = coo.row.astype(np.int64)
        cols = coo.col.astype(np.int64)
        _, loc = np.unique(problem.location_ids, return_inverse=True)
        loc = loc.astype(np.int64).ravel()
        order = np.lexsort((rows, loc[rows], cols))
        rows, cols = rows[order], cols[order]
        col_ptr = np.zeros(problem.n_targets + 1, np.int64)
        np.cumsum(np.bincount(cols, minlength=problem.n_targets), out=col_ptr[1:])
        return cls(problem, col_ptr, rows, cols, loc[rows], loc, int(loc.max()) + 1 if len(loc) else 0)

    def initial_prices(self, lam: np.ndarray) -> np.ndarray:
        """μ_ij = λ_j: at these prices the bound is ≥ L(λ) of the coverage-row Lagrangian (§10)."""
        return np.asarray(lam, np.float64)[self.ent_target].copy()

    def evaluate(self, mu: np.ndarray) -> tuple[float, np.ndarray]:
        """(lower bound, supergradient (nnz,)): y^j − x* restricted to each target's copy."""
        p = self.problem
        y = np.zeros(len(mu), np.bool_)
        parts = _target_parts(self.col_ptr, self.ent_loc, np.asarray(mu, np.float64), p.gamma.astype(np.int64),
                              p.weights.astype(np.float64), int(p.budget), y)
        r = np.bincount(self.ent_cand, weights=mu, minlength=p.n_candidates)
        x_val, x = max_over_x(r, self.loc, self.n_loc, int(p.budget))
        return float(parts - x_val), y.astype(np.float64) - x[self.ent_cand]


def target_hull_bound(problem: PlacementProblem, lam: np.ndarray, *, time_limit_s: float = 10.0,
                      incumbent_cost: float | None = None, max_iter: int = 100000,
                      should_stop: StopFn | None = None) -> BoundResult:
    """Subgradient ascent on the per-target prices μ from μ_ij = λ_j (Polyak steps toward
    `incumbent_cost`, else toward 1.05 × max(start, 1); step halved
    after 20 stalls, restarting from the best μ). Every evaluation is a valid bound; the
    best is returned (method METHOD; info: iterations, the start value)."""
    t0 = time.perf_counter()
    dec = TargetDecomposition.of(problem)
    mu = dec.initial_prices(lam)
    val, g = dec.evaluate(mu)
    start = best = val
    best_mu = mu.copy()
    target = incumbent_cost if incumbent_cost is not None else max(best, 1.0) * 1.05
    alpha, stall, it = 1.0, 0, 0
    while it < max_iter and time.perf_counter() - t0 < time_limit_s:
        if should_stop is not None and should_stop():
            break
        gn = float(np.dot(g, g))
        if gn <= 1e-12 or best >= target - 1e-9:
            break
        it += 1
        mu = mu + alpha * (target - val) / gn * g
        val, g = dec.evaluate(mu)
        if val > best + 1e-9 * max(1.0, abs(best)):
            best, best_mu, stall = val, mu.copy(), 0
        else:
            stall += 1
            if stall >= 20:
                alpha, stall = alpha * 0.5, 0
                mu = best_mu.copy()
                val, g = dec.evaluate(mu)
                if alpha < 1e-4:
                    break
    return BoundResult(max(best, 0.0), METHOD, time.perf_counter() - t0, None,
                       {"iterations": it, "start": start, "raw": best})
