"""Zone solver benchmark (issue 21): greedy-fast vs ``zones`` on the procedural warehouse,
with the full problem's Lagrangian bound.

V comes from the visibility cache (camplace.workflows.run.prepare with the default cache
folder, ~/.cache/camplace, or ``--cache``), so a second run skips the raycasting.

    python benchmarks/zones.py --size 10000 --time 300 --out benchmarks/results/zones.json

prints one markdown table row per solver and the cost drop of zones against greedy-fast
(goal at 10,000 m²: >= 3 % within 5 minutes).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=float, default=10000.0, help="warehouse floor area (m²)")
    ap.add_argument("--time", type=float, default=300.0, help="zones time limit (s)")
    ap.add_argument("--budget", type=int, default=None, help="camera budget (default: the scene's)")
    ap.add_argument("--tile-m", type=float, default=None, help="tile side (m; default: the solver's)")
    ap.add_argument("--tile-time", type=float, default=None, help="per-tile time limit (s)")
    ap.add_argument("--workers", type=int, default=1, help="processes for the tiles of one colour")
    ap.add_argument("--cache", type=Path, default=None, help="visibility cache folder")
    ap.add_argument("--no-cache", action="store_true", help="compute V without the cache")
    ap.add_argument("--out", type=Path, default=None, help="write the measurements as JSON here")
    args = ap.parse_args()

    from camplace.solvers import SOLVERS
    from camplace.visibility.cache import default_cache_dir
    from camplace.workflows.run import prepare, problem_from_visibility

    t = time.perf_counter()
    cache = None if args.no_cache else (args.cache or default_cache_dir())
    sc, vis = prepare(f"warehouse:{args.size:g}", cache_dir=cache)
    budget = sc.spec.placement.budget if args.budget is None else args.budget
    problem = problem_from_visibility(vis, budget)
    prep_s = time.perf_counter() - t
    out: dict = {"size_m2": args.size, "N_g": problem.n_candidates, "N_p": problem.n_targets,
                 "nnz": int(problem.V.nnz), "budget": budget, "prepare_s": prep_s, "cache": str(cache),
                 "load_avg_start": os.getloadavg()[0], "time_limit_s": args.time}
    t = time.perf_counter()
    g = SOLVERS["greedy-fast"](problem)
    out["greedy_fast"] = {"cost": g.objective, "s": time.perf_counter() - t}
    trace: list = []
    t = time.perf_counter()
    opts = {k: v for k, v in (("tile_m", args.tile_m), ("tile_time_s", args.tile_time)) if v is not None}
    z = SOLVERS["zones"](problem, time_limit_s=args.time, workers=args.workers, initial=tuple(g.selected.tolist()),
                         on_incumbent=lambda o, b: trace.append((round(time.perf_counter() - t, 2), o, b)), **opts)
    zs = time.perf_counter() - t
    out["zones"] = {"cost": z.objective, "s": zs, "bound": z.bound, "gap": z.gap, "status": z.status,
                    "sweeps": z.info.get("sweeps"), "tile_m": z.info.get("tile_m"), "trace": trace}
    drop = (g.objective - z.objective) / g.objective if g.objective else 0.0
    out["zones_vs_greedy_drop"] = drop
    out["load_avg_end"] = os.getloadavg()[0]
    print(f"warehouse:{args.size:g}: N_g {problem.n_candidates:,}, N_p {problem.n_targets:,}, nnz {problem.V.nnz:,}, "
          f"budget {budget}, prepare {prep_s:.1f} s")
    print("| solver | cost | seconds | bound | gap |")
    print("|---|---:|---:|---:|---:|")
    print(f"| greedy-fast | {g.objective:,.0f} | {out['greedy_fast']['s']:.1f} | | |")
    print(f"| zones | {z.objective:,.0f} | {zs:.1f} | {z.bound:,.0f} | {100 * (z.gap or 0):.1f} % |")
    print(f"zones lowers greedy-fast's cost by {100 * drop:.2f} % (goal >= 3 %)")
    if args.out:
        from camplace.core.files import atomic_write_json

        args.out.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_json(args.out, out)


if __name__ == "__main__":
    main()
