"""Import time of the real IFC files in ../shared/data/plans (issue 25; docs/plans.md, Real plans).

    python benchmarks/ifc_real.py [--repeats 3] [--plans DIR] [--cli]

For every storey of each file (and the default one): the best of ``repeats`` in-process
wall and CPU seconds of read_plan (open the file, read its relations, tessellate, cut
prisms, zones, the scene-schema check; imports warmed by a first call), its footprint (m²), rooms and
prisms, as a Markdown table. With ``--cli``: the wall seconds of one
``camplace scene import FILE`` on the default storey (Python start-up included). Prints
the load average before and after: on a shared machine the times are only as good as it.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

FILES = ("Duplex_A_20110907.ifc", "bim-whale_LargeBuilding.ifc", "Pabellon_de_Barcelona.ifc")


def best_of(repeats: int, fn) -> tuple[float, float, object]:
    """(best wall seconds, best CPU seconds of this process, last result) of ``repeats`` calls
    of fn(). The import runs on one thread: on an idle machine its wall time is its CPU time."""
    best, cpu, out = float("inf"), float("inf"), None
    for _ in range(repeats):
        t, c = time.perf_counter(), time.process_time()
        out = fn()
        best, cpu = min(best, time.perf_counter() - t), min(cpu, time.process_time() - c)
    return best, cpu, out


def storeys_of(path: Path) -> list[str | None]:
    """None (the default storey), then every storey of the file by name."""
    from camplace.scene.importers import read_plan

    return [None] + [s["name"] for s in read_plan(path).storeys]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--plans", type=Path, default=Path(__file__).resolve().parents[1].parent / "shared/data/plans")
    ap.add_argument("--cli", action="store_true", help="also time camplace scene import from the shell")
    args = ap.parse_args()
    from shapely.geometry import Polygon

    from camplace.scene.importers import read_plan

    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; best of {args.repeats}")
    if (args.plans / FILES[-1]).is_file():
        read_plan(args.plans / FILES[-1])  # the imports warmed
    print("| file | storey | import wall (s) | import CPU (s) | footprint (m²) | rooms | prisms |\n"
          "|---|---|---|---|---|---|---|")
    for name in FILES:
        path = args.plans / name
        if not path.is_file():
            print(f"| {name} | absent from {args.plans} | | | | | |")
            continue
        for storey in storeys_of(path):
            t, cpu, got = best_of(args.repeats, lambda: read_plan(path, storey=storey))
            data = got.scene
            label = storey or f"default ({got.used['storey'].split(' (')[0]})"
            rooms = len(data["zones"]) if got.used["rooms"][0].isdigit() else 0
            area = Polygon(data["room"]["footprint"]).area
            print(f"| {name} | {label} | {t:.2f} | {cpu:.2f} | {area:.1f} | {rooms} | "
                  f"{len(data['obstacles'])} |")
        if args.cli:
            with tempfile.TemporaryDirectory() as tmp:
                t = time.perf_counter()
                subprocess.run([sys.executable, "-c", "from camplace.cli import main; main()", "scene", "import",
                                str(path), "--out", str(Path(tmp) / "site.yaml")], check=True, capture_output=True)
                print(f"| {name} | `camplace scene import` | {time.perf_counter() - t:.2f} | | | | |")
    print(f"load average {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
