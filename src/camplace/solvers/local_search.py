"""One swap local search for every objective.

A move exchanges a selected camera a for an unselected candidate b (b's location free,
or a's own: a pose change), or adds b while the selection is below the budget (a = None);
every move keeps the money budget and the per-type limits. What a move is worth comes from an objective
(:class:`SwapObjective`): :class:`NominalObjective` scores the squared-shortfall cost
(greedy's 1-swap and the adaptive rounds' descent), camplace.solvers.robust scores the
worst single-failure cost. :func:`swap_search` drives either one:

- first improvement (``first_improvement=True``): each pass tries the add, then every
  selected camera in turn, and applies a move as soon as it improves (an add restarts
  the pass; a swap replaces the camera in place and the pass goes on);
- best improvement: each pass applies the single best move (a swap removes a and
  appends b); with ``max_stall > 0`` it goes on as a tabu search: when no move improves
  it takes the least bad one (the camera removed may not come back for ``tenure``
  passes) until ``max_stall`` moves in a row have not improved the best selection,
  which it returns.
"""

from __future__ import annotations

import time
from typing import Any, Iterable, Protocol

import numpy as np

from camplace.problem.gains import row, shortfall_cost, target_gains
from camplace.problem.model import PlacementProblem, TypeBudget
from camplace.solvers.base import OnIncumbent, ShouldStop, stopped

Key = Any  # an objective's score of a selection (compared only by the objective's `better`)


class SwapState:
    """The selection being searched: sel (list of candidate ids, in move order), cov
    (N_p,) int64 coverage, and the location / money / per-type rules of the moves."""

    def __init__(self, problem: PlacementProblem, selected: Iterable[int], money_tol: float = 1e-9) -> None:
        self.problem = problem
        self.sel = [int(i) for i in selected]
        self.cov = problem.coverage(np.array(self.sel, np.int64))
        _, self.loc = np.unique(problem.location_ids, return_inverse=True)
        self.loc_used = np.zeros(int(self.loc.max()) + 1 if len(self.loc) else 0, bool)
        self.loc_used[self.loc[self.sel]] = True
        self.is_sel = np.zeros(problem.n_candidates, bool)
        self.is_sel[self.sel] = True
        self.costs = problem.costs
        self.money_tol = float(money_tol)
        self.types = TypeBudget(problem, self.sel) if problem.has_type_limits else None

    def row(self, i: int) -> np.ndarray:
        """Target ids seen by candidate i."""
        return row(self.problem.V, i)

    def allowed(self, a: int | None) -> np.ndarray:
        """(N_g,) bool: the candidates b that may come in when a goes out (a = None: an add)."""
        free = ~self.loc_used[self.loc]
        if a is not None:
            free |= self.loc == self.loc[a]
        ok = ~self.is_sel & free
        money = self.problem.money_budget
        if money is not None:
            spent = float(self.costs[self.sel].sum()) if self.sel else 0.0
            if a is not None:
                spent -= self.costs[a]
            ok &= spent + self.costs <= money + self.money_tol
        if self.types is not None:
            full = self.types.full()
            if a is not None:  # a going out frees one camera of its own type
                full &= self.types.of != self.types.of[a]
            ok &= ~full
        return ok

    def apply(self, a: int | None, b: int, in_place: bool) -> None:
        """Swap a out (unless None) and b in; in_place puts b at a's position in sel."""
        if a is not None:
            if in_place:
                self.sel[self.sel.index(a)] = b
            else:
                self.sel.remove(a)
                self.sel.append(b)
            self.is_sel[a] = False
            self.loc_used[self.loc[a]] = False
            self.cov[self.row(a)] -= 1
            if self.types is not None:
                self.types.remove(a)
        else:
            self.sel.append(b)
        if self.types is not None:
            self.types.add(b)
        self.is_sel[b] = True
        self.loc_used[self.loc[b]] = True
        self.cov[self.row(b)] += 1


class SwapObjective(Protocol):
    """What swap_search needs of an objective. adds_first: try the add before the swaps."""

    adds_first: bool

    def start(self, state: SwapState) -> Key:
        """Key of the starting selection."""

    def begin_pass(self, state: SwapState) -> None:
        """Called once per pass before any move is scored."""

    def moves(self, state: SwapState, a: int | None, allowed: np.ndarray) -> Iterable[tuple[int, Key]]:
        """Candidate moves (b, key after the move) for removing a, b among ``allowed``."""

    def better(self, k1: Key, k2: Key) -> bool:
        """k1 strictly better than k2."""

    def moved(self, state: SwapState, a: int | None, b: int, key: Key) -> Key:
        """After a move was applied to state: the key of the current selection."""

    def done(self) -> bool:
        """Nothing left to gain (first improvement then stops without another pass)."""


def swap_deltas(problem: PlacementProblem, state: SwapState, a: int | None) -> tuple[np.ndarray, np.ndarray]:
    """((N_g,) the squared-shortfall cost's drop when a (None: nothing) goes out and b comes in,
    for every candidate b; (N_p,) the coverage without a)."""
    cov = state.cov
    if a is not None:
        cov = cov.copy()
        cov[state.row(a)] -= 1
    tg = target_gains(problem.gamma, problem.weights, cov)
    loss = float(tg[state.row(a)].sum()) if a is not None else 0.0
    return np.asarray(problem.V @ tg).ravel() - loss, cov


