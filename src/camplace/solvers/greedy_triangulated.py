"""``greedy-triangulated``: greedy with the triangulation requirement.

A camera counts toward Γ_j only if it forms a well-conditioned pair at j with another
selected camera that sees j (camplace.problem.triangulation has the pair test). The solver
needs geometry, which it gets through the problem: ``problem.candidate_positions``
(N_g, 3) m and ``problem.target_positions`` (N_p, 3) m (set by
camplace.workflows.run.problem_from_visibility); the registry never reduces its problem.
"""

from __future__ import annotations

import time

import numba
import numpy as np

from camplace.core.errors import InputError
from camplace.problem.triangulation import DEFAULT_MAX_DEG, DEFAULT_MIN_DEG, apply_add, check_angle_range, pair_up
from camplace.problem.model import PlacementProblem, TypeBudget, shortfall_cost
from camplace.solvers.base import OnIncumbent, Placement, ProgressFn, ShouldStop, deadline, stopped
from camplace.solvers.contract import Tags, make_solver
from camplace.solvers.greedy import marginal_gains


@numba.njit(cache=True)
def _effective_after_add(i, indptr, indices, cp, tp, cams_of, n_cams, paired, eff, gamma, w, cos_lo, cos_hi, half):
    """Cost drop of adding candidate i on the surrogate coverage e_j + half * (unpaired views
    at j): per target j in row i, e_j grows by (i pairs with some camera at j) + (cameras at
    j that had no partner and pair with i). half > 0 lets a first camera in an empty area
    count for something (a pair needs two cameras, which a one-step greedy cannot see)."""
    gain = 0.0
    for e in range(indptr[i], indptr[i + 1]):
        j = indices[e]
        c0 = eff[j] + half * (n_cams[j] - eff[j])
        if gamma[j] <= c0:
            continue
        own, add = pair_up(i, j, cp, tp, cams_of, n_cams, paired, cos_lo, cos_hi, False)
        if own:
            add += 1
        e1 = eff[j] + add
        c1 = e1 + half * (n_cams[j] + 1 - e1)
        d0 = gamma[j] - c0
        d1 = max(gamma[j] - c1, 0.0)
        gain += w[j] * (d0 * d0 - d1 * d1)
    return gain


@numba.njit(cache=True)
def _gains_all(cand, indptr, indices, cp, tp, cams_of, n_cams, paired, eff, gamma, w, cos_lo, cos_hi, half):
    out = np.zeros(len(cand))
    for k in range(len(cand)):
        out[k] = _effective_after_add(cand[k], indptr, indices, cp, tp, cams_of, n_cams, paired, eff, gamma, w,
                                      cos_lo, cos_hi, half)
    return out


def positions_of(problem: PlacementProblem) -> tuple[np.ndarray, np.ndarray]:
    """(candidate positions (N_g, 3), target positions (N_p, 3)) float64 of the problem;
    InputError naming the field when one is missing or of the wrong shape."""
    out = []
    for key, n in (("candidate_positions", problem.n_candidates), ("target_positions", problem.n_targets)):
        a = getattr(problem, key)
        if a is None or np.shape(a) != (n, 3):
            raise InputError(f"problem.{key}: expected an ({n}, 3) array of positions (m), got "
                             f"{None if a is None else np.shape(a)}", option=key)
        out.append(np.ascontiguousarray(a, np.float64))
    return out[0], out[1]


def solve_greedy_triangulated(problem: PlacementProblem, *, time_limit_s: float | None = None,
                              threads: int | None = None, seed: int = 0, should_stop: ShouldStop | None = None,
                              progress: ProgressFn | None = None, on_incumbent: OnIncumbent | None = None,
                              min_deg: float = DEFAULT_MIN_DEG, max_deg: float = DEFAULT_MAX_DEG,
                              unpaired_weight: float = 0.5) -> Placement:
    """Greedy on the triangulation-aware cost Σ_j w_j max(Γ_j − e_j, 0)², where e_j counts
    only the selected cameras at j that form a pair meeting at an angle in [min_deg, max_deg].

    This cost is not submodular (a camera can make an earlier one count), so every step
    re-evaluates every candidate (numba, O(nnz · coverage) per step), by its gain on the
    surrogate coverage e_j + unpaired_weight · (views at j without a partner yet): with
    weight 0 a lone camera in an empty area gains nothing and the greedy only grows
    clusters. A step whose best gain is 0 adds the candidate with the largest
    plain-coverage gain instead. ``objective`` is the plain cost of the selection; the
    triangulation-aware cost is in ``info['triangulated_cost']``. Status 'heuristic', or
    'interrupted' / 'time_limit' (the selection so far)."""
    t0 = time.perf_counter()
    end = deadline(time_limit_s)
    cos_lo, cos_hi = check_angle_range(min_deg, max_deg)
    cp, tp = positions_of(problem)
    V = problem.V
    indptr, indices = V.indptr.astype(np.int64), V.indices.astype(np.int64)
    n_g, n_p = V.shape
    max_c = max(problem.budget, 1)
    cams_of = np.full((n_p, max_c), -1, np.int64)
    paired = np.zeros((n_p, max_c), np.bool_)
    n_cams = np.zeros(n_p, np.int64)
    eff = np.zeros(n_p, np.int64)
    cov = np.zeros(n_p, np.int64)
    gamma = problem.gamma.astype(np.int64)
    w = problem.weights.astype(np.float64)
    costs = problem.costs
    spent = 0.0
    used: set[int] = set()
    types = TypeBudget(problem) if problem.has_type_limits else None
    selected: list[int] = []
    status = "heuristic"
    while len(selected) < problem.budget:
        if stopped(should_stop) or time.perf_counter() >= end:
            status = "interrupted" if stopped(should_stop) else "time_limit"
            break
        allowed = np.ones(n_g, bool)
        if used:
            allowed &= ~np.isin(problem.location_ids, list(used))
        if problem.money_budget is not None:
            allowed &= costs + spent <= problem.money_budget + 1e-9
        if types is not None:
            allowed &= ~types.full()
        cand = np.flatnonzero(allowed)
        if len(cand) == 0:
            break
        g = _gains_all(cand, indptr, indices, cp, tp, cams_of, n_cams, paired, eff, gamma, w, cos_lo, cos_hi,
                       float(unpaired_weight))
        best = int(cand[int(np.argmax(g))])
        if g.max() <= 0:
            plain = marginal_gains(problem, cov)[cand]
            if plain.max() <= 0:
                break
            best = int(cand[int(np.argmax(plain))])
        apply_add(best, indptr, indices, cp, tp, cams_of, n_cams, paired, eff, cos_lo, cos_hi)
        cov[indices[indptr[best]:indptr[best + 1]]] += 1
        selected.append(best)
        used.add(int(problem.location_ids[best]))
        if types is not None:
            types.add(best)
        spent += float(costs[best])
        if progress is not None:
            progress("greedy-triangulated", len(selected), int(problem.budget))
    sel = np.array(sorted(selected), np.int64)
    cost = problem.cost(sel)
    if on_incumbent is not None:
        on_incumbent(cost, None)
    return Placement(sel, cost, None, status, "greedy-triangulated", time.perf_counter() - t0,
                     {"order": selected, "triangulated_cost": shortfall_cost(gamma, w, eff),
                      "angle_range_deg": [min_deg, max_deg]})


GREEDY_TRIANGULATED = make_solver("greedy-triangulated", solve_greedy_triangulated, Tags(needs_positions=True),
                                  summary="Greedy counting only well-triangulating pairs (needs positions)")


__all__ = ["GREEDY_TRIANGULATED", "positions_of", "solve_greedy_triangulated"]
