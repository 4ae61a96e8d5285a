"""A part of a placement problem with the rest of the cameras fixed (coverage offset).

When the cameras outside a set of candidate rows are fixed, they give each target c_j^out
views for free; what is left to cover is Γ_j' = max(Γ_j − c_j^out, 0), and for any
selection x of the rows

    w_j max(Γ_j − c_j^out − c_j(x), 0)² = w_j max(Γ_j' − c_j(x), 0)²      (c_j(x) >= 0)

so the part's cost (camplace.problem.gains.shortfall_cost on Γ') differs from the full
cost only by the constant cost of the targets the rows cannot see. Used by the zone
solver (camplace.solvers.zones) per tile; the existing-camera reduction of a site
(camplace.workflows.sites) is the same offset over all candidates.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from camplace.problem.gains import shortfall
from camplace.problem.model import PlacementProblem


def offset_gamma(gamma: np.ndarray, coverage_out: np.ndarray) -> np.ndarray:
    """(N_p,) int64 Γ' = max(Γ − c_out, 0): the views still missing when c_out are given."""
    return shortfall(gamma, coverage_out)


def offset_subproblem(problem: PlacementProblem, rows: np.ndarray, cols: np.ndarray, coverage_out: np.ndarray, *,
                      budget: int, money_budget: float | None = None,
                      type_limits: dict[int, int] | None = None) -> PlacementProblem:
    """The problem on candidate ``rows`` (k,) and targets ``cols`` (m,) (sorted ids) with the
    fixed cameras' coverage ``coverage_out`` (N_p,) as an offset (Γ' = max(Γ − c_out, 0)),
    at most ``budget`` cameras, ``money_budget`` and ``type_limits`` (the part's share of the
    global limits). Location ids, prices, types and positions are the rows' own; the
    part's cost + the cost of the targets outside ``cols`` = the full cost when every
    target a row sees is in ``cols``."""
    r = np.asarray(rows, np.int64)
    c = np.asarray(cols, np.int64)
    V = sp.csr_matrix(problem.V[r][:, c]) if len(r) else sp.csr_matrix((0, len(c)), dtype=problem.V.dtype)
    pick = lambda a, idx: None if a is None else np.asarray(a)[idx]  # noqa: E731
    limits = None if not type_limits else {int(k): max(0, int(v)) for k, v in type_limits.items()}
    return replace(problem, V=V, gamma=offset_gamma(problem.gamma[c], np.asarray(coverage_out)[c]),
                   weights=np.asarray(problem.weights, np.float64)[c], budget=max(0, int(budget)),
                   location_ids=np.asarray(problem.location_ids)[r], camera_costs=pick(problem.camera_costs, r),
                   money_budget=money_budget, candidate_positions=pick(problem.candidate_positions, r),
                   target_positions=pick(problem.target_positions, c), type_ids=pick(problem.type_ids, r),
                   type_limits=limits)


__all__ = ["offset_gamma", "offset_subproblem"]
