"""Time to a proven gap <= 0.1 %: `mip` (tight convex model, HiGHS) vs `paper-mip`
(the paper's piecewise model, CBC), same instance, same machine, same run.

usage: python benchmarks/solver_speed.py SCENE BUDGETS [TIME_LIMIT_S] [THREADS]
e.g.   python benchmarks/solver_speed.py demo 4,6,8,10,12 60 2
Prints one JSON line per run and a markdown table at the end.
"""

from __future__ import annotations

import json
import sys

from camplace.workflows.run import prepare, problem_from_visibility
from camplace.solvers import solve


def main() -> None:
    scene = sys.argv[1]
    budgets = [int(b) for b in sys.argv[2].split(",")]
    limit = float(sys.argv[3]) if len(sys.argv) > 3 else 60.0
    threads = int(sys.argv[4]) if len(sys.argv) > 4 else 2
    _, vis = prepare(scene)
    rows = []
    for b in budgets:
        problem = problem_from_visibility(vis, b)
        for name in ("mip", "paper-mip"):
            p = solve(problem, name, time_limit_s=limit, threads=threads, mip_rel_gap=1e-3)
            row = {"scene": scene, "budget": b, "solver": name, "status": p.status, "objective": p.objective,
                   "bound": p.bound, "gap": p.gap, "seconds": round(p.seconds, 2),
                   "engine": p.info.get("engine", "highs"), "columns": p.info.get("columns"),
                   "rows": p.info.get("rows"), "nonzeros": p.info.get("nonzeros")}
            rows.append(row)
            print(json.dumps(row), flush=True)
    print(f"\n| N_s | mip: s / status / cost / proven gap | paper-mip: s / status / cost / proven gap | speed-up |")
    print("|---|---|---|---|")
    for b in budgets:
        m = next(r for r in rows if r["budget"] == b and r["solver"] == "mip")
        q = next(r for r in rows if r["budget"] == b and r["solver"] == "paper-mip")

        def cell(r):
            gap = "–" if r["gap"] is None else f"{100 * r['gap']:.2f} %"
            return f"{r['seconds']:.1f} / {r['status']} / {r['objective']:.0f} / {gap}"

        ok = m["status"] == "optimal" or (m["gap"] is not None and m["gap"] <= 1e-3)
        speed = f"≥ {q['seconds'] / m['seconds']:.1f}×" if ok and q["status"] != "optimal" else (
            f"{q['seconds'] / m['seconds']:.1f}×" if ok else "–")
        print(f"| {b} | {cell(m)} | {cell(q)} | {speed} |")


if __name__ == "__main__":
    main()
