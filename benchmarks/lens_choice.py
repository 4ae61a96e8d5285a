"""Lens choice (issue 27) on a scene whose cameras come from a catalogue (default the
built-in lens-store: DORI zones, the example catalogue of typical camera classes).

V is computed once over every model and focal setting; each variant is the same problem
restricted to the rows of some models (a row depends only on its own camera, so this is
the V each variant's own run would compute):

- ``<model> only`` for each fixed-focal model (the "single fixed lens" designs),
- ``fixed lenses only`` (every fixed-focal model, no varifocal),
- ``full catalogue`` (every model, varifocal lenses at their focal settings).

1. At the same money budget (``--money``, default the scene's) and camera budget, each
   variant is solved (``--solver``, default mip: HiGHS warm-started from the cost-scaled
   greedy, with its bound) and its coverage cost (shortfall) reported; ``--refine S`` also refines the full
   catalogue's placement for S seconds (focal lengths move continuously).
2. The same coverage for less money: ``min-cameras`` (least total price, a MIP with a proven
   lower bound) must reach a coverage cost, once on the fixed lenses only and once on the
   full catalogue (``--cover-time-limit`` each): the cost ``fixed lenses only`` reached in 1
   (target ``fixed``), and the cost the full catalogue reached in 1 (target ``full``; when
   the fixed lenses cannot reach it at any price, min-cameras says so and returns the
   cheapest set at the least cost they can reach).

Writes one JSON object to stdout.

    python benchmarks/lens_choice.py [lens-store] [--money 20] [--solver mip] [--time-limit 120]
                                     [--cover-time-limit 300] [--refine 60]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from camplace.solvers import solve
from camplace.visibility.engine import Visibility
from camplace.workflows.run import prepare, problem_from_visibility


def restrict(vis: Visibility, names: set[str]) -> Visibility:
    """The rows of ``vis`` whose camera model is one of ``names``."""
    c = vis.candidates
    keep = np.flatnonzero([c.cameras[k].name in names for k in c.camera_ids])
    return Visibility(vis.V[keep], c.subset(keep), vis.targets, vis.mode, dict(vis.info))


def describe(vis: Visibility, placement) -> dict:
    """What a placement bought: cost, coverage gap, cameras, total price, models with focal lengths."""
    c = vis.candidates
    cams = [c.cameras[int(c.camera_ids[i])] for i in placement.selected]
    prob_norm = float(np.dot(vis.targets.weights, vis.targets.gamma.astype(float) ** 2))
    return {"cost": float(placement.objective), "coverage_gap": float(placement.objective) / prob_norm,
            "cameras": len(cams), "price": round(float(sum(m.cost for m in cams)), 6), "status": placement.status,
            "seconds": round(placement.seconds, 2),
            "models": sorted(f"{m.name}@{m.focal_mm:.1f}mm" for m in cams)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scene", nargs="?", default="lens-store")
    ap.add_argument("--money", type=float, default=None, help="money budget (default: the scene's)")
    ap.add_argument("--budget", type=int, default=None, help="camera budget (default: the scene's)")
    ap.add_argument("--solver", default="mip")
    ap.add_argument("--time-limit", type=float, default=120.0, help="seconds per solve in part 1")
    ap.add_argument("--cover-time-limit", type=float, default=300.0, help="seconds per min-cameras solve in part 2")
    ap.add_argument("--refine", type=float, default=0.0, help="seconds of refinement of the full catalogue's placement")
    a = ap.parse_args()
    t = time.perf_counter()
    sc, vis = prepare(a.scene)
    spec = sc.spec
    money = spec.placement.money_budget if a.money is None else a.money
    budget = spec.placement.budget if a.budget is None else a.budget
    models = {m.name: m for m in vis.candidates.cameras}
    fixed = sorted(n for n, m in models.items() if m.lens is None or not m.lens.varifocal)
    variants = {**{f"{n} only": {n} for n in fixed}, "fixed lenses only": set(fixed), "full catalogue": set(models)}
    out: dict = {"scene": a.scene, "candidates": int(vis.V.shape[0]), "targets": int(vis.V.shape[1]),
                 "money_budget": money, "budget": budget, "solver": a.solver,
                 "prepare_s": round(time.perf_counter() - t, 1), "same_money": {}, "same_coverage": {}}
    sub = {}
    for name, names in variants.items():
        sub[name] = restrict(vis, names)
        prob = problem_from_visibility(sub[name], budget, money)
        p = solve(prob, a.solver, time_limit_s=a.time_limit)
        out["same_money"][name] = dict(describe(sub[name], p), bound=p.bound)
    singles = {k: v for k, v in out["same_money"].items() if k.endswith(" only") and k != "fixed lenses only"}
    out["best_single_fixed"] = min(singles, key=lambda k: singles[k]["cost"])
    if a.refine > 0:
        from camplace.improve.refine import refine_placement

        prob = problem_from_visibility(sub["full catalogue"], budget, money)
        grid = solve(prob, a.solver, time_limit_s=a.time_limit)
        rf = refine_placement(sc, sub["full catalogue"], prob, grid, time_limit_s=a.refine)
        out["same_money"]["full catalogue + refine"] = describe(rf.visibility, rf.placement)
    for which, variant in (("fixed", "fixed lenses only"), ("full", "full catalogue")):
        target = out["same_money"][variant]["cost"]
        res = out["same_coverage"][which] = {"max_cost": target}
        for name in ("fixed lenses only", "full catalogue"):
            prob = problem_from_visibility(sub[name], budget, None)
            p = solve(prob, "min-cameras", time_limit_s=a.cover_time_limit, max_cost=target, minimize="price")
            res[name] = dict(describe(sub[name], p), lower_bound=p.info.get("lower_bound"),
                             proven_minimal=p.info.get("proven_minimal"),
                             target_unreachable=bool(p.info.get("target_unreachable", False)))
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
