"""The exact scenario MIP of min_S W(S), solved by lazy scenario generation on HiGHS."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from camplace.problem.gains import removal_losses, target_costs, target_losses
from camplace.problem.model import PlacementProblem
from camplace.solvers.base import stopped
from camplace.solvers.highs_util import INF, MilpArrays, highs_from_arrays, location_rows, run_highs
from camplace.solvers.robust.failures import _better, _key

# ------------------------------------------------------------- scenario MIP --
#
# Exact model of min_S W(S) (docs/beyond-the-grid.md has the proof): for a set Σ of
# scenario cameras,  min t  s.t.  t >= z  and for each s in Σ
#   t >= z + D_s + Σ_{j in row s} Σ_k c_jk (u^s_jk − u_jk),     z = C0 + Σ_jk c_jk u_jk,
# nominal rows  Σ_i V_ij x_i + Σ_k u_jk >= Γ_j,  scenario rows  Σ_{i≠s} V_ij x_i + Σ_k u^s_jk >= Γ_j
# (j in row s), c_jk = w_j (2k − 1), u in [0, 1]. The same builder solves a subproblem:
# cameras `fixed` always selected (base coverage b; their scenarios always in Σ, with
# Γ − b + 1 on their rows and the targets no pool candidate sees folded into the
# constants C0, D_s), the rest chosen among `pool`.


@dataclass
class ScenarioResult:
    """selected: (k,) candidate ids (fixed + chosen, sorted); worst_case / cost: W and the
    nominal cost recomputed from V; bound: proven lower bound on the optimum of the
    (sub)problem solved (None if none); status: 'optimal' (every selected camera's
    scenario was in the model and HiGHS proved optimality), 'time_limit', 'interrupted',
    'feasible'; info: rounds, scenarios, sizes, seconds."""

    selected: np.ndarray
    worst_case: float
    cost: float
    bound: float | None
    status: str
    info: dict = field(default_factory=dict)


def _u_cols(gam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(row of each u column, its k (1-based)) for rows with Γ' = gam."""
    gam = np.asarray(gam, np.int64)
    rows = np.repeat(np.arange(len(gam)), gam)
    starts = np.cumsum(gam) - gam
    k = np.arange(int(gam.sum())) - np.repeat(starts, gam) + 1
    return rows, k


