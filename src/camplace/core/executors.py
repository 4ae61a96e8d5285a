"""Executors for chunked maps: in-process, a local process pool, or a Dask cluster.

Infrastructure every stage may use (the visibility stage maps blocks of candidate rows,
the zone solver maps floor tiles): ``fn(shared, task)`` for every task, where ``shared``
(e.g. occupancy grid, targets, candidates: tens of MB) is the same for all tasks and is
shipped to each worker once, and ``task`` is small (a row range). Every executor has the same interface, ``map_unordered(fn, shared, tasks)``,
which yields ``(task_index, result)`` as results arrive, so the caller can stream them
to disk or assemble them without holding everything twice. Results do not depend on the
executor: each task is computed by the same function on the same inputs.

- ``InProcessExecutor``: tasks run here one after another (the kernel itself is
  multi-threaded).
- ``ProcessPoolChunkExecutor``: ``workers`` local processes (``spawn`` start method:
  numba's OpenMP layer is not fork-safe); each gets ``shared`` once at start-up.
- ``DaskExecutor``: a ``dask.distributed`` cluster given by its scheduler address
  (``tcp://host:port``) or an existing ``Client``; ``shared`` is scattered (broadcast)
  once and tasks are submitted as futures.

All three derive from ``Executor`` (the protocol, and the shared context-manager
``close``). ``make_executor(workers, scheduler)`` picks one; ``CAMPLACE_SCHEDULER`` in the
environment stands for ``scheduler`` when it is not given.
"""

from __future__ import annotations

import abc
import contextlib
import os
import threading
import uuid
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any, Callable, Iterator, Sequence

from camplace.core.errors import InputError

SCHEDULER_ENV = "CAMPLACE_SCHEDULER"
TaskFn = Callable[[Any, Any], Any]

# Calls into the numba kernels are serialized inside one process: the kernel already
# uses every core it is given, and concurrent parallel launches from several threads
# (a threaded Dask worker) would oversubscribe the cores or trip numba's threading layer.
_CALL_LOCK = threading.Lock()
_WORKER_SHARED: Any = None  # the shared payload inside a process-pool worker


def _set_threads(n_threads: int | None) -> None:
    if n_threads:
        import numba

        numba.set_num_threads(max(1, min(int(n_threads), numba.config.NUMBA_NUM_THREADS)))


def run_task(fn: TaskFn, shared: Any, task: Any, n_threads: int | None = None) -> Any:
    """Run one task under the per-process kernel lock, with ``n_threads`` numba threads."""
    with _CALL_LOCK:
        _set_threads(n_threads)
        return fn(shared, task)


_POOL: dict = {}  # the on_threads pool of this process, by size (created at first use, kept: no thread start per call)


