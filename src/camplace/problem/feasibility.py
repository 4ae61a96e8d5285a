"""Sanity checks between stages: which targets can never reach their coverage.

A target that no candidate sees cannot be covered by any placement; one seen from
fewer distinct mount locations than its Γ cannot reach Γ (one camera per location).
Both are facts about the input (the scene, its mounts, its cameras), reported as a
warning, or as an error when the caller requires a feasible instance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
import scipy.sparse as sp


@dataclass(frozen=True)
class Feasibility:
    """unseen: (k,) int64 ids of targets with Γ > 0 that no candidate sees;
    short: (m,) int64 ids of targets seen from fewer distinct locations than Γ (unseen
    ones included); per-region counts of both in ``by_region`` (name -> (unseen, short))."""

    unseen: np.ndarray
    short: np.ndarray
    by_region: dict[str, tuple[int, int]]
    n_targets: int

    @property
    def ok(self) -> bool:
        return len(self.short) == 0

    def describe(self, positions: np.ndarray, region_ids: np.ndarray, region_names: tuple[str, ...],
                 examples: int = 3) -> str:
        """One line: counts, a few positions and the regions of the problem targets."""
        def pts(ids: np.ndarray) -> str:
            return ", ".join("(" + ", ".join(f"{v:.2f}" for v in positions[j]) + ")" for j in ids[:examples])

        parts = []
        if len(self.unseen):
            regs = ", ".join(f"{n}: {u}" for n, (u, _) in self.by_region.items() if u)
            parts.append(f"{len(self.unseen)} of {self.n_targets} targets are seen by no candidate "
                         f"({regs}; e.g. at {pts(self.unseen)} m)")
        only_short = np.setdiff1d(self.short, self.unseen)
        if len(only_short):
            regs = ", ".join(f"{n}: {s - u}" for n, (u, s) in self.by_region.items() if s - u)
            parts.append(f"{len(only_short)} more are seen from fewer mount locations than their required "
                         f"coverage ({regs}; e.g. at {pts(only_short)} m)")
        return "; ".join(parts) if parts else "every target can reach its required coverage"


@numba.njit(cache=True)
def _seen_and_locations(indptr, indices, order, loc, n_p):
    """((N_p,) candidates seeing each target, (N_p,) distinct locations seeing it): rows
    visited in ``order`` (grouped by location ``loc``), O(N_p) memory beyond V."""
    seen = np.zeros(n_p, np.int64)
    n_loc = np.zeros(n_p, np.int64)
    last = np.full(n_p, -1, np.int64)
    for i in order:
        L = loc[i]
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            seen[j] += 1
            if last[j] != L:
                last[j] = L
                n_loc[j] += 1
    return seen, n_loc


def check_feasibility(V: sp.csr_matrix, gamma: np.ndarray, location_ids: np.ndarray,
                      region_ids: np.ndarray, region_names: tuple[str, ...]) -> Feasibility:
    """V: (N_g, N_p) CSR 0/1; gamma: (N_p,); location_ids: (N_g,); region_ids: (N_p,)."""
    n_g, n_p = V.shape
    gamma = np.asarray(gamma, np.int64)
    if n_g:  # distinct locations per target, one pass over V's rows grouped by location (no copy of V)
        _, loc = np.unique(np.asarray(location_ids), return_inverse=True)
        loc = loc.astype(np.int64).ravel()
        seen, n_loc = _seen_and_locations(np.asarray(V.indptr, np.int64), V.indices,
                                          np.argsort(loc, kind="stable"), loc, n_p)
    else:
        seen = n_loc = np.zeros(n_p, np.int64)
    unseen = np.nonzero((gamma > 0) & (seen == 0))[0]
    short = np.nonzero(n_loc < gamma)[0]
    by_region = {}
    for r, name in enumerate(region_names):
        by_region[name] = (int(np.sum(region_ids[unseen] == r)), int(np.sum(region_ids[short] == r)))
    return Feasibility(unseen.astype(np.int64), short.astype(np.int64), by_region, int(n_p))
