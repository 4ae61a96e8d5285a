"""Atomic file writes: a file is written to a temporary name beside it, then renamed,
so a failed or interrupted run never leaves a half-written output.

Every file camplace writes goes through this module (tests/core/test_files.py checks the
sources for raw writes). ``AtomicBatch`` writes several files that belong together
(the contract files of one run): all are written to temporary names first and renamed
only when all of them are complete, so a failure leaves the previous set intact.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import shutil
import stat
import weakref
from pathlib import Path
from typing import Iterator

import numpy as np


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write data to a temporary file beside path (fsynced), then rename it over path."""
    path = Path(path)
    return _commit(_write_temp(path, data), path)


def _commit(tmp: str, path: Path) -> Path:
    """Rename the finished temporary file over path (deleted when that fails)."""
    try:
        os.replace(tmp, path)
    except BaseException:
        _unlink(tmp)
        raise
    return path


def atomic_write_text(path: str | Path, text: str) -> Path:
    return atomic_write_bytes(path, text.encode("utf-8"))


WRITE_THREADS = 8  # files written at once by atomic_write_texts (their fsyncs overlap)


def atomic_write_texts(texts: dict[Path, str]) -> list[Path]:
    """atomic_write_text for each path -> text, on WRITE_THREADS threads (each file still
    written whole and fsynced before its rename; thousands of small files, e.g. one per
    camera at site scale, wait on their fsyncs together instead of one after another:
    issue 37). Returns the paths in the given order; the first error is raised."""
    from concurrent.futures import ThreadPoolExecutor

    if len(texts) < 2:
        return [atomic_write_text(p, t) for p, t in texts.items()]
    with ThreadPoolExecutor(min(WRITE_THREADS, len(texts)), thread_name_prefix="camplace-write") as pool:
        return list(pool.map(atomic_write_text, texts.keys(), texts.values()))


def atomic_write_json(path: str | Path, obj: object) -> Path:
    return atomic_write_text(path, json.dumps(obj, indent=2, sort_keys=False) + "\n")


def atomic_copy(src: str | Path, path: str | Path) -> Path:
    """Copy the file ``src`` to ``path`` atomically (a temporary copy beside path, renamed)."""
    path = Path(path)

    def copy(f) -> None:
        with open(src, "rb") as s:
            shutil.copyfileobj(s, f, 1 << 20)

    return _commit(_write_temp(path, copy), path)


def atomic_savez(path: str | Path, *, compressed: bool = True, level: int | None = None, **arrays: np.ndarray) -> Path:
    path = Path(path)
    return _commit(_savez_temp(path, arrays, compressed, level), path)


def savez_level(f, arrays: dict, level: int) -> None:
    """np.savez_compressed(f, **arrays) at zlib ``level`` (1 fastest … 9 smallest; numpy's
    own is zlib's default, 6): the same .npz members, read back by np.load as before."""
    import zipfile

    with zipfile.ZipFile(f, mode="w", compression=zipfile.ZIP_DEFLATED, compresslevel=level, allowZip64=True) as zf:
        for name, val in arrays.items():
            with zf.open(name + ".npy", "w", force_zip64=True) as fh:
                np.lib.format.write_array(fh, np.asanyarray(val), allow_pickle=False)


def _savez_temp(path: Path, arrays: dict, compressed: bool = True, level: int | None = None) -> str:
    """np.savez_compressed (np.savez when not ``compressed``: ten times faster, for a run
    that must finish quickly; ``level``: that zlib level, savez_level) streamed into a new
    temporary file beside path (fsynced; no copy of the arrays or of the compressed bytes in
    memory); returns its name."""
    if compressed and level is not None:
        return _write_temp(path, lambda f: savez_level(f, arrays, level))
    save = np.savez_compressed if compressed else np.savez
    return _write_temp(path, lambda f: save(f, **arrays))


