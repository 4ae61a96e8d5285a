"""Stage 5 - the placement problem: V, Γ, weights, budget and location groups.

Solvers see only this object (no geometry). The cost of a selection x is
Σ_j w_j · max(Γ_j − Σ_i V_ij x_i, 0)²  (paper eq. 1 with weights).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from camplace.core.errors import InputError
from camplace.problem.gains import shortfall_cost  # the one home of gains and costs; re-exported here



@dataclass(frozen=True)
class PlacementProblem:
    """V: (N_g, N_p) CSR 0/1; gamma: (N_p,) int64; weights: (N_p,) float64;
    budget: at most this many cameras; location_ids: (N_g,) int64, at most one camera
    per location; camera_costs: (N_g,) float64 price of each candidate (default 1);
    candidate_positions / target_positions: optional (N_g, 3) / (N_p, 3) positions in m,
    only for solvers tagged needs_positions (not kept by reduce_problem); type_ids: (N_g,)
    int64 camera type of each candidate and type_limits {type id: n}: at most n selected
    cameras of that type (types not named, and type id −1, have no limit; issue 17)."""

    V: sp.csr_matrix
    gamma: np.ndarray
    weights: np.ndarray
    budget: int
    location_ids: np.ndarray
    camera_costs: np.ndarray | None = None
    money_budget: float | None = None  # Σ camera_costs[selected] must not exceed this (None: no limit)
    candidate_positions: np.ndarray | None = None  # (N_g, 3) m, for solvers that need geometry
    target_positions: np.ndarray | None = None  # (N_p, 3) m, for solvers that need geometry
    type_ids: np.ndarray | None = None  # (N_g,) int64 camera type of each candidate (−1: no type)
    type_limits: dict[int, int] | None = None  # type id -> at most this many selected cameras of it

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
        if self.type_limits:
            if self.type_ids is None or np.shape(self.type_ids) != (n_g,):
                raise InputError(f"problem: type_ids must have shape ({n_g},) when type_limits are given")
            if any(int(v) < 0 for v in self.type_limits.values()):
                raise InputError(f"problem: type_limits must be >= 0, got {self.type_limits}")

    @property
    def has_type_limits(self) -> bool:
        """True when some camera type has a limit (type_limits non-empty)."""
        return bool(self.type_limits)

    def limited_types(self) -> np.ndarray:
        """(N_g,) int64: each candidate's type where that type has a limit, else −1."""
        if not self.has_type_limits:
            return np.full(self.n_candidates, -1, np.int64)
        t = np.asarray(self.type_ids, np.int64)
        return np.where(np.isin(t, [int(k) for k in self.type_limits]), t, -1)

    def type_counts(self, selected: np.ndarray) -> dict[int, int]:
        """{limited type id: selected cameras of it} (every limited type, zeros included)."""
        t = self.limited_types()[np.asarray(selected, np.int64)]
        return {int(k): int(np.sum(t == int(k))) for k in (self.type_limits or {})}

    def type_ok(self, selected: np.ndarray) -> bool:
        """True when no camera type has more selected cameras than its limit."""
        return all(n <= int(self.type_limits[k]) for k, n in self.type_counts(selected).items())

    def type_full(self, selected: np.ndarray) -> np.ndarray:
        """(N_g,) bool: candidates whose type is at its limit with ``selected`` (adding one breaks it)."""
        lt = self.limited_types()
        full = [k for k, n in self.type_counts(selected).items() if n >= int(self.type_limits[k])]
        return np.isin(lt, full) if full else np.zeros(self.n_candidates, bool)

    def type_rows(self) -> tuple[sp.csr_matrix, np.ndarray]:
        """((T, N_g) CSR 0/1, (T,) float64): one row Σ_{i of type t} x_i <= limit_t per limited type."""
        keys = sorted(int(k) for k in (self.type_limits or {}))
        lt = self.limited_types()
        cols = np.flatnonzero(lt >= 0)
        rows = np.searchsorted(keys, lt[cols])
        A = sp.csr_matrix((np.ones(len(cols)), (rows, cols)), shape=(len(keys), self.n_candidates))
        return A, np.array([float(self.type_limits[k]) for k in keys])

    @property
    def n_candidates(self) -> int:
        return int(self.V.shape[0])

    @property
    def n_targets(self) -> int:
        return int(self.V.shape[1])

    @property
    def normalizer(self) -> float:
        """Σ_j w_j Γ_j², the cost of placing no camera (denominator of paper eq. 8): the
        shortfall cost at zero coverage, by the same formula (bit for bit the cost of no camera)."""
        return shortfall_cost(self.gamma, self.weights, np.zeros(self.n_targets, np.int64))

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
        if self.has_type_limits and not self.type_ok(sel):
            raise ValueError(f"cameras per type {self.type_counts(sel)} exceed the limits {self.type_limits}")

    def type_fields(self, rows: np.ndarray | None = None) -> dict:
        """{'type_ids', 'type_limits'} for a problem on candidate ``rows`` (default all)."""
        ids = self.type_ids
        if ids is not None and rows is not None:
            ids = np.asarray(ids)[np.asarray(rows, np.int64)]
        return {"type_ids": ids, "type_limits": self.type_limits}

    def take_candidates(self, rows: np.ndarray) -> "PlacementProblem":
        """The problem on candidate rows ``rows`` (k,) only: V, location ids, prices,
        types and positions subset; targets, budgets and type limits kept."""
        r = np.asarray(rows, np.int64)
        pick = lambda a: None if a is None else np.asarray(a)[r]  # noqa: E731
        return replace(self, V=sp.csr_matrix(self.V[r]), location_ids=np.asarray(self.location_ids)[r],
                       camera_costs=pick(self.camera_costs), type_ids=pick(self.type_ids),
                       candidate_positions=pick(self.candidate_positions))

    @property
    def costs(self) -> np.ndarray:
        """(N_g,) float64 price of each candidate (camera_costs, or 1 each when not given)."""
        if self.camera_costs is None:
            return np.ones(self.n_candidates)
        return np.asarray(self.camera_costs, np.float64)


