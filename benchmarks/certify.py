"""Benchmarks of issue 11 (certified placements): the anytime engine vs 10-minute baselines.

Usage (one job at a time on a 2-core machine; each writes one JSON line per instance):
    python benchmarks/certify.py highs   --out benchmarks/results/certify-highs.jsonl  [--time 600]
    python benchmarks/certify.py papermip --out benchmarks/results/certify-papermip.jsonl [--time 600]
    python benchmarks/certify.py engine  --out benchmarks/results/certify-engine.jsonl [--time 600]
    python benchmarks/certify.py hull --time 10 --out benchmarks/results/certify-hull.jsonl  # issue 37, §10
    python benchmarks/certify.py table      # the docs/results.md table from benchmarks/results/*.jsonl
Instances: standard-store at N_s = 20, 40, 60, 80 and store-a at N_s = 40 (`--only scene:N` to pick).
The engine run records the incumbent and bound it held at 10 s, 60 s and the end.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

INSTANCES = [("standard-store", 20), ("standard-store", 40), ("standard-store", 60), ("standard-store", 80),
             ("store-a", 40)]


CACHE = Path(__file__).resolve().parent / "results" / "instances"


def _problem(scene: str, budget: int):
    """The instance, from a cached visibility.npz when present (the same matrix for
    every method of a session), else built (and cached)."""
    from camplace.problem.instance import load_problem_npz, save_problem_npz

    path = CACHE / f"{scene}.npz"
    if not path.is_file():
        from camplace.workflows.run import prepare, problem_from_visibility

        _, vis = prepare(scene)
        CACHE.mkdir(parents=True, exist_ok=True)
        save_problem_npz(path, problem_from_visibility(vis, budget))
    return load_problem_npz(path, budget)[0]


def run_highs(problem, time_s: float, log_file: str | None) -> dict:
    """HiGHS branch-and-cut on the tight convex model, threads=1, warm start from greedy."""
    import highspy

    from camplace.solvers.bounds import build_highs
    from camplace.solvers.greedy import solve_greedy

    t0 = time.perf_counter()
    g = solve_greedy(problem)
    h, n_x = build_highs(problem, integer=True, threads=1, time_limit_s=time_s, log_file=log_file)
    build_s = time.perf_counter() - t0
    x = np.zeros(n_x)
    x[g.selected] = 1.0
    d = np.maximum(problem.gamma - problem.coverage(g.selected), 0)
    u = np.concatenate([(np.arange(1, gj + 1) <= dj).astype(float) for gj, dj in zip(problem.gamma, d)])
    sol = highspy.HighsSolution()
    sol.col_value = list(np.concatenate([x, u]))
    sol.value_valid = True
    h.setSolution(sol)
    t1 = time.perf_counter()
    h.run()
    info = h.getInfo()
    col = np.array(h.getSolution().col_value[:n_x])
    sel = np.flatnonzero(col > 0.5)
    return {"method": "highs-tight-mip", "greedy": g.objective, "objective": float(problem.cost(sel)),
            "highs_objective": float(info.objective_function_value), "bound": float(info.mip_dual_bound),
            "status": h.modelStatusToString(h.getModelStatus()), "nodes": int(info.mip_node_count),
            "build_s": round(build_s, 2), "solve_s": round(time.perf_counter() - t1, 2)}


def run_papermip(problem, time_s: float) -> dict:
    from camplace.solvers import SOLVERS

    if "paper-mip" not in SOLVERS:
        return {"method": "paper-mip", "error": "solver paper-mip not registered"}
    t0 = time.perf_counter()
    p = SOLVERS["paper-mip"](problem, time_limit_s=time_s, threads=1)
    return {"method": "paper-mip", "objective": float(problem.cost(p.selected)), "bound": p.bound,
            "status": p.status, "seconds": round(time.perf_counter() - t0, 2)}


def run_engine(problem, time_s: float, **options) -> dict:
    from camplace.solvers.certify import solve_certify

    import scipy.sparse as sp

    from camplace.problem.model import PlacementProblem

    # warm the numba caches (compiled once per install; not part of the solve)
    rng = np.random.default_rng(0)
    tiny = PlacementProblem(sp.csr_matrix((rng.random((30, 40)) < 0.3).astype(np.uint8)), rng.integers(0, 4, 40),
                            np.ones(40), 3, rng.integers(0, 10, 30))
    solve_certify(tiny, time_limit_s=0.5, threads=2)
    trace: list[dict] = []
    t0 = time.perf_counter()

    def on_state(state: dict) -> None:
        trace.append({"t": round(time.perf_counter() - t0, 2), **state})

    p = solve_certify(problem, time_limit_s=time_s, threads=2, seed=0, on_state=on_state, **options)
    snaps = {}
    for mark in (10, 60, time_s):
        before = [s for s in trace if s["t"] <= mark + 1e-9]
        if before:
            s = before[-1]
            snaps[str(int(mark))] = {"objective": s["objective"], "bound": s["bound"]}
    return {"method": "certify", "objective": p.objective, "bound": p.bound, "gap": p.gap,
            "incumbent_method": p.info.get("incumbent_method"), "bound_method": p.info.get("bound_method"),
            "snapshots": snaps, "seconds": round(time.perf_counter() - t0, 2), "trace": trace[-200:],
            "lp": p.info.get("lp"), "region": p.info.get("region"),
            "selected": np.isin(np.arange(problem.n_candidates), p.selected)}


def run_hull(problem, time_s: float) -> dict:
    """Issue 37: the per-target decomposition bound (certify.md §10) against today's bounds,
    each given `time_s`: (a) the certify engine (incumbent + bound, threads 2); (b) the
    coverage-row Lagrangian alone, started from (a)'s incumbent; (c) the per-target ascent
    from the same start; (d) the per-target ascent started where (b) ended."""
    from camplace.solvers.bounds import Lagrangian, lagrangian_bound
    from camplace.solvers.target_hull import target_hull_bound

    eng = run_engine(problem, time_s)
    sel = np.flatnonzero(eng.pop("selected"))
    ub, cov = float(problem.cost(sel)), problem.coverage(sel)
    lam0 = Lagrangian(problem).initial_multipliers(cov)
    lag = lagrangian_bound(problem, time_limit_s=time_s, incumbent_cost=ub, lam0=lam0)
    hull = target_hull_bound(problem, lam0, time_limit_s=time_s, incumbent_cost=ub)
    after = target_hull_bound(problem, lag.multipliers, time_limit_s=time_s, incumbent_cost=ub)
    row = lambda r: {"bound": r.bound, "seconds": round(r.seconds, 2), **{k: v for k, v in r.info.items()}}
    return {"method": "hull", "incumbent": ub, "engine_bound": eng["bound"], "engine_seconds": eng["seconds"],
            "lagrangian": row(lag), "target_hull": row(hull), "target_hull_after_lagrangian": row(after)}


def _ceil(b):
    return None if b is None else float(np.ceil(b - 1e-6))  # unit weights: costs are integers (docs/certify.md §4)


def table(results_dir: Path) -> str:
    """The docs/results.md table from the three .jsonl files."""
    def load(name):
        f = results_dir / f"certify-{name}.jsonl"
        rows = [json.loads(line) for line in f.read_text().splitlines()] if f.is_file() else []
        return {(r["scene"], r["budget"]): r for r in rows}

    eng, hig, pm = load("engine"), load("highs"), load("papermip")
    eng_by = {"10": load("engine-10"), "60": load("engine-60")}  # separate runs with that time limit
    head = ("| instance | N_s | engine 10 s cost / bound | engine 60 s cost / bound | engine 600 s cost / bound "
            "(gap) | HiGHS tight 600 s cost / bound | paper-mip CBC 600 s cost / bound |")
    lines = [head, "|" + "---|" * 7]
    fmt = lambda o, b: f"{o:,.0f} / {max(0.0, b):,.0f}" if b is not None else f"{o:,.0f} / -"  # noqa: E731
    for scene, n in INSTANCES:
        cells = [scene, str(n)]
        for mark in ("10", "60", "600"):
            e = eng_by.get(mark, {}).get((scene, n)) or eng.get((scene, n))
            s = (e or {}).get("snapshots", {}).get(mark)
            if e is not None and int(e["time_limit_s"]) == int(mark):
                s = {"objective": e["objective"], "bound": e["bound"]}  # the run's final answer
            if s is None:
                cells.append("not run")
            else:
                b = _ceil(s["bound"])
                gap = (s["objective"] - b) / s["objective"] if s["objective"] > 0 else 0.0
                cells.append(fmt(s["objective"], b) + (f" ({100 * gap:.1f} %)" if mark == "600" else ""))
        h = hig.get((scene, n))
        cells.append(fmt(h["objective"], _ceil(h["bound"])) if h else "not run")
        q = pm.get((scene, n))
        known = min([r["objective"] for d in (eng, hig, pm, *eng_by.values()) for r in [d.get((scene, n))]
                     if r and "objective" in r])
        if q and q.get("bound") is not None and q["bound"] > known + 0.5:
            q = dict(q, bound=None)  # reported a "bound" above a known placement: not a bound (see text)
        cells.append((fmt(q["objective"], _ceil(q["bound"])) if "objective" in q else q.get("error", "?")) if q else "not run")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    if argv is None and len(sys.argv) > 1 and sys.argv[1] == "table":
        print(table(Path(sys.argv[2]) if len(sys.argv) > 2 else Path(__file__).resolve().parent / "results"))
        return
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=["highs", "papermip", "engine", "hull"])
    ap.add_argument("--out", required=True)
    ap.add_argument("--time", type=float, default=600.0)
    ap.add_argument("--only", action="append", default=None, help="scene:N, repeatable")
    ap.add_argument("--region", action="store_true", help="engine: also the region decomposition bound")
    a = ap.parse_args(argv)
    todo = INSTANCES if not a.only else [(s.split(":")[0], int(s.split(":")[1])) for s in a.only]
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    for scene, n in todo:
        prob = _problem(scene, n)
        t0 = time.perf_counter()
        if a.what == "highs":
            res = run_highs(prob, a.time, str(out.with_suffix("")) + f"-{scene}-{n}.log")
        elif a.what == "papermip":
            res = run_papermip(prob, a.time)
        elif a.what == "hull":
            res = run_hull(prob, a.time)
        else:
            res = run_engine(prob, a.time, **({"region": True} if a.region else {}))
            res.pop("selected")
        res.update({"scene": scene, "budget": n, "time_limit_s": a.time,
                    "wall_s": round(time.perf_counter() - t0, 2)})
        with out.open("a") as f:
            f.write(json.dumps(res) + "\n")
        print(json.dumps({k: v for k, v in res.items() if k != "trace"}), file=sys.stderr, flush=True)


if __name__ == "__main__":
    main()
