"""LZF decompression (the codec of PCD ``DATA binary_compressed``), in numba.

LZF stream: a control byte ``c``; ``c < 32``: copy the next ``c + 1`` bytes literally;
otherwise a back reference of length ``(c >> 5) + 2`` (``7`` means one more length
byte follows) at distance ``((c & 31) << 8) + next byte + 1`` behind the output end.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def _lzf_kernel(src: np.ndarray, out: np.ndarray) -> int:
    """Decode ``src`` (uint8) into ``out`` (uint8); return bytes written, or -1 if corrupt."""
    n_in = src.shape[0]
    n_out = out.shape[0]
    ip = 0
    op = 0
    while ip < n_in:
        ctrl = int(src[ip])
        ip += 1
        if ctrl < 32:
            n = ctrl + 1
            if ip + n > n_in or op + n > n_out:
                return -1
            for k in range(n):
                out[op + k] = src[ip + k]
            ip += n
            op += n
        else:
            length = ctrl >> 5
            if length == 7:
                if ip >= n_in:
                    return -1
                length += int(src[ip])
                ip += 1
            if ip >= n_in:
                return -1
            ref = op - ((ctrl & 0x1F) << 8) - int(src[ip]) - 1
            ip += 1
            length += 2
            if ref < 0 or op + length > n_out:
                return -1
            for _ in range(length):  # may overlap: copy byte by byte
                out[op] = out[ref]
                op += 1
                ref += 1
    return op


def lzf_decompress(data: bytes | np.ndarray, size: int) -> bytes:
    """Decompress an LZF block to exactly ``size`` bytes; ValueError if it is corrupt."""
    src = np.frombuffer(data, dtype=np.uint8) if isinstance(data, (bytes, bytearray, memoryview)) else data
    out = np.empty(int(size), dtype=np.uint8)
    n = _lzf_kernel(src, out)
    if n != size:
        raise ValueError(f"corrupt LZF block (decoded {n} of {size} bytes)")
    return out.tobytes()


def lzf_compress_literal(data: bytes) -> bytes:
    """A valid (uncompressed) LZF stream: literal runs of at most 32 bytes. Enough for
    writing PCD ``binary_compressed`` files that any reader accepts."""
    out = bytearray()
    for s in range(0, len(data), 32):
        chunk = data[s:s + 32]
        out.append(len(chunk) - 1)
        out += chunk
    return bytes(out)
