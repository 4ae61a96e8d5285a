"""Ctrl-C and limits: the best placement found so far is written, marked 'interrupted';
an interrupted visibility stage resumes from its cached chunks."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from camplace.core.errors import Interrupted

REPO = Path(__file__).resolve().parents[2]
CHECK_RUN = REPO.parent / "shared" / "contract" / "check_run.py"


def _read_until(stream, prefix: str, timeout: float, seen: list[str]) -> bool:
    """Read lines from stream (a thread, so a silent child cannot hang the test)."""
    found = threading.Event()

    def reader() -> None:
        for line in stream:
            seen.append(line)
            if line.startswith(prefix):
                found.set()
                return

    th = threading.Thread(target=reader, daemon=True)
    th.start()
    return found.wait(timeout)


def _wait_for(path: Path, proc, timeout: float) -> float | None:
    """Seconds until ``path`` exists (None if the process ended or ``timeout`` passed first)."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout:
        if path.exists():
            return time.perf_counter() - t0
        if proc.poll() is not None:
            return None
        time.sleep(0.02)
    return None


def test_sigint_during_a_long_mip_keeps_its_incumbent_and_bound(tmp_path):
    """`camplace run standard-store --solver mip --time-limit 600` is a solve of minutes;
    SIGINT inside HiGHS (after the warm start, the tabu polish and the Lagrangian bound):
    placement.json and metrics.json within 2 s, the MIP's own incumbent and bound (not the
    greedy fallback), the report set as far as it fits, exit 130 within 10 s."""
    from camplace.solvers import SOLVERS

    assert "mip" in SOLVERS
    out = tmp_path / "out"
    env = dict(os.environ, CAMPLACE_CACHE=str(tmp_path / "cache"))
    proc = subprocess.Popen([sys.executable, "-m", "camplace.cli.app", "run", "standard-store", "--solver", "mip",
                             "--budget", "40", "--time-limit", "600", "--out", str(out), "--no-cache"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path)
    seen: list[str] = []
    try:
        assert _read_until(proc.stderr, "stage: mip", 180, seen), "".join(seen)
        time.sleep(8.0)  # greedy + tabu (2 s) + Lagrangian (3 s): HiGHS is starting on the model
        assert proc.poll() is None, "the MIP finished before it could be interrupted"
        t0 = time.perf_counter()
        proc.send_signal(signal.SIGINT)
        contract = _wait_for(out / "metrics.json", proc, 30)
        stdout, stderr = proc.communicate(timeout=60)
        waited = time.perf_counter() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    text = "".join(seen) + stderr
    assert proc.returncode == 130, text
    assert "Traceback" not in text
    assert "did not stop" not in text  # the MIP itself stopped: no greedy fallback
    assert contract is not None and contract < 2.0, f"contract files after {contract} s"
    assert waited < 10, f"took {waited:.1f} s to exit"
    p = json.loads((out / "placement.json").read_text())
    m = json.loads((out / "metrics.json").read_text())
    assert p["status"] == "interrupted"
    assert p["solver"] == "mip" and p["budget"] == 40
    assert 0 < len(p["cameras"]) <= 40
    assert p["bound"] is not None and 0 < p["bound"] <= p["objective"] + 1e-6  # its Lagrangian bound at least
    assert m["cost"] == pytest.approx(p["objective"])
    assert not [f for f in out.iterdir() if f.name.endswith(".tmp")]
    assert "skipped" in stdout or (out / "report.html").is_file()  # the report set: written or listed as skipped
    if CHECK_RUN.is_file():
        r = subprocess.run([sys.executable, str(CHECK_RUN), str(out)], capture_output=True, text=True)
        assert r.returncode == 0, r.stdout + r.stderr
    else:  # pragma: no cover
        pytest.skip("../shared/contract/check_run.py is absent: contract check skipped")


def test_ctrl_c_by_phase():
    """Before visibility a Ctrl-C aborts at once; while a placement is being made the first
    only sets the flag and the second asks to hurry; after the contract files the second
    aborts; once everything is written nothing happens."""
    from camplace.cli.common import StopFlag

    def ctrl_c() -> None:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)

    before = signal.getsignal(signal.SIGINT)  # whatever an earlier test (or pytest) left installed
    stop = StopFlag()
    with stop.installed():
        stop.stage("scene")
        with pytest.raises(KeyboardInterrupt):
            ctrl_c()
    stop = StopFlag()
    with stop.installed():
        stop.stage("solve")
        assert not stop()
        ctrl_c()  # first: only the flag
        assert stop() and not stop.hurry() and stop.report_deadline() is not None
        ctrl_c()  # second: hurry, still no exception (the contract files are to be written)
        assert stop.hurry()
        with pytest.raises(KeyboardInterrupt):
            stop.contract_written()  # ... and then leave
    stop = StopFlag()
    with stop.installed():
        stop.stage("solve")
        ctrl_c()
        stop.contract_written()  # the report set may run
        with pytest.raises(KeyboardInterrupt):
            ctrl_c()
        stop.finished()
        ctrl_c()  # nothing left to stop
    assert signal.getsignal(signal.SIGINT) is before  # the handler it found is restored


