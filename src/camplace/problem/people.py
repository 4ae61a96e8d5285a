"""The crowd-aware problem (issue 36): see the people, mixed with the empty store.

With P_V (N_g × M) the views of the points on the people of S crowd samples (Γ^p, weights
w^p already divided by S: camplace.targets.people), the crowd-aware cost of a selection x is

    (1 − λ) Σ_j w_j max(Γ_j − (V x)_j, 0)²  +  λ (N / N^p) Σ_k w^p_k max(Γ^p_k − (P_V x)_k, 0)²,

N = Σ_j w_j Γ_j², N^p = Σ_k w^p_k Γ^p_k², λ = ``people_weight``: the sample-average squared
shortfall of the people's points, mixed with the empty-store cost, each part scaled to the
same normaliser N. It is the ordinary cost of one PlacementProblem whose targets are the
empty-store targets (left out when λ = 1) followed by the people's points, so every solver,
bound and the refinement work on it unchanged; cost / N is the mixed coverage gap.

``persons_seen`` and ``persons_completed`` count the people whose every point is covered ≥ its
Γ^p (what metrics.json ``crowd.people.seen_by_gamma_pct`` counts on held-out crowds), for the
swap descent of ``people_cost: count`` (camplace.improve.people).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from camplace.core.errors import InputError
from camplace.problem.model import PlacementProblem
from camplace.problem.offset import offset_gamma
from camplace.targets.people import person_coverage


def part_weights(problem: PlacementProblem, gamma_p: np.ndarray, weights_p: np.ndarray,
                 people_weight: float, full_gamma: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(empty-store weights (N_p,), people weights (M,)) of the mixed cost (module doc);
    ``full_gamma``: the empty-store targets' Γ before any existing-camera offset (N uses it)."""
    lam = float(people_weight)
    g = np.asarray(problem.gamma if full_gamma is None else full_gamma, np.float64)
    norm = float(np.dot(problem.weights, g ** 2))
    norm_p = float(np.dot(weights_p, np.asarray(gamma_p, np.float64) ** 2))
    scale = lam * (norm if norm > 0 else 1.0) / norm_p if norm_p > 0 else 0.0
    return (1.0 - lam) * np.asarray(problem.weights, np.float64), scale * np.asarray(weights_p, np.float64)


def people_problem(problem: PlacementProblem, people_V: sp.csr_matrix, gamma_p: np.ndarray, weights_p: np.ndarray,
                   people_weight: float, people_positions: np.ndarray | None = None,
                   coverage_out: np.ndarray | None = None, full_gamma: np.ndarray | None = None) -> PlacementProblem:
    """The crowd-aware problem of ``problem`` (module doc). people_V (N_g, M) CSR; gamma_p,
    weights_p (M,); people_positions (M, 3) m (for solvers that need positions);
    ``coverage_out`` (M,): coverage of the people's points by fixed (existing) cameras, as
    the offset Γ^p' = max(Γ^p − c_out, 0); ``full_gamma`` as for part_weights."""
    lam = float(people_weight)
    if not 0.0 <= lam <= 1.0:
        raise InputError(f"people_weight: {lam} is not a share; expected 0 to 1", option="crowd")
    P = sp.csr_matrix(people_V, dtype=np.uint8)
    if P.shape[0] != problem.n_candidates:
        raise InputError(f"crowd: people rows {P.shape} do not match V {problem.V.shape}")
    w_e, w_p = part_weights(problem, gamma_p, weights_p, lam, full_gamma)
    g_p = np.asarray(gamma_p, np.int64)
    if coverage_out is not None:
        g_p = offset_gamma(g_p, np.asarray(coverage_out, np.int64))
    tp = problem.target_positions
    pp = None if people_positions is None else np.asarray(people_positions, np.float64).reshape(-1, 3)
    if lam >= 1.0:  # only the people
        return replace(problem, V=P, gamma=g_p, weights=w_p, target_positions=pp if tp is not None else None)
    V = sp.hstack([problem.V, P], format="csr", dtype=np.uint8)
    V.sort_indices()
    pos = None if tp is None or pp is None else np.r_[np.asarray(tp, np.float64), pp]
    return replace(problem, V=V, gamma=np.r_[np.asarray(problem.gamma, np.int64), g_p], weights=np.r_[w_e, w_p],
                   target_positions=pos)


def persons_seen(coverage: np.ndarray, gamma: np.ndarray, n_heights: int) -> int:
    """How many people have every point covered ≥ its Γ: coverage, gamma (P · H,) of the
    points on P people, H = n_heights points each (person p: points p · H .. p · H + H − 1)."""
    d = np.asarray(coverage, np.int64) - np.asarray(gamma, np.int64)
    return int(np.sum(person_coverage(d, n_heights) >= 0))


def persons_completed(V: sp.csr_matrix, coverage: np.ndarray, gamma: np.ndarray, n_heights: int) -> np.ndarray:
    """(N_g,) int64: for each row of V (N_g, P · H: views of the points, as persons_seen), how
    many people not yet seen (some point below its Γ at ``coverage``) have every point covered
    ≥ its Γ once that row's camera is added. A person counts when each point is at Γ − 1 or
    more and the row sees every point at exactly Γ − 1."""
    V = sp.csr_matrix(V)
    H = int(n_heights)
    d = np.asarray(coverage, np.int64) - np.asarray(gamma, np.int64)
    n_persons = len(d) // H
    near = person_coverage(d, H) == -1  # one view short at one or more points, none further
    person = np.arange(len(d), dtype=np.int64) // H
    need = np.flatnonzero((d == -1) & near[person])
    if len(need) == 0 or V.shape[0] == 0:
        return np.zeros(V.shape[0], np.int64)
    n_need = np.bincount(person[need], minlength=n_persons)
    A = sp.csr_matrix((np.ones(len(need), np.int32), (need, person[need])), shape=(len(d), n_persons))
    Y = sp.csr_matrix(V.astype(np.int32) @ A)
    done = Y.data == n_need[Y.indices]
    rows = np.repeat(np.arange(V.shape[0], dtype=np.int64), np.diff(Y.indptr))
    return np.bincount(rows[done], minlength=V.shape[0]).astype(np.int64)


def mixed_rows(rows: sp.csr_matrix, people_rows: sp.csr_matrix, people_weight: float) -> sp.csr_matrix:
    """New poses' rows of the crowd-aware problem: [rows | people_rows] (people_rows alone when λ = 1)."""
    P = sp.csr_matrix(people_rows, dtype=np.uint8)
    if float(people_weight) >= 1.0:
        return P
    out = sp.hstack([sp.csr_matrix(rows, dtype=np.uint8), P], format="csr", dtype=np.uint8)
    out.sort_indices()
    return out


__all__ = ["mixed_rows", "part_weights", "people_problem", "persons_completed", "persons_seen"]
