"""Point-cloud files: read and write PLY (ascii / binary), PCD (ascii / binary /
binary_compressed), XYZ / CSV / TXT, LAS / LAZ.

``load_point_cloud(path)`` -> :class:`PointCloud` with ``points`` (N, 3) float64 metres
(non-finite points dropped) and the scanner ``viewpoints`` (K, 3) the file records (PCD
``VIEWPOINT``; none for the other formats). Large LAS/LAZ and binary PLY files are read
in chunks (progress per chunk); with ``downsample`` each chunk is reduced to one point
per voxel as it is read, so memory follows the output, not the file.

Bad files: every header is checked against the file's real size before a body is read
(camplace.scene.loaders.guards), so a header promising 10^12 points is refused in one
line instead of allocated; non-finite points are dropped and counted
(``info["non_finite_dropped"]``, shown in the obstacle's log line); none left is an error.

PCD is read by camplace's own header parser and checks, with the LZF body decoded by
liblzf (camplace.scene.loaders.lzf), not by pypcd4. Measured by
``python benchmarks/readers.py --repeat 20`` (docs/benchmarks.md): on
../shared/data/room_scan1.pcd both give the same points in the same time (5.4 ms here,
5.8 ms pypcd4 + python-neo-lzf, to finite float64 (N, 3)), but on 121 bad copies of that
file (cut, flipped, junk inserted, POINTS 10^12) pypcd4 raised 83 raw exceptions
(pydantic ValidationError, ValueError, RuntimeError, UnicodeDecodeError, ...) that a
user would see as tracebacks, and it allocates what the header promises
(``np.zeros(POINTS)``); this reader gives 121 one-line InputErrors or valid clouds.
Wrapping pypcd4 would need this header check anyway, and it also drops camplace's
``# viewpoint`` lines (several scanner origins per file).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from camplace.core.errors import InputError
from camplace.core.files import atomic_write_bytes
from camplace.scene.loaders import Progress, header_lines
from camplace.scene.loaders.guards import check_las, check_ply, decode_text, promise
from camplace.scene.loaders.lzf import LZF_MAX_RATIO, lzf_compress_literal, lzf_decompress

CHUNK_POINTS = 2_000_000


@dataclass(frozen=True)
class PointCloud:
    """points: (N, 3) float64 m; viewpoints: (K, 3) float64 m scanner origins (K may be 0)."""

    points: np.ndarray
    viewpoints: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    info: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.points)


def voxel_keys(points: np.ndarray, size: float) -> np.ndarray:
    """(N, 3) m -> (N,) int64 key of the voxel of edge ``size`` holding each point."""
    c = np.floor(points / size).astype(np.int64) + (1 << 20)
    return (c[:, 0] << 42) | (c[:, 1] << 21) | c[:, 2]


def voxel_downsample(points: np.ndarray, size: float) -> np.ndarray:
    """One point per occupied voxel of edge ``size`` (m): the centroid of its points. (M, 3)."""
    if len(points) == 0:
        return points.reshape(0, 3)
    _, inv, counts = np.unique(voxel_keys(points, size), return_inverse=True, return_counts=True)
    out = np.zeros((len(counts), 3))
    for a in range(3):
        out[:, a] = np.bincount(inv.ravel(), weights=points[:, a], minlength=len(counts))
    return out / counts[:, None]


def _finite(points: np.ndarray) -> np.ndarray:
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    ok = np.isfinite(p).all(axis=1)
    return p if ok.all() else p[ok]


class _Reader:
    """Collects chunks, optionally voxel-downsampled as they arrive."""

    def __init__(self, downsample: float | None) -> None:
        self.downsample = downsample
        self.chunks: list[np.ndarray] = []
        self.n_read = 0
        self.n_finite = 0

    def add(self, xyz: np.ndarray) -> None:
        self.n_read += len(xyz)
        p = _finite(xyz)
        self.n_finite += len(p)
        if self.downsample:
            p = voxel_downsample(p, self.downsample)
        self.chunks.append(p)

    def points(self) -> np.ndarray:
        p = np.concatenate(self.chunks) if self.chunks else np.zeros((0, 3))
        if self.downsample and len(self.chunks) > 1:
            p = voxel_downsample(p, self.downsample)
        return p


# ---------------------------------------------------------------- PLY


def _read_ply(path: Path, r: _Reader, progress: Progress | None) -> dict:
    from plyfile import PlyData, PlyParseError

    check_ply(path)
    try:
        ply = PlyData.read(str(path), mmap="r")
    except (PlyParseError, ValueError, EOFError, IndexError, KeyError, UnicodeDecodeError) as err:
        raise InputError(f"{path}: not a readable PLY file ({str(err).splitlines()[0] if str(err) else type(err).__name__})") from None
    if "vertex" not in ply:
        raise InputError(f"{path}: PLY file has no 'vertex' element")
    v = ply["vertex"]
    names = v.data.dtype.names or ()
    if not all(k in names for k in "xyz"):
        raise InputError(f"{path}: PLY vertex element has no x, y, z properties (has {', '.join(names)})")
    n = len(v.data)
    for s in range(0, n, CHUNK_POINTS):
        d = v.data[s:s + CHUNK_POINTS]
        r.add(np.c_[d["x"], d["y"], d["z"]])
        if progress:
            progress("load scan", min(s + CHUNK_POINTS, n), n)
    vps = [[float(v) for v in c.split()[1:4]] for c in ply.comments
           if c.startswith("viewpoint ") and len(c.split()) >= 4]
    return {"format": "ply", "ply_format": "ascii" if ply.text else "binary", "has_faces": "face" in ply,
            "_viewpoints": vps}


def write_ply(path: str | Path, points: np.ndarray, binary: bool = True, viewpoints=None) -> Path:
    """Write points (N, 3) as a PLY file (float32 x y z), atomically. Scanner viewpoints
    (K, 3) go into ``comment viewpoint x y z`` lines, which load_point_cloud reads back."""
    p = np.asarray(points, np.float32).reshape(-1, 3)
    vps = [f"comment viewpoint {a:.6g} {b:.6g} {c:.6g}" for a, b, c in np.asarray(
        viewpoints if viewpoints is not None else np.zeros((0, 3)), float).reshape(-1, 3)]
    head = ["ply", "format " + ("binary_little_endian 1.0" if binary else "ascii 1.0"),
            "comment written by camplace", *vps, f"element vertex {len(p)}",
            "property float x", "property float y", "property float z", "end_header"]
    body = p.astype("<f4").tobytes() if binary else "".join(f"{a:.6g} {b:.6g} {c:.6g}\n" for a, b, c in p).encode()
    return atomic_write_bytes(Path(path), ("\n".join(head) + "\n").encode() + body)


# ---------------------------------------------------------------- PCD

_PCD_TYPES = {("F", 4): "<f4", ("F", 8): "<f8", ("U", 1): "u1", ("U", 2): "<u2", ("U", 4): "<u4",
              ("U", 8): "<u8", ("I", 1): "i1", ("I", 2): "<i2", ("I", 4): "<i4", ("I", 8): "<i8"}


def _pcd_header(path: Path, raw: bytes) -> tuple[dict, int]:
    head: dict[str, list[str]] = {"_VIEWPOINTS": []}
    for line, pos in header_lines(raw):
        if line.startswith("# viewpoint ") and len(line.split()) >= 5:  # camplace: one line per scanner
            head["_VIEWPOINTS"].append(line.split()[2:5])
            continue
        if not line or line.startswith("#"):
            continue
        key, *vals = line.split()
        head[key.upper()] = vals
        if key.upper() == "DATA":
            return head, pos
        if len(head) > 64:
            raise InputError(f"{path}: not a PCD file (no DATA line in the header)")
    raise InputError(f"{path}: PCD header has no DATA line")


def _pcd_viewpoints(path: Path, head: dict) -> np.ndarray:
    """(K, 3) scanner origins of a PCD header: camplace's ``# viewpoint`` lines, else VIEWPOINT."""
    rows = head["_VIEWPOINTS"] or ([head["VIEWPOINT"][:3]] if len(head.get("VIEWPOINT", [])) >= 3 else [])
    try:
        vp = np.array([[float(v) for v in row] for row in rows]).reshape(-1, 3)
    except ValueError:
        raise InputError(f"{path}: PCD VIEWPOINT holds something other than numbers") from None
    if not np.all(np.isfinite(vp)):
        raise InputError(f"{path}: PCD VIEWPOINT is not finite")
    return vp


