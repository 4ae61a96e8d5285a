"""Out-of-core visibility: V stored as row blocks, one ``.npz`` per block, under a
content-hash key.

A cache entry is a folder ``<root>/visibility/<key>/`` with ``meta.json`` and
``block-000000.npz``, ``block-000001.npz``, ... (CSR ``indptr`` (rows + 1,) int64 and
``indices`` (nnz,) int32 of the block's rows, uncompressed). Each block is written
atomically as soon as it is computed, so an interrupted run resumes from its finished
blocks and a second run loads them all. Once every block is there, V is also written
block by block as one CSR in three uncompressed ``.npy`` files (``V-indptr.npy``,
``V-indices.npy``, ``V-data.npy``) that later stages read memory-mapped
(``np.load(mmap_mode="r")``): V then lives in the page cache, not in the process's heap. The key hashes every input that can change V
(occupancy grid, targets, candidates, camera models, mode, chunking) and the code
version (package version + the source of the modules that compute V), so a changed
input never reuses a stale entry.

Default root: ``$CAMPLACE_CACHE`` or ``$XDG_CACHE_HOME/camplace`` or ``~/.cache/camplace``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import inspect
import io
import json
import os
import zipfile
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from camplace.core.errors import InputError
from camplace.core.files import atomic_npy_memmap, atomic_write_bytes, atomic_write_json

CACHE_ENV = "CAMPLACE_CACHE"
FORMAT = 1


def default_cache_dir() -> Path:
    """``$CAMPLACE_CACHE``, else ``$XDG_CACHE_HOME/camplace``, else ``~/.cache/camplace``."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV]).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base).expanduser() / "camplace"


def _update(h: "hashlib._Hash", obj: Any) -> None:
    """Feed a canonical encoding of obj (arrays, dataclasses, containers, scalars) to h."""
    if isinstance(obj, np.ndarray):
        a = np.ascontiguousarray(obj)
        h.update(f"nd{a.dtype.str}{a.shape}".encode())
        h.update(memoryview(a).cast("B") if a.size else b"")
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        h.update(f"dc{type(obj).__qualname__}".encode())
        for f in dataclasses.fields(obj):
            if f.name == "info":  # run statistics, not inputs
                continue
            h.update(f.name.encode())
            _update(h, getattr(obj, f.name))
    elif isinstance(obj, dict):
        h.update(f"d{len(obj)}".encode())
        for k in sorted(obj, key=str):
            _update(h, str(k))
            _update(h, obj[k])
    elif isinstance(obj, (list, tuple)):
        h.update(f"l{len(obj)}".encode())
        for v in obj:
            _update(h, v)
    elif isinstance(obj, (str, int, float, bool, type(None), np.generic)):
        h.update(f"{type(obj).__name__}:{obj!r};".encode())
    elif hasattr(obj, "model_dump"):  # pydantic models
        _update(h, obj.model_dump())
    else:
        raise TypeError(f"cannot hash {type(obj).__name__} for a cache key")


def content_key(*parts: Any) -> str:
    """Hex digest (32 chars) of the parts: numpy arrays by dtype, shape and bytes;
    dataclasses by their fields (``info`` skipped); containers and scalars by value."""
    h = hashlib.blake2b(digest_size=16)
    for p in parts:
        _update(h, p)
    return h.hexdigest()


def code_version(*modules: ModuleType) -> str:
    """Package version + a hash of the given modules' source (a code change = a new key)."""
    from camplace import __version__

    h = hashlib.blake2b(digest_size=8)
    for m in modules:
        try:
            h.update(Path(inspect.getsourcefile(m) or "").read_bytes())
        except (OSError, TypeError):
            h.update(m.__name__.encode())
    return f"{__version__}+{h.hexdigest()}"


