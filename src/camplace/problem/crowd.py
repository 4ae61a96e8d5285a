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

import numpy as np
import scipy.sparse as sp

from camplace.core.errors import InputError
from camplace.problem.model import PlacementProblem
from camplace.problem.offset import offset_gamma


def side_by_side(rows: sp.csr_matrix, n_samples: int) -> sp.csr_matrix:
    """(S · n, N_p) vertical stack (row s · n + i = row i of V_s) -> (n, S · N_p) CSR uint8
    whose row i is [V_1 row i | ... | V_S row i] (column s · N_p + j). Sorted indices stay
    sorted; vectorised, never dense."""
    rows = sp.csr_matrix(rows)
    S = int(n_samples)
    if S < 1 or rows.shape[0] % S:
        raise InputError(f"crowd: {rows.shape[0]} rows are not {S} samples of equal size")
    n, n_p = rows.shape[0] // S, rows.shape[1]
    lengths = np.diff(rows.indptr).astype(np.int64).reshape(S, n)
    indptr = np.r_[0, np.cumsum(lengths.sum(0))].astype(np.int64)
    start = indptr[:-1][None, :] + np.cumsum(lengths, axis=0) - lengths  # (S, n) where each piece goes
    shift = np.repeat((start.ravel() - rows.indptr[:-1]).astype(np.int64), lengths.ravel())
    dest = shift + np.arange(rows.nnz, dtype=np.int64)
    offset = np.repeat(np.arange(S, dtype=np.int64) * n_p, lengths.sum(1))
    indices = np.empty(rows.nnz, np.int64)
    indices[dest] = rows.indices + offset
    idx = indices.astype(np.int32) if S * n_p < 2**31 else indices
    return sp.csr_matrix((np.ones(rows.nnz, np.uint8), idx, indptr), shape=(n, S * n_p))


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
