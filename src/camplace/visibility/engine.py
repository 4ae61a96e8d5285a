"""One interface for the visibility engines, and the one loop that runs any of them.

An engine (camplace.visibility.voxel.VoxelEngine, camplace.visibility.pixel.PixelEngine;
by name: camplace.visibility.registry.get_engine) is a small frozen, picklable object
holding its parameters. ``compute_visibility(engine, occupancy, targets, candidates)``
cuts the candidates into blocks of ``engine.chunk_size`` rows and

1. looks each block up in the block cache (camplace.visibility.cache) under a content
   hash of the inputs, ``engine.cache_tag()`` and the source of ``engine.code_modules()``;
2. for the blocks not there, builds ``shared = engine.setup(occupancy, targets,
   candidates)`` once (shipped once to each worker of the executor,
   camplace.core.executors) and maps ``engine.rows(shared, start, stop)`` over them:
   the CSR (indptr, indices) pieces of V's rows [start, stop);
3. assembles V block by block (``chunked_rows``), never dense.

V does not depend on the executor, the cache or the chunking; camplace.visibility.testing
checks that for any engine. How to add one: docs/engines.md.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Protocol, runtime_checkable

import numpy as np
import scipy.sparse as sp

from camplace.cameras.candidates import Candidates
from camplace.core.errors import InputError
from camplace.scene.build import OccupancyGrid
from camplace.targets.build import Targets

Progress = Callable[[str, int, int], None]
RowBlock = tuple[np.ndarray, np.ndarray]  # (indptr (rows + 1,) int64 from 0, indices (nnz,) int32 ascending per row)


@dataclass(frozen=True)
class Visibility:
    """V: (N_g, N_p) CSR uint8, 1 where candidate i sees target j; rows follow
    ``candidates``, columns follow ``targets``; mode: the engine that computed it; engine:
    that engine with its parameters (None: the default ``mode`` engine), so a later stage
    that raycasts new poses (camplace.improve) adds rows computed under the same rule."""

    V: sp.csr_matrix
    candidates: Candidates
    targets: Targets
    mode: str = "voxel"
    info: dict = field(default_factory=dict)
    engine: Any = None


@runtime_checkable
class VisibilityEngine(Protocol):
    """What compute_visibility needs from an engine (a frozen dataclass of parameters).

    mode: the engine's name (Visibility.mode, the registry key); chunk_size: candidate
    rows per block (the unit of work and of the cache)."""

    mode: str
    chunk_size: int

    def cache_tag(self) -> str:
        """The mode and every parameter that changes V, as one string (enters the cache key)."""
        ...

    def code_modules(self) -> tuple[ModuleType, ...]:
        """The engine's own modules whose source decides V (enter the cache key's code version)."""
        ...

    def setup(self, occupancy: OccupancyGrid, targets: Targets, candidates: Candidates) -> Any:
        """The read-only state every block reads (picklable: shipped once per worker)."""
        ...

    def rows(self, shared: Any, start: int, stop: int) -> RowBlock:
        """V rows [start, stop) of the candidates as CSR pieces (see RowBlock)."""
        ...

    def info(self, candidates: Candidates, bounds: list[tuple[int, int]], computed: list[int], seconds: float,
             shared: Any | None) -> dict:
        """Engine statistics for Visibility.info: ``computed`` = the blocks raycast in this
        call (the others came from the cache), ``shared`` = the set-up (None when every
        block came from the cache)."""
        ...


def core_modules() -> tuple[ModuleType, ...]:
    """The modules whose code decides V for every engine: this loop, the ray walking, the
    lens models and the target quality limits."""
    from camplace.cameras import models
    from camplace.spec import quality
    from camplace.visibility import raywalk

    return sys.modules[__name__], raywalk, models, quality


def visibility_cache_key(engine: VisibilityEngine, occupancy: OccupancyGrid, targets: Targets,
                         candidates: Candidates) -> str:
    """Content hash of everything V depends on: the inputs, the engine's cache tag and
    chunking, and the code version of core_modules() + engine.code_modules()."""
    from camplace.visibility.cache import code_version, content_key

    occ = OccupancyGrid(np.packbits(occupancy.occupied, axis=None), occupancy.origin, occupancy.resolution)
    return content_key("visibility", code_version(*core_modules(), *engine.code_modules()), engine.cache_tag(),
                       int(engine.chunk_size), occupancy.occupied.shape, occ, targets, candidates)


def raycast_rows(engine: VisibilityEngine, occupancy: OccupancyGrid, targets: Targets,
                 candidates: Candidates) -> sp.csr_matrix:
    """V rows (len(candidates), N_p) CSR uint8 of a few new poses by ``engine``, here, without
    the cache: ``engine.setup`` then ``engine.rows`` over all of them (the refinement's trial
    poses, an adaptive round's candidates)."""
    n = len(candidates)
    if n == 0:
        return sp.csr_matrix((0, len(targets)), dtype=np.uint8)
    indptr, indices = engine.rows(engine.setup(occupancy, targets, candidates), 0, n)
    return sp.csr_matrix((np.ones(len(indices), np.uint8), indices, indptr), shape=(n, len(targets)))


def target_voxel(targets: Targets, option: str) -> float:
    """The targets' voxel edge (m, ``Targets.voxel_size``) for an engine rule that needs it;
    InputError(option=``option``) when the targets do not carry one."""
    v = targets.voxel_size
    if v is None or not float(v) > 0:
        raise InputError(f"{option}: this visibility rule needs the targets' voxel edge (Targets.voxel_size, "
                         f"a positive length in m), got {v}", option=option)
    return float(v)


def check_chunk_size(chunk_size: int) -> None:
    """InputError unless chunk_size (candidate rows per block) is a positive integer."""
    if int(chunk_size) != chunk_size or chunk_size < 1:
        raise InputError(f"chunk_size: expected a positive integer, got {chunk_size}", option="chunk_size")


def row_bounds(n: int, chunk_size: int) -> list[tuple[int, int]]:
    """[start, stop) of each block of ``chunk_size`` rows covering rows 0..n-1."""
    return [(s, min(s + chunk_size, n)) for s in range(0, n, chunk_size)]


def _engine_rows(shared: tuple, bounds: tuple[int, int]) -> RowBlock:
    """One unit of work for an executor: shared = (engine, engine.setup(...))."""
    engine, state = shared
    return engine.rows(state, bounds[0], bounds[1])


def compute_visibility(engine: VisibilityEngine, occupancy: OccupancyGrid, targets: Targets, candidates: Candidates,
                       *, executor=None, cache_dir: str | Path | None = None,
                       progress: Progress | None = None) -> Visibility:
    """V of every candidate (rows in candidate order) by ``engine``.

    Blocks of ``engine.chunk_size`` rows run on ``executor`` (camplace.core.executors;
    default in-process) and stream back as CSR pieces, copied into the final CSR arrays.
    With ``cache_dir`` each block is also stored under a content-hash key
    (camplace.visibility.cache): finished blocks are loaded instead of recomputed (a second
    run, or a run resumed after an interruption), and V is assembled block by block from
    disk. ``progress("visibility", done, total)`` after every block. The result does not
    depend on executor or cache."""
    t0 = time.perf_counter()
    n_p = len(targets)
    bounds = row_bounds(len(candidates), int(engine.chunk_size))
    store = None
    if cache_dir is not None:
        from camplace.visibility.cache import BlockStore

        store = BlockStore(cache_dir, visibility_cache_key(engine, occupancy, targets, candidates), bounds, n_p)
    built: list = []

    def make_shared() -> tuple:
        built.append(engine.setup(occupancy, targets, candidates))
        return engine, built[-1]

    V, cached = chunked_rows(n_p, bounds, _engine_rows, make_shared, executor, store, progress)
    secs = time.perf_counter() - t0
    from_cache = set(cached)
    computed = [k for k in range(len(bounds)) if k not in from_cache]
    extra = engine.info(candidates, bounds, computed, secs, built[0] if built else None)
    info = {"seconds": secs, "nnz": int(V.nnz), "chunks": len(bounds), **extra, "cached_chunks": len(cached),
            "executor": getattr(executor, "name", "in-process")}
    if store is not None:
        info["cache"] = str(store.dir)
    return Visibility(V, candidates, targets, engine.mode, info, engine)


def chunked_rows(n_cols: int, bounds: list[tuple[int, int]], task: Callable, make_shared: Callable[[], object],
                 executor=None, store=None, progress: Progress | None = None) -> tuple[sp.csr_matrix, list[int]]:
    """A CSR 0/1 matrix (uint8) built as row blocks: block k (rows bounds[k]) is
    ``task(shared, bounds[k])`` -> (indptr (rows + 1,) int64, indices (nnz,) int32).

    The blocks not in ``store`` (a camplace.visibility.cache.BlockStore, or None) run on ``executor``
    (camplace.core.executors; default in-process) and are stored as they arrive; ``shared``
    = ``make_shared()`` is built only when a block must be computed. The matrix is then
    assembled block by block (from the store when there is one), never densified.
    Returns (matrix, indices of the blocks loaded from the store)."""
    from camplace.core.executors import InProcessExecutor

    n = bounds[-1][1] if bounds else 0
    blocks: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    nnz = np.zeros(len(bounds), np.int64)
    todo, cached = [], []
    for k in range(len(bounds)):
        got = store.nnz(k) if store is not None else None
        if got is None:
            todo.append(k)
        else:
            nnz[k] = got
            cached.append(k)
    done = len(cached)
    if progress:
        progress("visibility", done, len(bounds))
    shared = None
    if todo:
        shared = make_shared()
        ex = executor if executor is not None else InProcessExecutor()
        for t, (indptr, indices) in ex.map_unordered(task, shared, [bounds[k] for k in todo]):
            k = todo[t]
            nnz[k] = len(indices)
            if store is not None:
                store.save(k, indptr, indices)
            else:
                blocks[k] = (indptr, indices)
            done += 1
            if progress:
                progress("visibility", done, len(bounds))
    if store is not None:  # out of core: V as memory-mapped CSR files in the cache entry
        V = _assembled(store, n, n_cols, bounds, nnz, task, make_shared, shared, cached)
        if V is not None:
            return V, cached
    indptr = np.zeros(n + 1, np.int64)
    indices = np.empty(int(nnz.sum()), np.int32)
    pos = 0
    for k, (s, e) in enumerate(bounds):
        blk = blocks.pop(k) if store is None else store.load(k)
        if blk is None or len(blk[1]) != nnz[k]:  # damaged or replaced in the cache since its count was read
            shared = make_shared() if shared is None else shared
            blk = task(shared, (s, e))
            if store is not None:
                store.save(k, *blk)
            if k in cached:
                cached.remove(k)
            grow = len(blk[1]) - int(nnz[k])
            nnz[k] = len(blk[1])
            if grow > 0:  # rare: make room for the recomputed block
                indices = np.concatenate([indices, np.empty(grow, np.int32)])
        bp, bi = blk
        indptr[s + 1:e + 1] = bp[1:] + pos
        indices[pos:pos + len(bi)] = bi
        pos += len(bi)
    indices = indices[:pos]
    V = sp.csr_matrix((np.ones(len(indices), np.uint8), indices, indptr), shape=(n, n_cols))
    return V, cached


class _BlockChanged(Exception):
    """A cached block was recomputed with another entry count during the assembly."""


def _assembled(store, n: int, n_cols: int, bounds: list[tuple[int, int]], nnz: np.ndarray, task: Callable,
               make_shared: Callable[[], object], shared, cached: list[int]) -> sp.csr_matrix | None:
    """V from the store's assembled CSR files (memory-mapped), writing them block by block
    first when missing; the working set is one block. None when a block changed size
    while being read (the caller then assembles in memory)."""
    got = store.load_assembled(n)
    if got is None or len(got[1]) != int(nnz.sum()):
        indptr = np.zeros(n + 1, np.int64)
        state = {"shared": shared}

        def blocks():
            pos = 0
            for k, (s, e) in enumerate(bounds):
                blk = store.load(k)
                if blk is None or len(blk[1]) != nnz[k]:  # damaged or replaced since its count was read
                    state["shared"] = make_shared() if state["shared"] is None else state["shared"]
                    blk = task(state["shared"], (s, e))
                    store.save(k, *blk)
                    if k in cached:
                        cached.remove(k)
                    if len(blk[1]) != nnz[k]:
                        raise _BlockChanged
                bp, bi = blk
                indptr[s + 1:e + 1] = bp[1:] + pos
                yield pos, bi
                pos += len(bi)

        try:
            got = store.write_assembled(indptr, int(nnz.sum()), blocks())
        except _BlockChanged:
            return None
    indptr, indices, data = got
    return sp.csr_matrix((data, indices, indptr), shape=(n, n_cols), copy=False)


def drop_blind_candidates(vis: Visibility) -> Visibility:
    """Remove candidates that see no target (rows of V with no entry). The empty rows
    hold no entries, so V's data and indices are shared, not copied."""
    counts = np.diff(vis.V.indptr)
    keep = counts > 0
    info = dict(vis.info, dropped_blind=int((~keep).sum()))
    indptr = np.r_[0, np.cumsum(counts[keep])].astype(vis.V.indptr.dtype)
    V = sp.csr_matrix((vis.V.data, vis.V.indices, indptr), shape=(int(keep.sum()), vis.V.shape[1]), copy=False)
    return Visibility(V, vis.candidates.subset(keep), vis.targets, vis.mode, info, vis.engine)
