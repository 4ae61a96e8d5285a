"""Do solvers keep ``time_limit_s``? Wall time of ``solve(...)`` for every registered solver.

usage: python benchmarks/time_limits.py [SCENE] [LIMITS] [BUDGET] [OUT.jsonl] [SOLVERS]
e.g.   nice python benchmarks/time_limits.py store-a 5,20 40 benchmarks/results/time_limits.jsonl
The problem is built once (prepare + problem_from_visibility); each solver then runs on it
with each limit. Prints one JSON line per run (also appended to OUT) and a markdown table:
solver, limit, wall time of the solve call, overrun = wall − limit (s), status.
"""

from __future__ import annotations

import json
import sys
import time

from camplace.solvers import SOLVERS, solve
from camplace.workflows.run import prepare, problem_from_visibility


def timed_solve(problem, name: str, limit: float) -> dict:
    """One run of solver ``name`` with time_limit_s=limit: wall time (s), overrun (s), status, cost."""
    t0 = time.perf_counter()
    p = solve(problem, name, time_limit_s=limit)
    wall = time.perf_counter() - t0
    return {"solver": name, "limit_s": limit, "wall_s": round(wall, 2), "overrun_s": round(wall - limit, 2),
            "status": p.status, "objective": round(float(p.objective), 3), "cameras": int(len(p.selected))}


def main() -> None:
    scene = sys.argv[1] if len(sys.argv) > 1 else "store-a"
    limits = [float(x) for x in (sys.argv[2] if len(sys.argv) > 2 else "5,20").split(",")]
    budget = int(sys.argv[3]) if len(sys.argv) > 3 else 40
    out_path = sys.argv[4] if len(sys.argv) > 4 else None
    names = sys.argv[5].split(",") if len(sys.argv) > 5 else list(SOLVERS)
    t = time.perf_counter()
    _, vis = prepare(scene)
    problem = problem_from_visibility(vis, budget)
    print(f"# {scene}: V {problem.V.shape}, nnz {problem.V.nnz}, budget {budget}, "
          f"built in {time.perf_counter() - t:.1f} s", file=sys.stderr, flush=True)
    rows = []
    for limit in limits:
        for name in names:
            row = dict(timed_solve(problem, name, limit), scene=scene, budget=budget)
            rows.append(row)
            print(json.dumps(row), flush=True)
            if out_path:
                with open(out_path, "a") as f:
                    f.write(json.dumps(row) + "\n")
    print("\n| solver | limit (s) | wall (s) | overrun (s) | status |")
    print("|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['solver']} | {r['limit_s']:g} | {r['wall_s']:.1f} | {r['overrun_s']:+.1f} | {r['status']} |")


if __name__ == "__main__":
    main()