class NominalObjective:
    """The squared-shortfall cost. A key is (improvement δ, tolerance); the current
    selection's key is None and a move beats it when δ > tolerance (abs_tol for an add,
    max(abs_tol, rel_tol · cost) for a swap); moves compare by δ. For each a, moves()
    gives the one best b (largest gain at the coverage without a; ties: lowest id). Its
    keys are relative to the current selection, so it serves descent only (max_stall = 0)."""

    adds_first = True

    def __init__(self, problem: PlacementProblem, *, rel_tol: float = 0.0, abs_tol: float = 1e-9,
                 on_incumbent: OnIncumbent | None = None) -> None:
        self.p = problem
        self.rel_tol, self.abs_tol = rel_tol, abs_tol
        self.on_incumbent = on_incumbent
        self.cost = 0.0

    def start(self, state: SwapState) -> Key:
        self.cost = shortfall_cost(self.p.gamma, self.p.weights, state.cov)
        return None

    def begin_pass(self, state: SwapState) -> None:
        return None

    def moves(self, state: SwapState, a: int | None, allowed: np.ndarray) -> Iterable[tuple[int, Key]]:
        delta, _ = swap_deltas(self.p, state, a)
        g = np.where(allowed, delta, -np.inf)
        if not len(g):
            return []
        b = int(np.argmax(g))
        if not np.isfinite(g[b]):
            return []
        tol = self.abs_tol if a is None else max(self.abs_tol, self.rel_tol * self.cost)
        return [(b, (float(g[b]), tol))]

    def better(self, k1: Key, k2: Key) -> bool:
        return k1[0] > k1[1] if k2 is None else k1[0] > k2[0]

    def moved(self, state: SwapState, a: int | None, b: int, key: Key) -> Key:
        self.cost = shortfall_cost(self.p.gamma, self.p.weights, state.cov)
        if self.on_incumbent and a is not None:
            self.on_incumbent(self.cost, None)
        return None

    def done(self) -> bool:
        return self.cost <= 0


def _timed_out(end: float, should_stop: ShouldStop | None) -> str | None:
    if time.perf_counter() > end:
        return "time_limit"
    if stopped(should_stop):
        return "interrupted"
    return None


def swap_search(problem: PlacementProblem, selected: Iterable[int], objective: SwapObjective, *,
                first_improvement: bool = False, end: float = float("inf"), should_stop: ShouldStop | None = None,
                max_passes: int | None = None, max_stall: int = 0, tenure: int = 0,
                money_tol: float = 1e-9) -> tuple[list[int], dict]:
    """Swap local search from ``selected`` (module doc). end: perf_counter() deadline.
    Returns (selection: the final one, or with max_stall > 0 the best seen; info: moves,
    passes, stopped ('converged' | 'time_limit' | 'interrupted' | 'max_passes'), seconds)."""
    t0 = time.perf_counter()
    state = SwapState(problem, selected, money_tol)
    cur = objective.start(state)
    if max_stall > 0 and cur is None:
        raise ValueError("swap_search: max_stall > 0 needs an objective with absolute keys")
    best_key, best_sel = cur, list(state.sel)
    tabu_until = np.zeros(problem.n_candidates, np.int64)
    moves = passes = stall = 0
    status = "converged"
    while True:
        if max_passes is not None and passes >= max_passes:
            status = "max_passes"
            break
        if first_improvement and objective.done():
            break
        cut = None if first_improvement else _timed_out(end, should_stop)  # first improvement: checked per camera
        if cut:
            status = cut
            break
        passes += 1
        objective.begin_pass(state)
        outs: list[int | None] = list(state.sel)
        if len(outs) < problem.budget:
            outs = [None] + outs if objective.adds_first else outs + [None]
        best, fallback, improved = (cur, None, None), None, False
        for a in outs:
            cut = None if a is None else _timed_out(end, should_stop)
            if cut:
                break
            allowed = state.allowed(a) & (tabu_until <= passes)
            for b, key in objective.moves(state, a, allowed):
                if first_improvement:
                    if objective.better(key, cur):
                        state.apply(a, b, in_place=True)
                        cur = objective.moved(state, a, b, key)
                        moves += 1
                        improved = True
                        break
                elif objective.better(key, best[0]):
                    best = (key, a, b)
                elif fallback is None or objective.better(key, fallback[0]):
                    fallback = (key, a, b)
            if improved and a is None:
                break  # an add restarts the pass
        if first_improvement:
            if cut:
                status = cut
                break
            if not improved:
                break
            continue
        if best[2] is None:
            if fallback is None or stall >= max_stall:
                break
            best = fallback  # tabu step: the least bad move
        key, a, b = best
        if a is not None:
            tabu_until[a] = passes + tenure
        state.apply(a, b, in_place=False)
        cur = objective.moved(state, a, b, key)
        moves += 1
        if max_stall > 0:
            if objective.better(cur, best_key):
                best_key, best_sel = cur, list(state.sel)
                stall = 0
            else:
                stall += 1  # moves since the best selection last improved
    sel = best_sel if max_stall > 0 else state.sel
    return sel, {"moves": moves, "passes": passes, "stopped": status, "seconds": time.perf_counter() - t0}


__all__ = ["NominalObjective", "SwapObjective", "SwapState", "swap_deltas", "swap_search"]
