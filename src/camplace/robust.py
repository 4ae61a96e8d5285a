"""Robustness to camera failure: which cameras are essential, and placements that stay
good when any one camera fails.

Failure cost of camera i in a selection S: cost(S minus i) (one matrix-vector product
over the selected rows gives all of them: removing i raises the cost by
Σ_{j in row i} w_j (max(Γ_j − c_j + 1, 0)² − max(Γ_j − c_j, 0)²)).
Worst case: W(S) = max_i cost(S minus i).

``robust_search`` (the ``--robust 1`` heuristic) minimises W(S) by best-improvement swap
local search started from the nominal placement: a move removes one selected camera and
adds one candidate drawn from a pool ranked by its gain in the current worst failure
scenario and by its nominal gain; moves are compared lexicographically by (W, second and
third worst failure costs, nominal cost). When no move improves it continues as a short
tabu search (least-bad move, the removed camera tabu for a few passes) and returns the
best selection seen, so the robust placement's worst case is <= the nominal placement's.
A valid lower bound on the optimal worst case: for any S,
W(S) >= cost(S minus i) >= OPT(N_s − 1), the optimum with one camera fewer, so any lower
bound on OPT(N_s − 1) (Lagrangian, ``camplace.solvers.bounds``) bounds the robust
optimum from below.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from camplace.problem import PlacementProblem, shortfall_cost
from camplace.solvers.base import Placement


def removal_losses(problem: PlacementProblem, selected: np.ndarray, cov: np.ndarray | None = None) -> np.ndarray:
    """(k,) cost added when each selected camera (in the given order) fails alone."""
    sel = np.asarray(selected, np.int64)
    if len(sel) == 0:
        return np.zeros(0)
    c = problem.coverage(sel) if cov is None else cov
    h = _h(problem.gamma, problem.weights, c)
    return np.asarray(problem.V[sel].astype(np.float64) @ h).ravel()


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


@dataclass(frozen=True)
class RobustResult:
    """placement: the robust selection (objective = its nominal cost); figures for both
    placements: nominal cost / worst-case cost and their coverage gaps; bound: lower
    bound on the optimal worst case (None if not computed)."""

    placement: Placement
    nominal: dict
    robust: dict
    bound: float | None
    info: dict = field(default_factory=dict)


def _figures(problem: PlacementProblem, sel: np.ndarray) -> dict:
    cost = problem.cost(sel)
    w, who = worst_case(problem, sel)
    n = problem.normalizer or 1.0
    return {"cost": cost, "coverage_gap": cost / n, "worst_case_cost": w, "worst_case_gap": w / n,
            "worst_failure_candidate": who, "cameras": int(len(sel))}


def _h(gamma: np.ndarray, w: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Per-target cost of losing one view: w (max(Γ − c + 1, 0)² − max(Γ − c, 0)²)."""
    d0 = np.maximum(gamma - c, 0).astype(np.float64)
    d1 = np.maximum(gamma - c + 1, 0).astype(np.float64)
    return w * (d1 * d1 - d0 * d0)


def _sq(gamma: np.ndarray, w: np.ndarray, c: np.ndarray) -> np.ndarray:
    d = np.maximum(gamma - c, 0).astype(np.float64)
    return w * d * d


TOP_M = 3  # moves compare the TOP_M worst failure costs, then the nominal cost (lexicographic)


def _better(k1: tuple, k2: tuple, tol: float = 1e-9) -> bool:
    """Lexicographic k1 < k2 with a tolerance (shorter keys: fewer cameras, compare what exists)."""
    for x, y in zip(k1, k2):
        if x < y - tol:
            return True
        if x > y + tol:
            return False
    return False


class _SwapScorer:
    """Exact (worst-case, nominal) cost of every swap from the current selection, each in
    O(|row a| + |row b| + entries of the selected rows on them) via a CSC of the rows."""

    def __init__(self, problem: PlacementProblem, sel: list[int], cov: np.ndarray) -> None:
        self.p, self.sel, self.cov = problem, sel, cov
        V = problem.V
        self.base = shortfall_cost(problem.gamma, problem.weights, cov)
        self.h = _h(problem.gamma, problem.weights, cov)
        S = V[np.array(sel, np.int64)] if sel else V[:0]
        self.Sc = S.tocsc()
        self.L = np.asarray(S.astype(np.float64) @ self.h).ravel() if sel else np.zeros(0)
        self.pos = {i: k for k, i in enumerate(sel)}

    def row(self, i: int) -> np.ndarray:
        V = self.p.V
        return V.indices[V.indptr[i]:V.indptr[i + 1]]

    def score(self, a: int | None, b: int) -> tuple[float, float]:
        p, cov = self.p, self.cov
        ra = self.row(a) if a is not None else np.zeros(0, np.int32)
        rb = self.row(b)
        T, inv = np.unique(np.r_[ra, rb], return_inverse=True)
        dc = np.bincount(inv, weights=np.r_[-np.ones(len(ra)), np.ones(len(rb))], minlength=len(T))
        g, w = p.gamma[T], p.weights[T]
        c_old = cov[T]
        c_new = c_old + dc.astype(np.int64)
        base = self.base + float(np.sum(_sq(g, w, c_new) - _sq(g, w, c_old)))
        h_new = _h(g, w, c_new)
        dh = h_new - self.h[T]
        nz = np.flatnonzero(dh != 0)
        L = self.L
        if len(nz) and len(L):
            cols = T[nz]
            st, en = self.Sc.indptr[cols], self.Sc.indptr[cols + 1]
            cnt = en - st
            idx = np.repeat(st - np.cumsum(np.r_[0, cnt[:-1]]), cnt) + np.arange(int(cnt.sum()))
            L = L + np.bincount(self.Sc.indices[idx], weights=np.repeat(dh[nz], cnt), minlength=len(L))
        else:
            L = L.copy()
        if a is not None:
            L[self.pos[a]] = -np.inf
        Lb = float(h_new[inv[len(ra):]].sum())
        allL = np.r_[L[np.isfinite(L)], Lb]
        top = np.sort(allL)[::-1][:TOP_M]
        return base + float(top[0]), base, tuple(base + top) + (base,)


