"""Certified placements: spend a time budget on both sides of the gap.

Incumbent side: tabu search (camplace.solvers.tabu) from greedy.
Bound side: Lagrangian bound warm-started from the incumbent's coverage; with time
to spare, the LP by HiGHS interior point; then Lagrangian fixing (drop every
candidate that cannot be in a selection cheaper than the incumbent, force locations
that must hold a camera) and HiGHS branch-and-cut on the reduced problem, whose
dual bound is valid for the whole problem (proofs in docs/certify.md).

With threads >= 2 (default) the tabu search runs in a second thread (its numba
kernel releases the GIL) while the bound side works; with threads = 1 the time is
split: 40 % tabu, then the bound side.
"""

from __future__ import annotations

import threading
import time
from typing import Callable

import numpy as np

from camplace.problem.model import PlacementProblem
from camplace.solvers.base import Placement
from camplace.solvers.contract import Tags, make_solver
from camplace.solvers.bounds import Lagrangian, lagrangian_bound, lp_bound, reduce_by_fixing, solve_reduced_mip
from camplace.solvers.tabu import TabuSearch


class _Board:
    """Best incumbent and bound so far, and who found them; reports every change."""

    def __init__(self, problem: PlacementProblem, on_incumbent, on_state, t0: float) -> None:
        self.problem = problem
        self.lock = threading.Lock()
        self.selected = np.zeros(0, np.int64)
        self.objective = float("inf")
        self.bound = 0.0
        self.incumbent_method = "none"
        self.bound_method = "trivial"
        self.on_incumbent = on_incumbent
        self.on_state = on_state
        self.t0 = t0
        # with integer weights every cost is an integer, so a bound rounds up
        w = problem.weights
        self.integral = bool(np.all(w == np.round(w)))

    def gap(self) -> float:
        if self.objective <= 0:
            return 0.0
        gap = (self.objective - self.bound) / self.objective
        return 0.0 if gap <= 1e-9 else gap

    def _report(self) -> None:
        if self.on_incumbent is not None:
            self.on_incumbent(self.objective, self.bound)
        if self.on_state is not None:
            self.on_state({"objective": self.objective, "bound": self.bound, "gap": self.gap(),
                           "incumbent_method": self.incumbent_method, "bound_method": self.bound_method})

    def offer_incumbent(self, selected: np.ndarray, method: str) -> None:
        sel = np.sort(np.asarray(selected, np.int64))
        cost = self.problem.cost(sel)  # recomputed from V: the reported cost is exact
        with self.lock:
            if cost < self.objective - 1e-9:
                self.problem.check_feasible(sel)
                self.selected, self.objective, self.incumbent_method = sel, cost, method
                self.bound = min(self.bound, cost)
                self._report()

    def offer_bound(self, bound: float, method: str) -> None:
        bound = float(bound)
        if self.integral and np.isfinite(bound):
            bound = float(np.ceil(bound - 1e-6))
        with self.lock:
            b = min(bound, self.objective)
            if b > self.bound + 1e-9:
                self.bound, self.bound_method = b, method
                self._report()


def _tabu_worker(ts: TabuSearch, board: _Board, stop: threading.Event, end: float, chunk: int,
                 stall_restarts: int | None = None) -> None:
    """Advance the tabu search until `end` (or `stall_restarts` restarts pass without a
    better placement), offering each new best to the board."""
    best = ts.best_cost
    since = ts.restarts
    while not stop.is_set() and time.perf_counter() < end:
        ts.run(chunk)
        if ts.best_cost < best - 1e-9:
            best = ts.best_cost
            since = ts.restarts
            board.offer_incumbent(ts.best_selected, "tabu")
        if board.gap() <= 0.0:
            break
        if stall_restarts is not None and ts.restarts - since >= stall_restarts:
            break


