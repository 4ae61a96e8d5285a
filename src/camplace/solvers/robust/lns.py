"""Large-neighbourhood search for the robust placement, with the scenario MIP as the repair."""

from __future__ import annotations

import time

import numpy as np

from camplace.problem.gains import removal_losses
from camplace.problem.model import PlacementProblem
from camplace.solvers.base import stopped
from camplace.solvers.robust.failures import _better, _key
from camplace.solvers.robust.scenario import scenario_mip

# Small sub-MIPs (tens of binaries): HiGHS presolve and its sub-MIP heuristics (RINS, RENS)
# cost 3-4 times the search itself (measured on standard-store neighbourhoods).
FAST_SUB_MIP = {"presolve": "off", "mip_heuristic_effort": 0.0, "mip_heuristic_run_rins": False,
                "mip_heuristic_run_rens": False}


def robust_lns(problem: PlacementProblem, start: np.ndarray, *, time_limit_s: float | None = 60.0,
               sub_time_s: float = 20.0, free_sizes: tuple[int, ...] = (2, 3, 5, 8), pool_size: int = 30,
               anchors: int = 3, donors: int = 2, seed: int = 0, t_lower: float = 0.0,
               should_stop=None) -> tuple[np.ndarray, dict]:
    """Large-neighbourhood search with the scenario MIP: pick an anchor (one of the
    ``anchors`` cameras whose failure costs most), free the k selected cameras sharing
    the most targets with it (k from ``free_sizes``), keep the others fixed, and solve the
    scenario MIP over a pool of the ``pool_size`` candidates that see the most still-needed
    targets of the freed cameras' rows (plus the freed cameras), with ``sub_time_s``.
    Accept when (W, nominal cost) drops lexicographically and start over from the worst
    camera; stop when every (anchor, k) pair fails, at the time limit or on should_stop.
    Deterministic for a seed when no sub-MIP hits its time limit."""
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    V = problem.V
    Vf = V.astype(np.float64)
    sel = np.unique(np.asarray(start, np.int64))
    best = _key(problem, sel)
    eps = 0.1 * float(np.min(problem.weights[problem.weights > 0], initial=1.0)) / max(problem.normalizer, 1.0)
    tries = accepted = 0
    attempt = 0
    history: list[dict] = []
    stopped_by = "converged"
    n_try = anchors * len(free_sizes)
    while attempt < n_try and len(sel):
        left = None if time_limit_s is None else time_limit_s - (time.perf_counter() - t0)
        if left is not None and left <= 0.5:
            stopped_by = "time_limit"
            break
        if stopped(should_stop):
            stopped_by = "interrupted"
            break
        loss = removal_losses(problem, sel)
        order = np.lexsort((sel, -loss))
        a = int(sel[order[attempt % min(anchors, len(sel))]])
        k = min(free_sizes[attempt // anchors], len(sel))
        ind = np.zeros(problem.n_targets)
        ind[V.indices[V.indptr[a]:V.indptr[a + 1]]] = 1.0
        ov = np.asarray(Vf[sel] @ ind).ravel()
        ov[sel == a] = np.inf
        free = sel[np.lexsort((sel, -ov))[:k]]
        if donors:  # and the cameras whose failure costs least: moving one may back up the anchor
            rest = np.flatnonzero(~np.isin(sel, free))
            free = np.r_[free, sel[rest[np.lexsort((sel[rest], loss[rest]))[:donors]]]]
        fixed = np.setdiff1d(sel, free)
        cov_fixed = problem.coverage(fixed)
        need = np.zeros(problem.n_targets)
        rows_free = np.unique(np.concatenate([V.indices[V.indptr[i]:V.indptr[i + 1]] for i in free[:k]]))
        need[rows_free] = problem.weights[rows_free] * (problem.gamma[rows_free] + 1 - cov_fixed[rows_free] > 0)
        score = np.asarray(Vf @ need).ravel() + rng.random(problem.n_candidates) * 1e-3  # seeded tie-break
        score[np.isin(problem.location_ids, problem.location_ids[fixed])] = -np.inf
        cand = np.flatnonzero(np.isfinite(score) & (score > 0.5))
        cand = cand[np.argsort(-score[cand], kind="stable")[:pool_size]]
        pool = np.union1d(cand, free)
        sub = None if left is None else min(sub_time_s, left)
        res = scenario_mip(problem, sel, pool=pool, fixed=fixed, time_limit_s=sub, eps=eps, t_lower=t_lower,
                           mip_rel_gap=1e-6, should_stop=should_stop, highs_options=FAST_SUB_MIP)
        tries += 1
        key = (res.worst_case, res.cost)
        history.append({"anchor": a, "free": int(k), "pool": int(len(pool)), "status": res.status,
                        "worst_case": res.worst_case, "cost": res.cost, "seconds": round(res.info["seconds"], 2)})
        if _better(key, best):
            sel, best = res.selected, key
            accepted += 1
            attempt = 0
        else:
            attempt += 1
    return sel, {"tries": tries, "accepted": accepted, "stopped": stopped_by, "history": history,
                 "seconds": time.perf_counter() - t0}


__all__ = ["FAST_SUB_MIP", "robust_lns"]