def test_ctrl_c_in_a_finalizer_prints_no_traceback_and_still_stops(capfd):
    """A Ctrl-C raised while Python runs a finalizer (a weakref callback, __del__) cannot
    leave it: Python prints it with a traceback and goes on. Installed, the flag keeps it
    quiet and delivers it again outside, so the command still stops."""
    from camplace.cli.common import StopFlag

    class Finalized:
        def __del__(self):
            raise KeyboardInterrupt

    stop = StopFlag()
    with stop.installed():
        stop.stage("solve")
        stop.contract_written()
        stop.count = 1  # after the first Ctrl-C: a second one ends the report set
        with pytest.raises(KeyboardInterrupt):
            Finalized()  # dropped at once: __del__ raises inside the finalizer
            time.sleep(2)
        stop.finished()
    assert "Traceback" not in capfd.readouterr().err


def test_interrupted_run_writes_the_contract_files_fast_and_lists_what_it_skipped(tmp_path):
    """After a Ctrl-C the report set gets what is left of its time: past the deadline each
    part is skipped and listed; a KeyboardInterrupt (a second Ctrl-C) during it only ends it."""
    from camplace.outputs.write import PLAN_SET, REPORT_PARTS, write_outputs
    from camplace.workflows.run import run

    r = run("demo", budget=3)
    args = (r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s)
    skipped: list[str] = []
    paths = write_outputs(tmp_path / "late", *args, scene=r.scene, compressed=False, deadline=lambda: 0.0,
                          skipped=skipped)
    assert set(paths) >= {"visibility.npz", "placement.json", "placement.csv", "metrics.json"}
    assert not [p for p in paths if p.endswith((".html", ".png", ".pdf")) or "/" in p]  # no part of the report set
    assert skipped == list(REPORT_PARTS)
    with np.load(tmp_path / "late" / "visibility.npz") as z:  # uncompressed, still the contract's arrays
        assert z["shape"].tolist() == list(r.visibility.V.shape)

    def second_ctrl_c() -> None:
        raise KeyboardInterrupt

    skipped = []
    paths = write_outputs(tmp_path / "hurry", *args, scene=r.scene, plan=False, on_contract=second_ctrl_c,
                          deadline=lambda: None, skipped=skipped)
    assert "placement.json" in paths and "report.html" not in paths
    assert skipped == [p for p in REPORT_PARTS if p != PLAN_SET]
    assert not (tmp_path / "hurry" / "report.html").exists()


