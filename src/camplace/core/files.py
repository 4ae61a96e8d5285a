"""Atomic file writes: a file is written to a temporary name beside it, then renamed,
so a failed or interrupted run never leaves a half-written output.

Every file camplace writes goes through this module (tests/core/test_files.py checks the
sources for raw writes). ``AtomicBatch`` writes several files that belong together
(the contract files of one run): all are written to temporary names first and renamed
only when all of them are complete, so a failure leaves the previous set intact.
"""

from __future__ import annotations

import io
import json
import os
import tempfile
import weakref
from pathlib import Path

import numpy as np


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write data to a temporary file beside path (fsynced), then rename it over path."""
    path = Path(path)
    tmp = _write_temp(path, data)
    try:
        os.replace(tmp, path)
    except BaseException:
        _unlink(tmp)
        raise
    return path


def atomic_write_text(path: str | Path, text: str) -> Path:
    return atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_json(path: str | Path, obj: object) -> Path:
    return atomic_write_text(path, json.dumps(obj, indent=2, sort_keys=False) + "\n")


def atomic_savez(path: str | Path, **arrays: np.ndarray) -> Path:
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    return atomic_write_bytes(path, buf.getvalue())


def _write_temp(path: Path, data: bytes) -> str:
    """Write data to a new temporary file beside path (fsynced); returns its name."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
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

    def stage_savez(self, path: str | Path, **arrays: np.ndarray) -> Path:
        buf = io.BytesIO()
        np.savez_compressed(buf, **arrays)
        return self.stage_bytes(path, buf.getvalue())

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
