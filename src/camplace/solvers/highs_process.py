"""Run a HiGHS model so that it can always be stopped, keeping what it found.

HiGHS polls its interrupt callbacks during simplex, IPM and branch-and-bound, but not in
its presolve nor in the root LP of a MIP: on a model of millions of nonzeros those take
tens of seconds to minutes in which a Ctrl-C (or a deadline) goes unheard. So a large
model (``CHILD_MIN_NNZ`` nonzeros or more, with something to stop it) runs in a child
process (camplace.solvers.highs_child): the parent polls ``should_stop`` and the deadline,
asks the child to stop through the interrupt callbacks, and kills it when it has not
answered ``KILL_AFTER_S`` later. The incumbents (improving-solution callback) and dual
bounds (interrupt callback) the child reported as it went are kept either way, so a
stopped or killed run still returns its best solution and bound. Small models run here,
in this thread, with the same callbacks.

Builders record the model arrays with :func:`remember_model` (and a start with
:func:`remember_start`), so the child gets them without reading them back from HiGHS.
"""

from __future__ import annotations

import pickle
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Callable

import highspy
import numpy as np

from camplace.solvers.base import ShouldStop, stopped

CHILD_MIN_NNZ = 300_000  # models this large run in a child process (their set-up polls nothing for seconds)
KILL_AFTER_S = 0.5  # a child asked to stop that has not answered by then is killed
POLL_S = 0.05
FINISH_S_PER_NNZ = 0.5e-6  # seconds per nonzero from an interrupt to the solution read back (2 s measured)
CHILD = Path(__file__).with_name("highs_child.py")
_SCHEDULER_THREADS: list[int | None] = [None]  # the 'threads' option of this process's first HiGHS run
INFO_FIELDS = ("objective_function_value", "mip_dual_bound", "mip_gap", "mip_node_count", "primal_solution_status")


@dataclass
class HighsRun:
    """What a HiGHS run left: model_status (highspy.HighsModelStatus) and its text, info
    (the INFO_FIELDS of HighsInfo), col_value (all columns) or None, row_dual or None
    (when asked for), stopped / deadline (interrupted by should_stop / by the deadline),
    in_child (ran in a child process), killed (the child did not answer and was killed;
    col_value and mip_dual_bound are then the last ones it reported)."""

    model_status: highspy.HighsModelStatus
    status_text: str
    info: SimpleNamespace
    col_value: np.ndarray | None
    row_dual: np.ndarray | None = None
    stopped: bool = False
    deadline: bool = False
    in_child: bool = False
    killed: bool = False


def remember_model(h: highspy.Highs, n_col: int, n_row: int, A, c, col_lower, col_upper, row_lower, row_upper,
                   integrality, sense: int = 1, offset: float = 0.0) -> None:
    """Record the arrays ``h`` was given (A: scipy csc with sorted indices), for :func:`run_model`'s child."""
    h._camplace_model = {"n_col": int(n_col), "n_row": int(n_row), "sense": int(sense), "offset": float(offset),
                         "c": np.asarray(c, np.float64), "col_lower": np.asarray(col_lower, np.float64),
                         "col_upper": np.asarray(col_upper, np.float64),
                         "row_lower": np.asarray(row_lower, np.float64),
                         "row_upper": np.asarray(row_upper, np.float64), "start": A.indptr.astype(np.int32),
                         "index": A.indices.astype(np.int32), "value": A.data.astype(np.float64),
                         "integrality": np.asarray(integrality, np.int32)}


def remember_start(h: highspy.Highs, values: np.ndarray) -> None:
    """Record the start solution ``h`` was given (all columns)."""
    h._camplace_start = np.asarray(values, np.float64)


def forget_model(h: highspy.Highs) -> None:
    """The model of ``h`` was changed in place (costs, bounds): it runs here from now on."""
    h._camplace_model = None


def subscribe_stop(h: highspy.Highs, should_stop: ShouldStop | None, end: float = float("inf")) -> dict:
    """Poll should_stop and the perf_counter() deadline ``end`` from HiGHS' MIP, simplex
    and IPM interrupt callbacks. Returns a dict whose "stop" (should_stop) or "deadline"
    turns True once HiGHS was interrupted for that reason."""
    flag = {"stop": False, "deadline": False}
    timed = bool(np.isfinite(end))
    if timed:  # HiGHS takes a while to return once interrupted: ask early enough
        end = end - FINISH_S_PER_NNZ * int(h.getNumNz())

    def interrupt(e) -> None:
        if stopped(should_stop):
            flag["stop"] = True
            e.interrupt()
        elif timed and time.perf_counter() >= end:
            flag["deadline"] = True
            e.interrupt()

    if should_stop is not None or timed:
        h.cbMipInterrupt.subscribe(interrupt)
        h.cbSimplexInterrupt.subscribe(interrupt)
        h.cbIpmInterrupt.subscribe(interrupt)
    return flag


def run_model(h: highspy.Highs, *, should_stop: ShouldStop | None = None, end: float = float("inf"),
              on_improving: Callable[[float, float], None] | None = None, duals: bool = False,
              in_child: bool | None = None) -> HighsRun:
    """``h.run()`` that can always be stopped (see the module doc). should_stop: polled;
    end: perf_counter() deadline; on_improving(objective, dual bound): each improving MIP
    solution; duals: read the row duals back; in_child: force (True) or forbid (False)
    the child process (default: by size, for a model recorded with remember_model)."""
    model = getattr(h, "_camplace_model", None)
    if in_child is None:
        in_child = (model is not None and int(h.getNumNz()) >= CHILD_MIN_NNZ
                    and (should_stop is not None or bool(np.isfinite(end))))
    if in_child and model is not None:
        return _run_in_child(h, model, should_stop, end, on_improving, duals)
    return _run_here(h, should_stop, end, on_improving, duals)


