"""The child side of camplace.solvers.highs_process, run as a script (``python highs_child.py``):
it imports no camplace module, so it starts in a fraction of a second.

stdin: one pickled job (the model arrays, the options, the start, the seconds left), then
the end of the file (the parent closed it, or is gone) asks HiGHS to stop (through its
interrupt callbacks).
stdout (the file descriptor it was started with; HiGHS' own output goes to /dev/null):
pickled messages ``("bound", dual_bound)``, ``("solution", objective, dual_bound, col_value)``
and at the end ``("done", result)``.
"""

from __future__ import annotations

import os
import pickle
import signal
import sys
import threading
import time

BOUND_EVERY_S = 0.5  # how often the dual bound of a running MIP is reported


def _send(out, lock: threading.Lock, msg: tuple) -> None:
    with lock:
        pickle.dump(msg, out, protocol=pickle.HIGHEST_PROTOCOL)
        out.flush()


def _highs(job: dict):
    import highspy
    import numpy as np

    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    for name, value in job["options"].items():
        h.setOptionValue(name, value)
    m = job["model"]
    h.passModel(int(m["n_col"]), int(m["n_row"]), int(len(m["index"])), int(highspy.MatrixFormat.kColwise),
                int(highspy.ObjSense.kMinimize if m["sense"] > 0 else highspy.ObjSense.kMaximize),
                float(m["offset"]), m["c"], m["col_lower"], m["col_upper"], m["row_lower"], m["row_upper"],
                m["start"], m["index"], m["value"], np.asarray(m["integrality"], np.int32))
    if job.get("start") is not None:
        sol = highspy.HighsSolution()
        sol.col_value = list(map(float, job["start"]))
        sol.value_valid = True
        h.setSolution(sol)
    return h


def main() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides when to stop
    out = os.fdopen(os.dup(1), "wb")
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)  # HiGHS' banner and logs must not reach the message pipe
    inp = sys.stdin.buffer
    job = pickle.load(inp)
    stop = threading.Event()

    def watch() -> None:
        inp.read(1)  # returns at the end of the file: the parent asks to stop, or is gone
        stop.set()

    threading.Thread(target=watch, daemon=True).start()
    lock = threading.Lock()
    import numpy as np

    import highspy

    h = _highs(job)
    mip_interrupt = highspy.cb.HighsCallbackType.kCallbackMipInterrupt
    end = float("inf") if job["seconds_left"] is None else time.monotonic() + float(job["seconds_left"])
    last = [0.0]

    def interrupt(e) -> None:
        now = time.monotonic()
        if e.callback_type == mip_interrupt and now - last[0] >= BOUND_EVERY_S:
            last[0] = now
            bound = getattr(e.data_out, "mip_dual_bound", None)
            if bound is not None and np.isfinite(bound):
                _send(out, lock, ("bound", float(bound)))
        if stop.is_set() or now >= end:
            e.interrupt()

    def improving(e) -> None:
        d = e.data_out
        _send(out, lock, ("solution", float(d.objective_function_value), float(d.mip_dual_bound),
                          np.asarray(d.mip_solution, np.float64)))

    h.cbMipInterrupt.subscribe(interrupt)
    h.cbSimplexInterrupt.subscribe(interrupt)
    h.cbIpmInterrupt.subscribe(interrupt)
    if job.get("improving"):
        h.cbMipImprovingSolution.subscribe(improving)
    h.run()
    ms = h.getModelStatus()
    info = h.getInfo()
    sol = h.getSolution()
    result = {"model_status": int(ms), "model_status_text": h.modelStatusToString(ms),
              "stopped": stop.is_set(), "deadline": time.monotonic() >= end,
              "info": {k: getattr(info, k) for k in ("objective_function_value", "mip_dual_bound", "mip_gap",
                                                     "mip_node_count", "primal_solution_status")},
              "col_value": np.asarray(sol.col_value, np.float64),
              "row_dual": np.asarray(sol.row_dual, np.float64) if job.get("duals") else None}
    _send(out, lock, ("done", result))


if __name__ == "__main__":
    main()
