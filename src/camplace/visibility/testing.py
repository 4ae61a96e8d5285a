"""Conformance checks for visibility engines: ``check_engine(engine, occupancy, targets, candidates)``.

Every engine (camplace.visibility.engine.VisibilityEngine) must give the same V bit for
bit whatever runs it: in-process, a 2-process pool, a Dask cluster (an in-process
LocalCluster; skipped, with the reason, when dask.distributed is missing), other block
sizes, and the block cache cold (every block computed and stored) and warm (every
block loaded). V must be (N_g, N_p) CSR uint8 of ones with ascending, unique column
indices per row; ``rows`` must return (indptr int64 from 0, indices int32) pieces; the
engine must pickle (it travels to workers) and name itself in its cache tag.

``check_engine`` returns one ``Check`` per item (status 'ok' or 'skipped' with the
reason) and raises AssertionError listing every failed one. Use it in a test::

    checks = check_engine(get_engine("voxel"), occupancy, targets, candidates, tmp_path)
"""

from __future__ import annotations

import dataclasses
import pickle
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator

import numpy as np
import scipy.sparse as sp

from camplace.cameras.candidates import Candidates
from camplace.scene.build import OccupancyGrid
from camplace.targets.build import Targets
from camplace.visibility.engine import Visibility, VisibilityEngine, compute_visibility
from camplace.core.executors import Executor, InProcessExecutor, ProcessPoolChunkExecutor

EXECUTORS = ("in-process", "process-pool", "dask")


@dataclass(frozen=True)
class Check:
    """One conformance item: name, status ('ok', 'failed', 'skipped') and why."""

    name: str
    status: str
    detail: str = ""


def csr_problems(V: sp.csr_matrix, shape: tuple[int, int]) -> list[str]:
    """What is wrong with V as a visibility matrix of ``shape`` (empty: nothing)."""
    out = []
    if not isinstance(V, sp.csr_matrix):
        return [f"V is a {type(V).__name__}, expected scipy.sparse.csr_matrix"]
    if V.shape != shape:
        out.append(f"shape {V.shape}, expected {shape}")
    if V.dtype != np.uint8:
        out.append(f"dtype {V.dtype}, expected uint8")
    if V.nnz and not np.all(V.data == 1):
        out.append("data holds values other than 1")
    if V.nnz and (V.indices.min() < 0 or V.indices.max() >= shape[1]):
        out.append("column indices out of range")
    step = np.diff(V.indices.astype(np.int64))
    row_start = np.zeros(max(V.nnz - 1, 0), bool)
    starts = V.indptr[1:-1]
    row_start[starts[(starts > 0) & (starts < V.nnz)] - 1] = True
    if np.any((step <= 0) & ~row_start):
        out.append("column indices not strictly ascending within a row")
    return out


def same_v(a: sp.csr_matrix, b: sp.csr_matrix) -> bool:
    """True when a and b have the same shape, indptr and indices."""
    return a.shape == b.shape and np.array_equal(a.indptr, b.indptr) and np.array_equal(a.indices, b.indices)


def _block_problems(engine: VisibilityEngine, occupancy: OccupancyGrid, targets: Targets,
                    candidates: Candidates) -> list[str]:
    """Problems of the raw ``rows`` pieces of the first block and of an empty block."""
    shared = engine.setup(occupancy, targets, candidates)
    stop = min(len(candidates), int(engine.chunk_size))
    out = []
    for s, e in ((0, stop), (stop, stop)):
        indptr, indices = engine.rows(shared, s, e)
        if indptr.dtype != np.int64 or indices.dtype != np.int32:
            out.append(f"rows({s}, {e}): dtypes {indptr.dtype}/{indices.dtype}, expected int64/int32")
        if len(indptr) != e - s + 1 or indptr[0] != 0 or indptr[-1] != len(indices):
            out.append(f"rows({s}, {e}): indptr does not describe {e - s} rows")
    return out


def _executors(names: tuple[str, ...]) -> Iterator[tuple[str, Callable[[], Executor] | None, str]]:
    """(name, factory or None, why skipped) of each executor to try."""
    for name in names:
        if name == "in-process":
            yield name, InProcessExecutor, ""
        elif name == "process-pool":
            yield name, lambda: ProcessPoolChunkExecutor(2, threads_per_worker=1), ""
        elif name == "dask":
            try:
                from dask.distributed import Client, LocalCluster  # noqa: F401
            except ImportError as err:
                yield name, None, f"dask.distributed is not installed ({err})"
                continue
            yield name, _local_dask, ""
        else:
            raise ValueError(f"executor: expected one of {EXECUTORS}, got {name!r}")