def same_threads(h: highspy.Highs) -> None:
    """HiGHS starts one global task scheduler at its first run in a process, with that run's
    'threads' option, and refuses a later run that asks for another count (status 'Not
    Set', nothing solved: a certify run after a zhao run lost its proof and waited out its
    limit). So every run in this process uses the first run's count (0: HiGHS' own)."""
    got = h.getOptionValue("threads")
    asked = int(got[1] if isinstance(got, tuple) else got)
    if _SCHEDULER_THREADS[0] is None:
        _SCHEDULER_THREADS[0] = asked
    elif asked != _SCHEDULER_THREADS[0]:
        h.setOptionValue("threads", _SCHEDULER_THREADS[0])


def _run_here(h, should_stop, end, on_improving, duals) -> HighsRun:
    same_threads(h)
    flag = subscribe_stop(h, should_stop, end)
    if on_improving is not None:
        h.cbMipImprovingSolution.subscribe(
            lambda e: on_improving(float(e.data_out.objective_function_value), float(e.data_out.mip_dual_bound)))
    h.run()
    ms = h.getModelStatus()
    info = h.getInfo()
    sol = h.getSolution()
    cols = np.asarray(sol.col_value, np.float64)
    return HighsRun(ms, h.modelStatusToString(ms), SimpleNamespace(**{k: getattr(info, k) for k in INFO_FIELDS}),
                    cols if len(cols) else None, np.asarray(sol.row_dual, np.float64) if duals else None,
                    flag["stop"], flag["deadline"])


def _changed_options(h: highspy.Highs) -> dict:
    """The options of ``h`` that differ from HiGHS' defaults, by name."""
    mine, default = h.getOptions(), highspy.HighsOptions()
    names = [n for n in dir(default) if not n.startswith("_") and not callable(getattr(default, n))]
    return {n: getattr(mine, n) for n in names if getattr(mine, n) != getattr(default, n)}


def _run_in_child(h, model: dict, should_stop, end: float, on_improving, duals: bool) -> HighsRun:
    ask_at = end - FINISH_S_PER_NNZ * len(model["index"]) if np.isfinite(end) else end
    left = None if not np.isfinite(ask_at) else max(0.01, ask_at - time.perf_counter())
    job = {"model": model, "options": _changed_options(h), "start": getattr(h, "_camplace_start", None),
           "seconds_left": left, "improving": on_improving is not None, "duals": duals}
    proc = subprocess.Popen([sys.executable, str(CHILD)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    got: dict = {"bound": None, "solution": None, "done": None}
    ask = threading.Event()

    def write() -> None:
        try:
            pickle.dump(job, proc.stdin, protocol=pickle.HIGHEST_PROTOCOL)
            proc.stdin.flush()
            ask.wait()
            proc.stdin.close()  # the end of the file: the child's stop request
        except (OSError, ValueError):  # the child is gone
            pass

    def read() -> None:
        try:
            while True:
                msg = pickle.load(proc.stdout)
                if msg[0] == "done":
                    got["done"] = msg[1]
                    return
                bound = msg[1] if msg[0] == "bound" else msg[2]
                if np.isfinite(bound):
                    got["bound"] = bound if got["bound"] is None else max(got["bound"], bound)
                if msg[0] == "solution":
                    got["solution"] = (msg[1], msg[3])
                    if on_improving is not None:
                        on_improving(msg[1], msg[2])
        except (EOFError, OSError, ValueError, pickle.UnpicklingError):
            return

    threads = [threading.Thread(target=f, daemon=True, name=f"camplace-highs-{f.__name__}") for f in (write, read)]
    for t in threads:
        t.start()
    reason, asked, killed = None, None, False
    try:
        while threads[1].is_alive():
            threads[1].join(POLL_S)
            now = time.perf_counter()
            if asked is None:
                reason = "stop" if stopped(should_stop) else "deadline" if now >= end else None
                if reason is not None:
                    asked = now
                    ask.set()
            elif now - asked > KILL_AFTER_S and threads[1].is_alive():
                proc.kill()
                killed = True
                break
    finally:
        ask.set()
        if proc.poll() is None and (killed or got["done"] is None):
            proc.kill()
        proc.wait()
        threads[1].join(1.0)
        for f in (proc.stdin, proc.stdout):
            try:
                f.close()
            except OSError:
                pass
    return _child_result(got, reason, killed, duals)


def _child_result(got: dict, reason: str | None, killed: bool, duals: bool) -> HighsRun:
    MS = highspy.HighsModelStatus
    done = got["done"]
    if done is not None:
        return HighsRun(MS(done["model_status"]), done["model_status_text"], SimpleNamespace(**done["info"]),
                        done["col_value"] if len(done["col_value"]) else None, done["row_dual"] if duals else None,
                        done["stopped"] or reason == "stop", done["deadline"] or reason == "deadline", True, False)
    sol = got["solution"]
    bound = -np.inf if got["bound"] is None else got["bound"]
    info = SimpleNamespace(objective_function_value=np.inf if sol is None else sol[0], mip_dual_bound=bound,
                           mip_gap=np.inf, mip_node_count=0, primal_solution_status=0 if sol is None else 2)
    ms = MS.kTimeLimit if reason == "deadline" else MS.kInterrupt if reason == "stop" else MS.kSolveError
    text = "Killed after an interrupt" if killed else "Child process failed"
    return HighsRun(ms, text, info, None if sol is None else sol[1], None, reason == "stop",
                    reason == "deadline", True, killed)


__all__ = ["CHILD_MIN_NNZ", "HighsRun", "forget_model", "remember_model", "remember_start", "run_model",
           "subscribe_stop"]
