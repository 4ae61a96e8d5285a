"""Quality in the same time (issue 37): coverage gap and seconds of the ``quality="high"``
chain (camplace.improve.quality.high_quality) against the default run's greedy + refinement,
on standard-store with 20 cameras, for several seeds and time budgets.

Each row: the grid solve (the scene's solver) from the same V, then the improvement; the
coverage gap is cost / Σ w Γ² of the final selection (its cost recomputed from the extended
V). Wall seconds and process CPU seconds (all threads) are both written: on a loaded
machine the CPU seconds say what an idle one would take.

    python benchmarks/quality.py --budgets 20,25 --seeds 0,1,2 --out benchmarks/results/quality.json
    python benchmarks/quality.py --density 1 --steps tabu:0.15,adaptive:0.35,refine:0.1   # the scene's own grid
    python benchmarks/quality.py --end-to-end --repeats 3     # whole camplace.run(..., quality="high")
    python benchmarks/quality.py --end-to-end --repeats 1 --high-only --quality-time 300   # a longer budget

``--density D``: the chain runs on V of the grid with every mount's spacing / D (what
``quality="high"`` raycasts, camplace.workflows.quality.denser_candidates; the default
row stays on the scene's grid). Each row also holds the 1-minute load average at its end.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from camplace.improve.quality import QUALITY_STEPS, high_quality
from camplace.improve.refine import refine_placement
from camplace.solvers import solve
from camplace.workflows.quality import QUALITY_DENSITY
from camplace.workflows.run import prepare, problem_from_visibility


def clocks() -> tuple[float, float]:
    """(wall s, process CPU s)."""
    return time.perf_counter(), time.process_time()


def since(c: tuple[float, float]) -> tuple[float, float]:
    w, p = clocks()
    return round(w - c[0], 2), round(p - c[1], 2)


def load() -> float:
    """The 1-minute load average (the machine is shared: wall seconds are under this load)."""
    return round(os.getloadavg()[0], 2)


def gap(problem, sel) -> float:
    t = problem
    return float(t.cost(sel) / np.sum(t.weights * t.gamma.astype(np.float64) ** 2))


def parse_steps(text: str | None):
    if not text:
        return QUALITY_STEPS
    out = []
    for part in text.split(","):
        name, share = part.split(":")
        out.append((name, float(share)))
    return tuple(out)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default="standard-store")
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--budgets", default="25", help="time budgets (s) of the improvement chain")
    ap.add_argument("--seeds", default="0")
    ap.add_argument("--steps", default=None, help="e.g. tabu:0.35,refine:0.2,adaptive:0.3,refine:0.15")
    ap.add_argument("--density", type=int, default=QUALITY_DENSITY,
                    help="the chain's grid: every mount's spacing / this (1: the scene's grid)")
    ap.add_argument("--adaptive-rounds", type=int, default=3, help="rounds of each adaptive step (at most)")
    ap.add_argument("--end-to-end", action="store_true",
                    help="time camplace.run(scene, refine=True) and camplace.run(scene, quality='high') whole")
    ap.add_argument("--repeats", type=int, default=3, help="--end-to-end: runs of each")
    ap.add_argument("--quality-time", type=float, default=30.0, help="--end-to-end: quality_time_s of the high runs")
    ap.add_argument("--high-only", action="store_true", help="--end-to-end: the quality='high' runs only")
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args()
    rows = []
    if a.end_to_end:
        import camplace

        for rep in range(a.repeats):
            for quality in ("high",) if a.high_only else ("default", "high"):
                c = clocks()
                r = camplace.run(a.scene, a.n, quality=quality, refine=True, quality_time_s=a.quality_time)
                w, p = since(c)
                rows.append({"variant": f"run quality={quality}", "repeat": rep, "gap": r.metrics.coverage_gap,
                             "quality_time_s": a.quality_time if quality == "high" else None,
                             "wall_s": w, "cpu_s": p, "load": load(),
                             "timings_s": {k: round(v, 2) for k, v in r.timings_s.items()}})
                print(json.dumps(rows[-1]), flush=True)
    else:
        c = clocks()
        sc, vis = prepare(a.scene)
        print(json.dumps({"prepare": since(c)}), flush=True)
        problem = problem_from_visibility(vis, a.n)
        c = clocks()
        grid = solve(problem, sc.spec.placement.solver)
        gs = since(c)
        c = clocks()
        rf = refine_placement(sc, vis, problem, grid, time_limit_s=60.0)
        w, p = since(c)
        rows.append({"variant": "default (greedy + refine)", "seed": 0, "gap": gap(rf.problem, rf.placement.selected),
                     "wall_s": round(gs[0] + w, 2), "cpu_s": round(gs[1] + p, 2), "load": load()})
        print(json.dumps(rows[-1]), flush=True)
        if a.density > 1:  # V of the denser grid, and the grid solve on it
            c = clocks()
            sc, vis = prepare(a.scene, candidate_density=a.density)
            print(json.dumps({"prepare": since(c), "density": a.density, "V": list(vis.V.shape),
                              "nnz": int(vis.V.nnz)}), flush=True)
            problem = problem_from_visibility(vis, a.n)
            c = clocks()
            grid = solve(problem, sc.spec.placement.solver)
            gs = since(c)
        steps = parse_steps(a.steps)
        norm = float(np.sum(problem.weights * problem.gamma.astype(np.float64) ** 2))
        for budget in (float(b) for b in a.budgets.split(",")):
            for seed in (int(s) for s in a.seeds.split(",")):
                c = clocks()
                q = high_quality(sc, vis, problem, grid, budget, seed=seed, steps=steps,
                                 adaptive_rounds_max=a.adaptive_rounds)
                w, p = since(c)
                rows.append({"variant": f"high {budget:g} s", "steps": a.steps or "default", "seed": seed,
                             "density": a.density, "adaptive_rounds": a.adaptive_rounds, "load": load(),
                             "gap": gap(q.problem, q.placement.selected), "wall_s": round(gs[0] + w, 2),
                             "cpu_s": round(gs[1] + p, 2),
                             "trace": [(h["step"], h["seconds"], round(h["cost"] / norm, 4)) for h in q.steps]})
                print(json.dumps(rows[-1]), flush=True)
    if a.out:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(json.dumps({"machine": f"{platform.machine()}, {__import__('os').cpu_count()} cores",
                                     "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