class BlockStore:
    """The blocks of one V under ``root/visibility/<key>/``. ``bounds``: the row range
    [start, stop) of each block; ``n_cols``: N_p."""

    def __init__(self, root: str | Path, key: str, bounds: list[tuple[int, int]], n_cols: int) -> None:
        self.root = Path(root).expanduser()
        self.key = key
        self.bounds = [[int(a), int(b)] for a, b in bounds]
        self.n_cols = int(n_cols)
        self.dir = self.root / "visibility" / key
        meta = {"format": FORMAT, "key": key, "n_blocks": len(self.bounds), "n_cols": self.n_cols,
                "bounds": self.bounds}
        meta_path = self.dir / "meta.json"
        try:
            if meta_path.is_file():
                old = json.loads(meta_path.read_text())
                if old != meta:  # same key, different layout: never mix blocks
                    for p in [*self.dir.glob("block-*.npz"), *self.dir.glob("V-*.npy")]:
                        p.unlink()
                    atomic_write_json(meta_path, meta)
            else:
                atomic_write_json(meta_path, meta)
        except (OSError, ValueError) as err:
            raise InputError(f"cache_dir: cannot use the cache folder {self.root} ({err})",
                             option="cache_dir") from None

    def path(self, k: int) -> Path:
        return self.dir / f"block-{k:06d}.npz"

    def has(self, k: int) -> bool:
        return self.path(k).is_file()

    def done(self) -> list[int]:
        """Indices of the blocks already stored."""
        return [k for k in range(len(self.bounds)) if self.has(k)]

    def save(self, k: int, indptr: np.ndarray, indices: np.ndarray) -> None:
        """Store block k atomically (uncompressed npz)."""
        a, b = self.bounds[k]
        if len(indptr) != b - a + 1 or indptr[-1] != len(indices):
            raise ValueError(f"block {k}: indptr/indices do not describe rows [{a}, {b})")
        buf = io.BytesIO()
        np.savez(buf, indptr=np.asarray(indptr, np.int64), indices=np.asarray(indices, np.int32))
        atomic_write_bytes(self.path(k), buf.getvalue())

    def nnz(self, k: int) -> int | None:
        """Entries of stored block k (reads its indptr only), or None when missing or unreadable."""
        a, b = self.bounds[k]
        try:
            with np.load(self.path(k), allow_pickle=False) as z:
                indptr = z["indptr"]
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
            return None
        return int(indptr[-1]) if len(indptr) == b - a + 1 else None

    def load(self, k: int) -> tuple[np.ndarray, np.ndarray] | None:
        """(indptr, indices) of block k, or None when missing or unreadable (then recompute)."""
        a, b = self.bounds[k]
        try:
            with np.load(self.path(k), allow_pickle=False) as z:
                indptr, indices = z["indptr"], z["indices"]
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
            return None
        if len(indptr) != b - a + 1 or int(indptr[-1]) != len(indices) or \
                (len(indices) and (indices.min() < 0 or indices.max() >= self.n_cols)):
            return None
        return indptr.astype(np.int64, copy=False), indices.astype(np.int32, copy=False)

    ASSEMBLED = ("indptr", "indices", "data")

    def assembled_path(self, name: str) -> Path:
        """``V-<name>.npy`` of the assembled CSR (name in ASSEMBLED)."""
        return self.dir / f"V-{name}.npy"

    def load_assembled(self, n_rows: int) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(indptr (n_rows + 1,) int64, indices (nnz,) int32, data (nnz,) uint8) of the
        assembled V, memory-mapped read-only; None when missing or inconsistent."""
        try:
            indptr, indices, data = (np.load(self.assembled_path(n), mmap_mode="r", allow_pickle=False)
                                     for n in self.ASSEMBLED)
        except (OSError, ValueError, EOFError):
            return None
        ok = (indptr.dtype == np.int64 and indices.dtype == np.int32 and data.dtype == np.uint8
              and indptr.shape == (n_rows + 1,) and len(indices) == len(data)
              and int(indptr[0]) == 0 and int(indptr[-1]) == len(indices))
        return (indptr, indices, data) if ok else None

    def write_assembled(self, indptr: np.ndarray, nnz: int, block_indices) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Write the assembled V of ``nnz`` entries: the blocks' indices from ``block_indices``
        (an iterator of (offset, indices) in block order, which also fills ``indptr``
        (rows + 1,) int64, in memory: it is small), each file atomically; returns
        load_assembled()'s memory maps."""
        nnz = int(nnz)
        with atomic_npy_memmap(self.assembled_path("indices"), np.int32, (nnz,)) as out:
            for pos, bi in block_indices:
                out[pos:pos + len(bi)] = bi
        with atomic_npy_memmap(self.assembled_path("data"), np.uint8, (nnz,)) as out:
            step = 1 << 26
            for a in range(0, nnz, step):
                out[a:a + step] = 1
        if int(indptr[-1]) != nnz:
            raise ValueError(f"cache: the blocks hold {int(indptr[-1])} entries, expected {nnz}")
        with atomic_npy_memmap(self.assembled_path("indptr"), np.int64, indptr.shape) as out:
            out[:] = indptr
        got = self.load_assembled(len(indptr) - 1)
        if got is None:  # pragma: no cover - the files were just written
            raise OSError(f"cache: cannot read back the assembled V in {self.dir}")
        return got
