"""Crowds (issue 28): V_s time per sample against V's own time, and the crowd-aware
placement against the empty-store one, both scored on held-out crowds.

For each density the scene's V is thinned by the ``--samples`` optimisation crowds
(camplace.visibility.crowd; V_s time per sample, warm, timed twice); then, for each
solver, the same solver with the same time limit places ``--budget`` cameras

    empty-store   on V (the paper's problem: nobody in the store);
    crowd-aware   on the stacked sample-average problem (camplace.problem.crowd);

and both placements are scored on the ``--score-samples`` held-out crowds (another
random stream of the same seed: crowds neither placement saw) with the crowd metrics of
camplace.metrics.crowd, and on the empty store (the cost each pays there). Writes one
JSON object to stdout (``--out FILE``: also to FILE) and a markdown table to stderr.

    python benchmarks/crowds.py [--scene standard-store] [--budget 40] [--densities 0.3,1.0]
        [--solvers greedy,tabu] [--time-limit 60] [--samples 16] [--score-samples 32]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

from camplace.solvers import solve
from camplace.spec.crowd import CrowdSpec
from camplace.targets.crowd import sample_crowds
from camplace.visibility.crowd import crowd_rows
from camplace.visibility.engine import compute_visibility
from camplace.visibility.voxel import VoxelEngine
from camplace.workflows.crowd import crowd_problem, score_in_crowd
from camplace.workflows.run import prepare, problem_from_visibility


def timed(fn, *args, **kw):
    t0 = time.perf_counter()
    out = fn(*args, **kw)
    return out, time.perf_counter() - t0


def scores(sc, vis, problem, selected, crowd: CrowdSpec) -> dict:
    m = score_in_crowd(sc, vis, selected, crowd).summary
    out = {k: m[k] for k in ("coverage_gap", "seen_by_gamma_pct", "triangulatable_pct")}
    cov = problem.coverage(selected)
    out["empty_store_gap"] = problem.cost(selected) / problem.normalizer
    out["empty_store_triangulatable_pct"] = 100.0 * float(np.mean(cov >= 2))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="standard-store")
    ap.add_argument("--budget", type=int, default=40)
    ap.add_argument("--densities", default="0.3,1.0")
    ap.add_argument("--solvers", default="greedy,tabu")
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--score-samples", type=int, default=32)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    sc, vis = prepare(a.scene)
    p = problem_from_visibility(vis, a.budget)
    V = vis.V
    v_s = [timed(compute_visibility, VoxelEngine(), sc.occupancy, vis.targets, vis.candidates)[1] for _ in range(2)]
    res = {"scene": a.scene, "budget": a.budget, "V": list(V.shape), "nnz": int(V.nnz), "V_seconds": v_s,
           "load_average": os.getloadavg(), "cpus": os.cpu_count(), "samples": a.samples,
           "score_samples": a.score_samples, "time_limit_s": a.time_limit, "densities": {}}
    rows = []
    for d in (float(x) for x in a.densities.split(",")):
        crowd = CrowdSpec(density=d, samples=a.samples, score_samples=a.score_samples, seed=a.seed)
        crowds = sample_crowds(sc, crowd)
        per = []
        for _ in range(2):
            out, t = timed(crowd_rows, V, vis.candidates.positions, vis.targets.positions, crowds)
            per.append(t / crowds.n_samples)
        cp, t_build = timed(crowd_problem, sc, vis, p, crowd)
        entry = {"persons": float(np.mean(crowds.counts)), "kept_pct": 100.0 * out.nnz / (V.nnz * crowds.n_samples),
                 "V_s_seconds_per_sample": per, "crowd_problem_seconds": t_build,
                 "stacked": [int(v) for v in cp.problem.V.shape], "stacked_nnz": int(cp.problem.V.nnz), "solvers": {}}
        for solver in a.solvers.split(","):
            opts = {} if solver.startswith("greedy") else {"time_limit_s": a.time_limit}
            e, te = timed(solve, p, solver, **opts)
            c, tc = timed(solve, cp.problem, solver, **opts)
            got = {"empty-store": {"solve_seconds": te, **scores(sc, vis, p, e.selected, crowd)},
                   "crowd-aware": {"solve_seconds": tc, "in_sample_gap": c.objective / cp.problem.normalizer,
                                   **scores(sc, vis, p, c.selected, crowd)}}
            got["empty-store"]["in_sample_gap"] = cp.problem.cost(e.selected) / cp.problem.normalizer
            entry["solvers"][solver] = got
            for name, g in got.items():
                rows.append(f"| {d:g} | {solver} | {name} | {g['coverage_gap']['mean']:.4f} ± "
                            f"{g['coverage_gap']['std']:.4f} | {g['triangulatable_pct']['mean']:.2f} | "
                            f"{g['seen_by_gamma_pct']['mean']:.2f} | {g['in_sample_gap']:.4f} | "
                            f"{g['empty_store_gap']:.4f} | {g['empty_store_triangulatable_pct']:.2f} | "
                            f"{g['solve_seconds']:.1f} |")
            print(rows[-2], rows[-1], sep="\n", file=sys.stderr, flush=True)
        res["densities"][str(d)] = entry
    res["load_average_end"] = os.getloadavg()
    text = json.dumps(res, indent=2)
    print(text)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text + "\n")
    print("| density /m² | solver | placement | held-out crowd gap (mean ± std) | triangulatable in crowd % | "
          "seen ≥ Γ in crowd % | crowd gap on its own crowds | empty-store gap | empty-store triangulatable % | "
          "solve s |", file=sys.stderr)
    print("\n".join(rows), file=sys.stderr)


if __name__ == "__main__":
    main()