def on_threads(n_rows: int, run: Callable[[int, int], Any], min_rows: int = 64) -> list[Any]:
    """``run(a, b)`` over consecutive pieces [a, b) of range(n_rows), on up to
    numba.get_num_threads() threads (pieces of at least ``min_rows``); the results in order.
    For numba kernels compiled serial and ``nogil``: such a kernel compiles about twice as
    fast as a ``parallel=True`` one (a new install compiles every kernel once) and launches
    no thread team per call. The pieces never call on_threads themselves."""
    import numba

    n = max(1, min(numba.get_num_threads(), n_rows // max(1, min_rows)))
    if n == 1:
        return [run(0, n_rows)]
    from concurrent.futures import ThreadPoolExecutor

    pool = _POOL.get(n)
    if pool is None:
        pool = _POOL[n] = ThreadPoolExecutor(n, thread_name_prefix="camplace-kernel")
    cuts = [n_rows * k // n for k in range(n + 1)]
    return list(pool.map(run, cuts[:-1], cuts[1:]))


class Executor(abc.ABC):
    """The executor protocol: ``map_unordered(fn, shared, tasks)`` yields ``(task index,
    fn(shared, task))`` as results arrive; ``name`` (for Visibility.info) and ``workers``
    (how many run at once). A context manager: ``close()`` on exit frees what the
    executor owns (nothing, by default)."""

    name: str = "executor"
    workers: int = 1

    @abc.abstractmethod
    def map_unordered(self, fn: TaskFn, shared: Any, tasks: Sequence[Any]) -> Iterator[tuple[int, Any]]:
        """(index into tasks, result) of every task, in completion order."""

    def close(self) -> None:
        """Free the executor's resources (idempotent)."""

    def __enter__(self) -> "Executor":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def check_workers(workers: int) -> None:
    """InputError unless ``workers`` is a positive integer."""
    if workers < 1:
        raise InputError(f"workers: expected a positive integer, got {workers}", option="workers")


class InProcessExecutor(Executor):
    """Run the tasks here, in order (the kernel is parallel inside each task)."""

    name = "in-process"
    workers = 1

    def map_unordered(self, fn: TaskFn, shared: Any, tasks: Sequence[Any]) -> Iterator[tuple[int, Any]]:
        for k, task in enumerate(tasks):
            yield k, run_task(fn, shared, task)


def _pool_init(shared: Any, n_threads: int | None) -> None:
    global _WORKER_SHARED
    _WORKER_SHARED = shared
    _set_threads(n_threads)


@contextlib.contextmanager
def sigint_ignored():
    """Block SIGINT while worker processes are spawned: they inherit the blocked mask
    (across exec), so a Ctrl-C - sent by the terminal to the whole process group -
    reaches only the parent, which stops cleanly between chunks (camplace.workflows.run),
    instead of killing workers mid-start and hanging the pool. The parent gets a SIGINT
    sent meanwhile as soon as the mask is restored."""
    import signal

    if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - non-POSIX
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _pool_call(fn: TaskFn, task: Any) -> Any:
    return run_task(fn, _WORKER_SHARED, task)


class ProcessPoolChunkExecutor(Executor):
    """``workers`` local processes (spawned); ``shared`` is sent to each once."""

    name = "process-pool"

    def __init__(self, workers: int, threads_per_worker: int | None = None) -> None:
        check_workers(workers)
        self.workers = int(workers)
        cores = os.cpu_count() or 1
        self.threads_per_worker = threads_per_worker or max(1, cores // self.workers)

    def map_unordered(self, fn: TaskFn, shared: Any, tasks: Sequence[Any]) -> Iterator[tuple[int, Any]]:
        import multiprocessing as mp

        if not tasks:
            return
        ctx = mp.get_context("spawn")
        n = min(self.workers, len(tasks))
        with ProcessPoolExecutor(n, mp_context=ctx, initializer=_pool_init,
                                 initargs=(shared, self.threads_per_worker)) as pool:
            with sigint_ignored():  # the workers are spawned here and keep SIGINT ignored (see below)
                futures = {pool.submit(_pool_call, fn, t): k for k, t in enumerate(tasks)}
            try:
                for fut in as_completed(futures):
                    yield futures[fut], fut.result()
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise


class DaskExecutor(Executor):
    """Tasks on a dask.distributed cluster: ``DaskExecutor("tcp://host:port")`` or
    ``DaskExecutor(client=Client(...))``. ``threads_per_task``: numba threads per task
    (default: all the worker machine's cores)."""

    name = "dask"

    def __init__(self, address: str | None = None, client: Any = None, threads_per_task: int | None = None,
                 timeout_s: float = 10.0) -> None:
        from dask.distributed import Client

        self._own = client is None
        if client is None:
            if not address or "://" not in address:
                raise InputError(f"scheduler: expected a Dask scheduler address like tcp://host:8786, got "
                                 f"'{address}'", option="scheduler")
            try:
                client = Client(address, timeout=f"{timeout_s}s", set_as_default=False)
            except (OSError, TimeoutError) as err:
                raise InputError(f"scheduler: cannot connect to the Dask scheduler at {address} ({err})",
                                 option="scheduler") from None
        self.client = client
        self.threads_per_task = threads_per_task
        self.workers = max(1, len(client.scheduler_info().get("workers", {})))

    def map_unordered(self, fn: TaskFn, shared: Any, tasks: Sequence[Any]) -> Iterator[tuple[int, Any]]:
        from dask.distributed import as_completed as dask_as_completed

        if not tasks:
            return
        shared_f = self.client.scatter(shared, broadcast=True, hash=False)
        run = uuid.uuid4().hex[:12]
        futures = [self.client.submit(run_task, fn, shared_f, t, self.threads_per_task, pure=False,
                                      key=f"camplace-chunk-{run}-{k}") for k, t in enumerate(tasks)]
        index = {f.key: k for k, f in enumerate(futures)}
        try:
            for fut in dask_as_completed(futures, loop=self.client.loop):
                k = index[fut.key]
                yield k, fut.result()
                fut.release()
        finally:
            self.client.cancel(futures)
            self.client.cancel([shared_f])

    def close(self) -> None:
        if self._own:
            self.client.close()
            self._own = False


def make_executor(workers: int = 1, scheduler: str | None = None) -> Executor:
    """Dask when a scheduler address is given (or ``CAMPLACE_SCHEDULER`` is set), a local
    process pool when ``workers`` > 1, in-process otherwise."""
    scheduler = scheduler or os.environ.get(SCHEDULER_ENV) or None
    if scheduler:
        return DaskExecutor(scheduler)
    if workers is None or workers <= 1:
        if workers is not None:
            check_workers(workers)
        return InProcessExecutor()
    return ProcessPoolChunkExecutor(workers)
