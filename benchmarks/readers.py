"""Own readers against the field's libraries: speed on ../shared/data, robustness on bad files.

    python benchmarks/readers.py [--repeat 7] [--cases 40]

Speed: best of ``repeat`` warm reads, to the same product (finite (N, 3) float64 points
for PCD; every leaf with its state and size for OctoMap). Robustness: the same mutated
files for both readers (truncated at, byte flipped at, junk inserted at a random offset,
the header's count set to 10^12; seed 0), counted as ``clean`` (the reader's documented
error, or a valid result), ``other`` (any other exception: a traceback for a user) and
``silent`` (a result although the body does not hold what the header says).
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def best_ms(f, repeat: int) -> float:
    f()
    ts = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t)
    return min(ts) * 1e3


def mutations(raw: bytes, n: int, count_key: bytes) -> list[tuple[str, bytes]]:
    """Bad copies of ``raw``: n of each kind at random offsets, and one huge header count."""
    rng = np.random.default_rng(0)
    out = []
    for k in range(n):
        i = int(rng.integers(0, len(raw)))
        out.append(("truncate", raw[:i]))
        out.append(("flip", raw[:i] + bytes([raw[i] ^ 0xFF]) + raw[i + 1:]))
        out.append(("insert", raw[:i] + bytes(rng.integers(0, 256, 8).astype(np.uint8)) + raw[i:]))
    out.append(("huge", re.sub(count_key + rb" \d+", count_key + b" 1000000000000", raw, count=1)))
    return out


def own_pcd(path: Path):
    from camplace.scene.loaders.pointcloud import load_point_cloud

    return load_point_cloud(path).points


def lib_pcd(path: Path):
    import pypcd4

    p = pypcd4.PointCloud.from_path(path).numpy(("x", "y", "z")).astype(np.float64)
    return p[np.all(np.isfinite(p), axis=1)]


def own_bt(path: Path):
    from camplace.scene.loaders.octomap import load_octomap

    om = load_octomap(path)
    return len(om.occupied_size), len(om.free_size)


def lib_bt(path: Path):
    import pyoctomap

    tree = pyoctomap.OcTree(0.1)
    if not tree.readBinary(str(path)):
        raise ValueError("pyoctomap: readBinary failed")
    occ = free = 0
    for leaf in tree.begin_leafs():
        leaf.getCoordinate(), leaf.getSize()
        if tree.isNodeOccupied(leaf):
            occ += 1
        else:
            free += 1
    return occ, free


def robustness(read, clean_errors: tuple, cases: list[tuple[str, bytes]], suffix: str, expect_n: int) -> dict:
    """Counts of clean / other / silent outcomes of ``read`` over the bad files."""
    counts = {"clean": 0, "other": 0, "silent": 0}
    with tempfile.TemporaryDirectory() as d:
        for i, (kind, raw) in enumerate(cases):
            p = Path(d) / f"{i}{suffix}"
            p.write_bytes(raw)
            try:
                got = read(p)
            except clean_errors:
                counts["clean"] += 1
                continue
            except BaseException:  # noqa: BLE001 - the point is to count these
                counts["other"] += 1
                continue
            n = len(got) if isinstance(got, np.ndarray) else sum(got)
            # a cut or a huge count that still reads is a silent accept when fewer points came back
            counts["silent" if kind in ("truncate", "huge") and n < expect_n else "clean"] += 1
    return counts


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--cases", type=int, default=40)
    a = ap.parse_args()
    from camplace.core.errors import InputError

    pcd, bt = DATA / "room_scan1.pcd", DATA / "geb079.bt"
    if not (pcd.is_file() and bt.is_file()):
        sys.exit(f"{DATA}: room_scan1.pcd / geb079.bt not found")
    rows = []
    pcd_cases = mutations(pcd.read_bytes(), a.cases, b"POINTS")
    bt_cases = mutations(bt.read_bytes(), a.cases, b"size")
    rows.append(("PCD room_scan1.pcd", "camplace", best_ms(lambda: own_pcd(pcd), a.repeat),
                 robustness(own_pcd, (InputError,), pcd_cases, ".pcd", 112_586)))
    rows.append(("PCD room_scan1.pcd", "pypcd4 1.5 + python-neo-lzf", best_ms(lambda: lib_pcd(pcd), a.repeat),
                 robustness(lib_pcd, (), pcd_cases, ".pcd", 112_586)))
    rows.append(("OctoMap geb079.bt", "camplace", best_ms(lambda: own_bt(bt), a.repeat),
                 robustness(own_bt, (InputError,), bt_cases, ".bt", 428_144)))
    rows.append(("OctoMap geb079.bt", "pyoctomap 1.2", best_ms(lambda: lib_bt(bt), a.repeat),
                 robustness(lib_bt, (ValueError,), bt_cases, ".bt", 428_144)))
    import lzf

    from camplace.scene.loaders.lzf import lzf_decompress

    raw = pcd.read_bytes()
    pos = raw.index(b"DATA binary_compressed\n") + 23
    csize, usize = (int(v) for v in np.frombuffer(raw[pos:pos + 8], "<u4"))
    block = raw[pos + 8:pos + 8 + csize]
    print(f"LZF block of room_scan1.pcd ({csize:,} -> {usize:,} bytes): liblzf "
          f"{best_ms(lambda: lzf.decompress(block, usize), 20):.2f} ms, camplace.lzf "
          f"{best_ms(lambda: lzf_decompress(block, usize), 20):.2f} ms")
    n = 3 * a.cases + 1
    print(f"\n| file | reader | read ms (best of {a.repeat}) | bad files ({n}): clean / other exception / silent |")
    print("|---|---|---:|---|")
    for f, who, ms, c in rows:
        print(f"| {f} | {who} | {ms:.1f} | {c['clean']} / {c['other']} / {c['silent']} |")


if __name__ == "__main__":
    main()
