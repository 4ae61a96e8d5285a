"""HiGHS keeps one task scheduler per process, started by the first run's 'threads' option,
and refuses a later run asking for another count (status 'Not Set', nothing solved): every
in-process run uses the first run's count (camplace.solvers.highs_process.same_threads)."""

from __future__ import annotations

import highspy
import numpy as np

from camplace.solvers.highs_process import run_model


def _tiny(threads: int) -> highspy.Highs:
    """max x0 + x1 subject to x0 + x1 <= 1.5, 0 <= x <= 1 (optimum 1.5)."""
    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("threads", threads)
    h.addVars(2, np.zeros(2), np.ones(2))
    h.changeColsCost(2, np.array([0, 1], np.int32), np.array([-1.0, -1.0]))
    h.addRow(-highspy.kHighsInf, 1.5, 2, np.array([0, 1], np.int32), np.array([1.0, 1.0]))
    return h


def test_runs_asking_for_other_thread_counts_still_solve():
    for threads in (2, 1, 3, 0, 1):
        run = run_model(_tiny(threads), in_child=False)
        assert run.model_status == highspy.HighsModelStatus.kOptimal, (threads, run.status_text)
        assert run.info.objective_function_value == -1.5
