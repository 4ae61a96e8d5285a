"""V of the built-in scenes by the voxel engine: warm wall and CPU time (min of R runs, no
cache), and a hash of V checked against the hashes the kernel before issue 37 produced.

Usage: python benchmarks/visibility_speed.py [SCENE ...] [--repeat R] [--cold] [--refine-like]

Each scene's V is computed once to load (or compile) the kernels, then R times; the
minimum is reported because the machine is shared (other jobs only ever add time).
``--cold`` also times the kernels' compile in a fresh process with an empty
NUMBA_CACHE_DIR (the first run after an install); ``--refine-like`` the CPU time per pose
of small calls as refine makes them. Exits 1 if a V differs from the
reference hash. Prints a markdown table for docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

# sha256 of V (shape, indptr, indices, data) as the kernel before issue 37 computed it
REFERENCE = {
    "demo": "f477ff55dab2b53c",
    "standard-store": "3f1a597764d4d987",
    "store-a": "17a69df426644dda",
    "catalogue-store": "c7024433bfc4e643",
    "lens-store": "bc5abf8d0c966060",
}


def v_hash(V) -> str:
    """sha256 (first 16 hex digits) of a CSR matrix's shape, indptr, indices and data."""
    h = hashlib.sha256(np.asarray(V.shape, np.int64).tobytes())
    for a in (V.indptr.astype(np.int64), V.indices.astype(np.int32), V.data.astype(np.uint8)):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def timed(scene: str, repeat: int) -> tuple[object, float, float]:
    """(V, min wall s, min CPU s) of the voxel engine's V for ``scene`` over ``repeat`` warm runs."""
    from conftest import builtin_inputs
    from camplace.visibility.voxel import compute_visibility

    sc, t, c = builtin_inputs(scene)
    v = compute_visibility(sc.occupancy, t, c)  # load / compile the kernels
    walls, cpus = [], []
    for _ in range(repeat):
        c0, w0 = time.process_time(), time.perf_counter()
        v = compute_visibility(sc.occupancy, t, c)
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    return v.V, min(walls), min(cpus)


COLD = """
import sys, time
sys.path.insert(0, {tests!r})
from conftest import builtin_inputs
from camplace.visibility.voxel import compute_visibility
sc, t, c = builtin_inputs("demo")
sub = c.subset(__import__("numpy").arange(len(c)) < 8)
t0, c0 = time.perf_counter(), time.process_time()
compute_visibility(sc.occupancy, t, sub)
print(time.perf_counter() - t0, time.process_time() - c0)
"""


def cold_compile() -> tuple[float, float]:
    """(wall s, CPU s) of the first V (8 demo candidates) in a fresh process with an empty numba cache."""
    with tempfile.TemporaryDirectory() as d:
        env = dict(os.environ, NUMBA_CACHE_DIR=d)
        code = COLD.format(tests=str(Path(__file__).resolve().parents[1] / "tests"))
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
        wall, cpu = out.stdout.split()[-2:]
        return float(wall), float(cpu)


def refine_like(scene: str = "standard-store", n: int = 800, per_call: int = 8, repeat: int = 5) -> float:
    """ms CPU per pose of V rows for ``n`` random poses of ``scene``, ``per_call`` poses a call
    (as refine raycasts its trial poses; here each at its own position), min of ``repeat``."""
    from conftest import builtin_inputs
    from camplace.visibility import voxel

    sc, t, c = builtin_inputs(scene)
    idx = np.random.default_rng(0).permutation(len(c))[:n]
    grid = voxel.target_grid(t, voxel.default_grid_cell(c))
    voxel._block_arrays(sc.occupancy, t, c, 0, per_call, grid)  # load the kernels
    best = float("inf")
    for _ in range(repeat):
        c0 = time.process_time()
        for k in range(0, n, per_call):
            sub = c.subset(idx[k:k + per_call])
            voxel._block_arrays(sc.occupancy, t, sub, 0, len(sub), grid)
        best = min(best, time.process_time() - c0)
    return best / n * 1000.0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenes", nargs="*", default=["demo", "standard-store", "store-a"])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--cold", action="store_true", help="also time the kernels' compile on an empty numba cache")
    ap.add_argument("--refine-like", action="store_true", help="also time 800 random standard-store poses, 8 a call")
    a = ap.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, python "
          f"{platform.python_version()}, load {os.getloadavg()[0]:.2f}")
    print("| scene | N_g | N_p | nnz(V) | wall s (min) | CPU s (min) | hash | same V |")
    print("|---|---|---|---|---|---|---|---|")
    bad = False
    for scene in a.scenes:
        V, wall, cpu = timed(scene, a.repeat)
        h = v_hash(V)
        ref = REFERENCE.get(scene)
        same = "no reference" if ref is None else ("yes" if h == ref else "**NO**")
        bad |= ref is not None and h != ref
        print(f"| {scene} | {V.shape[0]} | {V.shape[1]} | {V.nnz:,} | {wall:.3f} | {cpu:.3f} | {h} | {same} |")
    if a.cold:
        wall, cpu = cold_compile()
        print(f"cold compile (empty NUMBA_CACHE_DIR, first V of 8 demo candidates): wall {wall:.1f} s, CPU {cpu:.1f} s")
    if a.refine_like:
        print(f"refine-like raycasts (800 random standard-store poses, 8 a call): {refine_like():.3f} ms CPU per pose")
    print(f"load after: {os.getloadavg()[0]:.2f}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
