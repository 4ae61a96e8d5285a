"""Work of the report set beside this process: a forked child process (matplotlib holds the GIL).

``Forked(fn)`` starts ``fn()`` in a child process made by ``os.fork`` (Linux only: the child
shares this process's memory as it is, so nothing is pickled on the way in); ``result()``
returns what ``fn`` returned (pickled back through a pipe) or raises the error it raised.
The child writes no file and touches no thread of this process, so ``fn`` must be pure
drawing and encoding (the plan set's PDF, DXF and glTF bytes: camplace.outputs.handover).
Where fork is unavailable (not Linux, ``FORK`` False) or fails (no memory for it), or the
child dies without an answer, ``fn`` runs in this process at ``result()``: the same bytes,
only later. ``cancel()`` ends a child whose result is no longer wanted (an interrupt, a
deadline).

A fork copies only the forking thread; a lock another thread held at that moment stays held
in the child. Should the child ever block on one, it stops using CPU: ``result()`` watches
the child's CPU time (/proc) while it waits and, after ``STALL_S`` seconds without any, ends
it and does the work here, so a stuck child costs time, never a hung run.
"""

from __future__ import annotations

import gc
import os
import pickle
import select
import signal
import sys
import warnings
from collections.abc import Callable
from typing import Generic, TypeVar

T = TypeVar("T")

FORK = sys.platform.startswith("linux") and hasattr(os, "fork")  # tests switch it off to compare
STALL_S = 20.0  # s of waiting without the child using any CPU: it is stuck (module doc)


class Forked(Generic[T]):
    """``fn()`` run in a forked child process; ``result()`` waits for it (see the module)."""

    def __init__(self, fn: Callable[[], T]) -> None:
        self.fn = fn
        self.pid: int | None = None
        self.fd: int | None = None
        if FORK:
            self._start()

    def _start(self) -> None:
        r, w = os.pipe()
        try:
            with warnings.catch_warnings():  # Python >= 3.12 warns of fork in a threaded process; the child uses none
                warnings.simplefilter("ignore", DeprecationWarning)
                pid = os.fork()
        except OSError:
            os.close(r)
            os.close(w)
            return
        if pid == 0:  # the child: answer through the pipe, then leave without any clean-up of the parent's state
            try:
                os.close(r)
                gc.freeze()  # the parent's objects: never swept here (a sweep would copy every page it touches)
                signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
                _answer(w, self.fn)
            finally:
                os._exit(0)
        os.close(w)
        self.pid, self.fd = pid, r

    def result(self) -> T:
        """fn's result (or its error raised here); fn runs here when no child answered."""
        if self.pid is None:
            return self.fn()
        try:
            data = _read_all(self.fd, self.pid)  # all of it before waiting: a full pipe would block the child
            if data is not None:
                os.close(self.fd)
                self.fd = None
                os.waitpid(self.pid, 0)
                self.pid = None
        finally:
            self.cancel()
        if not data:  # the child died without answering (killed) or is stuck: do the work here
            return self.fn()
        ok, value = pickle.loads(data)
        if ok:
            return value
        raise value

    def cancel(self) -> None:
        """End the child (if still running) and forget it."""
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None
        if self.pid is not None:
            try:
                os.kill(self.pid, signal.SIGKILL)
                os.waitpid(self.pid, 0)
            except (ProcessLookupError, ChildProcessError):
                pass
            self.pid = None


def _cpu_ticks(pid: int) -> int | None:
    """User + system CPU clock ticks of process ``pid`` (/proc/PID/stat); None where unreadable."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            fields = f.read().rsplit(b")", 1)[1].split()
        return int(fields[11]) + int(fields[12])  # utime, stime: fields 14 and 15 of stat(5)
    except (OSError, IndexError, ValueError):
        return None


def _read_all(fd: int, pid: int, poll_s: float = 1.0) -> bytes | None:
    """Everything the child writes to ``fd`` until it closes it; None when the child used no
    CPU for STALL_S seconds (stuck: module doc)."""
    chunks: list[bytes] = []
    ticks, idle = _cpu_ticks(pid), 0.0
    while True:
        ready, _, _ = select.select([fd], [], [], poll_s)
        if ready:
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                return b"".join(chunks)
            chunks.append(chunk)
            idle = 0.0
            continue
        now = _cpu_ticks(pid)
        idle = idle + poll_s if now is not None and now == ticks else 0.0
        ticks = now
        if idle >= STALL_S:
            return None


def _answer(fd: int, fn: Callable[[], object]) -> None:
    """Write the pickled (True, fn()) or (False, its error) to the pipe ``fd``."""
    try:
        payload = pickle.dumps((True, fn()), protocol=pickle.HIGHEST_PROTOCOL)
    except BaseException as err:  # noqa: BLE001 - every error goes back to the parent
        try:
            payload = pickle.dumps((False, err))
        except Exception:  # noqa: BLE001 - an error that does not pickle: its words
            payload = pickle.dumps((False, RuntimeError(f"{type(err).__name__}: {err}")))
    with os.fdopen(fd, "wb") as f:
        f.write(payload)
