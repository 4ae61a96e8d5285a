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


def test_sigint_during_a_long_mip_writes_the_best_placement(tmp_path):
    """`camplace run standard-store --solver mip --time-limit 600` is a solve of minutes
    (its root LP alone takes ~1-3 min here); SIGINT during it must give exit 130 and a
    valid placement.json with status 'interrupted' within seconds."""
    from camplace.solvers import SOLVERS

    assert "mip" in SOLVERS
    out = tmp_path / "out"
    env = dict(os.environ, CAMPLACE_CACHE=str(tmp_path / "cache"))
    proc = subprocess.Popen([sys.executable, "-m", "camplace.cli.app", "run", "standard-store", "--solver", "mip",
                             "--budget", "40", "--time-limit", "600", "--out", str(out), "--no-cache"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path)
    seen: list[str] = []
    try:
        assert _read_until(proc.stderr, "stage: solve", 120, seen), "".join(seen)
        time.sleep(1.5)  # inside the MIP (warm start or HiGHS)
        assert proc.poll() is None, "the MIP finished before it could be interrupted"
        t0 = time.perf_counter()
        proc.send_signal(signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=90)
        waited = time.perf_counter() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    text = "".join(seen) + stderr
    assert proc.returncode == 130, text
    assert "Traceback" not in text
    assert "interrupted" in text
    assert waited < 60, f"took {waited:.1f} s to stop"
    p = json.loads((out / "placement.json").read_text())
    m = json.loads((out / "metrics.json").read_text())
    assert p["status"] == "interrupted"
    assert p["solver"] == "mip" and p["budget"] == 40
    assert 0 < len(p["cameras"]) <= 40
    assert p["bound"] is None or p["bound"] <= p["objective"] + 1e-6
    assert m["cost"] == pytest.approx(p["objective"])
    assert not [f for f in out.iterdir() if f.name.endswith(".tmp")]
    if CHECK_RUN.is_file():
        r = subprocess.run([sys.executable, str(CHECK_RUN), str(out)], capture_output=True, text=True)
        assert r.returncode == 0, r.stdout + r.stderr
    else:  # pragma: no cover
        pytest.skip("../shared/contract/check_run.py is absent: contract check skipped")


def test_second_ctrl_c_aborts():
    from camplace.cli.app import _StopFlag

    stop = _StopFlag()
    before = signal.getsignal(signal.SIGINT)  # whatever an earlier test (or pytest) left installed
    with stop.installed():
        assert not stop()
        os.kill(os.getpid(), signal.SIGINT)  # first: only the flag
        time.sleep(0.05)
        assert stop()
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGINT)  # second: abort
            time.sleep(0.5)
    assert signal.getsignal(signal.SIGINT) is before  # the handler it found is restored


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
    assert 0.6 <= took < 5
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
