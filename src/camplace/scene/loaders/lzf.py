"""LZF, the codec of PCD ``DATA binary_compressed``: decoding by liblzf (the C reference
implementation, through the ``lzf`` module of python-neo-lzf, the one pypcd4 uses), with
the size checks camplace needs around it; writing stays a literal-run stream.

Why the library and not the numba decoder this module had (measured before the switch,
best of 20): on the LZF block of ../shared/data/room_scan1.pcd (599,800 -> 1,351,032
bytes) liblzf decoded in 1.3 ms against 1.9 ms for the numba kernel, it needs no JIT
compile on a cold cache, and it rejects corrupt streams as the kernel did (ValueError on a
cut, flipped or junk block; the bad files of tests/scene/test_bad_files.py and the 121 of
``python benchmarks/readers.py`` all end in one-line InputErrors or valid clouds).
Why not pypcd4 for the whole PCD file: see camplace.scene.loaders.pointcloud.

LZF stream: a control byte ``c``; ``c < 32``: copy the next ``c + 1`` bytes literally;
otherwise a back reference of length ``(c >> 5) + 2`` (``7`` means one more length
byte follows) at distance ``((c & 31) << 8) + next byte + 1`` behind the output end.
A back reference of 3 bytes yields at most 264 bytes, so a stream decodes to at most
``LZF_MAX_RATIO`` times its size.
"""

from __future__ import annotations

import lzf
import numpy as np

LZF_MAX_RATIO = 88  # 264 output bytes from a 3-byte back reference


def lzf_decompress(data: bytes | np.ndarray, size: int) -> bytes:
    """Decompress an LZF block to exactly ``size`` bytes; ValueError if it is corrupt or
    could not produce ``size`` bytes (no more than LZF_MAX_RATIO x its length is allocated)."""
    src = bytes(data) if not isinstance(data, bytes) else data
    size = int(size)
    if size < 0 or size > LZF_MAX_RATIO * len(src) + 1:
        raise ValueError(f"corrupt LZF block ({len(src)} bytes cannot decode to {size})")
    if size == 0:
        if src:
            raise ValueError("corrupt LZF block (data for an empty output)")
        return b""
    try:
        out = lzf.decompress(src, size)
    except ValueError:
        out = None
    if out is None or len(out) != size:
        got = "more" if out is None else len(out)
        raise ValueError(f"corrupt LZF block (decoded {got} of {size} bytes)")
    return out


def lzf_compress_literal(data: bytes) -> bytes:
    """A valid (uncompressed) LZF stream: literal runs of at most 32 bytes. Enough for
    writing PCD ``binary_compressed`` files that any reader accepts."""
    out = bytearray()
    for s in range(0, len(data), 32):
        chunk = data[s:s + 32]
        out.append(len(chunk) - 1)
        out += chunk
    return bytes(out)