class _ScenarioModel:
    """Arrays of the scenario model over `pool` with `fixed` cameras selected."""

    def __init__(self, problem: PlacementProblem, pool: np.ndarray, fixed: np.ndarray) -> None:
        self.p = problem
        self.pool = np.asarray(pool, np.int64)
        self.fixed = np.asarray(fixed, np.int64)
        self.pos = {int(c): k for k, c in enumerate(self.pool)}
        V = problem.V
        gamma = np.asarray(problem.gamma, np.int64)
        w = np.asarray(problem.weights, np.float64)
        b = problem.coverage(self.fixed)
        VP = V[self.pool]
        T = np.unique(VP.indices)  # targets some pool candidate sees and that can still cost:
        graw = gamma[T] - b[T]
        T = T[(graw >= 1) | ((graw == 0) & (b[T] > 0))]  # (the others cost 0 in every scenario)
        outside = np.ones(problem.n_targets, bool)
        outside[T] = False
        self.C0 = float(np.sum(target_costs(gamma[outside], w[outside], b[outside])))
        self.h_out = np.where(outside, target_losses(gamma, w, b), 0.0)  # cost of losing a view, outside T
        # merge targets alike in every scenario: same pool column, same Γ − b, same fixed cameras
        VPc = sp.csc_matrix(VP[:, T])
        VPc.sort_indices()
        VF = sp.csc_matrix(V[self.fixed][:, T]) if len(self.fixed) else sp.csc_matrix((0, len(T)))
        VF.sort_indices()
        graw = gamma[T] - b[T]
        key_to: dict[tuple, int] = {}
        group = np.empty(len(T), np.int64)
        for j in range(len(T)):
            key = (int(graw[j]), VPc.indices[VPc.indptr[j]:VPc.indptr[j + 1]].tobytes(),
                   VF.indices[VF.indptr[j]:VF.indptr[j + 1]].tobytes())
            group[j] = key_to.setdefault(key, len(key_to))
        n_grp = len(key_to)
        rep = np.full(n_grp, -1, np.int64)
        rep[group[::-1]] = np.arange(len(T))[::-1]
        self.T = T[rep]  # one target per merged group
        self.tpos = np.full(problem.n_targets, -1, np.int64)
        self.tpos[T] = group
        self.graw = graw[rep]
        self.g = np.maximum(self.graw, 0)  # Γ' of each group
        self.w = np.bincount(group, weights=w[T], minlength=n_grp)
        self.VPT = sp.csc_matrix(VPc[:, rep], dtype=np.float64)

    def row_T(self, cand: int) -> np.ndarray:
        V = self.p.V
        r = self.tpos[V.indices[V.indptr[cand]:V.indptr[cand + 1]]]
        return np.unique(r[r >= 0])

    def build(self, scen: list[int], eps: float, t_lower: float) -> tuple[MilpArrays, dict]:
        """MILP arrays with the failure scenarios of the candidates ``scen`` (ids, each
        fixed or in the pool). Columns: x (pool), t, z, nominal u, scenario u blocks."""
        prob = self.p
        n_x = len(self.pool)
        nom_t = np.flatnonzero(self.g > 0)
        nu_rows, nu_k = _u_cols(self.g[nom_t])
        n_nu = len(nu_rows)
        nu_start = np.full(len(self.T), -1, np.int64)
        nu_start[nom_t] = np.cumsum(self.g[nom_t]) - self.g[nom_t]
        c_nu = self.w[nom_t][nu_rows] * (2 * nu_k - 1)
        col_t, col_z, col_u = n_x, n_x + 1, n_x + 2
        R, C, D = [], [], []  # COO triplets
        rlo, rhi = [], []
        cost_u = [c_nu]
        nrow = 0

        def cover(targets_local: np.ndarray, gam: np.ndarray, excl: int | None, u0: int) -> int:
            """Coverage rows Σ_{i≠excl} V_ij x_i + Σ_k u_jk >= gam for the listed targets."""
            nonlocal nrow
            keep = gam > 0
            tl, gm = targets_local[keep], gam[keep]
            sub = self.VPT[:, tl].tocoo()
            m = np.ones(sub.nnz, bool) if excl is None else sub.row != excl
            R.append(nrow + sub.col[m]); C.append(sub.row[m]); D.append(np.ones(int(m.sum())))
            ur, _ = _u_cols(gm)
            R.append(nrow + ur); C.append(u0 + np.arange(len(ur))); D.append(np.ones(len(ur)))
            rlo.append(gm.astype(np.float64)); rhi.append(np.full(len(gm), INF))
            nrow += len(gm)
            return len(ur)

        cover(nom_t, self.g[nom_t], None, col_u)
        # z = C0 + Σ c u
        R.append(np.array([nrow])); C.append(np.array([col_z])); D.append(np.array([1.0]))
        R.append(np.full(n_nu, nrow)); C.append(col_u + np.arange(n_nu)); D.append(-c_nu)
        rlo.append([self.C0]); rhi.append([self.C0]); nrow += 1
        # t >= z
        R.append(np.array([nrow, nrow])); C.append(np.array([col_t, col_z])); D.append(np.array([1.0, -1.0]))
        rlo.append([0.0]); rhi.append([INF]); nrow += 1
        ucol = col_u + n_nu
        fixed_set = set(self.fixed.tolist())
        for cand in scen:
            pos = None if cand in fixed_set else self.pos[cand]
            tl = self.row_T(cand)
            if pos is None:  # fixed camera: one view fewer on its row, constant outside T
                gam = np.maximum(self.graw[tl] + 1, 0)
                Dk = float(self.h_out[self.p.V.indices[self.p.V.indptr[cand]:self.p.V.indptr[cand + 1]]].sum())
            else:
                gam = self.g[tl]
                Dk = 0.0
            u0 = ucol
            n_us = cover(tl, gam, pos, u0)
            keep = gam > 0
            tk, gk = tl[keep], gam[keep]
            ur, uk = _u_cols(gk)
            cs = self.w[tk][ur] * (2 * uk - 1)
            cost_u.append(np.zeros(n_us))
            # t − z − Σ c u^s + Σ c u_nominal(row s) >= D_s
            nt = tl[self.g[tl] > 0]
            nr, nk = _u_cols(self.g[nt])
            ncols = col_u + nu_start[nt][nr] + nk - 1
            ncost = self.w[nt][nr] * (2 * nk - 1)
            R.append(np.full(2 + n_us + len(ncols), nrow))
            C.append(np.r_[col_t, col_z, u0 + np.arange(n_us), ncols])
            D.append(np.r_[1.0, -1.0, -cs, ncost])
            rlo.append([Dk]); rhi.append([INF]); nrow += 1
            ucol += n_us
        n_col = ucol
        # budget, money, locations, per-type limits (pool only)
        R.append(np.full(n_x, nrow)); C.append(np.arange(n_x)); D.append(np.ones(n_x))
        rlo.append([-INF]); rhi.append([float(prob.budget - len(self.fixed))]); nrow += 1
        if prob.money_budget is not None:
            R.append(np.full(n_x, nrow)); C.append(np.arange(n_x)); D.append(prob.costs[self.pool])
            rlo.append([-INF]); rhi.append([float(prob.money_budget - prob.costs[self.fixed].sum())]); nrow += 1
        L = location_rows(prob.location_ids[self.pool]).tocoo()
        if L.nnz:
            R.append(nrow + L.row); C.append(L.col); D.append(L.data)
            rlo.append(np.full(L.shape[0], -INF)); rhi.append(np.ones(L.shape[0])); nrow += L.shape[0]
        if prob.has_type_limits:  # per-type limits on the pool, less what the fixed cameras use
            A_t, limits = prob.type_rows()
            T = A_t[:, self.pool].tocoo()
            used = np.asarray(A_t[:, self.fixed].sum(axis=1)).ravel()
            R.append(nrow + T.row); C.append(T.col); D.append(T.data)
            rlo.append(np.full(len(limits), -INF)); rhi.append(limits - used); nrow += len(limits)
        A = sp.csc_matrix((np.concatenate(D), (np.concatenate(R), np.concatenate(C))), shape=(nrow, n_col))
        c = np.zeros(n_col)
        c[col_t] = 1.0
        c[col_z] = eps
        col_lo = np.zeros(n_col)
        col_hi = np.ones(n_col)
        col_lo[col_t], col_hi[col_t] = t_lower, INF
        col_lo[col_z], col_hi[col_z] = -INF, INF
        integ = np.zeros(n_col, np.int32)
        integ[:n_x] = 1
        arrays = MilpArrays(c, A, np.concatenate([np.asarray(x, np.float64) for x in rlo]),
                            np.concatenate([np.asarray(x, np.float64) for x in rhi]), col_lo, col_hi, integ, n_x)
        return arrays, {"n_x": n_x, "col_t": col_t, "col_z": col_z, "rows": nrow, "cols": n_col, "nnz": int(A.nnz),
                        "scenarios": len(scen)}

    def start_values(self, arrays: MilpArrays, meta: dict, chosen: np.ndarray) -> np.ndarray:
        """Column values of a selection (pool positions): x, the smallest u, z, t."""
        x = np.zeros(meta["n_x"])
        x[np.asarray(chosen, np.int64)] = 1.0
        A = sp.csr_matrix(arrays.A)
        A.sort_indices()
        vals = np.zeros(arrays.shape[1])
        vals[:meta["n_x"]] = x
        # coverage rows: u columns of a row filled in order up to the deficit
        Ax = A[:, :meta["n_x"]] @ x
        ucols = np.arange(meta["n_x"] + 2, arrays.shape[1])
        Au = A[:, ucols].tocsc()
        Au.sort_indices()
        row_of_u = Au.indices[Au.indptr[:-1]]  # first nonzero = its coverage row (rows come before cost rows)
        deficit = np.maximum(arrays.row_lower - Ax, 0)
        order = np.argsort(row_of_u, kind="stable")
        r = row_of_u[order]
        first = np.searchsorted(r, r)
        rank = np.arange(len(r)) - first + 1
        vals[ucols[order]] = (rank <= np.round(deficit[r])).astype(np.float64)
        rows_z = A[:, meta["col_z"]].tocoo().row
        zrow = rows_z[0]
        rest = A[zrow].toarray().ravel()
        rest[meta["col_z"]] = 0
        vals[meta["col_z"]] = arrays.row_lower[zrow] - rest @ vals
        trows = A[:, meta["col_t"]].tocoo().row
        At = A[trows]
        other = At @ vals  # without t (t is still 0)
        vals[meta["col_t"]] = max(arrays.col_lower[meta["col_t"]], float(np.max(arrays.row_lower[trows] - other)))
        return vals