def _read_pcd(path: Path, r: _Reader, progress: Progress | None) -> tuple[dict, np.ndarray]:
    raw = path.read_bytes()
    if not raw.strip():
        raise InputError(f"{path}: the file is empty")
    head, pos = _pcd_header(path, raw)
    decode_text(path, raw[:pos], "the PCD header", "utf-8")
    try:
        fields = head["FIELDS"]
        sizes = [int(s) for s in head["SIZE"]]
        types = head["TYPE"]
        counts = [int(c) for c in head.get("COUNT", ["1"] * len(fields))]
        n = int(head["POINTS"][0]) if "POINTS" in head else int(head["WIDTH"][0]) * int(head["HEIGHT"][0])
        mode = head["DATA"][0].lower()
    except (KeyError, IndexError, ValueError):
        raise InputError(f"{path}: PCD header lacks FIELDS/SIZE/TYPE/POINTS or has bad values") from None
    if not (len(fields) == len(sizes) == len(types) == len(counts)) or min(counts, default=0) < 1:
        raise InputError(f"{path}: PCD header FIELDS/SIZE/TYPE/COUNT have different lengths or a COUNT < 1")
    if not all(k in fields for k in "xyz"):
        raise InputError(f"{path}: PCD file has no x, y, z fields (has {', '.join(fields)})")
    try:
        dts = [np.dtype(_PCD_TYPES[(t.upper(), s)]) for t, s in zip(types, sizes)]
    except KeyError:
        raise InputError(f"{path}: PCD TYPE/SIZE {list(zip(types, sizes))} not supported") from None
    vp = _pcd_viewpoints(path, head)
    if n == 0:
        raise InputError(f"{path}: the PCD file holds no points (POINTS 0)")
    cols: dict[str, np.ndarray] = {}
    body = raw[pos:]
    record = sum(d.itemsize * c for d, c in zip(dts, counts))
    # ascii: at least a digit and a separator per value; compressed: LZF expands at most LZF_MAX_RATIO x
    promise(path, "points", n, 2 * sum(counts) if mode == "ascii" else record,
            len(body) * (LZF_MAX_RATIO if mode == "binary_compressed" else 1))
    if mode == "ascii":
        try:
            table = np.loadtxt(body.decode("ascii", "replace").splitlines(), dtype=np.float64, ndmin=2)
        except ValueError as err:
            raise InputError(f"{path}: PCD ascii data unreadable ({str(err).splitlines()[0]})") from None
        if table.shape[0] < n or table.shape[1] < sum(counts):
            raise InputError(f"{path}: PCD ascii data has {table.shape[0]} rows x {table.shape[1]} columns, "
                             f"header says {n} x {sum(counts)}")
        c0 = 0
        for f, c in zip(fields, counts):
            cols[f] = table[:n, c0]
            c0 += c
    elif mode == "binary":
        dt = np.dtype([(f"f{i}", d, (c,)) for i, (d, c) in enumerate(zip(dts, counts))])
        if len(body) < n * dt.itemsize:
            raise InputError(f"{path}: PCD binary data is truncated ({len(body)} bytes, need {n * dt.itemsize})")
        rec = np.frombuffer(body, dtype=dt, count=n)
        for i, f in enumerate(fields):
            cols[f] = rec[f"f{i}"][:, 0]
    elif mode == "binary_compressed":
        if len(body) < 8:
            raise InputError(f"{path}: PCD binary_compressed block is truncated")
        csize, usize = (int(v) for v in np.frombuffer(body[:8], dtype="<u4"))
        need = sum(n * s * c for s, c in zip(sizes, counts))
        if usize != need or csize > len(body) - 8 or usize > LZF_MAX_RATIO * csize:
            raise InputError(f"{path}: PCD binary_compressed sizes do not match the header "
                             f"(compressed {csize} of {len(body) - 8} bytes, uncompressed {usize}, expected {need})")
        try:
            data = lzf_decompress(np.frombuffer(body, dtype=np.uint8, count=csize, offset=8), usize)
        except ValueError as err:
            raise InputError(f"{path}: {err}") from None
        off = 0
        for f, d, c in zip(fields, dts, counts):  # field after field (structure of arrays)
            arr = np.frombuffer(data, dtype=d, count=n * c, offset=off).reshape(n, c)
            cols[f] = arr[:, 0]
            off += n * c * d.itemsize
    else:
        raise InputError(f"{path}: PCD DATA '{mode}' not supported (ascii, binary, binary_compressed)")
    r.add(np.c_[cols["x"], cols["y"], cols["z"]])
    if progress:
        progress("load scan", n, n)
    return {"format": "pcd", "pcd_data": mode}, vp