class TypeBudget:
    """Cameras left per limited type while a selection grows or changes (issue 17):
    ``allows(i)`` before adding candidate i, ``add`` / ``remove`` after; ``swap_ok(out, in)``."""

    def __init__(self, problem: PlacementProblem, selected=()) -> None:
        self.of = problem.limited_types()
        self.left = {int(k): int(v) for k, v in (problem.type_limits or {}).items()}
        for i in selected:
            self.add(int(i))

    def allows(self, i: int) -> bool:
        t = int(self.of[i])
        return t < 0 or self.left[t] > 0

    def add(self, i: int) -> None:
        t = int(self.of[i])
        if t >= 0:
            self.left[t] -= 1

    def remove(self, i: int) -> None:
        t = int(self.of[i])
        if t >= 0:
            self.left[t] += 1

    def swap_ok(self, out: int, into: int) -> bool:
        """True when replacing selected ``out`` by ``into`` keeps every type limit."""
        t = int(self.of[into])
        return t < 0 or self.left[t] > 0 or int(self.of[out]) == t

    def full(self) -> np.ndarray:
        """(N_g,) bool: candidates whose type has no camera left."""
        done = [t for t, n in self.left.items() if n <= 0]
        return np.isin(self.of, done) if done else np.zeros(len(self.of), bool)


def type_arrays(problem: PlacementProblem) -> tuple[np.ndarray, np.ndarray]:
    """((N_g,) int64 dense limited-type index of each candidate or −1, (T,) int64 limits;
    T >= 1 so the compiled code always gets an array)."""
    lt = problem.limited_types()
    keys = sorted(int(k) for k in (problem.type_limits or {}))
    ctype = np.where(lt >= 0, np.searchsorted(keys, lt), -1).astype(np.int64)
    tlim = np.array([int(problem.type_limits[k]) for k in keys] or [0], np.int64)
    return ctype, tlim


def with_type_limits(problem: PlacementProblem, camera_ids: np.ndarray, camera_names,
                     max_per_type: dict[str, int] | None) -> PlacementProblem:
    """``problem`` with type_ids from camera_ids (N_g,) (index into camera_names; see
    ``type_ids_of``) and type_limits from max_per_type {camera name: at most n cameras}
    (the scene's mount_rules.max_per_type); unchanged without limits. A name no candidate
    uses limits nothing."""
    if not max_per_type:
        return problem
    names = list(camera_names)
    limits = {names.index(n): int(v) for n, v in max_per_type.items() if n in names}
    return replace(problem, type_ids=type_ids_of(camera_ids, names), type_limits=limits or None)


