"""Checks run on a file's header before a library parses its body, so that a corrupt or
hostile header (a count of 10^12 points, an offset past the end) is refused with one
line naming the file instead of making the library allocate what the header promises.

The rule: the records a header promises, times their smallest possible size in bytes,
must fit in the bytes the file really holds after the header.
"""

from __future__ import annotations

import struct
from pathlib import Path

from camplace.core.errors import InputError
from camplace.scene.loaders import header_lines

PLY_SIZES = {"char": 1, "int8": 1, "uchar": 1, "uint8": 1, "short": 2, "int16": 2, "ushort": 2, "uint16": 2,
             "int": 4, "int32": 4, "uint": 4, "uint32": 4, "float": 4, "float32": 4, "double": 8, "float64": 8}
HEADER_LIMIT = 1 << 16  # bytes: a text header longer than this is not a header
LAZ_MAX_RATIO = 1000  # promised point bytes per compressed byte beyond which a LAZ count is absurd
LAZ_CHUNK = 50_000  # points per chunk that LASzip writes by default


def promise(path: Path, what: str, count: int, record: int, available: int) -> None:
    """InputError unless ``count`` records of at least ``record`` bytes fit in ``available`` bytes."""
    if count < 0:
        raise InputError(f"{path}: the header gives a negative count of {what} ({count})")
    if count * record > available:
        raise InputError(f"{path}: truncated, or a wrong header: it promises {count:,} {what} (at least "
                         f"{count * record:,} bytes) but only {available:,} bytes follow it")


def decode_text(path: Path, raw: bytes, what: str, encoding: str = "ascii") -> str:
    """``raw`` decoded, or InputError naming the first byte that is not ``encoding`` text."""
    try:
        return raw.decode(encoding)
    except UnicodeDecodeError as err:
        raise InputError(f"{path}: {what} is not {encoding.upper()} text (byte 0x{raw[err.start]:02x} "
                         f"at offset {err.start})") from None


