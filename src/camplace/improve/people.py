"""People seen by Γ^p cameras (issue 36): a swap descent that counts them.

The crowd-aware problem's squared cost (camplace.problem.people) values a person point's
first view (Γ^p = 2: 4 − 1) three times its second (1 − 0): its optimisers buy first views of
rarely seen people, and the share of people seen by ≥ 2 cameras barely moves.
``people_swap`` starts from a placement of that problem and descends (1-swap, first
improvement: camplace.solvers.local_search) on

    J(x) = cost(x) / N − β · n(x) / P,

cost the crowd-aware problem's own (mixed, squared) cost, N its normaliser, n(x) the
number of the optimisation crowds' people whose every point is covered ≥ its Γ^p
(camplace.problem.people.persons_seen: what metrics.json ``crowd.people.seen_by_gamma_pct``
counts on the held-out crowds), P the people in all, β = ``count_weight``. A move is the
best b for each camera a going out (the squared part's gains, camplace.problem.gains, plus
β / P per person it completes: camplace.problem.people.persons_completed), taken when J drops.

The cost cap (``cost_limit``, issue 36): E(x), the squared cost of the problem's columns
before ``start`` (the empty-store part), may not rise above ``cost_limit`` — a hard
constraint, not a penalty. A swap whose E would end above max(cost_limit, E now) is refused,
and so is a refinement pose (``pose_scores``: −inf) whose E would end above ``cost_limit``
(the caller passes max(cap, E at the refinement's start)): a descent that starts at or below
the cap never ends above it, one that starts above it never rises.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from camplace.problem.gains import shortfall_cost, target_gains
from camplace.problem.model import PlacementProblem
from camplace.problem.people import persons_completed, persons_seen
from camplace.solvers.local_search import SwapState, swap_deltas, swap_search


class PeopleCountObjective:
    """J of the module doc as a camplace.solvers.local_search.SwapObjective: the people are
    the problem's columns from ``start`` on, ``n_heights`` points each. A key is (δ, tol), δ
    the drop of J; the current selection's key is None (descent only, as NominalObjective).
    ``cost_limit``: the cap on the empty-store part's cost E (module doc; None: no cap)."""

    adds_first = True

    def __init__(self, problem: PlacementProblem, start: int, n_heights: int, count_weight: float,
                 abs_tol: float = 1e-12, cost_limit: float | None = None) -> None:
        self.p = problem
        self.col0, self.H = int(start), int(n_heights)
        self.PV = sp.csr_matrix(problem.V[:, self.col0:])
        self.limit = None if cost_limit is None else float(cost_limit)
        self.EV = sp.csr_matrix(problem.V[:, :self.col0]) if self.limit is not None else None
        self.gamma_p = np.asarray(problem.gamma, np.int64)[self.col0:]
        n_persons = max(len(self.gamma_p) // max(self.H, 1), 1)
        self.norm = problem.normalizer if problem.normalizer > 0 else 1.0
        self.per_person = float(count_weight) / n_persons
        self.abs_tol = abs_tol
        self.seen = 0

    def value(self, cov: np.ndarray) -> float:
        """J at coverage ``cov`` (N,)."""
        return (shortfall_cost(self.p.gamma, self.p.weights, cov) / self.norm
                - self.per_person * persons_seen(cov[self.col0:], self.gamma_p, self.H))

    def pose_scores(self, rows: sp.csr_matrix, g: np.ndarray, cov_other: np.ndarray) -> np.ndarray:
        """(K,) J's drop when a camera with one of ``rows`` (K, N) joins the others (coverage
        ``cov_other``; g: the squared cost's gains there): the refinement's pose_score."""
        R = sp.csr_matrix(rows)
        out = (np.asarray(R @ g).ravel() / self.norm + self.per_person *
               persons_completed(R[:, self.col0:], cov_other[self.col0:], self.gamma_p, self.H))
        if self.limit is None:
            return out
        return np.where(self.empty_cost_with(R[:, :self.col0], cov_other) > self.cap(self.limit), -np.inf, out)

    def empty_cost(self, cov: np.ndarray) -> float:
        """E at coverage ``cov`` (N,): the squared cost of the columns before ``start``."""
        c0 = self.col0
        return shortfall_cost(self.p.gamma[:c0], self.p.weights[:c0], cov[:c0])

    def empty_cost_with(self, rows: sp.csr_matrix, cov: np.ndarray) -> np.ndarray:
        """(K,) E when a camera with one of ``rows`` (K, start) joins coverage ``cov`` (N,)."""
        c0 = self.col0
        tg = target_gains(self.p.gamma[:c0], self.p.weights[:c0], cov[:c0])
        return self.empty_cost(cov) - np.asarray(rows @ tg).ravel()

    def cap(self, allowed: float) -> float:
        """The largest E a move may reach when ``allowed`` is the most it may be (a relative
        tolerance for float sums)."""
        return allowed + 1e-9 * max(abs(allowed), 1.0)

    def start(self, state: SwapState):
        self.seen = persons_seen(state.cov[self.col0:], self.gamma_p, self.H)
        return None

    def begin_pass(self, state: SwapState) -> None:
        return None

    def moves(self, state: SwapState, a: int | None, allowed: np.ndarray):
        delta, cov = swap_deltas(self.p, state, a)
        cp = cov[self.col0:]
        kept = persons_seen(cp, self.gamma_p, self.H) - self.seen  # people lost with a (≤ 0)
        g = delta / self.norm + self.per_person * (persons_completed(self.PV, cp, self.gamma_p, self.H) + kept)
        if self.limit is not None:  # the cost cap: no move past max(limit, E now)
            allowed = allowed & (self.empty_cost_with(self.EV, cov) <= self.cap(max(self.limit,
                                                                                      self.empty_cost(state.cov))))
        g = np.where(allowed, g, -np.inf)
        if not len(g):
            return []
        b = int(np.argmax(g))
        if not np.isfinite(g[b]):
            return []
        return [(b, (float(g[b]), self.abs_tol))]

    def better(self, k1, k2) -> bool:
        return k1[0] > k1[1] if k2 is None else k1[0] > k2[0]

    def moved(self, state: SwapState, a: int | None, b: int, key) -> None:
        self.seen = persons_seen(state.cov[self.col0:], self.gamma_p, self.H)
        return None

    def done(self) -> bool:
        return False


def people_swap(problem: PlacementProblem, selected: np.ndarray, start: int, n_heights: int, count_weight: float,
                *, end: float = float("inf"), should_stop=None,
                cost_limit: float | None = None) -> tuple[np.ndarray, dict]:
    """The 1-swap descent on J (module doc) from ``selected``, under the cost cap
    ``cost_limit`` (None: none): (selection (k,) int64 sorted, info: moves, stopped,
    seconds, people seen before / after)."""
    t0 = time.perf_counter()
    obj = PeopleCountObjective(problem, start, n_heights, count_weight, cost_limit=cost_limit)
    sel0 = np.asarray(selected, np.int64)
    before = persons_seen(problem.coverage(sel0)[obj.col0:], obj.gamma_p, obj.H)
    sel, info = swap_search(problem, [int(i) for i in sel0], obj, first_improvement=True, end=end,
                            should_stop=should_stop, money_tol=1e-12)
    out = np.array(sorted(sel), np.int64)
    after = persons_seen(problem.coverage(out)[obj.col0:], obj.gamma_p, obj.H)
    return out, {"moves": int(info["moves"]), "stopped": info["stopped"], "seconds": time.perf_counter() - t0,
                 "people": len(obj.gamma_p) // max(obj.H, 1), "people_seen_before": before, "people_seen": after}


__all__ = ["PeopleCountObjective", "people_swap"]