def scenario_mip(problem: PlacementProblem, start: np.ndarray, *, pool: np.ndarray | None = None,
                 fixed: np.ndarray | None = None, time_limit_s: float | None = 60.0, threads: int | None = None,
                 seed: int = 0, eps: float = 0.0, t_lower: float = 0.0, mip_rel_gap: float | None = 1e-6,
                 init_scenarios: int | None = 5, highs_options: dict | None = None, should_stop=None,
                 max_rounds: int = 200) -> ScenarioResult:
    """min_S max_{s in S} cost(S minus s) by scenario generation on the exact scenario MIP:
    solve with the scenarios of the cameras in Σ (first: those of ``start``), add the
    scenarios of the selected cameras missing from Σ, repeat until none is missing. A model
    with a subset of the scenarios is a relaxation, so every round's HiGHS dual bound is a
    lower bound on the optimum; the round where none is missing, solved to optimality,
    proves its selection optimal. ``fixed`` cameras are kept (a subproblem: the optimum and
    bound are then those of the selections containing them), the others are chosen in
    ``pool`` (default: every candidate at a location no fixed camera uses). ``start`` (a
    feasible selection containing ``fixed``, its other cameras in the pool) warm-starts
    every round. eps > 0 adds eps·nominal cost to the objective (ties in W broken toward a
    lower nominal cost; the bound is divided by 1 + eps). t_lower: a known lower bound on
    the optimum (added as t >= t_lower). Deterministic with threads=1 unless a time limit
    cuts a round."""
    t0 = time.perf_counter()
    fixed = np.zeros(0, np.int64) if fixed is None else np.unique(np.asarray(fixed, np.int64))
    if pool is None:
        used = np.isin(problem.location_ids, problem.location_ids[fixed])
        pool = np.flatnonzero(~used)
    pool = np.unique(np.asarray(pool, np.int64))
    start = np.unique(np.asarray(start, np.int64))
    if not np.all(np.isin(fixed, start)) or not np.all(np.isin(start[~np.isin(start, fixed)], pool)):
        raise ValueError("scenario_mip: start must contain the fixed cameras and choose the others in the pool")
    problem.check_feasible(start)
    model = _ScenarioModel(problem, pool, fixed)
    best_sel = start
    best = _key(problem, start)
    chosen = np.array([model.pos[int(c)] for c in start if c not in set(fixed.tolist())], np.int64)
    if len(start):  # first scenarios: the start's most costly failures
        loss = removal_losses(problem, start)
        order = np.lexsort((start, -loss))
        n0 = len(start) if init_scenarios is None else min(init_scenarios, len(start))
        sigma = set(int(c) for c in start[order[:n0]])
    else:
        sigma = set()
    bound: float | None = None
    status = "time_limit"
    info: dict = {"rounds": 0, "pool": int(len(pool)), "fixed": int(len(fixed)), "targets": int(len(model.T)),
                  "nodes": 0}
    for _ in range(max_rounds):
        left = None if time_limit_s is None else time_limit_s - (time.perf_counter() - t0)
        if left is not None and left <= 0.05:
            break
        if stopped(should_stop):
            status = "interrupted"
            break
        arrays, meta = model.build(sorted(sigma), eps, t_lower)
        h = highs_from_arrays(arrays)
        sv = model.start_values(arrays, meta, chosen)
        left = None if time_limit_s is None else max(0.05, time_limit_s - (time.perf_counter() - t0))
        out = run_highs(h, time_limit_s=left, threads=threads, seed=seed, should_stop=should_stop, start=sv,
                        mip_rel_gap=mip_rel_gap, options=highs_options)
        info["rounds"] += 1
        info.update(scenarios=meta["scenarios"], rows=meta["rows"], columns=meta["cols"], nonzeros=meta["nnz"],
                    nodes=info["nodes"] + out.nodes)
        if out.bound is not None:
            b = max(out.bound / (1.0 + eps), t_lower)
            bound = b if bound is None else max(bound, b)
        if out.values is None:
            status = out.status if out.status in ("time_limit", "interrupted") else "feasible"
            break
        ch = np.flatnonzero(out.values[:meta["n_x"]] > 0.5)
        sel = np.sort(np.r_[fixed, model.pool[ch]])
        try:
            problem.check_feasible(sel)
        except ValueError:
            status = "feasible"
            break
        key = _key(problem, sel)
        if _better(key, best):
            best, best_sel, chosen = key, sel, ch
        # scenarios the model left out that this selection violates (failure cost above t)
        t_model = float(out.values[meta["col_t"]])
        fail = key[1] + removal_losses(problem, sel)
        tol = 1e-7 * max(1.0, abs(t_model))
        missing = {int(c) for c, f in zip(sel, fail) if f > t_model + tol and int(c) not in sigma}
        if not missing:
            status = out.status if out.status in ("optimal", "time_limit", "interrupted") else "feasible"
            break
        sigma |= missing
        if out.status != "optimal":
            status = out.status if out.status in ("time_limit", "interrupted") else "feasible"
            break
    else:
        status = "feasible"
    if bound is not None:
        bound = min(bound, best[0])
    info["seconds"] = time.perf_counter() - t0
    return ScenarioResult(best_sel, best[0], best[1], bound, status, info)



__all__ = ["ScenarioResult", "scenario_mip"]
