"""A whole building end to end (issue 33): a generated five-storey office IFC of the size
of a real one (about 3,400 m² of floor, 90 rooms), ``camplace run FILE --storey all
--budget 40`` as a user runs it, timed as one process with its peak memory.

    python benchmarks/building.py [--floors 5] [--nx 6] [--ny 3] [--budget 40] [--keep DIR]

Prints one JSON line (wall seconds, peak RSS in GiB of the camplace process, floor area,
rooms, cameras per storey, coverage gap, the load average before and after) and appends it
to benchmarks/results/building.jsonl. Goal: <= 180 s and <= 4 GiB on the 2-core machine.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from camplace.scene.importers.ifc_build import GridBuilding, write_grid_building

RESULTS = Path(__file__).resolve().parent / "results" / "building.jsonl"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--floors", type=int, default=5)
    ap.add_argument("--nx", type=int, default=6)
    ap.add_argument("--ny", type=int, default=3)
    ap.add_argument("--budget", type=int, default=40)
    ap.add_argument("--keep", type=Path, default=None, help="write the IFC and the run folder here")
    args = ap.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="camplace-building-"))
    work.mkdir(parents=True, exist_ok=True)
    b = GridBuilding(nx=args.nx, ny=args.ny, room=(6.3, 6.0), height=3.5, slab=0.3)
    floors = tuple(f"Level {k}" for k in range(args.floors))
    ifc = write_grid_building(work / "office.ifc", b, unit="mm", floors=floors)
    out = work / "run"
    load0 = os.getloadavg()
    t = time.perf_counter()
    cmd = [sys.executable, "-c", "from camplace.cli import main; main()", "--quiet", "run", str(ifc), "--storey",
           "all", "--budget", str(args.budget), "--out", str(out), "--no-cache"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if proc.returncode != 0:
        sys.exit(f"run failed ({proc.returncode}): {proc.stderr[-2000:]}")
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024**2  # KiB -> GiB
    metrics = json.loads((out / "metrics.json").read_text())
    row = {"floors": args.floors, "rooms": args.floors * args.nx * args.ny,
           "floor_area_m2": round(args.floors * b.outline_area(), 1), "budget": args.budget,
           "wall_s": round(wall, 1), "peak_rss_gib": round(peak, 2),
           "cameras_per_storey": {s["storey"]: s["cameras"] for s in metrics["storeys"]},
           "coverage_gap": round(metrics["coverage_gap"], 4),
           "timings_s": {k: round(v, 1) for k, v in metrics["timings_s"].items()},
           "load_before": [round(v, 2) for v in load0], "load_after": [round(v, 2) for v in os.getloadavg()]}
    print(json.dumps(row))
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    with RESULTS.open("a") as f:
        f.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    main()