def robust_search(problem: PlacementProblem, initial: np.ndarray, *, time_limit_s: float | None = 60.0,
                  pool: int = 24, should_stop=None, max_stall: int = 0, tenure: int = 5) -> tuple[np.ndarray, dict]:
    """Swap local search on (worst single-failure cost, 2nd and 3rd worst, nominal cost) in
    lexicographic order, from ``initial``: moves that keep the worst case but lower the next
    ones cross the plateaus of the max. With max_stall > 0 it goes on as a tabu search:
    when no move improves, it takes the least bad move (the camera removed may not come
    back for ``tenure`` passes), until max_stall passes in a row have not improved the best
    selection, and returns the best selection seen.
    Returns the selection and info (moves, passes, seconds, stopped)."""
    t0 = time.perf_counter()
    V = problem.V
    Vf = V.astype(np.float64)
    gamma, w = problem.gamma, problem.weights
    costs = problem.costs
    locs = problem.location_ids
    n_loc = int(locs.max()) + 1 if len(locs) else 0
    sel = [int(i) for i in np.asarray(initial, np.int64)]
    cov = problem.coverage(np.array(sel, np.int64))

    def gains(c: np.ndarray) -> np.ndarray:
        d0 = np.maximum(gamma - c, 0).astype(np.float64)
        d1 = np.maximum(d0 - 1, 0)
        return np.asarray(Vf @ (w * (d0 * d0 - d1 * d1))).ravel()

    sc = _SwapScorer(problem, sel, cov)
    top0 = np.sort(sc.L)[::-1][:TOP_M] if len(sc.L) else np.zeros(1)
    cur = (sc.base + float(top0[0]), sc.base, tuple(sc.base + top0) + (sc.base,))
    moves = passes = stall = 0
    stopped = "converged"
    tabu: dict[int, int] = {}
    best_key, best_sel = cur[2], sorted(sel)
    while True:
        if time_limit_s is not None and time.perf_counter() - t0 > time_limit_s:
            stopped = "time_limit"
            break
        if should_stop is not None and should_stop():
            stopped = "interrupted"
            break
        passes += 1
        used = np.zeros(n_loc, bool)
        used[locs[sel]] = True
        spent = float(costs[sel].sum()) if sel else 0.0
        worst = sel[int(np.argmax(sc.L))] if sel else None
        c_w = cov.copy()
        if worst is not None:
            c_w[sc.row(worst)] -= 1
        g_w, g_n = gains(c_w), gains(cov)
        free = ~used[locs]
        ranked: list[int] = []
        for g in (g_w, g_n):
            cand = np.flatnonzero(free & (g > 0))
            ranked.extend(cand[np.argsort(-g[cand], kind="stable")[:pool]].tolist())
        if worst is not None:  # same-location alternatives (a turned camera) of the worst camera
            same = np.flatnonzero(locs == locs[worst])
            same = same[same != worst]
            ranked.extend(same[np.argsort(-g_w[same], kind="stable")[:pool]].tolist())
        ranked = list(dict.fromkeys(ranked))
        best = (cur, None, None)
        fallback = None  # best non-improving, non-tabu move (tabu phase)
        outs: list[int | None] = list(sel) + ([None] if len(sel) < problem.budget else [])
        for a in outs:
            for b in ranked:
                if a is not None and b == a:
                    continue
                if b in tabu and tabu[b] > passes:
                    continue
                if used[locs[b]] and (a is None or locs[a] != locs[b]):
                    continue
                if problem.money_budget is not None and \
                        spent - (costs[a] if a is not None else 0.0) + costs[b] > problem.money_budget + 1e-9:
                    continue
                s2 = sc.score(a, b)
                if _better(s2[2], best[0][2]):
                    best = (s2, a, b)
                elif fallback is None or _better(s2[2], fallback[0][2]):
                    fallback = (s2, a, b)
            if time_limit_s is not None and time.perf_counter() - t0 > time_limit_s:
                break
        if best[2] is None:
            if fallback is None or stall >= max_stall:
                break
            best = fallback  # tabu step: the least bad move; the moved cameras may not return for `tenure` passes
        cur, a, b = best
        if a is not None:
            tabu[a] = passes + tenure
            sel.remove(a)
            cov[sc.row(a)] -= 1
        sel.append(b)
        cov[sc.row(b)] += 1
        sc = _SwapScorer(problem, sel, cov)
        moves += 1
        if _better(cur[2], best_key):
            best_key, best_sel = cur[2], sorted(sel)
            stall = 0
        else:
            stall += 1  # passes since the best selection last improved
    return np.array(sorted(best_sel), np.int64), {"moves": moves, "passes": passes, "stopped": stopped,
                                                  "seconds": time.perf_counter() - t0}


