"""camplace.outputs.background.Forked: work in a forked child, its answer or its error back here."""

from __future__ import annotations

import os
import time

import pytest

from camplace.core.errors import InputError
from camplace.outputs import background
from camplace.outputs.background import Forked

forks = pytest.mark.skipif(not background.FORK, reason="fork: Linux only")


@forks
def test_the_result_comes_from_a_child_process():
    here = os.getpid()
    job = Forked(lambda: (os.getpid(), b"x" * 200_000))  # larger than a pipe's buffer
    pid, data = job.result()
    assert pid != here and data == b"x" * 200_000
    assert job.pid is None and job.fd is None


@forks
def test_the_child_error_is_raised_here_with_its_words_and_option():
    def bad():
        raise InputError("paper: expected A4, A3 or letter, got 'B5'", option="paper")

    with pytest.raises(InputError, match="got 'B5'") as info:
        Forked(bad).result()
    assert info.value.option == "paper"


@forks
def test_an_error_that_does_not_pickle_comes_back_as_its_words():
    class Local(Exception):  # a local class does not pickle
        pass

    def bad():
        raise Local("no pickle")

    with pytest.raises(RuntimeError, match="Local: no pickle"):
        Forked(bad).result()


def test_without_fork_the_work_runs_here_at_result(monkeypatch):
    monkeypatch.setattr(background, "FORK", False)
    calls = []
    job = Forked(lambda: calls.append(os.getpid()) or 7)
    assert calls == [] and job.pid is None
    assert job.result() == 7 and calls == [os.getpid()]


@forks
def test_cancel_ends_the_child_and_leaves_no_zombie():
    job = Forked(lambda: time.sleep(30))
    pid = job.pid
    t0 = time.perf_counter()
    job.cancel()
    assert time.perf_counter() - t0 < 5 and job.pid is None
    with pytest.raises(ChildProcessError):
        os.waitpid(pid, os.WNOHANG)


@forks
def test_a_child_killed_before_answering_is_replaced_by_the_work_here():
    here = os.getpid()
    job = Forked(lambda: here if os.getpid() == here else time.sleep(30))  # the child never answers
    os.kill(job.pid, 9)
    assert job.result() == here


@forks
def test_a_stuck_child_is_ended_and_the_work_done_here(monkeypatch):
    """A child blocked on a lock (here: asleep, using no CPU) is given up after STALL_S s."""
    monkeypatch.setattr(background, "STALL_S", 2.0)
    here = os.getpid()
    job = Forked(lambda: here if os.getpid() == here else time.sleep(60))
    pid = job.pid
    t0 = time.perf_counter()
    assert job.result() == here
    assert time.perf_counter() - t0 < 20 and job.pid is None
    with pytest.raises(ChildProcessError):
        os.waitpid(pid, os.WNOHANG)


@forks
def test_a_busy_child_is_not_taken_for_a_stuck_one(monkeypatch):
    monkeypatch.setattr(background, "STALL_S", 2.0)

    def busy():
        t = time.process_time()
        while time.process_time() - t < 3.0:  # CPU, no answer, for longer than STALL_S
            pass
        return os.getpid()

    assert Forked(busy).result() != os.getpid()
