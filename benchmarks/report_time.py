"""Time the report set (report.html, PNG figures, exports, camera views) of a run.

    python benchmarks/report_time.py [SCENE] [BUDGET] [REPEATS] [PART]

PART (optional): time only the parts whose name contains it (e.g. 'report=True').

Prints the wall and CPU seconds of each part (best of REPEATS, after one warm-up) and
the sizes of report.html and the PNGs. CPU seconds count this process's threads and its
finished child processes (plan.pdf is made in a forked child: camplace.outputs.background).
The machine's load average is printed too: on a shared machine wall time scales with it,
CPU time much less.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def main() -> None:
    scene = sys.argv[1] if len(sys.argv) > 1 else "standard-store"
    budget = int(sys.argv[2]) if len(sys.argv) > 2 else 40
    reps = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    only = sys.argv[4] if len(sys.argv) > 4 else ""
    from camplace.outputs.exports import write_exports
    from camplace.outputs.figures import SceneView, coverage_slices, write_figures
    from camplace.workflows.run import run
    from camplace.outputs.write import placement_dict, write_outputs
    from camplace.outputs.report_html import camera_views, render_report

    r = run(scene, budget=budget, solver="greedy")
    vis, t = r.visibility, r.visibility.targets
    sel = r.placement.selected
    pd = placement_dict(r.scene.name, r.placement, budget, vis.candidates)
    cov = np.bincount(vis.V[sel].indices, minlength=vis.V.shape[1])
    view = SceneView.from_scene(r.scene)
    hists = {n: x["coverage_histogram"] for n, x in r.metrics.regions.items()}
    out = Path(tempfile.mkdtemp(prefix="camplace-report-"))
    parts = {
        "exports (opencv + colmap)": lambda: write_exports(out, pd["cameras"]),
        "PNG figures": lambda: write_figures(out, view, t.positions, t.is_surface, cov, pd["cameras"], hists),
        "camera views (1 s budget)": lambda: camera_views(r.scene, vis, sel),
        "camera views, all (no budget)": lambda: camera_views(r.scene, vis, sel, budget_s=float("inf")),
        "report.html text": lambda: render_report(view, pd, r.metrics.to_dict(), t.positions, t.is_surface, cov,
                                                  t.gamma, t.region_ids, t.region_names, t.region_kinds,
                                                  vis.V.shape[0], [], coverage_slices(view, t.positions,
                                                                                       t.is_surface, cov)),
        "write_outputs, report=False": lambda: write_outputs(out, r.scene.name, vis, r.placement, budget, r.metrics,
                                                             r.timings_s, scene=r.scene, report=False),
        "write_outputs, report=True (all)": lambda: write_outputs(out, r.scene.name, vis, r.placement, budget,
                                                                  r.metrics, r.timings_s, scene=r.scene),
    }
    print(f"{scene}, {len(sel)} cameras, {len(t)} targets; load average {os.getloadavg()[0]:.1f} "
          f"on {os.cpu_count()} cores")
    print(f"  {'part':<36} {'wall':>7} {'CPU':>7} {'median':>7}   (best of {reps}, median wall; "
          f"CPU = all threads and child processes)")
    for name, fn in parts.items():
        if only not in name:
            continue
        fn()  # warm-up (imports, numba)
        runs = [_timed(fn) for _ in range(reps)]
        wall, cpu = min(w for w, _ in runs), min(c for _, c in runs)
        print(f"  {name:<36} {wall:6.2f}s {cpu:6.2f}s {float(np.median([w for w, _ in runs])):6.2f}s")
    views, skipped = camera_views(r.scene, vis, sel)
    print(f"  camera views rendered in budget: {len(views)} of {len(sel)}")
    print(f"  report.html {(out / 'report.html').stat().st_size / 1e6:.2f} MB, "
          f"PNGs {sum(p.stat().st_size for p in out.glob('*.png')) / 1e6:.2f} MB in {out}")


def _cpu() -> float:
    """CPU seconds of this process (all threads) and of its finished children (plan.pdf's forked child)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def _timed(fn) -> tuple[float, float]:
    t0, c0 = time.perf_counter(), _cpu()
    fn()
    return time.perf_counter() - t0, _cpu() - c0


if __name__ == "__main__":
    main()