@contextlib.contextmanager
def atomic_npy_memmap(path: str | Path, dtype, shape: tuple[int, ...]) -> Iterator[np.ndarray]:
    """A writable memory map of a new ``.npy`` file (``dtype``, ``shape``) on a temporary
    name beside ``path``; leaving the ``with`` block normally flushes, fsyncs and renames
    it over ``path``, an exception deletes it. For arrays too large to build in memory
    (out-of-core V, camplace.visibility.cache)."""
    path = Path(path)
    fd, tmp = _open_temp(path)
    os.close(fd)
    try:
        arr = np.lib.format.open_memmap(tmp, mode="w+", dtype=dtype, shape=tuple(int(n) for n in shape))
        yield arr
        arr.flush()
        del arr
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
    except BaseException:
        _unlink(tmp)
        raise
    _commit(tmp, path)


def _open_temp(path: Path) -> tuple[int, str]:
    """A new temporary file beside path, open for writing: (fd, name). Its mode is the one
    an ordinary write would give: path's own mode when path exists, else 0666 less the
    umask (the kernel applies it), never the private 0600 of tempfile.mkstemp."""
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        mode = stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        mode = None
    while True:
        tmp = str(path.parent / f".{path.name}.{secrets.token_hex(4)}.tmp")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
        except FileExistsError:
            continue
        break
    if mode is not None:
        try:
            os.fchmod(fd, mode)
        except OSError:  # not the file's owner: the umask's mode, as a plain write would keep
            pass
    return fd, tmp


def _write_temp(path: Path, data) -> str:
    """Write data (bytes, or a function writing into the open binary file) to a new
    temporary file beside path (fsynced); returns its name."""
    fd, tmp = _open_temp(path)
    try:
        with os.fdopen(fd, "wb") as f:
            if callable(data):
                data(f)
            else:
                f.write(data)
            f.flush()
            os.fsync(f.fileno())
    except BaseException:
        _unlink(tmp)
        raise
    return tmp


def _unlink(tmp: str) -> None:
    try:
        os.unlink(tmp)
    except FileNotFoundError:
        pass


class AtomicBatch:
    """Files written together: ``stage_*`` writes each to a temporary name; leaving the
    ``with`` block normally renames them all into place (in staging order), leaving it
    by an exception (or KeyboardInterrupt) deletes the temporaries and keeps every old
    file untouched.

    >>> with AtomicBatch() as b:
    ...     b.stage_json(out / "placement.json", obj)
    ...     b.stage_bytes(out / "visibility.npz", data)
    """

    def __init__(self) -> None:
        self._staged: list[tuple[str, Path]] = []
        # used without ``with``: temporaries of a batch never committed are removed when it is collected
        weakref.finalize(self, AtomicBatch._cleanup, self._staged)

    @staticmethod
    def _cleanup(staged: list[tuple[str, Path]]) -> None:
        for tmp, _ in staged:
            _unlink(tmp)

    def stage_bytes(self, path: str | Path, data: bytes) -> Path:
        path = Path(path)
        self._staged.append((_write_temp(path, data), path))
        return path

    def stage_text(self, path: str | Path, text: str) -> Path:
        return self.stage_bytes(path, text.encode("utf-8"))

    def stage_json(self, path: str | Path, obj: object) -> Path:
        return self.stage_text(path, json.dumps(obj, indent=2, sort_keys=False) + "\n")

    def stage_savez(self, path: str | Path, *, compressed: bool = True, level: int | None = None,
                    **arrays: np.ndarray) -> Path:
        path = Path(path)
        self._staged.append((_savez_temp(path, arrays, compressed, level), path))
        return path

    def commit(self) -> list[Path]:
        done = []
        for tmp, path in self._staged:
            os.replace(tmp, path)
            done.append(path)
        self._staged.clear()
        return done

    def abort(self) -> None:
        for tmp, _ in self._staged:
            _unlink(tmp)
        self._staged.clear()

    def __enter__(self) -> "AtomicBatch":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            try:
                self.commit()
            except BaseException:
                self.abort()
                raise
        else:
            self.abort()