def robust_bound(problem: PlacementProblem, coverage_hint: np.ndarray | None = None,
                 time_limit_s: float = 10.0, incumbent_cost: float | None = None) -> float | None:
    """Lower bound on min_S max_i cost(S minus i): a Lagrangian lower bound of the nominal
    problem with one camera fewer (None when the bounds module is unavailable)."""
    if problem.budget < 1:
        return None
    try:
        from camplace.solvers.bounds import lagrangian_bound
    except ImportError:  # pragma: no cover - bounds land with issue 11
        return None
    fewer = replace(problem, budget=problem.budget - 1)
    res = lagrangian_bound(fewer, time_limit_s=time_limit_s, coverage=coverage_hint, incumbent_cost=incumbent_cost)
    return max(0.0, float(res.bound))


def robust_placement(problem: PlacementProblem, nominal: Placement, *, time_limit_s: float | None = 60.0,
                     bound_time_s: float = 10.0, pool: int = 24, max_stall: int = 20,
                     should_stop=None) -> RobustResult:
    """The ``--robust 1`` heuristic from the nominal placement, with figures for both
    placements and a lower bound on the optimal worst case."""
    t0 = time.perf_counter()
    sel, info = robust_search(problem, nominal.selected, time_limit_s=time_limit_s, pool=pool,
                              should_stop=should_stop, max_stall=max_stall)
    problem.check_feasible(sel)
    nom, rob = _figures(problem, np.asarray(nominal.selected, np.int64)), _figures(problem, sel)
    bound = None
    if bound_time_s > 0:  # hint: the robust placement minus its worst camera is a feasible (N_s − 1) selection
        keep = sel[sel != rob["worst_failure_candidate"]]
        bound = robust_bound(problem, problem.coverage(keep), bound_time_s, rob["worst_case_cost"])
    if bound is not None:
        bound = min(bound, rob["worst_case_cost"])
    info = dict(info, nominal=nom, robust=rob, worst_case_bound=bound,
                nominal_cost_given_up=rob["cost"] - nom["cost"],
                worst_case_gained=nom["worst_case_cost"] - rob["worst_case_cost"])
    p = Placement(sel, rob["cost"], None, "heuristic", f"{nominal.solver}+robust1",
                  nominal.seconds + time.perf_counter() - t0, dict(nominal.info, robust=info))
    return RobustResult(p, nom, rob, bound, info)


def essential_from_folder(out_dir) -> tuple[list[dict], dict]:
    """``essential_cameras`` for a run's output folder (visibility.npz + placement.json):
    (ranking with each camera's candidate_id, position and type, summary dict)."""
    import json
    from pathlib import Path

    from camplace.errors import InputError
    from camplace.instance import load_problem_npz

    out = Path(out_dir)
    for name in ("visibility.npz", "placement.json"):
        if not (out / name).is_file():
            raise InputError(f"{out}: {name} not found (expected the output folder of camplace run / evaluate)")
    try:
        pdict = json.loads((out / "placement.json").read_text())
        cams = pdict["cameras"]
        ids = [c["candidate_id"] for c in cams]
    except (ValueError, KeyError, TypeError) as err:
        raise InputError(f"{out / 'placement.json'}: not a camplace placement ({err})") from None
    if any(i is None for i in ids):
        raise InputError(f"{out / 'placement.json'}: some cameras are not rows of V (candidate_id null); "
                         "score the placement with `camplace evaluate` first")
    problem, _ = load_problem_npz(out / "visibility.npz", len(ids))
    sel = np.asarray(ids, np.int64)
    if len(sel) and (sel.min() < 0 or sel.max() >= problem.n_candidates):
        raise InputError(f"{out / 'placement.json'}: candidate_id outside the rows of visibility.npz")
    ranking = essential_cameras(problem, sel)
    by_id = {int(c["candidate_id"]): c for c in cams}
    for r in ranking:
        c = by_id[r["candidate_id"]]
        r.update(position=c.get("position"), yaw_deg=c.get("yaw_deg"), pitch_deg=c.get("pitch_deg"),
                 camera=c.get("camera"))
    w, who = worst_case(problem, sel)
    cost = problem.cost(sel)
    return ranking, {"cost": cost, "worst_case_cost": w, "worst_failure_candidate": who,
                     "coverage_gap": cost / problem.normalizer if problem.normalizer > 0 else 0.0}


__all__ = ["RobustResult", "essential_from_folder", "essential_cameras", "removal_losses", "robust_bound", "robust_placement",
           "robust_search", "worst_case"]
