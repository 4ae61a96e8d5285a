"""Benchmark of the region-decomposition bound (issue 11, docs/certify.md §6-8): how far
past the LP does it get, and how fast?

Usage (one job at a time on a 2-core machine):
    python benchmarks/region_bound.py --only standard-store:20 --time 300 --regions 16 \
        --out benchmarks/results/region-bound.jsonl
For each instance: reduce it (as `camplace.solvers.solve` does), solve the LP by HiGHS
interior point (threads=1), then run region_bound from the LP duals (x_frac = the LP
primal) for --time seconds. Records the LP bound, the region bound, the bound at the
starting prices, every evaluation and the 1-minute load average before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from certify import INSTANCES, _problem  # noqa: E402  (the same cached instances)


def run(scene: str, budget: int, time_s: float, regions: int | None, region_time_s: float, ub: float | None) -> dict:
    from camplace.problem.model import reduce_problem
    from camplace.solvers.bounds import lp_bound
    from camplace.solvers.region_bound import region_bound

    load0 = os.getloadavg()[0]
    prob = reduce_problem(_problem(scene, budget)).problem
    t0 = time.perf_counter()
    lp = lp_bound(prob, threads=1)
    lp_s = time.perf_counter() - t0
    if lp.info.get("status") != "optimal":
        return {"error": f"LP {lp.info.get('status')}", "lp_s": round(lp_s, 1)}
    lam = np.maximum(np.asarray(lp.info["row_dual"][:prob.n_targets]), 0.0)
    trace = []
    t1 = time.perf_counter()
    res = region_bound(prob, lam=lam, x_frac=lp.info["x"], n_regions=regions, time_limit_s=time_s,
                       region_time_s=region_time_s, incumbent_cost=ub,
                       on_bound=lambda v: trace.append((round(time.perf_counter() - t1, 1), v)))
    return {"lp_bound": lp.bound, "lp_s": round(lp_s, 1), "region_bound": res.bound,
            "first": res.info["first"], "history": res.info["history"], "iterations": res.info["iterations"],
            "regions": res.info["regions"], "region_solves_optimal": res.info["region_solves_optimal"],
            "region_s": round(res.seconds, 1), "improvements": trace, "incumbent": ub,
            "region_time_s": region_time_s, "load_before": load0, "load_after": os.getloadavg()[0]}


BEST_KNOWN = {("standard-store", 20): 21874.0, ("standard-store", 40): 3758.0, ("standard-store", 60): 709.0,
              ("standard-store", 80): 287.0, ("store-a", 40): 15722.0}  # certify-engine.jsonl, 600 s


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--time", type=float, default=300.0)
    ap.add_argument("--regions", type=int, default=None)
    ap.add_argument("--region-time", type=float, default=2.0)
    ap.add_argument("--only", action="append", default=None, help="scene:N, repeatable")
    a = ap.parse_args(argv)
    todo = INSTANCES if not a.only else [(s.split(":")[0], int(s.split(":")[1])) for s in a.only]
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    for scene, n in todo:
        res = run(scene, n, a.time, a.regions, a.region_time, BEST_KNOWN.get((scene, n)))
        res.update({"scene": scene, "budget": n, "time_limit_s": a.time, "n_regions_arg": a.regions})
        with out.open("a") as f:
            f.write(json.dumps(res) + "\n")
        print(json.dumps({k: v for k, v in res.items() if k != "history"}), file=sys.stderr, flush=True)


if __name__ == "__main__":
    main()
