"""The one memory guard: how much a run may plan to use, the error when a size won't fit, and
``release_pages`` (drop a memory-mapped array's resident pages from this process).

The limit is ``CAMPLACE_MAX_MEMORY_GB`` when set, else 80 % of physical RAM; a library
call that takes ``max_memory_bytes`` passes it as ``limit``. Every refusal is worded by
``memory_error`` and names the parameter ``max_memory_bytes`` (``InputError.option``).
"""

from __future__ import annotations

import math
import os

import numpy as np

from camplace.core.errors import InputError

GIB = 1024**3
MEMORY_ENV = "CAMPLACE_MAX_MEMORY_GB"
LIMIT_HINT = f"or raise the limit (max_memory_bytes) or set {MEMORY_ENV}"


def memory_limit_bytes() -> int:
    """The memory a run may plan to use (bytes): ``CAMPLACE_MAX_MEMORY_GB`` if set, else 80 % of RAM."""
    env = os.environ.get(MEMORY_ENV)
    if env:
        try:
            v = float(env)
        except ValueError:
            raise InputError(f"{MEMORY_ENV}: expected a number of GiB, got '{env}'") from None
        if not (v > 0 and math.isfinite(v)):
            raise InputError(f"{MEMORY_ENV}: expected a positive number of GiB, got '{env}'")
        return int(v * GIB)
    try:
        return int(0.8 * os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-POSIX
        return 8 * GIB


def format_bytes(b: float) -> str:
    """``25.5 GiB`` (from 0.1 GiB up) or ``12 MiB``."""
    return f"{b / GIB:.1f} GiB" if b >= 0.1 * GIB else f"{b / 1024**2:.0f} MiB"


def memory_error(subject: str, need: float, limit: float, fix: str, items: str = "") -> InputError:
    """The one wording of a refusal: ``subject would need [items (]N of memory, limit L[)]; fix, or raise
    the limit (max_memory_bytes) or set CAMPLACE_MAX_MEMORY_GB``.

    subject: what is too big (file and key path first); need, limit: bytes; items: the
    count behind the bytes, e.g. ``2.71e+10 occupancy cells``; fix: what to change."""
    amount = (f"{items} ({format_bytes(need)} of memory, limit {format_bytes(limit)})" if items
              else f"about {format_bytes(need)} of memory (limit {format_bytes(limit)})")
    return InputError(f"{subject} would need {amount}; {fix}, {LIMIT_HINT}", option="max_memory_bytes")


def check_memory(need: float, subject: str, fix: str, *, items: str = "", limit: float | None = None) -> int:
    """``need`` (bytes) as an int; ``memory_error`` when over ``limit`` (default: memory_limit_bytes())."""
    limit = memory_limit_bytes() if limit is None else limit
    if need > limit:
        raise memory_error(subject, need, limit, fix, items)
    return int(need)


def grid_bytes(shape: tuple[int, ...], bytes_per_cell: float) -> int:
    """Bytes of a dense grid of ``shape`` cells at ``bytes_per_cell`` (arrays + temporaries)."""
    return int(math.prod(int(s) for s in shape) * bytes_per_cell)


def check_grid_memory(shape: tuple[int, ...], bytes_per_cell: float, what: str, limit: int | None = None) -> int:
    """The bytes a grid of ``shape`` needs; ``memory_error`` when over ``limit``."""
    cells = math.prod(int(s) for s in shape)
    return check_memory(grid_bytes(shape, bytes_per_cell), f"{what}: a {'x'.join(str(int(s)) for s in shape)} grid",
                        "use a coarser occupancy_resolution or crop the scan",
                        items=f"{cells:.3g} cells of {bytes_per_cell:g} bytes", limit=limit)


def release_pages(*arrays: np.ndarray) -> int:
    """Drop the resident pages of the memory-mapped files under ``arrays`` (e.g. V's
    ``indices`` / ``data`` from the cache) from this process (madvise MADV_DONTNEED): they
    stay in the page cache and fault back in on the next read, so values never change;
    the process's resident size falls by what it had touched. Returns how many maps
    were released (arrays not backed by a map are skipped)."""
    import mmap

    done = 0
    for a in arrays:
        b = a
        while b is not None:
            m = getattr(b, "_mmap", None) if isinstance(b, np.memmap) else (b if isinstance(b, mmap.mmap) else None)
            if m is not None and hasattr(m, "madvise") and hasattr(mmap, "MADV_DONTNEED"):
                try:
                    m.madvise(mmap.MADV_DONTNEED)
                    done += 1
                except (OSError, ValueError):  # closed map, or a platform without it: nothing to release
                    pass
                break
            b = getattr(b, "base", None)
    return done
