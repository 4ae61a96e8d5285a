"""Import time of plans on a generated 1,000 m² storey (docs/plans.md).

    python benchmarks/plans.py [--repeats 3] [--out DIR] [--formats ifc,dxf,png] [--run]

IFC: a 5 x 4 grid of 7.07 x 7.07 m rooms (20 IfcSpaces, 1,000 m² between wall centre
lines, 0.2 m walls with a door between every pair of neighbours, a window, slabs) written
with ifcopenshell.api (camplace.scene.importers.ifc_build), in millimetres. Prints the
best of ``repeats`` in-process times of import_plan (the scene mapping) and of
build_scene on it (the occupancy grid at 5 cm), and the wall time of one
``camplace scene import`` from the shell (Python start-up included). DXF and PNG: the
same storey drawn by tests/scene/plan_drawings.py (HATCH walls on A-WALL, door boxes on
A-DOOR, A-AREA rooms in mm; a 0.02 m/px image). With ``--run``: the wall time of
``camplace run PLAN --grid-only --no-plan --no-cache`` on each (with its stage seconds), and of
``camplace run --storey all`` on the same storey stacked twice (two storeys, one folder
each, storeys.json).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def best_of(repeats: int, fn) -> tuple[float, object]:
    """(best seconds, last result) of ``repeats`` calls of fn()."""
    best, out = float("inf"), None
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def ifc_storey(folder: Path) -> Path:
    """The generated 1,000 m² IFC storey (20 rooms)."""
    from camplace.scene.importers.ifc_build import GridBuilding, write_grid_building

    return write_grid_building(folder / "storey-1000.ifc", GridBuilding(nx=5, ny=4, room=(7.07, 7.07)), unit="mm")


def _cli(*args: str) -> float:
    """Wall seconds of one camplace command from the shell (Python start-up included)."""
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", "from camplace.cli import main; main()", *args], check=True,
                   capture_output=True)
    return time.perf_counter() - t


def plan_files(out: Path, formats: list[str]) -> dict[str, Path]:
    """The generated 1,000 m² storey in each of ``formats`` (ifc, dxf, png)."""
    from camplace.scene.importers.ifc_build import GridBuilding

    b = GridBuilding(nx=5, ny=4, room=(7.07, 7.07))
    files = {}
    if "ifc" in formats:
        files["ifc"] = ifc_storey(out)
    if "dxf" in formats or "png" in formats:
        sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
        from tests.scene.plan_drawings import draw_grid_dxf, draw_grid_png

        if "dxf" in formats:
            files["dxf"] = draw_grid_dxf(out / "storey-1000.dxf", b)
        if "png" in formats:
            files["png"] = draw_grid_png(out / "storey-1000.png", b)
    return files


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--formats", default="ifc", help="comma-separated: ifc, dxf, png")
    ap.add_argument("--run", action="store_true", help="also time camplace run on each (and --storey all)")
    args = ap.parse_args()
    from shapely.geometry import Polygon

    from camplace.scene.build import build_scene
    from camplace.scene.importers import import_plan
    from camplace.spec.loading import parse_scene

    out = args.out or Path(tempfile.mkdtemp(prefix="plans-"))
    out.mkdir(parents=True, exist_ok=True)
    t_write, files = best_of(1, lambda: plan_files(out, [f.strip() for f in args.formats.split(",")]))
    print(f"wrote {', '.join(p.name for p in files.values())} in {t_write:.2f} s")
    for kind, path in files.items():
        extra = ["--scale", "0.02"] if kind == "png" else []
        t_import, data = best_of(args.repeats, lambda: import_plan(path, **({"scale": 0.02} if kind == "png" else {})))
        t_build, scene = best_of(args.repeats, lambda: build_scene(parse_scene(data, str(path))))
        t_cli = _cli("scene", "import", str(path), *extra, "--out", str(out / f"site-{kind}.yaml"))
        area = Polygon(data["room"]["footprint"]).area
        print(f"{kind.upper()} {path.name}: {path.stat().st_size / 1e6:.2f} MB; footprint {area:.1f} m², "
              f"{len(data['zones'])} rooms, {len(data['obstacles'])} prisms")
        print(f"  import_plan {t_import:.2f} s, build_scene {t_build:.2f} s "
              f"({scene.occupancy.occupied.size / 1e6:.1f} M cells), camplace scene import {t_cli:.2f} s (wall)")
        if args.run:
            t_run = _cli("run", str(path), *extra, "--out", str(out / f"run-{kind}"), "--grid-only", "--no-plan",
                         "--no-cache")
            m = json.loads((out / f"run-{kind}" / "metrics.json").read_text())
            print(f"  camplace run {t_run:.1f} s (wall): coverage gap {m['coverage_gap']:.4f}, "
                  + ", ".join(f"{k} {v:.2f}" for k, v in m["timings_s"].items() if v >= 0.005))
    if args.run and "ifc" in files:
        from camplace.scene.importers.ifc_build import GridBuilding, write_grid_building

        two = write_grid_building(out / "two-storeys.ifc", GridBuilding(nx=5, ny=4, room=(7.07, 7.07)), unit="mm",
                                  floors=("Ground Floor", "First Floor"))
        t_all = _cli("run", str(two), "--storey", "all", "--out", str(out / "run-storeys"), "--grid-only", "--no-plan",
                     "--no-cache")
        rows = json.loads((out / "run-storeys" / "storeys.json").read_text())["storeys"]
        print(f"IFC {two.name} --storey all: {t_all:.1f} s (wall), "
              + ", ".join(f"{r['storey']} {r['cameras']} cameras gap {r['coverage_gap']:.4f}" for r in rows))


if __name__ == "__main__":
    main()