def check_ply(path: Path) -> None:
    """Refuse a PLY file whose header is not text or promises more rows than the file holds."""
    size = path.stat().st_size
    with open(path, "rb") as f:
        head = f.read(HEADER_LIMIT)
    if not head.startswith(b"ply"):
        raise InputError(f"{path}: not a PLY file (it must start with 'ply')")
    end = head.find(b"end_header")
    nl = head.find(b"\n", end) if end >= 0 else -1
    if nl < 0:
        raise InputError(f"{path}: PLY header has no 'end_header' line")
    decode_text(path, head[:nl], "the PLY header")
    binary, elements = False, []  # (name, count, min bytes per row)
    for line, _ in header_lines(head[:nl + 1]):
        w = line.split()
        if not w:
            continue
        if w[0] == "format" and len(w) > 1:
            binary = w[1] != "ascii"
        elif w[0] == "element" and len(w) == 3 and w[2].lstrip("-").isdigit():
            elements.append([w[1], int(w[2]), 0])
        elif w[0] == "property" and elements and len(w) >= 3:
            ty = w[2] if w[1] == "list" else w[1]
            elements[-1][2] += PLY_SIZES.get(ty, 1) if binary else 2  # ascii: a digit and a separator
    for name, count, _ in elements:
        promise(path, f"'{name}' rows", count, 0, 0)  # refuses a negative count
    need = sum(count * row for _, count, row in elements)
    if need > size - nl - 1:
        name, count, _ = max(elements, key=lambda e: e[1] * e[2])
        promise(path, f"'{name}' rows", count, max(need // max(count, 1), 1), size - nl - 1)


def _u(raw: bytes, fmt: str, off: int) -> int:
    return struct.unpack_from("<" + fmt, raw, off)[0]


def _laszip_chunk_size(path: Path, h: bytes, offset: int) -> int:
    """The chunk size (points) in the 'laszip encoded' VLR of a LAZ file (0xFFFFFFFF: variable)."""
    header_size, n_vlr = _u(h, "H", 94), _u(h, "I", 100)
    promise(path, "VLRs", n_vlr, 54, offset - header_size)
    with open(path, "rb") as f:
        f.seek(header_size)
        vlrs = f.read(offset - header_size)
    pos = 0
    for _ in range(n_vlr):
        if pos + 54 > len(vlrs):
            break
        length = _u(vlrs, "H", pos + 20)
        if vlrs[pos + 2:pos + 16] == b"laszip encoded" and _u(vlrs, "H", pos + 18) == 22204 and length >= 16 \
                and pos + 54 + 16 <= len(vlrs):
            return _u(vlrs, "I", pos + 54 + 12)
        pos += 54 + length
    raise InputError(f"{path}: LAZ file without a readable 'laszip encoded' VLR")


def check_las(path: Path) -> None:
    """Refuse a LAS/LAZ file whose public header, point count or LAZ chunk table cannot
    fit the file (laspy / lazrs would allocate what they promise)."""
    size = path.stat().st_size
    with open(path, "rb") as f:
        h = f.read(375)
    if len(h) < 227 or not h.startswith(b"LASF"):
        raise InputError(f"{path}: not a LAS/LAZ file (no 'LASF' header of 227 bytes)")
    header_size, offset, fmt, reclen = _u(h, "H", 94), _u(h, "I", 96), h[104], _u(h, "H", 105)
    count = _u(h, "I", 107)
    if h[25] >= 4 and len(h) >= 255:
        count = max(count, _u(h, "Q", 247))
    if not 227 <= header_size <= offset <= size:
        raise InputError(f"{path}: LAS header size {header_size} / point offset {offset} do not fit "
                         f"the file's {size:,} bytes")
    body = size - offset
    if not fmt & 0xC0:  # uncompressed points
        promise(path, "points", count, max(reclen, 1), body)
        return
    promise(path, "points", count, max(reclen, 1), body * LAZ_MAX_RATIO)
    chunk = _laszip_chunk_size(path, h, offset)
    if chunk != 0xFFFFFFFF and chunk > max(count, LAZ_CHUNK):  # lazrs allocates a whole chunk of points
        raise InputError(f"{path}: LAZ chunk size {chunk:,} exceeds the {count:,} points of the file")
    with open(path, "rb") as f:
        f.seek(offset)
        table = _u(f.read(8).ljust(8, b"\0"), "q", 0)
        if offset + 8 <= table <= size - 8:
            f.seek(table)
            n_chunks = _u(f.read(8), "I", 4)
            promise(path, "LAZ chunks", n_chunks, 1, body)


GLTF_COMPONENT_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
GLTF_TYPE_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


def check_glb(path: Path) -> None:
    """Refuse a GLB whose chunks do not tile the file or whose accessors promise more
    bytes than its binary chunk holds."""
    import json

    raw = path.read_bytes()
    if len(raw) < 20 or raw[:4] != b"glTF":
        raise InputError(f"{path}: not a GLB file (no 'glTF' header)")
    if _u(raw, "I", 8) != len(raw):
        raise InputError(f"{path}: GLB header says {_u(raw, 'I', 8):,} bytes, the file has {len(raw):,}")
    chunks, pos = {}, 12
    while pos + 8 <= len(raw):
        n, kind = _u(raw, "I", pos), raw[pos + 4:pos + 8]
        if pos + 8 + n > len(raw):
            raise InputError(f"{path}: GLB chunk at byte {pos} runs past the end of the file")
        chunks.setdefault(kind, raw[pos + 8:pos + 8 + n])
        pos += 8 + n
    try:
        doc = json.loads(decode_text(path, chunks.get(b"JSON", b""), "the GLB JSON chunk", "utf-8"))
        accessors = [(int(a.get("count", 0)), GLTF_COMPONENT_BYTES.get(a.get("componentType"), 1)
                      * GLTF_TYPE_COMPONENTS.get(a.get("type"), 1)) for a in doc.get("accessors", [])]
    except (ValueError, TypeError, AttributeError):
        raise InputError(f"{path}: the GLB JSON chunk is not a glTF document") from None
    for count, item in accessors:
        promise(path, "accessor elements", count, item, len(chunks.get(b"BIN\0", b"")))
