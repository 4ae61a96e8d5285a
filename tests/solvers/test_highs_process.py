"""HiGHS that can always be stopped (camplace.solvers.highs_process): a model run in a child
process gives what it gives here; a child that does not answer a stop is killed and what
it reported (incumbent, bound) is kept."""

from __future__ import annotations

import time

import numpy as np
import pytest
import scipy.sparse as sp

import camplace.solvers.highs_process as hp
from camplace.problem.model import PlacementProblem
from camplace.solvers.mip import tight_model_arrays, tight_start
from camplace.solvers.highs_util import highs_from_arrays, set_start


@pytest.fixture(scope="module")
def model():
    rng = np.random.default_rng(3)
    V = sp.csr_matrix((rng.random((40, 120)) < 0.12).astype(np.uint8))
    prob = PlacementProblem(V, np.full(120, 2, np.int64), np.ones(120), 5, np.arange(40) // 2)
    return prob, *tight_model_arrays(prob)


def test_a_model_in_a_child_process_gives_the_same_answer(model):
    prob, arrays, layout = model
    runs = []
    for in_child in (False, True):
        h = highs_from_arrays(arrays)
        set_start(h, tight_start(prob, layout, np.arange(5) * 2))
        seen = []
        runs.append((hp.run_model(h, should_stop=lambda: False, in_child=in_child,
                                  on_improving=lambda o, b: seen.append(o)), seen))
    (here, seen_here), (child, seen_child) = runs
    assert child.in_child and not here.in_child and not child.killed
    assert here.status_text == child.status_text == "Optimal"
    assert child.info.objective_function_value == pytest.approx(here.info.objective_function_value)
    assert child.info.mip_dual_bound == pytest.approx(here.info.mip_dual_bound)
    sel = np.flatnonzero(child.col_value[:layout.n_x] > 0.5)
    assert prob.cost(sel) == pytest.approx(child.info.objective_function_value)
    assert seen_child and seen_child[-1] == pytest.approx(child.info.objective_function_value)


STUCK = """
import os, pickle, sys, time
import numpy as np
out = os.fdopen(os.dup(1), "wb")
job = pickle.load(sys.stdin.buffer)
n = len(job["model"]["c"])
pickle.dump(("solution", 7.0, 3.0, np.ones(n)), out); out.flush()
pickle.dump(("bound", 4.0), out); out.flush()
time.sleep(60)  # a presolve or root LP that polls nothing
"""


def test_a_child_that_does_not_answer_is_killed_and_its_reports_kept(model, tmp_path, monkeypatch):
    _, arrays, _ = model
    script = tmp_path / "stuck.py"
    script.write_text(STUCK)
    monkeypatch.setattr(hp, "CHILD", script)
    h = highs_from_arrays(arrays)
    asked = time.perf_counter() + 1.0
    improving = []
    run = hp.run_model(h, should_stop=lambda: time.perf_counter() > asked, in_child=True,
                       on_improving=lambda o, b: improving.append((o, b)))
    took = time.perf_counter() - asked
    assert run.killed and run.stopped and run.status_text.startswith("Killed")
    assert took < hp.KILL_AFTER_S + 0.5
    assert run.info.objective_function_value == 7.0 and run.info.primal_solution_status == 2
    assert run.info.mip_dual_bound == 4.0  # the best bound it reported
    assert run.col_value is not None and len(run.col_value) == arrays.shape[1]
    assert improving == [(7.0, 3.0)]


def test_the_child_imports_no_camplace_module():
    """It must start fast: no package import (camplace.solvers imports every solver)."""
    text = hp.CHILD.read_text()
    assert "import camplace" not in text and "from camplace" not in text
