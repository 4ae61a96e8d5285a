"""Single camera failures: what each selected camera's failure costs, the worst case, and
the ranking of essential cameras. W(S) = max_i cost(S minus i); the removal losses of all
selected cameras are one matrix-vector product (camplace.problem.gains.removal_losses)."""

from __future__ import annotations

import numpy as np

from camplace.problem.gains import removal_losses
from camplace.problem.model import PlacementProblem


def worst_case(problem: PlacementProblem, selected: np.ndarray) -> tuple[float, int | None]:
    """(max over single failures of the cost, candidate id of the worst failure or None)."""
    sel = np.asarray(selected, np.int64)
    cost = problem.cost(sel)
    if len(sel) == 0:
        return cost, None
    loss = removal_losses(problem, sel)
    k = int(np.argmax(loss))
    return cost + float(loss[k]), int(sel[k])


def essential_cameras(problem: PlacementProblem, selected: np.ndarray) -> list[dict]:
    """Selected cameras ranked by the cost added if each one fails (largest first):
    dicts with candidate_id, added_cost, cost_if_fails, coverage_gap_if_fails."""
    sel = np.asarray(selected, np.int64)
    cost = problem.cost(sel)
    loss = removal_losses(problem, sel)
    norm = problem.normalizer
    order = np.lexsort((sel, -loss))
    return [{"rank": r + 1, "candidate_id": int(sel[k]), "added_cost": float(loss[k]),
             "cost_if_fails": cost + float(loss[k]),
             "coverage_gap_if_fails": (cost + float(loss[k])) / norm if norm > 0 else 0.0}
            for r, k in enumerate(order)]



def _better(k1: tuple, k2: tuple, tol: float = 1e-9) -> bool:
    """Lexicographic k1 < k2 with a tolerance (shorter keys: fewer cameras, compare what exists)."""
    for x, y in zip(k1, k2):
        if x < y - tol:
            return True
        if x > y + tol:
            return False
    return False


def _key(problem: PlacementProblem, sel: np.ndarray) -> tuple[float, float]:
    """(worst single-failure cost, nominal cost) of a selection: the order of robust moves."""
    return worst_case(problem, sel)[0], problem.cost(sel)


__all__ = ["essential_cameras", "removal_losses", "worst_case"]
