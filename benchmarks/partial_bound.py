"""Benchmark of the partial Lagrangian bound (issue 11, docs/certify.md §9): one costly
target region exact with the budget, the rest Lagrangian at the LP duals.

Usage: python benchmarks/partial_bound.py --only standard-store:40 --time 120 --share 0.3 \
           --out benchmarks/results/partial-bound.jsonl
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
from certify import INSTANCES, _problem  # noqa: E402


def main(argv: list[str] | None = None) -> None:
    from camplace.problem.model import reduce_problem
    from camplace.solvers.bounds import lp_bound
    from camplace.solvers.region_bound import costly_region, partial_lagrangian_bound

    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--time", type=float, default=120.0)
    ap.add_argument("--share", type=float, default=0.3)
    ap.add_argument("--only", action="append", default=None, help="scene:N, repeatable")
    a = ap.parse_args(argv)
    todo = INSTANCES if not a.only else [(s.split(":")[0], int(s.split(":")[1])) for s in a.only]
    for scene, n in todo:
        load0 = os.getloadavg()[0]
        prob = reduce_problem(_problem(scene, n)).problem
        t0 = time.perf_counter()
        lp = lp_bound(prob, threads=1)
        lp_s = time.perf_counter() - t0
        lam = np.maximum(np.asarray(lp.info["row_dual"][:prob.n_targets]), 0.0)
        region = costly_region(prob, lam, share=a.share)
        res = partial_lagrangian_bound(prob, lam, region, time_limit_s=a.time)
        row = {"scene": scene, "budget": n, "lp_bound": lp.bound, "lp_s": round(lp_s, 1), "share": a.share,
               "partial_bound": res.bound, "seconds": round(res.seconds, 1), **{k: v for k, v in res.info.items()},
               "load_before": load0, "load_after": os.getloadavg()[0], "time_limit_s": a.time}
        with Path(a.out).open("a") as f:
            f.write(json.dumps(row) + "\n")
        print(json.dumps(row), file=sys.stderr, flush=True)


if __name__ == "__main__":
    main()