def type_ids_of(camera_ids: np.ndarray, camera_names) -> np.ndarray:
    """(N_g,) int64 camera type of each candidate: the first index in ``camera_names`` of
    its camera's name, so every focal setting of one type (the same name; issue 27)
    counts toward that type's limit."""
    names = list(camera_names)
    first = np.array([names.index(n) for n in names], np.int64)
    return first[np.asarray(camera_ids, np.int64)] if len(names) else np.asarray(camera_ids, np.int64)


def build_problem(V: sp.csr_matrix, gamma: np.ndarray, weights: np.ndarray | None, budget: int,
                  location_ids: np.ndarray | None = None) -> PlacementProblem:
    """Problem from arrays; location_ids default to one location per candidate."""
    V = sp.csr_matrix(V)
    n_g, n_p = V.shape
    w = np.ones(n_p) if weights is None else np.asarray(weights, np.float64)
    loc = np.arange(n_g, dtype=np.int64) if location_ids is None else np.asarray(location_ids, np.int64)
    return PlacementProblem(V, np.asarray(gamma, np.int64), w, int(budget), loc)


def feasible_selections(problem: PlacementProblem, max_size: int | None = None):
    """Yield every feasible selection ((k,) int64, sorted) of at most max_size (default
    N_s) cameras, the empty one first. Exponential: for tests and tiny instances."""
    import itertools

    top = problem.budget if max_size is None else max_size
    for k in range(0, min(top, problem.n_candidates) + 1):
        for c in itertools.combinations(range(problem.n_candidates), k):
            sel = np.array(c, np.int64)
            try:
                if max_size is None:
                    problem.check_feasible(sel)
            except ValueError:
                continue
            if max_size is not None and (len(np.unique(problem.location_ids[sel])) != k
                                         or not problem.type_ok(sel)):
                continue
            yield sel


def brute_force_optimum(problem: PlacementProblem, max_candidates: int = 14) -> tuple[float, np.ndarray]:
    """(optimal cost, one optimal selection) by enumerating every feasible selection.
    Exponential: for tests and tiny instances only (InputError above max_candidates)."""
    if problem.n_candidates > max_candidates:
        raise InputError(f"brute force: {problem.n_candidates} candidates, at most {max_candidates} allowed")
    best, best_sel = problem.normalizer, np.zeros(0, np.int64)
    for sel in feasible_selections(problem):
        cost = problem.cost(sel)
        if cost < best:
            best, best_sel = cost, sel
    return best, best_sel


# ---------------------------------------------------------------------------
# Reductions that keep the optimum (applied by camplace.solvers.solve before any solver)


@dataclass(frozen=True)
class Reduction:
    """A reduced problem and the maps back. candidates: (N_g',) int64 original id of each
    reduced row; target_map: (N_p,) int64 reduced target of each original target (−1:
    dropped because it can never cost anything: Γ_j = 0 or w_j = 0); info: sizes
    before/after and what each rule removed."""

    problem: PlacementProblem
    candidates: np.ndarray
    target_map: np.ndarray
    info: dict

    def lift(self, selected: np.ndarray) -> np.ndarray:
        """Reduced candidate ids -> sorted original candidate ids."""
        return np.sort(self.candidates[np.asarray(selected, np.int64)])


