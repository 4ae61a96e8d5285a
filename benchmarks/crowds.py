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
        [--solvers greedy,tabu] [--time-limit 60] [--samples 64] [--score-samples 32]
        [--workers N | --scheduler tcp://HOST:PORT] [--timing-only] [--refine SECONDS]

``--refine SECONDS``: the CLI's default path instead — ``camplace.run`` with the solver and
then the refinement off the grid (``SECONDS`` each; the crowd-aware one scores its trial
poses on its crowds), both placements scored the same way.
Issue 36: the placements are also scored on the people themselves (% of the held-out
crowds' people seen by ≥ 2 / ≥ Γ^p cameras, camplace.workflows.crowd), the crowd-aware
one is the people-aware problem (camplace.problem.people; ``--people-weight``, default the
scene's) over the candidates plus the steep pitches a crowd-aware run offers
(``--no-steep``: without them); ``--no-timing`` skips timing V and V_s; ``--count-weight`` β and
``--max-cost-rise`` the cost cap of ``people_cost: count``.
``--timing-only``: V and V_s times only (no placements), e.g. on a site-scale scene
(``--scene warehouse:5000``) with V_s on a process pool (``--workers 2``) or a Dask cluster.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

from camplace.metrics.crowd import sample_figures
from camplace.problem.crowd import sample_coverage
from camplace.solvers import solve
from camplace.spec.crowd import CrowdSpec
from camplace.targets.crowd import SCORE, sample_crowds
from camplace.targets.people import people_targets, person_coverage
from camplace.visibility.crowd import crowd_rows, people_grid
from camplace.visibility.people import people_rows
from camplace.visibility.registry import engine_of
from camplace.visibility.engine import compute_visibility
from camplace.visibility.voxel import VoxelEngine
from camplace.workflows.crowd import crowd_problem, score_in_crowd
from camplace.workflows.run import prepare, problem_from_visibility


def timed(fn, *args, **kw):
    t0 = time.perf_counter()
    out = fn(*args, **kw)
    return out, time.perf_counter() - t0


def per_sample(sc, vis, selected, crowd: CrowdSpec) -> dict[str, np.ndarray]:
    """The crowd figures of ``selected`` in each held-out crowd: name -> (S,)."""
    held = sample_crowds(sc, crowd, SCORE)
    sel = np.asarray(selected, np.int64)
    rows = crowd_rows(vis.V[sel], vis.candidates.positions[sel], vis.targets.positions, held)
    cov = sample_coverage(rows, held.n_samples, np.arange(len(sel)))
    t = vis.targets
    figs = [sample_figures(t.gamma, t.weights, c) for c in cov]
    return {**{k: np.array([f[k] for f in figs]) for k in figs[0]}, **people_per_sample(sc, vis, selected, crowd)}


def people_per_sample(sc, vis, selected, crowd: CrowdSpec) -> dict[str, np.ndarray]:
    """% of the persons of each held-out crowd seen by ≥ 2 / ≥ Γ^p cameras: name -> (S,)."""
    held = sample_crowds(sc, crowd, SCORE)
    people = people_targets(held, vis.targets, crowd.people_heights, crowd.people_gamma)
    fp = np.asarray(sc.footprint, float)
    seen = people_rows(engine_of(vis), sc.occupancy, people, vis.candidates.subset(np.asarray(selected, np.int64)),
                       people_grid(held, fp.min(0), fp.max(0)))
    cov = person_coverage(np.asarray(seen.sum(axis=0)).ravel(), people.n_heights)
    who = np.repeat(np.arange(held.n_samples), held.counts)
    n = np.maximum(held.counts, 1)
    return {f"people_seen_by_{k}_pct": 100.0 * np.bincount(who, weights=(cov >= g), minlength=held.n_samples) / n
            for k, g in (("2", 2), ("gamma", crowd.people_gamma))}


def paired(a: dict, b: dict) -> dict:
    """b − a per held-out crowd (the same crowds): mean, standard error, crowds where b is better."""
    out = {}
    for k, better in (("coverage_gap", -1), ("triangulatable_pct", 1), ("seen_by_gamma_pct", 1),
                      ("people_seen_by_2_pct", 1), ("people_seen_by_gamma_pct", 1)):
        d = b[k] - a[k]
        out[k] = {"mean": float(d.mean()), "stderr": float(d.std(ddof=1) / np.sqrt(len(d))),
                  "better_in": int(np.sum(better * d > 0)), "of": int(len(d))}
    return out


def scores(sc, vis, problem, selected, crowd: CrowdSpec) -> dict:
    m = score_in_crowd(sc, vis, selected, crowd).summary
    out = {k: m[k] for k in ("coverage_gap", "seen_by_gamma_pct", "triangulatable_pct")}
    out.update({f"people_{k}": m["people"][k] for k in ("seen_by_2_pct", "seen_by_gamma_pct")})
    out["selected"] = [int(i) for i in selected]
    cov = problem.coverage(selected)
    out["empty_store_gap"] = problem.cost(selected) / problem.normalizer
    out["empty_store_triangulatable_pct"] = 100.0 * float(np.mean(cov >= 2))
    return out


def refined(a, solver: str, opts: dict, crowd: CrowdSpec) -> dict:
    """Both placements through camplace.run with the refinement (the CLI's default path)."""
    from camplace.workflows.run import run

    got, per = {}, {}
    for name, aware in (("empty-store", False), ("crowd-aware", True)):
        keys = {"density": crowd.density, "samples": crowd.samples, "score_samples": crowd.score_samples,
                "seed": crowd.seed, "optimise": aware or None, "people_weight": crowd.people_weight,
                "people_gamma": crowd.people_gamma, "people_cost": crowd.people_cost,
                "people_count_weight": crowd.people_count_weight, "max_cost_rise": crowd.max_cost_rise}
        r, t = timed(run, a.scene, a.budget, solver, refine=True, refine_time_s=a.refine, crowd=keys, **opts)
        c = r.metrics.crowd.to_dict()
        cov = r.problem.coverage(r.placement.selected)
        got[name] = {"solve_seconds": r.timings_s["solve"] + r.timings_s.get("refine", 0.0), "run_seconds": t,
                     **{k: c[k] for k in ("coverage_gap", "seen_by_gamma_pct", "triangulatable_pct")},
                     **{f"people_{k}": c["people"][k] for k in ("seen_by_2_pct", "seen_by_gamma_pct")},
                     "in_sample_gap": float("nan") if not aware else c["optimisation"]["coverage_gap"],
                     "empty_store_gap": r.metrics.coverage_gap,
                     "empty_store_triangulatable_pct": 100.0 * float(np.mean(cov >= 2))}
        per[name] = per_sample(r.scene, r.visibility, r.placement.selected, crowd)
    got["paired"] = paired(per["empty-store"], per["crowd-aware"])
    return got


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="standard-store")
    ap.add_argument("--budget", type=int, default=40)
    ap.add_argument("--densities", default="0.3,1.0")
    ap.add_argument("--solvers", default="greedy,tabu")
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--samples", type=int, default=CrowdSpec().samples)
    ap.add_argument("--score-samples", type=int, default=32)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--scheduler", default=None)
    ap.add_argument("--timing-only", action="store_true")
    ap.add_argument("--refine", type=float, default=None)
    ap.add_argument("--people-weight", type=float, default=None)
    ap.add_argument("--people-gamma", type=int, default=None)
    ap.add_argument("--people-cost", choices=("count", "squared"), default=None)
    ap.add_argument("--count-weight", type=float, default=None)
    ap.add_argument("--max-cost-rise", type=float, default=None,
                    help="the cost cap of people_cost count (default the scene's; a huge value: no cap)")
    ap.add_argument("--no-timing", action="store_true", help="skip timing V and V_s (placements only)")
    ap.add_argument("--no-steep", action="store_true", help="no steep candidate pitches for the crowd-aware placement")
    a = ap.parse_args()
    from camplace.core.executors import make_executor

    sc, vis = prepare(a.scene, workers=a.workers, scheduler=a.scheduler)
    p = problem_from_visibility(vis, a.budget)
    steep = () if a.no_steep else tuple(CrowdSpec(density=1.0, optimise=True).offers_steep())
    # the crowd-aware placement chooses among the same poses and the steep views a crowd-aware run offers
    sc2, vis2 = (sc, vis) if not steep else prepare(a.scene, workers=a.workers, scheduler=a.scheduler,
                                                      extra_pitches=steep)
    p2 = problem_from_visibility(vis2, a.budget)
    V = vis.V
    v_s = [] if a.no_timing else [timed(compute_visibility, VoxelEngine(), sc.occupancy, vis.targets,
                                         vis.candidates)[1] for _ in range(2)]
    res = {"scene": a.scene, "budget": a.budget, "V": list(V.shape), "nnz": int(V.nnz), "V_seconds": v_s,
           "load_average": os.getloadavg(), "cpus": os.cpu_count(), "samples": a.samples,
           "score_samples": a.score_samples, "time_limit_s": a.time_limit, "densities": {}}
    rows = []
    for d in (float(x) for x in a.densities.split(",")):
        pw = {} if a.people_weight is None else {"people_weight": a.people_weight}
        if a.people_gamma is not None:
            pw["people_gamma"] = a.people_gamma
        if a.people_cost is not None:
            pw["people_cost"] = a.people_cost
        if a.count_weight is not None:
            pw["people_count_weight"] = a.count_weight
        if a.max_cost_rise is not None:
            pw["max_cost_rise"] = a.max_cost_rise
        crowd = CrowdSpec(density=d, samples=a.samples, score_samples=a.score_samples, seed=a.seed, **pw)
        crowds = sample_crowds(sc, crowd)
        per = []
        with make_executor(a.workers, a.scheduler) as ex:
            for _ in range(0 if a.no_timing else 2):
                out, t = timed(crowd_rows, V, vis.candidates.positions, vis.targets.positions, crowds, executor=ex)
                per.append(t / crowds.n_samples)
        if a.timing_only:
            res["densities"][str(d)] = {"persons": float(np.mean(crowds.counts)), "V_s_seconds_per_sample": per,
                                        "kept_pct": 100.0 * out.nnz / (V.nnz * crowds.n_samples),
                                        "executor": getattr(ex, "name", "in-process")}
            print(f"density {d:g}: V {min(v_s):.2f} s, V_s {min(per):.3f} s per sample ({a.workers} workers)",
                  file=sys.stderr, flush=True)
            continue
        cp, t_build = timed(crowd_problem, sc2, vis2, p2, crowd)
        entry = {"persons": float(np.mean(crowds.counts)),
                 "kept_pct": None if a.no_timing else 100.0 * out.nnz / (V.nnz * crowds.n_samples),
                 "V_s_seconds_per_sample": per, "crowd_problem_seconds": t_build,
                 "stacked": [int(v) for v in cp.problem.V.shape], "stacked_nnz": int(cp.problem.V.nnz), "solvers": {}}
        for solver in a.solvers.split(","):
            opts = {} if solver.startswith("greedy") else {"time_limit_s": a.time_limit}
            if a.refine is not None:
                got = refined(a, solver, opts, crowd)
            else:
                e, te = timed(solve, p, solver, **opts)
                c, tc = timed(solve, cp.problem, solver, **opts)
                c = cp.count_step(cp.problem, c)  # people_cost count: the swap descent (as camplace.run)
                got = {"empty-store": {"solve_seconds": te, **scores(sc, vis, p, e.selected, crowd)},
                       "crowd-aware": {"solve_seconds": tc, "in_sample_gap": cp.problem.cost(c.selected) / cp.problem.normalizer,
                                       **scores(sc2, vis2, p2, c.selected, crowd)}}
                ce = crowd_problem(sc, vis, p, crowd).problem
                got["empty-store"]["in_sample_gap"] = ce.cost(e.selected) / ce.normalizer
                got["paired"] = paired(per_sample(sc, vis, e.selected, crowd),
                                       per_sample(sc2, vis2, c.selected, crowd))
            entry["solvers"][solver] = got
            for name in ("empty-store", "crowd-aware"):
                g = got[name]
                rows.append(f"| {a.scene} | {d:g} | {solver} | {name} | {g['people_seen_by_2_pct']['mean']:.1f} ± "
                            f"{g['people_seen_by_2_pct']['std']:.1f} | {g['people_seen_by_gamma_pct']['mean']:.1f} | "
                            f"{g['coverage_gap']['mean']:.4f} ± "
                            f"{g['coverage_gap']['std']:.4f} | {g['triangulatable_pct']['mean']:.2f} | "
                            f"{g['seen_by_gamma_pct']['mean']:.2f} | {g['in_sample_gap']:.4f} | "
                            f"{g['empty_store_gap']:.4f} | {g['empty_store_triangulatable_pct']:.2f} | "
                            f"{g['solve_seconds']:.1f} |")
            pr = got["paired"]
            print(rows[-2], rows[-1], f"paired (crowd-aware − empty-store): people seen by ≥ 2 "
                  f"{pr['people_seen_by_2_pct']['mean']:+.2f} ± {pr['people_seen_by_2_pct']['stderr']:.2f} (better "
                  f"in {pr['people_seen_by_2_pct']['better_in']}/{pr['people_seen_by_2_pct']['of']}), gap {pr['coverage_gap']['mean']:+.4f} ± "
                  f"{pr['coverage_gap']['stderr']:.4f} (better in {pr['coverage_gap']['better_in']}/"
                  f"{pr['coverage_gap']['of']}), triangulatable {pr['triangulatable_pct']['mean']:+.2f} ± "
                  f"{pr['triangulatable_pct']['stderr']:.2f} (better in {pr['triangulatable_pct']['better_in']})",
                  sep="\n", file=sys.stderr, flush=True)
        res["densities"][str(d)] = entry
    res["load_average_end"] = os.getloadavg()
    text = json.dumps(res, indent=2)
    print(text)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text + "\n")
    print("| scene | density /m² | solver | placement | people seen by ≥ 2 % (mean ± std) | people seen by ≥ Γ^p % | "
          "held-out crowd gap (mean ± std) | triangulatable in crowd % | "
          "seen ≥ Γ in crowd % | crowd gap on its own crowds | empty-store gap | empty-store triangulatable % | "
          "solve s |", file=sys.stderr)
    print("\n".join(rows), file=sys.stderr)


if __name__ == "__main__":
    main()