def test_solver_that_ignores_the_stop_request_is_left_behind():
    """A solver stuck in a phase that polls nothing: solve_stoppable returns the greedy
    placement, status 'interrupted', about grace_s after the request."""
    import scipy.sparse as sp

    import camplace.solvers as solvers
    from camplace.workflows.run import solve_stoppable
    from camplace.problem.model import PlacementProblem

    release = threading.Event()

    def stubborn(problem, *, time_limit_s=None, threads=None, seed=0, should_stop=None, progress=None,
                 on_incumbent=None):
        release.wait(30)
        raise AssertionError("never returns in time")

    rng = np.random.default_rng(0)
    V = sp.csr_matrix((rng.random((30, 50)) < 0.2).astype(np.uint8))
    prob = PlacementProblem(V, np.full(50, 2, np.int64), np.ones(50), 5, np.arange(30) // 2)
    from camplace.solvers.contract import make_solver

    solvers.SOLVERS["stubborn-test"] = make_solver("stubborn-test", stubborn)
    try:
        t0 = time.perf_counter()
        asked = t0 + 0.2
        log: list[str] = []
        p = solve_stoppable(prob, "stubborn-test", log=log, grace_s=0.5,
                            should_stop=lambda: time.perf_counter() > asked)
        took = time.perf_counter() - t0
    finally:
        release.set()
        del solvers.SOLVERS["stubborn-test"]
    assert p.status == "interrupted"
    greedy = solvers.solve(prob, "greedy")
    assert np.array_equal(p.selected, greedy.selected) and p.objective == greedy.objective
    assert 0.6 <= took < 3
    assert any("did not stop" in line for line in log)


def test_solver_errors_propagate_through_the_worker_thread():
    import scipy.sparse as sp

    import camplace.solvers as solvers
    from camplace.workflows.run import solve_stoppable
    from camplace.problem.model import PlacementProblem

    def broken(problem, *, time_limit_s=None, threads=None, seed=0, should_stop=None, progress=None,
               on_incumbent=None):
        raise ValueError("boom")

    V = sp.csr_matrix(np.eye(3, dtype=np.uint8))
    prob = PlacementProblem(V, np.ones(3, np.int64), np.ones(3), 1, np.arange(3))
    from camplace.solvers.contract import make_solver

    solvers.SOLVERS["broken-test"] = make_solver("broken-test", broken)
    try:
        with pytest.raises(ValueError, match="boom"):
            solve_stoppable(prob, "broken-test", should_stop=lambda: False)
    finally:
        del solvers.SOLVERS["broken-test"]


def test_interrupted_visibility_resumes_from_cached_chunks(tmp_path, monkeypatch):
    """Stop after two visibility chunks: Interrupted (nothing to write); the next run
    loads those two chunks from the cache and computes the rest, giving the same V."""
    import dataclasses

    import camplace.workflows.run as pipeline
    from camplace.visibility.registry import get_engine

    monkeypatch.setattr(pipeline, "get_engine", lambda mode, **kw: dataclasses.replace(get_engine(mode, **kw),
                                                                                       chunk_size=64))
    calls = {"n": 0}

    def stop_after_two_chunks() -> bool:
        calls["n"] += 1
        return calls["n"] > 2  # polled at (0, n), after chunk 1, after chunk 2

    cache = tmp_path / "cache"
    with pytest.raises(Interrupted) as exc:
        pipeline.prepare("demo", should_stop=stop_after_two_chunks, cache_dir=cache)
    assert exc.value.exit_code == 130 and "2/" in str(exc.value)
    _, resumed = pipeline.prepare("demo", cache_dir=cache)
    assert resumed.info["cached_chunks"] == 2 and resumed.info["chunks"] > 2
    _, fresh = pipeline.prepare("demo")
    assert (resumed.V != fresh.V).nnz == 0 and resumed.V.shape == fresh.V.shape


def test_time_limit_option_reaches_the_solver(monkeypatch):
    import camplace.solvers as solvers
    from camplace.workflows.run import run

    got = {}
    real = solvers.SOLVERS["greedy"]

    def spy(problem, **options):
        got.update(options)
        return real.fn(problem, **options)

    import dataclasses

    monkeypatch.setitem(solvers.SOLVERS, "greedy", dataclasses.replace(real, fn=spy))
    run("demo", time_limit_s=7.5)
    assert 7.0 < got["time_limit_s"] <= 7.5  # the limit, less the problem reduction's time
    run("demo")
    assert 599.0 < got["time_limit_s"] <= 600.0  # the scene's placement.time_limit_s default


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux /proc")
def test_visibility_workers_do_not_receive_ctrl_c():
    """Worker processes are spawned with SIGINT blocked: a terminal's Ctrl-C (sent to the
    whole process group) reaches only the parent, which stops between chunks."""
    import re

    from camplace.core.executors import sigint_ignored

    def blocked(pid: int) -> bool:
        status = Path(f"/proc/{pid}/status").read_text()
        return bool(int(re.search(r"SigBlk:\s*([0-9a-f]+)", status).group(1), 16) & (1 << (signal.SIGINT - 1)))

    with sigint_ignored():
        child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(10)"])
    try:
        assert not blocked(os.getpid())  # the parent's mask is restored
        assert blocked(child.pid)
        child.send_signal(signal.SIGINT)
        time.sleep(0.5)
        assert child.poll() is None
    finally:
        child.kill()
        child.wait()