def write_pcd(path: str | Path, points: np.ndarray, data: str = "binary", viewpoints=None) -> Path:
    """Write points (N, 3) as PCD v0.7 (float32 x y z); data: ascii, binary or binary_compressed.
    The first viewpoint goes into VIEWPOINT, every one into a ``# viewpoint x y z`` comment."""
    p = np.asarray(points, np.float32).reshape(-1, 3)
    vps = np.asarray(viewpoints if viewpoints is not None else np.zeros((0, 3)), float).reshape(-1, 3)
    viewpoint = vps[0] if len(vps) else np.zeros(3)
    extra = "".join(f"# viewpoint {a:.6g} {b:.6g} {c:.6g}\n" for a, b, c in vps) if len(vps) > 1 else ""
    head = ("# .PCD v0.7 - Point Cloud Data file format\n" + extra + "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
            f"TYPE F F F\nCOUNT 1 1 1\nWIDTH {len(p)}\nHEIGHT 1\n"
            f"VIEWPOINT {viewpoint[0]:g} {viewpoint[1]:g} {viewpoint[2]:g} 1 0 0 0\nPOINTS {len(p)}\nDATA {data}\n")
    if data == "ascii":
        body = "".join(f"{a:.6g} {b:.6g} {c:.6g}\n" for a, b, c in p).encode()
    elif data == "binary":
        body = p.astype("<f4").tobytes()
    elif data == "binary_compressed":
        raw = np.ascontiguousarray(p.T).astype("<f4").tobytes()
        comp = lzf_compress_literal(raw)
        body = np.array([len(comp), len(raw)], "<u4").tobytes() + comp
    else:
        raise ValueError(f"unknown PCD data kind {data!r}")
    return atomic_write_bytes(Path(path), head.encode() + body)


