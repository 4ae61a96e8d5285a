"""Import time of plans on a generated 1,000 m² storey (docs/plans.md).

    python benchmarks/plans.py [--repeats 3] [--out DIR]

IFC: a 5 x 4 grid of 7.07 x 7.07 m rooms (20 IfcSpaces, 1,000 m² between wall centre
lines, 0.2 m walls with a door between every pair of neighbours, a window, slabs) written
with ifcopenshell.api (camplace.scene.importers.ifc_build), in millimetres. Prints the
best of ``repeats`` in-process times of import_plan (the scene mapping) and of
build_scene on it (the occupancy grid at 5 cm), and the wall time of one
``camplace scene import`` from the shell (Python start-up included).
"""

from __future__ import annotations

import argparse
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    from shapely.geometry import Polygon

    from camplace.scene.build import build_scene
    from camplace.scene.importers import import_plan
    from camplace.spec.loading import parse_scene

    out = args.out or Path(tempfile.mkdtemp(prefix="plans-"))
    out.mkdir(parents=True, exist_ok=True)
    t_write, path = best_of(1, lambda: ifc_storey(out))
    t_import, data = best_of(args.repeats, lambda: import_plan(path))
    t_build, scene = best_of(args.repeats, lambda: build_scene(parse_scene(data, str(path))))
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", "from camplace.cli import main; main()", "scene", "import", str(path), "--out", str(out / "site.yaml")],
                   check=True, capture_output=True)
    t_cli = time.perf_counter() - t
    area = Polygon(data["room"]["footprint"]).area
    print(f"IFC {path.name}: {path.stat().st_size / 1e6:.2f} MB written in {t_write:.2f} s; footprint {area:.0f} m², "
          f"{len(data['zones'])} rooms, {len(data['obstacles'])} prisms")
    print(f"  import_plan {t_import:.2f} s, build_scene {t_build:.2f} s "
          f"({scene.occupancy.occupied.size / 1e6:.1f} M cells), camplace scene import {t_cli:.2f} s (wall)")


if __name__ == "__main__":
    main()
