"""Stage 5 - the placement problem: V, Γ, weights, budget and location groups.

Solvers see only this object (no geometry). The cost of a selection x is
Σ_j w_j · max(Γ_j − Σ_i V_ij x_i, 0)²  (paper eq. 1 with weights).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from camplace.errors import InputError


def shortfall_cost(gamma: np.ndarray, weights: np.ndarray, coverage: np.ndarray) -> float:
    """Σ_j w_j max(Γ_j − c_j, 0)²; all (N_p,)."""
    short = np.maximum(np.asarray(gamma, np.int64) - np.asarray(coverage, np.int64), 0).astype(np.float64)
    return float(np.dot(weights, short * short))


@dataclass(frozen=True)
class PlacementProblem:
    """V: (N_g, N_p) CSR 0/1; gamma: (N_p,) int64; weights: (N_p,) float64;
    budget: at most this many cameras; location_ids: (N_g,) int64, at most one camera
    per location; camera_costs: (N_g,) float64 price of each candidate (default 1)."""

    V: sp.csr_matrix
    gamma: np.ndarray
    weights: np.ndarray
    budget: int
    location_ids: np.ndarray
    camera_costs: np.ndarray | None = None
    money_budget: float | None = None  # Σ camera_costs[selected] must not exceed this (None: no limit)

    def __post_init__(self) -> None:
        n_g, n_p = self.V.shape
        if self.gamma.shape != (n_p,) or self.weights.shape != (n_p,):
            raise InputError(f"problem: gamma/weights must have shape ({n_p},) to match V {self.V.shape}")
        if self.location_ids.shape != (n_g,):
            raise InputError(f"problem: location_ids must have shape ({n_g},) to match V {self.V.shape}")
        if self.budget < 0:
            raise InputError(f"problem: budget must be >= 0, got {self.budget}")
        if np.any(self.gamma < 0):
            raise InputError("problem: gamma must be non-negative integers")
        if self.money_budget is not None and not self.money_budget >= 0:
            raise InputError(f"problem: money_budget must be >= 0, got {self.money_budget}")

    @property
    def n_candidates(self) -> int:
        return int(self.V.shape[0])

    @property
    def n_targets(self) -> int:
        return int(self.V.shape[1])

    @property
    def normalizer(self) -> float:
        """Σ_j w_j Γ_j², the cost of placing no camera (denominator of paper eq. 8)."""
        g = self.gamma.astype(np.float64)
        return float(np.dot(self.weights, g * g))

    def coverage(self, selected: np.ndarray) -> np.ndarray:
        """(N_p,) int64: how many selected candidates see each target."""
        sel = np.asarray(selected, dtype=np.int64)
        cov = np.zeros(self.n_targets, np.int64)
        if len(sel):
            rows = self.V[sel]
            np.add.at(cov, rows.indices, 1)
        return cov

    def cost(self, selected: np.ndarray) -> float:
        return shortfall_cost(self.gamma, self.weights, self.coverage(selected))

    def check_feasible(self, selected: np.ndarray) -> None:
        """Raise ValueError if the selection breaks the budget or the one-per-location rule."""
        sel = np.asarray(selected, dtype=np.int64)
        if len(np.unique(sel)) != len(sel):
            raise ValueError("a candidate is selected twice")
        if len(sel) > self.budget:
            raise ValueError(f"{len(sel)} cameras exceed the budget {self.budget}")
        if len(sel) and (sel.min() < 0 or sel.max() >= self.n_candidates):
            raise ValueError("candidate id out of range")
        locs = self.location_ids[sel]
        if len(np.unique(locs)) != len(locs):
            raise ValueError("two selected cameras share a location")
        if self.money_budget is not None and len(sel):
            spent = float(self.costs[sel].sum())
            if spent > self.money_budget + 1e-9 * max(1.0, self.money_budget):
                raise ValueError(f"cameras cost {spent:g}, over the money budget {self.money_budget:g}")

    @property
    def costs(self) -> np.ndarray:
        """(N_g,) float64 price of each candidate (camera_costs, or 1 each when not given)."""
        if self.camera_costs is None:
            return np.ones(self.n_candidates)
        return np.asarray(self.camera_costs, np.float64)


def build_problem(V: sp.csr_matrix, gamma: np.ndarray, weights: np.ndarray | None, budget: int,
                  location_ids: np.ndarray | None = None) -> PlacementProblem:
    """Problem from arrays; location_ids default to one location per candidate."""
    V = sp.csr_matrix(V)
    n_g, n_p = V.shape
    w = np.ones(n_p) if weights is None else np.asarray(weights, np.float64)
    loc = np.arange(n_g, dtype=np.int64) if location_ids is None else np.asarray(location_ids, np.int64)
    return PlacementProblem(V, np.asarray(gamma, np.int64), w, int(budget), loc)