def dominated_candidates(V: sp.csr_matrix, location_ids: np.ndarray, costs: np.ndarray,
                         types: np.ndarray | None = None) -> np.ndarray:
    """(N_g,) bool: candidate a is dominated when another candidate b at the SAME location
    sees a superset of its targets at no higher price (exact ties: the lower id survives),
    and (with ``types``, (N_g,) limited type or −1) b is of a's type or of no limited type.
    Replacing a by b keeps every constraint and never raises any cost, so dropping a keeps
    the optimum. (Across locations this is not valid: it can break one-per-location.)"""
    n_g = V.shape[0]
    out = np.zeros(n_g, bool)
    order = np.argsort(location_ids, kind="stable")
    locs = location_ids[order]
    bounds = np.flatnonzero(np.diff(locs)) + 1
    nnz = np.diff(V.indptr)
    for group in np.split(order, bounds):
        if len(group) < 2:
            continue
        sub = V[group].astype(np.int32)
        inter = (sub @ sub.T).toarray()
        n = nnz[group]
        c = costs[group]
        t = None if types is None else types[group]
        # key order: more targets, then cheaper, then lower id wins
        subset = inter == n[:, None]  # subset[a, b]: row a ⊆ row b
        np.fill_diagonal(subset, False)
        better = (n[None, :] > n[:, None]) | ((n[None, :] == n[:, None]) & (
            (c[None, :] < c[:, None]) | ((c[None, :] == c[:, None]) & (group[None, :] < group[:, None]))))
        dom = subset & (c[None, :] <= c[:, None]) & better
        if t is not None:  # b may stand in for a only if it uses no limit a does not use
            dom &= (t[None, :] == t[:, None]) | (t[None, :] < 0)
        out[group[dom.any(axis=1)]] = True
    return out


def reduce_problem(problem: PlacementProblem, dominance: bool = True) -> Reduction:
    """Apply, in order: drop targets that never cost anything (Γ_j = 0 or w_j = 0); drop
    candidates that see no remaining target; drop candidates dominated at their own
    location (:func:`dominated_candidates`); merge targets with identical columns and Γ
    into one target whose weight is the sum. The reduced problem has the same optimal
    cost, and cost(lift(s)) == reduced cost(s) for every selection s."""
    import time

    t0 = time.perf_counter()
    V = sp.csr_matrix(problem.V)
    n_g, n_p = V.shape
    info: dict = {"candidates_before": n_g, "targets_before": n_p, "nonzeros_before": int(V.nnz)}
    live_t = np.nonzero((problem.gamma > 0) & (problem.weights > 0))[0]
    info["dropped_zero_targets"] = int(n_p - len(live_t))
    Vt = V[:, live_t].tocsr()
    row_nnz = np.diff(Vt.indptr)
    keep_c = row_nnz > 0
    info["dropped_blind_candidates"] = int((~keep_c).sum())
    costs = problem.costs
    if dominance:
        cand = np.nonzero(keep_c)[0]
        types = problem.limited_types()[cand] if problem.has_type_limits else None
        dom = dominated_candidates(Vt[cand], problem.location_ids[cand], costs[cand], types)
        keep_c[cand[dom]] = False
        info["dropped_dominated_candidates"] = int(dom.sum())
    cand = np.nonzero(keep_c)[0]
    Vc = Vt[cand]
    # merge identical (column, Γ)
    cols = sp.csc_matrix(Vc)
    cols.sort_indices()
    gamma_live = problem.gamma[live_t]
    key_to_new: dict[tuple, int] = {}
    group_of = np.empty(len(live_t), np.int64)
    for j in range(len(live_t)):
        key = (int(gamma_live[j]), cols.indices[cols.indptr[j]:cols.indptr[j + 1]].tobytes())
        g = key_to_new.setdefault(key, len(key_to_new))
        group_of[j] = g
    n_new = len(key_to_new)
    first = np.full(n_new, -1, np.int64)
    first[group_of[::-1]] = np.arange(len(live_t))[::-1]
    weights = np.bincount(group_of, weights=problem.weights[live_t], minlength=n_new)
    Vr = sp.csr_matrix(cols[:, first])
    Vr.sort_indices()
    target_map = np.full(n_p, -1, np.int64)
    target_map[live_t] = group_of
    info["merged_targets"] = int(len(live_t) - n_new)
    reduced = PlacementProblem(Vr, gamma_live[first].astype(np.int64), weights.astype(np.float64), problem.budget,
                               np.asarray(problem.location_ids)[cand],
                               None if problem.camera_costs is None else costs[cand], problem.money_budget,
                               type_ids=None if problem.type_ids is None else np.asarray(problem.type_ids)[cand],
                               type_limits=problem.type_limits)
    info.update(candidates_after=int(len(cand)), targets_after=int(n_new), nonzeros_after=int(Vr.nnz),
                seconds=time.perf_counter() - t0)
    return Reduction(reduced, cand.astype(np.int64), target_map, info)
