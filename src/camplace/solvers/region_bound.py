"""A lower bound past the LP: Lagrangian decomposition over target regions
(proof in docs/certify.md § "Region decomposition bound").

Partition the targets into regions R. The cost splits, F(x) = Σ_R F_R(x), F_R counting
only R's targets, and F_R depends only on the candidates C_R that see R. For any
price vector μ_R over C_R,

    F_R(x) ≥ h_R(μ_R) − μ_R·x,   h_R(μ_R) = min over integer y ∈ X of F_R(y) + μ_R·y,

for every feasible integer x (x itself is a candidate y). Summing,
F(x) ≥ Σ_R h_R(μ_R) − max_{x∈X} r·x with r_i = Σ_{R ∋ i} μ_R,i, and the last max is
exact (top N per-location maxima). Each h_R is a small MIP of the same kind (only R's
targets) solved by HiGHS; any proven lower bound on it (HiGHS's dual bound when it
stops early, or the region's own Lagrangian) keeps the bound valid. Because every
region subproblem is integer it cannot spread fractional cameras, so the bound can
exceed the LP; started from μ_R = V_R λ_R (λ: Lagrange multipliers of the coverage
rows) it is never below the Lagrangian bound L(λ). The multipliers μ are then improved
by subgradient ascent (the bound reported is the best evaluation, each one valid).

`partial_lagrangian_bound` is the other bound here (§9): one region's coverage rows kept
exact together with the budget and the locations, the other rows dualized with λ; the
budget binds in that single MIP, so it passes the LP where small decomposition regions
cannot.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp

from camplace.problem.model import PlacementProblem
from camplace.solvers.bounds import BoundResult, Lagrangian, _u_part, build_highs, convex_start, lagrangian_bound
from camplace.solvers.highs_util import run_model, set_start

StopFn = Callable[[], bool]
METHOD = "region decomposition (Lagrangian + HiGHS on target regions)"


def target_regions(problem: PlacementProblem, n_regions: int, seed: int = 0) -> np.ndarray:
    """(N_p,) int64 region label of each target, geometry-free: targets are grouped
    by the set of locations that see them (k-means on the normalized target × location
    incidence, deterministic for a seed). Targets no candidate sees get label −1."""
    from scipy.cluster.vq import kmeans2

    V = sp.csr_matrix(problem.V)
    n_g, n_p = V.shape
    labels = np.full(n_p, -1, np.int64)
    if n_g == 0 or n_p == 0:
        return labels
    _, loc = np.unique(problem.location_ids, return_inverse=True)
    n_loc = int(loc.max()) + 1
    Lm = sp.csr_matrix((np.ones(n_g), (loc, np.arange(n_g))), shape=(n_loc, n_g))
    M = sp.csr_matrix((Lm @ V.astype(np.float64)).T)  # (N_p, n_loc) how many poses of l see j
    M.data[:] = 1.0
    seen = np.flatnonzero(np.diff(M.indptr) > 0)
    k = int(max(1, min(n_regions, len(seen))))
    if k == 1:
        labels[seen] = 0
        return labels
    F = M[seen]
    if n_loc > 256:  # keep the dense feature matrix small: a fixed random projection
        rng = np.random.default_rng(seed)
        F = F @ rng.standard_normal((n_loc, 64))
    else:
        F = F.toarray()
    F = F / np.maximum(np.linalg.norm(F, axis=1, keepdims=True), 1e-12)
    uniq, inv = np.unique(np.round(F, 12), axis=0, return_inverse=True)
    if len(uniq) <= k:  # as many distinct signatures as regions: one region each
        labels[seen] = inv.ravel()
        return labels
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # kmeans2 warns about empty clusters; they are dropped below
        _, lab = kmeans2(F, k, minit="++", seed=seed, iter=30)
    _, lab = np.unique(lab, return_inverse=True)  # drop empty clusters
    labels[seen] = lab
    return labels


def max_over_x(r: np.ndarray, loc: np.ndarray, n_loc: int, budget: int) -> tuple[float, np.ndarray]:
    """max Σ r_i x_i over x with at most `budget` ones, at most one per location
    (dense location ids `loc`): the sum of the `budget` largest positive per-location
    maxima. Returns (value, the maximizing 0/1 x)."""
    n = len(r)
    best = np.full(n_loc, -1, np.int64)
    val = np.zeros(n_loc)
    pos = np.flatnonzero(r > 0)
    if len(pos) and budget > 0:
        order = pos[np.lexsort((pos, -r[pos]))]  # by value desc, then id
        first = np.unique(loc[order], return_index=True)
        best[first[0]] = order[first[1]]
        val[first[0]] = r[order[first[1]]]
    top = np.argsort(-val, kind="stable")[:budget]
    top = top[val[top] > 0]
    x = np.zeros(n)
    x[best[top]] = 1.0
    return float(val[top].sum()), x


@dataclass
class _Region:
    cols: np.ndarray  # (|R|,) target ids
    cand: np.ndarray  # (|C_R|,) candidate ids
    sub: PlacementProblem  # R's targets, C_R's candidates, same budget
    Vr: sp.csr_matrix  # (|C_R|, |R|) float64
    loc: np.ndarray  # dense location id of each candidate of C_R
    n_loc: int
    highs: object = None
    n_x: int = 0


class RegionDecomposition:
    """The Lagrangian decomposition of the placement problem over target regions.
    `evaluate(mu)` returns a valid lower bound on the optimal cost for any prices mu
    (a list with one (|C_R|,) array per region)."""

    def __init__(self, problem: PlacementProblem, labels: np.ndarray, threads: int | None = 1, seed: int = 0) -> None:
        self.problem = problem
        self.threads = threads
        self.seed = seed
        V = sp.csr_matrix(problem.V)
        VC = sp.csc_matrix(V)
        unseen = labels < 0
        self.constant = float(np.dot(problem.weights[unseen], problem.gamma[unseen].astype(np.float64) ** 2))
        _, self.loc = np.unique(problem.location_ids, return_inverse=True)
        self.n_loc = int(self.loc.max()) + 1 if len(self.loc) else 0
        self.regions: list[_Region] = []
        for R in range(int(labels.max()) + 1 if len(labels) and labels.max() >= 0 else 0):
            cols = np.flatnonzero(labels == R)
            if len(cols) == 0:
                continue
            sub_c = VC[:, cols].tocsr()
            cand = np.flatnonzero(np.diff(sub_c.indptr) > 0)
            Vr = sp.csr_matrix(sub_c[cand], dtype=np.float64)
            sub = PlacementProblem(sp.csr_matrix(sub_c[cand]), problem.gamma[cols].astype(np.int64),
                                   problem.weights[cols].astype(np.float64), problem.budget,
                                   problem.location_ids[cand])
            _, rl = np.unique(sub.location_ids, return_inverse=True)
            self.regions.append(_Region(cols, cand, sub, Vr, rl.astype(np.int64), int(rl.max()) + 1 if len(rl) else 0))

    def initial_prices(self, lam: np.ndarray) -> list[np.ndarray]:
        """μ_R = V_R λ_R: each candidate priced at the value of R's targets it sees; the
        decomposition bound at these prices is ≥ the Lagrangian bound L(λ)."""
        out = []
        for reg in self.regions:
            out.append(np.asarray(reg.Vr @ lam[reg.cols]).ravel())
        return out

    def evaluate(self, mus: list[np.ndarray], lam_r: list[np.ndarray] | None = None, region_time_s: float = 5.0,
                 end: float | None = None, should_stop: StopFn | None = None):
        """The decomposition bound at prices `mus` (one (|C_R|,) array per region):
        constant + Σ_R (proven lower bound on h_R(μ_R)) − max_{x∈X} Σ_R μ_R·x.
        lam_r: per-region multipliers for the fallback bound of a subproblem HiGHS does not
        finish (default 0). Returns (bound, region solutions y_R, linking solution x0,
        number of subproblems solved to optimality), or None when stopped midway."""
        r = np.zeros(self.problem.n_candidates)
        for reg, mu in zip(self.regions, mus):
            np.add.at(r, reg.cand, mu)
        link, x0 = max_over_x(r, self.loc, self.n_loc, self.problem.budget)
        total = self.constant
        ys = []
        n_opt = 0
        for k, (reg, mu) in enumerate(zip(self.regions, mus)):
            lr = np.zeros(len(reg.cols)) if lam_r is None else lam_r[k]
            fb, y_fb = self.region_lagrangian(reg, mu, lr)
            if should_stop is not None and should_stop():
                return None
            left = region_time_s if end is None else min(region_time_s, end - time.perf_counter())
            dual, y, optimal = self.solve_region(reg, mu, left, x0[reg.cand], should_stop)
            n_opt += int(optimal)
            total += max(fb, dual)
            ys.append(y if y is not None else y_fb)
        return total - link, ys, x0, n_opt

    def region_lagrangian(self, reg: _Region, mu: np.ndarray, lam_r: np.ndarray) -> tuple[float, np.ndarray]:
        """A lower bound on h_R(μ) by weak duality on the region's coverage rows with
        multipliers λ_R ≥ 0: U_R(λ_R) − max_{y∈X} (V_R λ_R − μ)·y. Returns (bound, y)."""
        q = reg.sub
        u_val, _ = _u_part(lam_r, q.gamma, q.weights)
        r = np.asarray(reg.Vr @ lam_r).ravel() - mu
        v, y = max_over_x(r, reg.loc, reg.n_loc, q.budget)
        return float(u_val - v), y

    def solve_region(self, reg: _Region, mu: np.ndarray, time_limit_s: float, start: np.ndarray | None,
                     should_stop: StopFn | None = None) -> tuple[float, np.ndarray | None, bool]:
        """HiGHS on min F_R(y) + μ·y over integer y ∈ X: (proven lower bound on h_R,
        best y found or None, solved to optimality)."""
        import highspy

        if reg.highs is None:
            h, n_x = build_highs(reg.sub, integer=True, threads=self.threads, seed=self.seed)
            h.setOptionValue("presolve", "off")  # presolve costs seconds here and gains little
            h.setOptionValue("mip_rel_gap", 1e-6)
            reg.highs, reg.n_x = h, n_x
        h, n_x = reg.highs, reg.n_x
        h.clearSolver()  # no incumbent or basis from the previous prices may prune this run
        h.changeColsCost(n_x, np.arange(n_x, dtype=np.int32), np.asarray(mu, np.float64))
        h.setOptionValue("time_limit", float(max(0.01, time_limit_s)))
        if start is not None:
            set_start(h, convex_start(reg.sub, start))
        run = run_model(h, should_stop=should_stop, in_child=False)  # a small model, changed in place between runs
        info = run.info
        optimal = run.model_status == highspy.HighsModelStatus.kOptimal
        dual = float(info.mip_dual_bound)
        if not np.isfinite(dual):
            dual = -np.inf
        y = None
        if info.primal_solution_status == 2 and run.col_value is not None:
            y = np.round(np.asarray(run.col_value[:n_x]))
        return dual, y, optimal


def region_bound(problem: PlacementProblem, *, lam: np.ndarray | None = None, n_regions: int | None = None,
                 time_limit_s: float = 60.0, region_time_s: float = 5.0, incumbent_cost: float | None = None,
                 max_iter: int = 1000, labels: np.ndarray | None = None, threads: int | None = 1, seed: int = 0,
                 should_stop: StopFn | None = None, on_bound: Callable[[float], None] | None = None,
                 step: float = 1.0, x_frac: np.ndarray | None = None, smooth: float = 0.3) -> BoundResult:
    """The region-decomposition lower bound (docs/certify.md § Region decomposition).

    lam: (N_p,) Lagrange multipliers to start from (default: a short subgradient run);
    n_regions: number of target regions (default N_p / 400, at least 2); labels: an
    explicit (N_p,) region label per target instead (−1: unseen targets only);
    region_time_s: HiGHS time per region subproblem; x_frac: (N_g,) a fractional point
    of conv(X) maximizing r·x at the start (the LP primal at LP duals), used as the
    linking part of the first supergradient (at LP duals the integer linking solution is
    one of many ties and a poor direction); later directions use a running average of
    the linking solutions (weight `smooth` on the newest). Every evaluation is a valid lower
    bound; the best is returned. info: iterations, regions, evaluations, first (the
    bound at the starting prices), lagrangian (L(λ) at the start)."""
    t0 = time.perf_counter()
    end = t0 + float(time_limit_s)

    def stop() -> bool:
        return time.perf_counter() >= end or (should_stop is not None and should_stop())

    lg = Lagrangian(problem)
    if lam is None:
        res = lagrangian_bound(problem, time_limit_s=max(0.1, 0.2 * time_limit_s), incumbent_cost=incumbent_cost,
                               should_stop=should_stop, lagr=lg)
        lam = res.multipliers
    lam = np.maximum(np.asarray(lam, np.float64), 0.0)
    L0 = lg.evaluate(lam)[0]
    if labels is None:
        k = max(2, int(round(problem.n_targets / 400))) if n_regions is None else int(n_regions)
        labels = target_regions(problem, k, seed=seed)
    dec = RegionDecomposition(problem, labels, threads=threads, seed=seed)
    mus = dec.initial_prices(lam)
    lam_r = [lam[reg.cols] for reg in dec.regions]
    best = -np.inf
    best_mu = [m.copy() for m in mus]
    best_g: list[np.ndarray] | None = None
    best_gn = 0.0
    target = incumbent_cost
    history: list[float] = []
    n_solved = 0
    it = 0
    alpha = float(step)
    stall = 0
    first = None
    x_ref: np.ndarray | None = None
    while it < max_iter and not stop():
        ev = dec.evaluate(mus, lam_r, region_time_s, end=end, should_stop=stop)
        if ev is None:
            break
        value, ys, x0, n_opt = ev
        n_solved += n_opt
        history.append(value)
        if first is None:
            first = value
        it += 1
        # supergradient of the decomposition in μ_R: y_R − x0 restricted to C_R (x0 from a
        # smoothed average of linking solutions: only the direction, never the bound)
        x_ref = (np.asarray(x_frac, np.float64) if x_frac is not None else x0) if x_ref is None \
            else (1.0 - smooth) * x_ref + smooth * x0
        g = [y - x_ref[reg.cand] for reg, y in zip(dec.regions, ys)]
        gn = float(sum(np.dot(v, v) for v in g))
        if target is None:
            target = problem.cost(np.flatnonzero(x0 > 0.5))
        if best_g is None or value > best + 1e-9 * max(1.0, abs(best)):
            best, best_mu, best_g, best_gn = value, [m.copy() for m in mus], g, gn
            stall = 0
            if on_bound is not None and best > L0:
                on_bound(best)
        else:
            stall += 1
            if stall >= 2:  # back to the best prices with half the step
                alpha *= 0.5
                stall = 0
                mus, g, gn, value = [m.copy() for m in best_mu], best_g, best_gn, best
        if gn <= 1e-12 or alpha < 1e-3:
            break  # every region agrees with the linking solution (or steps vanished)
        gap = max(target - value, 1e-6 * max(1.0, abs(target)))
        t = alpha * gap / gn
        mus = [m + t * v for m, v in zip(mus, g)]
    out = max(best, L0, 0.0)
    out -= 1e-7 * max(1.0, abs(out))  # HiGHS's dual bounds hold up to its tolerances (certify.md §5)
    return BoundResult(max(out, 0.0), METHOD, time.perf_counter() - t0, lam,
                       {"iterations": it, "regions": len(dec.regions), "lagrangian": L0, "first": first,
                        "history": history, "region_solves_optimal": n_solved})


PARTIAL_METHOD = "partial Lagrangian (one region exact, HiGHS)"


def partial_lagrangian_bound(problem: PlacementProblem, lam: np.ndarray, region: np.ndarray, *,
                             time_limit_s: float = 60.0, threads: int | None = 1, seed: int = 0,
                             should_stop: StopFn | None = None) -> BoundResult:
    """Dualize only the coverage rows of the targets outside `region` (bool (N_p,) or ids)
    with multipliers λ ≥ 0 and keep the region's rows, the budget and the locations
    exact (docs/certify.md §9):

        OPT ≥ U_out(λ) + min over integer x ∈ X of F_region(x) − Σ_i r_i x_i,
        r_i = Σ_{j ∉ region} V_ij λ_j,

    the min solved by HiGHS (its dual bound is used, valid whenever it stops). The budget
    binds in this subproblem, unlike in small decomposition regions, so it can pass the LP;
    it is never below L(λ) (the value reported is max(L(λ), that bound))."""
    t0 = time.perf_counter()
    lam = np.maximum(np.asarray(lam, np.float64), 0.0)
    mask = np.zeros(problem.n_targets, bool)
    mask[np.asarray(region)] = True
    cols, out = np.flatnonzero(mask), np.flatnonzero(~mask)
    L = Lagrangian(problem).evaluate(lam)[0]
    u_out, _ = _u_part(lam[out], problem.gamma[out].astype(np.int64), problem.weights[out].astype(np.float64))
    V = sp.csr_matrix(problem.V)
    r = np.asarray(V[:, out].astype(np.float64) @ lam[out]).ravel()
    sub = PlacementProblem(sp.csr_matrix(V[:, cols]), problem.gamma[cols].astype(np.int64),
                           problem.weights[cols].astype(np.float64), problem.budget, problem.location_ids)
    info: dict = {"region_targets": int(len(cols)), "lagrangian": L}
    dual = -np.inf
    left = time_limit_s - (time.perf_counter() - t0)
    if left > 0.05 and problem.n_candidates:
        h, n_x = build_highs(sub, integer=True, threads=threads, seed=seed, time_limit_s=left, x_cost=-r)
        h.setOptionValue("mip_rel_gap", 1e-6)
        run = run_model(h, should_stop=should_stop, end=t0 + time_limit_s)
        hinfo = run.info
        info.update(status=run.status_text, nodes=int(hinfo.mip_node_count))
        d = float(hinfo.mip_dual_bound)
        if np.isfinite(d):
            dual = d
    value = max(L, float(u_out) + dual)
    value -= 1e-7 * max(1.0, abs(value))  # HiGHS's tolerances (certify.md §5)
    info["raw"] = float(u_out) + dual if np.isfinite(dual) else None
    return BoundResult(max(value, 0.0), PARTIAL_METHOD, time.perf_counter() - t0, lam, info)


def costly_region(problem: PlacementProblem, lam: np.ndarray, share: float = 0.3, n_regions: int = 16,
                  seed: int = 0) -> np.ndarray:
    """(N_p,) bool: whole k-means regions (target_regions) with the largest Lagrangian
    u-part cost per target, added until they hold `share` of the targets."""
    labels = target_regions(problem, n_regions, seed=seed)
    lam = np.maximum(np.asarray(lam, np.float64), 0.0)
    mask = np.zeros(problem.n_targets, bool)
    if labels.max() < 0:
        return mask
    per = np.zeros(int(labels.max()) + 1)
    cnt = np.bincount(labels[labels >= 0], minlength=len(per))
    for R in range(len(per)):
        cols = np.flatnonzero(labels == R)
        per[R] = _u_part(lam[cols], problem.gamma[cols].astype(np.int64), problem.weights[cols].astype(np.float64))[0]
    order = np.argsort(-(per / np.maximum(cnt, 1)), kind="stable")
    for R in order:
        mask[labels == R] = True
        if mask.sum() >= share * problem.n_targets:
            break
    return mask
