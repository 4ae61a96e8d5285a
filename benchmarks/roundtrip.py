"""Round trips of a box scene through real-space inputs (issue 5 acceptance).

box scene -> synthetic scan (PLY, range noise, occlusion) | mesh export (OBJ, solid) |
OctoMap export (.bt) -> loaded back as the scene's occlusion (boxes kept as labels) ->
placement -> the chosen poses raycast and scored on the ORIGINAL box scene. The
acceptance: |gap(round trip) - gap(box scene directly)| <= 0.02.

    python benchmarks/roundtrip.py                      # standard-store, budget 40
    python benchmarks/roundtrip.py --scene demo --budget 6 --step 0.5 --viewpoints 3
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from camplace.spec.builtin import resolve_scene
from camplace.scene.loaders.pointcloud import write_point_cloud
from camplace.workflows.run import run
from camplace.scene.build import build_scene
from camplace.workflows.scan import evaluate_selection, export_mesh, export_octomap, roundtrip_spec, scan_scene


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="standard-store")
    ap.add_argument("--budget", type=int, default=40)
    ap.add_argument("--solver", default="greedy")
    ap.add_argument("--step", type=float, default=0.4, help="scanner angular step (deg)")
    ap.add_argument("--viewpoints", type=int, default=None, help="default: enough to see 99 %% of the floor")
    ap.add_argument("--noise", type=float, default=0.01)
    ap.add_argument("--json", type=Path, default=None)
    a = ap.parse_args()

    spec, base, src = resolve_scene(a.scene)
    box = build_scene(spec, base, src)
    rows = []
    t = time.perf_counter()
    direct = run(a.scene, budget=a.budget, solver=a.solver)
    gap0 = direct.metrics.coverage_gap
    rows.append({"route": "box scene (direct)", "gap": gap0, "gap_on_box": gap0, "seconds": time.perf_counter() - t})
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        t = time.perf_counter()
        cloud = scan_scene(box, n_viewpoints=a.viewpoints, step_deg=a.step, noise=a.noise)
        ply = write_point_cloud(tmp / "scan.ply", cloud.points, cloud.viewpoints)
        t_scan = time.perf_counter() - t
        export_mesh(box, tmp / "scene.obj")
        export_octomap(box, tmp / "scene.bt")
        for kind, path, extra in (("point_cloud", ply, f"{len(cloud.points):,} pts, scan {t_scan:.1f} s"),
                                  ("mesh", tmp / "scene.obj", ""), ("octomap", tmp / "scene.bt", "")):
            t = time.perf_counter()
            rs = roundtrip_spec(spec, kind, path)
            r = run(rs, budget=a.budget, solver=a.solver)
            secs = time.perf_counter() - t
            m = evaluate_selection(box, r.visibility.candidates, r.placement.selected)
            rows.append({"route": kind, "gap": r.metrics.coverage_gap, "gap_on_box": m.coverage_gap,
                         "delta": m.coverage_gap - gap0, "seconds": secs, "targets": len(r.visibility.targets),
                         "note": extra, "file_bytes": Path(path).stat().st_size})
    print(f"scene {a.scene}, budget {a.budget}, solver {a.solver}, scan step {a.step} deg, "
          f"{a.viewpoints or 'auto'} viewpoints, noise {a.noise} m")
    print(f"{'route':<20} {'gap (own scene)':>15} {'gap on box scene':>17} {'delta':>8} {'run s':>7}  note")
    for r in rows:
        print(f"{r['route']:<20} {r['gap']:>15.4f} {r['gap_on_box']:>17.4f} {r.get('delta', 0.0):>+8.4f} "
              f"{r['seconds']:>7.1f}  {r.get('note', '')}")
    if a.json:
        a.json.write_text(json.dumps(rows, indent=2) + "\n")


if __name__ == "__main__":
    main()