class _LocalDask(Executor):
    """A DaskExecutor on an in-process LocalCluster (threads), closed with it."""

    name = "dask"

    def __init__(self) -> None:
        from dask.distributed import Client, LocalCluster

        from camplace.core.executors import DaskExecutor

        self._cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None)
        self._inner = DaskExecutor(client=Client(self._cluster, set_as_default=False), threads_per_task=1)
        self.workers = self._inner.workers

    def map_unordered(self, fn, shared, tasks):
        return self._inner.map_unordered(fn, shared, tasks)

    def close(self) -> None:
        self._inner.client.close()
        self._cluster.close()


def _local_dask() -> Executor:
    return _LocalDask()


def check_engine(engine: VisibilityEngine, occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                 cache_dir: str | Path | None = None, executors: tuple[str, ...] = EXECUTORS) -> list[Check]:
    """Run the conformance checks of ``engine`` on one scene (see the module docstring).

    cache_dir: an empty folder for the cache checks (default: a temporary one);
    executors: which of EXECUTORS to try. Returns the checks; raises AssertionError
    naming every failed one."""
    checks: list[Check] = []

    def record(name: str, problems: list[str]) -> None:
        checks.append(Check(name, "failed" if problems else "ok", "; ".join(problems)))

    shape = (len(candidates), len(targets))
    record("interface", [] if isinstance(engine, VisibilityEngine) else ["not a VisibilityEngine"])
    tag = engine.cache_tag()
    record("cache tag", [] if isinstance(tag, str) and tag.startswith(engine.mode) else
           [f"cache_tag() {tag!r} does not start with the mode {engine.mode!r}"])
    record("pickle", _pickle_problems(engine))
    record("rows", _block_problems(engine, occupancy, targets, candidates))
    ref = compute_visibility(engine, occupancy, targets, candidates)
    record("V", csr_problems(ref.V, shape) + _vis_problems(ref, engine))

    def agree(name: str, vis: Visibility, extra: list[str] = ()) -> None:
        record(name, ([] if same_v(vis.V, ref.V) else ["V differs from the in-process V"]) + list(extra))

    for name, make, why in _executors(tuple(executors)):
        if make is None:
            checks.append(Check(f"executor {name}", "skipped", why))
            continue
        with make() as ex:
            agree(f"executor {name}", compute_visibility(engine, occupancy, targets, candidates, executor=ex))
    if dataclasses.is_dataclass(engine) and "chunk_size" in {f.name for f in dataclasses.fields(engine)}:
        other = dataclasses.replace(engine, chunk_size=max(1, min(int(engine.chunk_size), len(candidates)) // 3))
        agree("chunking", compute_visibility(other, occupancy, targets, candidates))
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(cache_dir) if cache_dir is not None else Path(tmp)
        cold = compute_visibility(engine, occupancy, targets, candidates, cache_dir=root)
        agree("cache cold", cold, [] if cold.info["cached_chunks"] == 0 else
              [f"{cold.info['cached_chunks']} blocks loaded from an empty cache"])
        warm = compute_visibility(engine, occupancy, targets, candidates, cache_dir=root)
        agree("cache warm", warm, [] if warm.info["cached_chunks"] == warm.info["chunks"] else
              [f"{warm.info['cached_chunks']} of {warm.info['chunks']} blocks loaded"])
    failed = [c for c in checks if c.status == "failed"]
    if failed:
        raise AssertionError(f"{engine!r} fails: " + "; ".join(f"{c.name}: {c.detail}" for c in failed))
    return checks


def _pickle_problems(engine: VisibilityEngine) -> list[str]:
    """The engine travels to process-pool and Dask workers: it must pickle to an equal one."""
    try:
        same = pickle.loads(pickle.dumps(engine)) == engine
    except (pickle.PicklingError, AttributeError, TypeError) as err:
        return [f"the engine does not pickle ({err})"]
    return [] if same else ["the engine does not unpickle to an equal one"]


def _vis_problems(vis: Visibility, engine: VisibilityEngine) -> list[str]:
    """The Visibility record around V: mode and statistics."""
    out = []
    if vis.mode != engine.mode:
        out.append(f"Visibility.mode {vis.mode!r}, expected {engine.mode!r}")
    if vis.info.get("nnz") != vis.V.nnz:
        out.append("info['nnz'] is not V.nnz")
    return out
