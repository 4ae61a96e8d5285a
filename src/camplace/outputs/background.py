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
"""

from __future__ import annotations

import gc
import os
import pickle
import signal
import sys
import warnings
from collections.abc import Callable
from typing import Generic, TypeVar

T = TypeVar("T")

FORK = sys.platform.startswith("linux") and hasattr(os, "fork")  # tests switch it off to compare


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
            with os.fdopen(self.fd, "rb") as f:
                self.fd = None
                data = f.read()  # all of it before waiting: a full pipe would block the child
            os.waitpid(self.pid, 0)
            self.pid = None
        finally:
            self.cancel()
        if not data:  # the child died without answering (killed): do the work here
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
