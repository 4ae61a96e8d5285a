"""Wall time of each pipeline stage on the built-in stores (issue 2 benchmark).

Usage: python benchmarks/stages.py [SCENE ...] [--budget N] [--repeat R]

Runs the pipeline R times per scene in one process; the first run includes numba's
compilation (or its on-disk cache load), the later ones are warm. Prints a markdown
table for docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

from camplace.workflows.run import run


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scenes", nargs="*", default=["standard-store", "store-a"])
    ap.add_argument("--budget", type=int, default=40)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, python {platform.python_version()}")
    print("| scene | run | N_g | N_p | nnz(V) | scene s | targets s | candidates s | visibility s | solve s | metrics s | total s | cost | gap |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for scene in a.scenes:
        for k in range(a.repeat):
            t0 = time.perf_counter()
            r = run(scene, budget=a.budget, solver="greedy")
            total = time.perf_counter() - t0
            t = r.timings_s
            V = r.visibility.V
            print(f"| {scene} | {'cold' if k == 0 else 'warm'} | {V.shape[0]} | {V.shape[1]} | {V.nnz:,} | "
                  f"{t['scene']:.3f} | {t['targets']:.3f} | {t['candidates']:.3f} | {t['visibility']:.3f} | "
                  f"{t['solve']:.3f} | {t['metrics']:.3f} | {total:.2f} | {r.metrics.cost:.0f} | {r.metrics.coverage_gap:.4f} |")


if __name__ == "__main__":
    main()