def solve_certify(problem: PlacementProblem, *, time_limit_s: float | None = None, threads: int | None = None,
                  seed: int = 0, should_stop: Callable[[], bool] | None = None, progress=None, on_incumbent=None,
                  on_state: Callable[[dict], None] | None = None, lp: bool | None = None,
                  reduced_mip: bool = True, region: bool | None = None, tenure_add: int | None = None,
                  tenure_rem: int | None = None, stall_limit: int | None = None, perturb: int | None = None,
                  k_rcl: int = 3) -> Placement:
    """Incumbent by tabu search, bound by Lagrangian (+ LP, + fixing and exact reduced
    MIP), within `time_limit_s` (default 60 s). Placement.bound is the best proven
    bound; info has incumbent_method, bound_method, gap and both sides' history.
    on_incumbent(objective, bound) and on_state(dict) are called whenever a side improves.
    `lp`: solve the LP by interior point (default: when time_limit_s >= 60).
    `region`: after the LP, spend a third of the time left on the partial Lagrangian
    bound (costly target regions holding 60 % of the targets exact) and a quarter of
    the rest on the region decomposition bound (camplace.solvers.region_bound, docs/certify.md §6-9), started
    from the LP duals when the LP finished, else from the Lagrangian multipliers
    (it also turns the LP on). Default (None): the partial bound alone, when
    time_limit_s >= 300 and the LP finished; False: neither."""
    if problem.money_budget is not None:  # issue 10: tabu and fixing ignore prices; the MIP models the money row
        from dataclasses import replace as _replace

        from camplace.solvers.mip import solve_mip

        p = solve_mip(problem, time_limit_s=60.0 if time_limit_s is None else time_limit_s, threads=threads,
                      seed=seed, should_stop=should_stop, progress=progress, on_incumbent=on_incumbent)
        return _replace(p, solver="certify", info=dict(p.info, money_budget="delegated to mip"))
    t0 = time.perf_counter()
    T = 60.0 if time_limit_s is None else float(time_limit_s)
    end = t0 + T
    n_threads = 2 if threads is None else max(1, int(threads))
    history: list[tuple[float, float, float]] = []

    def _state(s: dict) -> None:
        history.append((round(time.perf_counter() - t0, 3), s["objective"], s["bound"]))
        if on_state is not None:
            on_state(s)

    board = _Board(problem, on_incumbent, _state, t0)
    stop_evt = threading.Event()

    def stop_now() -> bool:
        if should_stop is not None and should_stop():
            stop_evt.set()
        return stop_evt.is_set() or time.perf_counter() >= end

    ts = TabuSearch(problem, seed=seed, tenure_add=tenure_add, tenure_rem=tenure_rem, stall_limit=stall_limit,
                    perturb=perturb, k_rcl=k_rcl)
    board.offer_incumbent(ts.best_selected, "greedy")
    if problem.budget == 0 or problem.n_candidates == 0:
        board.offer_bound(board.objective, "exact (nothing to choose)")
    worker = None
    if board.gap() > 0:
        if n_threads >= 2:
            worker = threading.Thread(target=_tabu_worker, args=(ts, board, stop_evt, end, 10), daemon=True)
            worker.start()
        else:
            _tabu_worker(ts, board, stop_evt, t0 + 0.4 * T, 10, stall_restarts=8)

    def tick() -> None:
        if progress is not None:
            progress("certify", int(min(T, time.perf_counter() - t0)), int(max(1, round(T))))

    # --- bound side -------------------------------------------------------
    lg = Lagrangian(problem) if board.gap() > 0 else None
    lam = None
    lp_info: dict = {}
    region_info: dict = {}
    x_lp = None  # the LP primal, when the LP finished
    red_info: dict = {}
    if lg is not None:
        with board.lock:
            cov = problem.coverage(board.selected)
            ub = board.objective
        remaining = end - time.perf_counter()
        want_lp = ((T >= 60) or bool(region)) if lp is None else lp
        share = 0.1 if want_lp else (0.35 if reduced_mip else 1.0)
        res = lagrangian_bound(problem, time_limit_s=max(0.5, share * remaining), incumbent_cost=ub, coverage=cov,
                               should_stop=stop_now, lagr=lg,
                               on_bound=lambda v: (board.offer_bound(v, "lagrangian"), tick()))
        board.offer_bound(res.bound, "lagrangian")
        lam = res.multipliers
        if want_lp and not stop_now() and board.gap() > 0:
            remaining = end - time.perf_counter()
            # under 5 minutes the LP is the best bound in reach: give it most of the time
            lpr = lp_bound(problem, time_limit_s=(0.5 if T >= 300 else 0.75) * remaining, threads=1, end=end,
                           should_stop=stop_now)
            lp_info = {"status": lpr.info.get("status"), "seconds": round(lpr.seconds, 2)}
            if lpr.info.get("status") == "optimal":
                board.offer_bound(lpr.bound, "lp")
                n_p = problem.n_targets
                lam_lp = np.maximum(np.asarray(lpr.info["row_dual"][:n_p]), 0.0)
                L_lp = lg.evaluate(lam_lp)[0]
                board.offer_bound(L_lp, "lagrangian (LP duals)")
                if L_lp >= res.info["raw"]:
                    lam = lam_lp
                    x_lp = lpr.info["x"]
        partial_on = (T >= 300 and x_lp is not None) if region is None else bool(region)
        if partial_on and lam is not None and not stop_now() and board.gap() > 0:
            # from the LP duals and primal when the LP finished, else from the Lagrangian's λ
            from camplace.solvers.region_bound import (METHOD, PARTIAL_METHOD, costly_region,
                                                        partial_lagrangian_bound, region_bound)

            with board.lock:
                ub = board.objective
            start_lp = x_lp is not None
            # one costly region exact, the rest Lagrangian (the budget binds there) ...
            pres = partial_lagrangian_bound(problem, lam, costly_region(problem, lam, share=0.6, seed=seed),
                                            time_limit_s=(end - time.perf_counter()) / 3.0, seed=seed,
                                            should_stop=stop_now)
            board.offer_bound(pres.bound, PARTIAL_METHOD)
            # ... then the decomposition over all regions with subgradient ascent
            rres = None
            if region and not stop_now() and board.gap() > 0:  # only on request: it rarely passes the LP
                rres = region_bound(problem, lam=lam, x_frac=x_lp, incumbent_cost=ub,
                                    time_limit_s=(end - time.perf_counter()) / 4.0, seed=seed,
                                    should_stop=stop_now, on_bound=lambda v: board.offer_bound(v, METHOD))
            if rres is not None:
                board.offer_bound(rres.bound, METHOD)
            region_info = {"bound": rres.bound if rres else None, "start": "lp duals" if start_lp else "lagrangian",
                           "start_bound": pres.info["lagrangian"],
                           "iterations": rres.info["iterations"] if rres else 0,
                           "regions": rres.info["regions"] if rres else 0,
                           "seconds": round(rres.seconds, 2) if rres else 0.0,
                           "partial_bound": pres.bound, "partial_targets": pres.info["region_targets"],
                           "partial_seconds": round(pres.seconds, 2)}
        tick()
        if reduced_mip and not stop_now() and board.gap() > 0:
            # polish λ against the current incumbent, then fix and solve exactly
            with board.lock:
                ub = board.objective
                inc = board.selected.copy()
            remaining = end - time.perf_counter()
            if remaining > 2:
                res2 = lagrangian_bound(problem, time_limit_s=0.15 * remaining, incumbent_cost=ub, lam0=lam,
                                        should_stop=stop_now, lagr=lg,
                                        on_bound=lambda v: board.offer_bound(v, "lagrangian"))
                board.offer_bound(res2.bound, "lagrangian")
                if res2.info["raw"] >= lg.evaluate(lam)[0]:
                    lam = res2.multipliers
            red = reduce_by_fixing(problem, lam, ub, lg)
            red_info = {"ub": ub, "candidates_kept": int(red.keep.sum()), "locations_forced": int(len(red.forced))}
            remaining = end - time.perf_counter()
            # worth it only when fixing left a small problem or there is time for a big one
            kept_nnz = int(np.diff(problem.V.indptr)[red.keep].sum())
            small = red.keep.sum() <= 0.25 * problem.n_candidates or kept_nnz <= 100_000
            if remaining > 2 and (small or remaining >= 120) and not stop_now():
                bnd, sel, info = solve_reduced_mip(problem, red, inc, time_limit_s=remaining - 1.0,
                                                   threads=1, seed=seed, should_stop=stop_now, end=end)
                red_info.update(info)
                if sel is not None:
                    board.offer_incumbent(sel, "reduced-mip")
                board.offer_bound(bnd, "lagrangian fixing + HiGHS on the reduced problem")
        # spend what is left on the Lagrangian (it is anytime)
        remaining = end - time.perf_counter()
        if remaining > 0.5 and not stop_now() and board.gap() > 0:
            with board.lock:
                ub = board.objective
            res3 = lagrangian_bound(problem, time_limit_s=remaining * (0.5 if worker is None else 1.0),
                                    incumbent_cost=ub, lam0=lam,
                                    should_stop=stop_now, lagr=lg,
                                    on_bound=lambda v: (board.offer_bound(v, "lagrangian"), tick()))
            board.offer_bound(res3.bound, "lagrangian")
    if worker is None and n_threads == 1 and board.gap() > 0 and not stop_now():
        _tabu_worker(ts, board, stop_evt, end, 10)  # single thread: the rest goes back to tabu
    if worker is not None:
        # the bound side is done; the incumbent side keeps the rest of the time
        while worker.is_alive() and not stop_now() and board.gap() > 0:
            worker.join(timeout=0.2)
            tick()
        stop_evt.set()
        worker.join()
    tick()
    interrupted = should_stop is not None and should_stop()
    gap = board.gap()
    status = "optimal" if gap <= 1e-9 else ("interrupted" if interrupted else "time_limit")
    info = {"incumbent_method": board.incumbent_method, "bound_method": board.bound_method, "gap": gap,
            "tabu_iterations": ts.iterations, "tabu_restarts": ts.restarts, "seed": int(seed),
            "threads": n_threads, "history": history, "lp": lp_info, "fixing": red_info,
            "region": region_info}
    return Placement(board.selected, board.objective, board.bound, status, "certify", time.perf_counter() - t0, info)


CERTIFY = make_solver("certify", solve_certify, Tags(gives_bound=True),
                      summary="Tabu incumbent and proven bounds (Lagrangian, LP, reduced MIP)")
