"""Camera catalogue: greedy with cost-scaled gains under a money budget.

With cameras of several prices and a money budget B (Σ_i price_i x_i <= B) the plain
greedy (largest cost drop first) can spend the budget on expensive cameras. The
cost-effective greedy adds the candidate with the largest drop *per unit price*; on
its own it can miss one expensive camera worth more than many cheap ones, so, as in
the budgeted submodular maximisation of Khuller, Moss & Naor (1999) and CELF (Leskovec
et al. 2007), both runs are made and the better selection is returned (a constant-factor
guarantee for the monotone submodular cost drop when the number-of-cameras budget does
not bind). Both use the lazy (CELF) evaluation of ``camplace.solvers.greedy``: a
submodular gain divided by a fixed price still only shrinks. Optional 1-swap descent
afterwards (``local_search=True``) keeps the budget, the money budget and one camera
per location.

The two greedy runs (``cost_scaled_greedy``, ``solve_catalogue_greedy``, registered as
solver 'greedy-money') live in camplace.solvers.greedy, next to the plain greedy that
delegates to them under a money budget; this module keeps the repair for solvers whose
moves ignore prices.
"""

from __future__ import annotations

import numpy as np

from camplace.problem.gains import removal_losses
from camplace.problem.model import PlacementProblem, TypeBudget
from camplace.solvers.greedy import (MIN_PRICE, cost_scaled_greedy, marginal_gains, solve_catalogue_greedy,
                                     swap_local_search)


def fill(problem: PlacementProblem, sel: list[int], cov: np.ndarray, price: np.ndarray | None = None) -> None:
    """Greedy additions to ``sel`` (largest gain, or gain / price) while the budget allows
    and some candidate every rule allows (free location, type not full, money budget)
    lowers the cost; ``sel`` and its coverage ``cov`` (N_p,) are updated in place."""
    V = problem.V
    used = set(problem.location_ids[sel].tolist())
    while len(sel) < problem.budget:
        g = marginal_gains(problem, cov) if price is None else marginal_gains(problem, cov) / price
        ok = ~np.isin(problem.location_ids, list(used)) & (g > 0) & ~TypeBudget(problem, sel).full()
        if problem.money_budget is not None:
            ok &= problem.costs <= problem.money_budget - float(problem.costs[sel].sum()) + 1e-9
        if not ok.any():
            break
        j = int(np.argmax(np.where(ok, g, -np.inf)))
        sel.append(j)
        used.add(int(problem.location_ids[j]))
        cov[V.indices[V.indptr[j]:V.indptr[j + 1]]] += 1


def repair_to_money_budget(problem: PlacementProblem, selected: np.ndarray, *, end: float = float("inf"),
                           compare_greedy: bool = True) -> np.ndarray:
    """Make any selection respect the money budget (for solvers whose moves ignore prices):
    drop the least cost-effective camera (smallest cost rise per unit price) until the
    total price fits, fill with cost-scaled greedy additions that still fit, then 1-swap
    descent (which keeps the money budget). A selection that already fits is only
    improved, never made worse; with compare_greedy the cost-scaled greedy + 1-swap is
    returned instead when it is better. Returns sorted candidate ids."""
    sel = [int(i) for i in np.asarray(selected, np.int64)]
    if problem.money_budget is None:
        return np.array(sorted(sel), np.int64)
    price = np.maximum(problem.costs, MIN_PRICE)
    V = problem.V
    cov = problem.coverage(np.array(sel, np.int64))
    while sel and float(problem.costs[sel].sum()) > problem.money_budget + 1e-9:
        loss = removal_losses(problem, np.array(sel), cov) / price[sel]
        k = int(np.argmin(loss))
        i = sel.pop(k)
        cov[V.indices[V.indptr[i]:V.indptr[i + 1]]] -= 1
    fill(problem, sel, cov, price)
    sel, _, _ = swap_local_search(problem, sel, end=end)
    out = np.array(sorted(int(i) for i in sel), np.int64)
    if compare_greedy:  # never worse than the catalogue greedy + 1-swap
        g = solve_catalogue_greedy(problem, local_search=True).selected
        if problem.cost(g) < problem.cost(out) - 1e-9:
            out = g
    return out


def repair_to_type_limits(problem: PlacementProblem, selected: np.ndarray, *,
                          end: float = float("inf")) -> np.ndarray:
    """Make any selection keep the per-type limits (problem.type_limits; for solvers whose
    moves ignore them): while a type is over its limit drop its camera whose removal raises
    the cost least, fill with greedy additions every rule allows (free location, type not
    full, money budget), then 1-swap descent (which keeps every rule). A selection that
    already fits is only improved, never made worse. Returns sorted candidate ids."""
    sel = [int(i) for i in np.asarray(selected, np.int64)]
    if not problem.has_type_limits:
        return np.array(sorted(sel), np.int64)
    V = problem.V
    cov = problem.coverage(np.array(sel, np.int64))
    lt = problem.limited_types()
    for t, limit in problem.type_limits.items():
        while sum(1 for i in sel if lt[i] == int(t)) > int(limit):
            mine = [k for k, i in enumerate(sel) if lt[i] == int(t)]
            loss = removal_losses(problem, np.array([sel[k] for k in mine]), cov)
            i = sel.pop(mine[int(np.argmin(loss))])
            cov[V.indices[V.indptr[i]:V.indptr[i + 1]]] -= 1
    fill(problem, sel, cov)
    sel, _, _ = swap_local_search(problem, sel, end=end)
    return np.array(sorted(int(i) for i in sel), np.int64)


__all__ = ["cost_scaled_greedy", "repair_to_money_budget", "repair_to_type_limits", "solve_catalogue_greedy"]
