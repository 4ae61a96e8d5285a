"""Single-failure robustness (issue 10, ``--robust 1``) on the cached store instances:
the swap/tabu heuristic, then the scenario-MIP large-neighbourhood search, and the lower
bounds on the optimal worst case W* (Lagrangian bound with one camera fewer, mean-failure
LP bound, and optionally the scenario-MIP dual bound on the whole problem).

    python benchmarks/robust_mip.py --out benchmarks/results/robust_mip.json
    python benchmarks/robust_mip.py --scenes store-a --budgets 40 --robust-s 200 --bound-mip-s 60 --mean-bound-s 300

The nominal placement is tabu (``--tabu-s``, seed 0), as in benchmarks/beyond_grid.py.
Instances: benchmarks/results/instances/<scene>.npz (written by benchmarks/certify.py).
Writes the JSON rows and a markdown table beside it (.md).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

from camplace.problem.instance import load_problem_npz
from camplace.solvers.robust import robust_placement, worst_case
from camplace.solvers import solve

CACHE = Path(__file__).resolve().parent / "results" / "instances"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", default="standard-store,store-a")
    ap.add_argument("--budgets", default="20,40")
    ap.add_argument("--tabu-s", type=float, default=30.0)
    ap.add_argument("--robust-s", type=float, default=200.0, help="heuristic (30 %%) + scenario-MIP LNS")
    ap.add_argument("--bound-s", type=float, default=10.0, help="Lagrangian bound with one camera fewer")
    ap.add_argument("--bound-mip-s", type=float, default=0.0, help="scenario MIP on the whole problem")
    ap.add_argument("--mean-bound-s", type=float, default=300.0, help="mean-failure LP bound")
    ap.add_argument("--out", type=Path, default=Path("benchmarks/results/robust_mip.json"))
    a = ap.parse_args()
    rows = []
    for scene in a.scenes.split(","):
        for n in (int(b) for b in a.budgets.split(",")):
            problem, _ = load_problem_npz(CACHE / f"{scene}.npz", n)
            load0 = os.getloadavg()[0]
            t = time.perf_counter()
            nominal = solve(problem, "tabu", time_limit_s=a.tabu_s, seed=0)
            t_nom = time.perf_counter() - t
            t = time.perf_counter()
            rb = robust_placement(problem, nominal, time_limit_s=a.robust_s, bound_time_s=a.bound_s,
                                  bound_mip_s=a.bound_mip_s, mean_bound_s=a.mean_bound_s)
            sec = time.perf_counter() - t
            w, _ = worst_case(problem, rb.placement.selected)
            assert abs(w - rb.robust["worst_case_cost"]) < 1e-6
            heur = rb.info["heuristic"]
            lns = rb.info.get("lns", {})
            row = {"scene": scene, "budget": n, "nominal_solver": nominal.solver, "nominal_s": t_nom,
                   "nominal_cost": rb.nominal["cost"], "nominal_worst": rb.nominal["worst_case_cost"],
                   "nominal_gap": rb.nominal["coverage_gap"], "nominal_worst_gap": rb.nominal["worst_case_gap"],
                   "heuristic_cost": heur["cost"], "heuristic_worst": heur["worst_case_cost"],
                   "heuristic_s": heur["seconds"], "robust_cost": rb.robust["cost"],
                   "robust_worst": rb.robust["worst_case_cost"], "robust_gap": rb.robust["coverage_gap"],
                   "robust_worst_gap": rb.robust["worst_case_gap"], "method": rb.info["method"],
                   "lns_tries": lns.get("tries"), "lns_accepted": lns.get("accepted"),
                   "lns_stopped": lns.get("stopped"),
                   "lns_optimal_subproblems": sum(h["status"] == "optimal" for h in lns.get("history", [])),
                   "bounds": rb.info["bounds"], "bound": rb.bound, "bound_mip": rb.info.get("bound_mip"),
                   "bound_s": rb.info.get("bound_seconds"), "lns_s": lns.get("seconds"),
                   "robust_s": sec, "load_start": load0, "load_end": os.getloadavg()[0]}
            rows.append(row)
            print(json.dumps(row), flush=True)
            a.out.parent.mkdir(parents=True, exist_ok=True)
            a.out.write_text(json.dumps({"machine": f"{platform.machine()}, {os.cpu_count()} cores", "rows": rows},
                                        indent=1))
    a.out.with_suffix(".md").write_text(markdown(rows))


def markdown(rows: list[dict]) -> str:
    out = ["| scene | N_s | nominal: cost / W | heuristic: cost / W | + scenario-MIP LNS: cost / W | "
           "LNS tries (optimal, accepted) | Lagrangian bound (N_s − 1) | mean-failure LP bound | "
           "scenario-MIP bound | "
           "gap W to bound | s | load |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        b = r["bounds"]
        lag = b.get("lagrangian_fewer_camera")
        mip = b.get("scenario_mip")
        mean = b.get("mean_failure_lp")
        gap = (r["robust_worst"] - r["bound"]) / r["robust_worst"] if r["bound"] is not None else None
        out.append(f"| {r['scene']} | {r['budget']} | {r['nominal_cost']:,.0f} / {r['nominal_worst']:,.0f} | "
                   f"{r['heuristic_cost']:,.0f} / {r['heuristic_worst']:,.0f} | "
                   f"{r['robust_cost']:,.0f} / {r['robust_worst']:,.0f} | "
                   f"{r['lns_tries']} ({r['lns_optimal_subproblems']}, {r['lns_accepted']}) | "
                   f"{'-' if lag is None else f'{lag:,.0f}'} | {'-' if mean is None else f'{mean:,.0f}'} | "
                   f"{'-' if mip is None else f'{mip:,.0f}'} | "
                   f"{'-' if gap is None else f'{100 * gap:.1f} %'} | {r['robust_s']:.0f} | "
                   f"{r['load_start']:.1f}–{r['load_end']:.1f} |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()
