"""Beyond the grid (issue 10): refinement, adaptive candidates and single-failure
robustness against the best grid incumbent, on the built-in stores.

For each scene and budget: the grid incumbent is the better of greedy + 1-swap and tabu
(``--tabu-s`` seconds); then pose refinement, adaptive candidates (and adaptive followed
by refinement) start from it. Every off-grid placement is written as a run folder and
scored again from scratch by ``camplace.workflows.evaluate.evaluate`` (the library behind
``camplace evaluate``: the poses are raycast afresh), and that fresh cost is what the
table reports. The robust placement (``--robust 1``) starts from the same incumbent.

    python benchmarks/beyond_grid.py --out benchmarks/results/beyond_grid.json
    python benchmarks/beyond_grid.py --parts robust --out benchmarks/results/beyond_grid_robust.json
    python benchmarks/beyond_grid.py --parts triangulation --out benchmarks/results/triangulation.md
    python benchmarks/beyond_grid.py --parts catalogue --tabu-s 30 --out benchmarks/results/catalogue.md

Writes the JSON rows and a markdown table beside it (.md).
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

from camplace.improve.adaptive import adaptive_rounds
from camplace.workflows.evaluate import evaluate
from camplace.metrics.coverage import compute_metrics
from camplace.workflows.run import problem_from_visibility, prepare
from camplace.improve.refine import refine_placement
from camplace.outputs.write import write_outputs
from camplace.solvers.robust import robust_placement
from camplace.solvers import solve


def fresh_cost(scene: str, vis, problem, placement, folder: Path) -> float:
    """Write the placement as a run folder, then score its placement.json from scratch."""
    m = compute_metrics(problem, placement.selected)
    write_outputs(folder, scene, vis, placement, problem.budget, m, {}, report=False)
    return float(evaluate(scene, folder / "placement.json").placement.objective)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", default="standard-store,store-a")
    ap.add_argument("--budgets", default="20,40")
    ap.add_argument("--tabu-s", type=float, default=30.0)
    ap.add_argument("--refine-s", type=float, default=120.0)
    ap.add_argument("--adaptive-rounds", type=int, default=3)
    ap.add_argument("--adaptive-s", type=float, default=120.0)
    ap.add_argument("--robust-s", type=float, default=60.0)
    ap.add_argument("--out", type=Path, default=Path("benchmarks/results/beyond_grid.json"))
    ap.add_argument("--work", type=Path, default=Path("/tmp/camplace-beyond-grid"))
    ap.add_argument("--parts", default="grid-moves,robust",
                    help="grid-moves (refine, adaptive) and/or robust; or alone: triangulation, catalogue")
    a = ap.parse_args()
    if a.parts in ("triangulation", "catalogue"):
        text = (triangulation_table(a.scenes.split(","), [int(b) for b in a.budgets.split(",")])
                if a.parts == "triangulation" else catalogue_table(a.tabu_s))
        a.out.with_suffix(".md").write_text(text)
        print(text)
        return
    rows = []
    for scene in a.scenes.split(","):
        sc, vis = prepare(scene)
        for n in (int(b) for b in a.budgets.split(",")):
            problem = problem_from_visibility(vis, n)
            t = time.perf_counter()
            g = solve(problem, "greedy", local_search=True)
            tg = time.perf_counter() - t
            t = time.perf_counter()
            tb = solve(problem, "tabu", time_limit_s=a.tabu_s, seed=0)
            tt = time.perf_counter() - t
            grid = min((g, tb), key=lambda p: p.objective)
            row = {"scene": scene, "budget": n, "greedy_swap": g.objective, "greedy_swap_s": tg,
                   "tabu": tb.objective, "tabu_s": tt, "grid": grid.objective, "grid_solver": grid.solver,
                   "grid_s": tg + tt}
            work = a.work / f"{scene}-{n}"
            if "grid-moves" in a.parts:
                grid_moves(a, sc, vis, problem, grid, scene, work, row)
            if "robust" in a.parts:
                robust_row(a, problem, grid, row)
            rows.append(row)
            print(json.dumps(row), flush=True)
            a.out.parent.mkdir(parents=True, exist_ok=True)
            a.out.write_text(json.dumps({"machine": f"{platform.machine()}, {__import__('os').cpu_count()} cores",
                                         "rows": rows}, indent=1))
    a.out.with_suffix(".md").write_text(markdown(rows))


def grid_moves(a, sc, vis, problem, grid, scene, work, row) -> None:
    """Refinement, adaptive candidates and both, each scored afresh."""
    t = time.perf_counter()
    rf = refine_placement(sc, vis, problem, grid, time_limit_s=a.refine_s)
    row.update(refine=rf.refined_cost, refine_s=time.perf_counter() - t, refine_trials=rf.info["trials"],
               refine_moved=rf.info["moved"])
    row["refine_fresh"] = fresh_cost(scene, rf.visibility, rf.problem, rf.placement, work / "refine")
    t = time.perf_counter()
    ad = adaptive_rounds(sc, vis, problem, grid, rounds=a.adaptive_rounds, time_limit_s=a.adaptive_s)
    row.update(adaptive=ad.placement.objective, adaptive_s=time.perf_counter() - t,
               adaptive_rounds=[{k: h[k] for k in ("round", "candidates", "cost")} for h in ad.rounds])
    row["adaptive_fresh"] = fresh_cost(scene, ad.visibility, ad.problem, ad.placement, work / "adaptive")
    t = time.perf_counter()
    both = refine_placement(sc, ad.visibility, ad.problem, ad.placement, time_limit_s=a.refine_s)
    row.update(adaptive_refine=both.refined_cost, adaptive_refine_s=row["adaptive_s"] + time.perf_counter() - t)
    row["adaptive_refine_fresh"] = fresh_cost(scene, both.visibility, both.problem, both.placement,
                                              work / "adaptive-refine")


def robust_row(a, problem, grid, row) -> None:
    """The --robust 1 heuristic from the grid incumbent."""
    t = time.perf_counter()
    rb = robust_placement(problem, grid, time_limit_s=a.robust_s, bound_time_s=10.0)
    row.update(robust_s=time.perf_counter() - t, nominal_cost=rb.nominal["cost"],
               nominal_worst=rb.nominal["worst_case_cost"], robust_cost=rb.robust["cost"],
               robust_worst=rb.robust["worst_case_cost"], robust_bound=rb.bound,
               nominal_gap=rb.nominal["coverage_gap"], nominal_worst_gap=rb.nominal["worst_case_gap"],
               robust_gap=rb.robust["coverage_gap"], robust_worst_gap=rb.robust["worst_case_gap"],
               robust_moves=rb.info["moves"])


def triangulation_table(scenes: list[str], budgets: list[int]) -> str:
    """Plain greedy against the triangulation-aware greedy (--well-triangulated)."""
    from camplace.problem.model import shortfall_cost
    from camplace.metrics.triangulation import well_triangulated_of_selection
    from camplace.problem.triangulation import effective_coverage

    out = ["| scene | N_s | greedy | cost | triangulation-aware cost | well triangulated | non-triangulatable | s |",
           "|---|---|---|---|---|---|---|---|"]
    for scene in scenes:
        sc, vis = prepare(scene)
        cp, tp = vis.candidates.positions, vis.targets.positions
        for n in budgets:
            problem = problem_from_visibility(vis, n)
            t = time.perf_counter()
            plain = solve(problem, "greedy")
            runs = [("plain", plain.selected, time.perf_counter() - t)]
            t = time.perf_counter()
            tri = solve(problem, "greedy-triangulated")  # positions come with the problem
            runs.append(("--well-triangulated", tri.selected, time.perf_counter() - t))
            for name, sel, sec in runs:
                eff = effective_coverage(vis.V[sel], cp[sel], tp)
                well = well_triangulated_of_selection(vis.V, cp, tp, sel)
                cov = problem.coverage(sel)
                out.append(f"| {scene} | {n} | {name} | {problem.cost(sel):,.0f} | "
                           f"{shortfall_cost(problem.gamma, problem.weights, eff):,.0f} | {100 * well.mean():.1f} % | "
                           f"{100 * np.mean(cov < 2):.1f} % | {sec:.1f} |")
    return "\n".join(out) + "\n"


def catalogue_table(time_limit_s: float = 30.0) -> str:
    """Every registered solver on catalogue-store (money budget 10, at most 14 cameras)."""
    from camplace.solvers import SOLVERS

    sc, vis = prepare("catalogue-store")
    problem = problem_from_visibility(vis, sc.spec.placement.budget, sc.spec.placement.money_budget)
    names = [c.name for c in vis.candidates.cameras]
    out = ["| solver | cost | bound | cameras | money spent | types | s |", "|---|---|---|---|---|---|---|"]
    for s in SOLVERS:
        t = time.perf_counter()
        p = solve(problem, s, time_limit_s=time_limit_s)
        sec = time.perf_counter() - t
        sel = p.selected
        problem.check_feasible(sel) if not getattr(SOLVERS[s], "ignores_budget", False) else None
        kinds = [names[c] for c in vis.candidates.camera_ids[sel]]
        mix = ", ".join(f"{k} {kinds.count(k)}" for k in names if k in kinds)
        b = "-" if p.bound is None else f"{p.bound:,.0f}"
        out.append(f"| {s} | {p.objective:,.0f} | {b} | {len(sel)} | {problem.costs[sel].sum():.1f} | {mix} | {sec:.1f} |")
    return "\n".join(out) + "\n"


def markdown(rows: list[dict]) -> str:
    pct = lambda new, old: f"{100 * (new - old) / old:+.1f} %" if old else "-"  # noqa: E731
    out = ["| scene | N_s | grid incumbent (s) | refined, fresh raycast (s) | adaptive, fresh (s) | "
           "adaptive + refine, fresh (s) |", "|---|---|---|---|---|---|"]
    for r in (r for r in rows if "refine_fresh" in r):
        out.append(f"| {r['scene']} | {r['budget']} | {r['grid']:.0f} ({r['grid_solver']}, {r['grid_s']:.0f}) | "
                   f"{r['refine_fresh']:.0f} ({pct(r['refine_fresh'], r['grid'])}, {r['refine_s']:.0f}) | "
                   f"{r['adaptive_fresh']:.0f} ({pct(r['adaptive_fresh'], r['grid'])}, {r['adaptive_s']:.0f}) | "
                   f"{r['adaptive_refine_fresh']:.0f} ({pct(r['adaptive_refine_fresh'], r['grid'])}, "
                   f"{r['adaptive_refine_s']:.0f}) |")
    out += ["", "| scene | N_s | nominal: cost / worst single failure | robust: cost / worst single failure | "
            "nominal cost given up | worst case gained | lower bound on the robust optimum | robust search (s) |",
            "|---|---|---|---|---|---|---|---|"]
    for r in (r for r in rows if "robust_cost" in r):
        b = "-" if r["robust_bound"] is None else f"{r['robust_bound']:.0f}"
        out.append(f"| {r['scene']} | {r['budget']} | {r['nominal_cost']:.0f} / {r['nominal_worst']:.0f} | "
                   f"{r['robust_cost']:.0f} / {r['robust_worst']:.0f} | {r['robust_cost'] - r['nominal_cost']:+.0f} | "
                   f"{r['nominal_worst'] - r['robust_worst']:.0f} | {b} | {r['robust_s']:.0f} |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()