# ---------------------------------------------------------------- XYZ / CSV


def _numbers(line: str, delim: str | None) -> bool:
    """Whether the first three fields of a text row are numbers (nan and inf count)."""
    try:
        return len([float(v) for v in line.split(delim)[:3]]) == 3
    except ValueError:
        return False


def _read_text(path: Path, r: _Reader, progress: Progress | None) -> dict:
    text = decode_text(path, path.read_bytes(), "the file", "utf-8")
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith(("#", "//"))]
    if not lines:
        raise InputError(f"{path}: the file is empty (no point rows)")
    delim = "," if "," in lines[-1] else (";" if ";" in lines[-1] else None)
    skip = 0 if _numbers(lines[0], delim) else 1  # a header row such as "x,y,z"
    try:
        table = np.loadtxt(lines[skip:], delimiter=delim, usecols=(0, 1, 2), ndmin=2, dtype=np.float64)
    except (ValueError, IndexError) as err:
        raise InputError(f"{path}: expected rows of at least 3 numbers x y z "
                         f"({str(err).splitlines()[0] if str(err) else 'unreadable'})") from None
    r.add(table)
    if progress:
        progress("load scan", len(table), len(table))
    return {"format": "xyz"}


def write_xyz(path: str | Path, points: np.ndarray, delimiter: str = " ") -> Path:
    """Write points (N, 3) as text rows ``x y z`` (or CSV with delimiter ',')."""
    p = np.asarray(points, float).reshape(-1, 3)
    head = "x,y,z\n" if delimiter == "," else ""
    body = "".join(f"{a:.6g}{delimiter}{b:.6g}{delimiter}{c:.6g}\n" for a, b, c in p)
    return atomic_write_bytes(Path(path), (head + body).encode())


