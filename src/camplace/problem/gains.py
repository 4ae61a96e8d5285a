"""Gains and costs of the squared shortfall, in one place (numpy and numba side by side).

With coverage c_j (views of target j), the deficit is d_j = max(Γ_j − c_j, 0) and the cost
Σ_j w_j d_j². One more view of target j lowers its cost by

    g_j(c) = w_j (d0² − d1²),  d0 = max(Γ_j − c_j, 0),  d1 = max(d0 − 1, 0)   (= w_j (2 d0 − 1) if d0 > 0)

and one view fewer raises it by g_j(c − 1). A candidate's gain is the sum of g_j over its
row of V (V @ g), a selected camera's removal loss the sum of g_j(c − 1) over its row.

The numpy functions take arrays, or any ``problem`` with ``V`` (CSR, N_g × N_p), ``gamma``,
``weights`` (N_p,) and ``coverage(selected)``; the ``*_nb`` functions are numba kernels
for the compiled solvers (tabu) on CSR arrays (indptr, indices).
"""

from __future__ import annotations

from typing import Protocol

import numba
import numpy as np
import scipy.sparse as sp


class GainProblem(Protocol):
    """What the gain functions need of a placement problem."""

    V: sp.csr_matrix
    gamma: np.ndarray
    weights: np.ndarray

    def coverage(self, selected: np.ndarray) -> np.ndarray: ...


# --------------------------------------------------------------------------- per target (N_p,)


def shortfall(gamma: np.ndarray, coverage: np.ndarray) -> np.ndarray:
    """(N_p,) int64 deficit max(Γ_j − c_j, 0)."""
    return np.maximum(np.asarray(gamma, np.int64) - np.asarray(coverage, np.int64), 0)


def target_costs(gamma: np.ndarray, weights: np.ndarray, coverage: np.ndarray) -> np.ndarray:
    """(N_p,) float64 w_j max(Γ_j − c_j, 0)²."""
    d = shortfall(gamma, coverage).astype(np.float64)
    return weights * d * d


def shortfall_cost(gamma: np.ndarray, weights: np.ndarray, coverage: np.ndarray) -> float:
    """Σ_j w_j max(Γ_j − c_j, 0)²; all (N_p,). (einsum, not np.dot: OpenBLAS runs a dot of
    over ~10,000 terms on a thread team, which costs milliseconds on a loaded machine.)"""
    short = shortfall(gamma, coverage).astype(np.float64)
    return float(np.einsum("i,i->", np.asarray(weights, np.float64), short * short))


def target_gains(gamma: np.ndarray, weights: np.ndarray, coverage: np.ndarray) -> np.ndarray:
    """(N_p,) float64 g_j: cost drop from one more view of target j at coverage c."""
    d0 = shortfall(gamma, coverage).astype(np.float64)
    d1 = np.maximum(d0 - 1, 0)
    return weights * (d0 * d0 - d1 * d1)


def target_losses(gamma: np.ndarray, weights: np.ndarray, coverage: np.ndarray) -> np.ndarray:
    """(N_p,) float64: cost rise from one view fewer of target j at coverage c (g_j(c − 1))."""
    return target_gains(gamma, weights, np.asarray(coverage, np.int64) - 1)


# --------------------------------------------------------------------------- per candidate


def row(V: sp.csr_matrix, i: int) -> np.ndarray:
    """Target ids (columns) of row i of a CSR matrix."""
    return V.indices[V.indptr[i]:V.indptr[i + 1]]


def marginal_gains(problem: GainProblem, coverage: np.ndarray) -> np.ndarray:
    """(N_g,) float64: cost drop of adding each candidate to a selection with this coverage."""
    return np.asarray(problem.V @ target_gains(problem.gamma, problem.weights, coverage)).ravel()


def row_gain(problem: GainProblem, i: int, coverage: np.ndarray) -> float:
    """Cost drop of adding candidate i at this coverage (one row: O(|row i|))."""
    cols = row(problem.V, i)
    d = problem.gamma[cols] - coverage[cols]
    pos = d > 0
    return float(np.dot(problem.weights[cols][pos], 2 * d[pos] - 1))


def removal_losses(problem: GainProblem, selected: np.ndarray, coverage: np.ndarray | None = None) -> np.ndarray:
    """(k,) cost added when each selected camera (in the given order) fails alone;
    ``coverage`` (N_p,) is the selection's (computed when None)."""
    sel = np.asarray(selected, np.int64)
    if len(sel) == 0:
        return np.zeros(0)
    c = problem.coverage(sel) if coverage is None else coverage
    h = target_losses(problem.gamma, problem.weights, c)
    return np.asarray(problem.V[sel].astype(np.float64) @ h).ravel()


# --------------------------------------------------------------------------- numba kernels


@numba.njit(cache=True)
def target_gain_nb(w, g, c):
    """Cost drop for one more view of a target with weight w, Γ = g, coverage c."""
    d = g - c
    if d > 0:
        return w * (2 * d - 1)
    return 0.0


@numba.njit(cache=True)
def row_gain_nb(i, indptr, indices, gamma, weights, cov):
    """Cost drop of adding candidate i (CSR row i) at coverage cov."""
    s = 0.0
    for p in range(indptr[i], indptr[i + 1]):
        j = indices[p]
        s += target_gain_nb(weights[j], gamma[j], cov[j])
    return s


@numba.njit(cache=True)
def row_loss_nb(r, indptr, indices, gamma, weights, cov):
    """Cost rise of removing selected candidate r (CSR row r) from coverage cov."""
    s = 0.0
    for p in range(indptr[r], indptr[r + 1]):
        j = indices[p]
        s += target_gain_nb(weights[j], gamma[j], cov[j] - 1)
    return s


__all__ = ["GainProblem", "marginal_gains", "removal_losses", "row", "row_gain", "row_gain_nb", "row_loss_nb",
           "shortfall", "shortfall_cost", "target_costs", "target_gain_nb", "target_gains", "target_losses"]
