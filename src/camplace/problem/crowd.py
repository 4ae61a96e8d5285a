"""Crowds as scenarios (issue 28): the one home of the stacking.

Crowd sample s thins V to V_s ⊆ V (camplace.visibility.crowd). The sample-average crowd
cost of a selection x,

    (1/S) Σ_s Σ_j w_j max(Γ_j − Σ_i V_s,ij x_i, 0)²,

is the ordinary cost of a PlacementProblem whose targets are S stacked copies of the
targets (column s · N_p + j = target j in sample s, weight w_j / S, Γ_j) and whose V is
[V_1 | V_2 | ... | V_S]: so every solver, bound and the refinement work on it unchanged.
Its normaliser Σ_s Σ_j (w_j / S) Γ_j² equals the problem's, so cost / normaliser is the
crowd coverage gap averaged over the samples (paper eq. 8).
"""

from __future__ import annotations

from dataclasses import replace

import numba
import numpy as np
import scipy.sparse as sp

from camplace.core.errors import InputError
from camplace.problem.model import PlacementProblem
from camplace.problem.offset import offset_gamma


@numba.njit(cache=True)
def _interleave(src_ptr, src_idx, S, n, n_p, out_ptr, out_idx):  # pragma: no cover - compiled
    """Row i of the output = the pieces of source rows s · n + i, s = 0..S-1, columns + s · n_p."""
    pos = 0
    for i in range(n):
        out_ptr[i] = pos
        for s in range(S):
            r = s * n + i
            off = s * n_p
            for e in range(src_ptr[r], src_ptr[r + 1]):
                out_idx[pos] = src_idx[e] + off
                pos += 1
    out_ptr[n] = pos


def side_by_side(rows: sp.csr_matrix, n_samples: int) -> sp.csr_matrix:
    """(S · n, N_p) vertical stack (row s · n + i = row i of V_s) -> (n, S · N_p) CSR uint8
    whose row i is [V_1 row i | ... | V_S row i] (column s · N_p + j). Sorted indices stay
    sorted; one compiled pass, never dense."""
    rows = sp.csr_matrix(rows)
    S = int(n_samples)
    if S < 1 or rows.shape[0] % S:
        raise InputError(f"crowd: {rows.shape[0]} rows are not {S} samples of equal size")
    n, n_p = rows.shape[0] // S, rows.shape[1]
    indptr = np.empty(n + 1, np.int64)
    indices = np.empty(rows.nnz, np.int32 if S * n_p < 2**31 else np.int64)
    _interleave(np.asarray(rows.indptr, np.int64), rows.indices, S, n, n_p, indptr, indices)
    return sp.csr_matrix((np.ones(rows.nnz, np.uint8), indices, indptr), shape=(n, S * n_p))


def stacked_problem(problem: PlacementProblem, rows: sp.csr_matrix, n_samples: int,
                    coverage_out: np.ndarray | None = None) -> PlacementProblem:
    """The sample-average crowd problem of ``problem`` (N_g × N_p, full Γ): ``rows`` the
    vertical stack of its V_s (camplace.visibility.crowd.crowd_rows, (S · N_g, N_p)).
    ``coverage_out`` (S, N_p): coverage by fixed cameras in each sample (existing cameras,
    thinned by the same crowds), as the offset Γ_s' = max(Γ − c_out,s, 0)."""
    S = int(n_samples)
    V = side_by_side(rows, S)
    if V.shape[0] != problem.n_candidates or V.shape[1] != S * problem.n_targets:
        raise InputError(f"crowd: stacked V {V.shape} does not match {S} samples of V {problem.V.shape}")
    gamma = np.tile(np.asarray(problem.gamma, np.int64), S)
    if coverage_out is not None:
        gamma = offset_gamma(gamma, np.asarray(coverage_out, np.int64).ravel())
    tp = problem.target_positions
    return replace(problem, V=V, gamma=gamma, weights=np.tile(np.asarray(problem.weights, np.float64) / S, S),
                   target_positions=None if tp is None else np.tile(np.asarray(tp, np.float64), (S, 1)))


def per_sample(values: np.ndarray, n_samples: int) -> np.ndarray:
    """(S · N_p,) values over stacked targets -> (S, N_p): row s = sample s."""
    v = np.asarray(values)
    return v.reshape(int(n_samples), -1)


def sample_coverage(rows: sp.csr_matrix, n_samples: int, selected: np.ndarray) -> np.ndarray:
    """(S, N_p) int64 coverage of ``selected`` (rows of V, (k,)) in each sample, from the
    vertical stack ``rows`` (S · n, N_p)."""
    S = int(n_samples)
    n, n_p = rows.shape[0] // S, rows.shape[1]
    sel = np.asarray(selected, np.int64)
    pick = (np.arange(S, dtype=np.int64)[:, None] * n + sel[None, :]).ravel()
    sub = sp.csr_matrix(rows)[pick]
    counts = np.diff(sub.indptr)
    which = np.repeat(np.repeat(np.arange(S, dtype=np.int64), len(sel)), counts)
    return np.bincount(which * n_p + sub.indices, minlength=S * n_p).reshape(S, n_p).astype(np.int64)


__all__ = ["per_sample", "sample_coverage", "side_by_side", "stacked_problem"]