# ---------------------------------------------------------------- LAS / LAZ


def _read_las(path: Path, r: _Reader, progress: Progress | None) -> dict:
    import laspy

    check_las(path)
    try:
        with laspy.open(str(path)) as f:
            n = int(f.header.point_count)
            done = 0
            for chunk in f.chunk_iterator(CHUNK_POINTS):
                r.add(np.c_[np.asarray(chunk.x), np.asarray(chunk.y), np.asarray(chunk.z)])
                done += len(chunk)
                if progress:
                    progress("load scan", done, max(n, 1))
    except BaseException as err:  # lazrs raises RuntimeError, and a Rust panic (a BaseException) on odd data
        known = (laspy.errors.LaspyException, ValueError, RuntimeError, OSError, EOFError)
        if not isinstance(err, known) and type(err).__name__ != "PanicException":
            raise
        msg = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise InputError(f"{path}: not a readable LAS/LAZ file ({msg})") from None
    return {"format": "laz" if path.suffix.lower() == ".laz" else "las"}


def write_las(path: str | Path, points: np.ndarray, scale: float = 0.001) -> Path:
    """Write points (N, 3) as LAS 1.2 point format 0 (LAZ if the suffix is .laz)."""
    import io

    import laspy

    p = np.asarray(points, float).reshape(-1, 3)
    header = laspy.LasHeader(point_format=0, version="1.2")
    header.scales = np.array([scale] * 3)
    header.offsets = p.min(0) if len(p) else np.zeros(3)
    las = laspy.LasData(header)
    las.x, las.y, las.z = p[:, 0], p[:, 1], p[:, 2]
    buf = io.BytesIO()
    las.write(buf, do_compress=Path(path).suffix.lower() == ".laz")
    return atomic_write_bytes(Path(path), buf.getvalue())


# ---------------------------------------------------------------- entry points


def load_point_cloud(path: str | Path, downsample: float | None = None,
                     progress: Progress | None = None) -> PointCloud:
    """Read a point-cloud file by its suffix (.ply .pcd .xyz .csv .txt .pts .las .laz).

    downsample: voxel edge (m) applied while reading (None = keep every point)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: point cloud file not found")
    if p.stat().st_size == 0:
        raise InputError(f"{p}: the file is empty")
    suf = p.suffix.lower()
    r = _Reader(downsample)
    vp = np.zeros((0, 3))
    if suf == ".ply":
        info = _read_ply(p, r, progress)
        vp = np.array(info.pop("_viewpoints"), float).reshape(-1, 3)
    elif suf == ".pcd":
        info, vp = _read_pcd(p, r, progress)
    elif suf in (".xyz", ".csv", ".txt", ".pts"):
        info = _read_text(p, r, progress)
    elif suf in (".las", ".laz"):
        info = _read_las(p, r, progress)
    else:
        raise InputError(f"{p}: unknown point cloud format '{suf}'; expected .ply, .pcd, .xyz, .csv, .txt, .las or .laz")
    pts = r.points()
    if len(pts) == 0:
        raise InputError(f"{p}: the file holds no finite points ({r.n_read} read)")
    info.update({"path": str(p), "points_read": r.n_read, "non_finite_dropped": r.n_read - r.n_finite,
                 "points": len(pts)})
    if downsample:
        info["downsample_while_reading_m"] = downsample
    return PointCloud(pts, vp, info)


def write_point_cloud(path: str | Path, points: np.ndarray, viewpoints=None) -> Path:
    """Write points (N, 3) in the format named by the suffix (.ply .pcd .xyz .csv .las .laz);
    PLY and PCD also record the scanner viewpoints (K, 3)."""
    suf = Path(path).suffix.lower()
    if suf == ".ply":
        return write_ply(path, points, viewpoints=viewpoints)
    if suf == ".pcd":
        return write_pcd(path, points, "binary", viewpoints)
    if suf in (".xyz", ".txt", ".pts"):
        return write_xyz(path, points)
    if suf == ".csv":
        return write_xyz(path, points, ",")
    if suf in (".las", ".laz"):
        return write_las(path, points)
    raise InputError(f"{path}: cannot write point clouds as '{suf}'; expected .ply, .pcd, .xyz, .csv, .las or .laz")
