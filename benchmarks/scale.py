"""Site-scale benchmark (issue 7): time and peak memory of each stage on the procedural
warehouse at several floor areas, locally and with a local Dask cluster, and the
log-log growth exponents of the cost in N_g, N_p and nnz(V).

Each (size, mode) runs in its own subprocess so that peak memory (ru_maxrss) is that
run's alone. Modes: ``local`` (in-process, numba threads = all cores; every stage and
the solvers) and ``dask`` (visibility only, on a ``LocalCluster`` of ``--dask-workers``
single-threaded worker processes; cluster start-up timed separately). Both print a
hash of V, so the table shows the two paths gave the same matrix.

    python benchmarks/scale.py --sizes 1000 5000 10000 --dask-workers 2 \
        --out benchmarks/results/scale.json

writes the JSON and prints a markdown table (pasted into docs/benchmarks.md).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np


def _rss_peak_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _v_hash(V) -> str:
    h = hashlib.blake2b(digest_size=8)
    h.update(np.asarray(V.indptr, np.int64).tobytes())
    h.update(np.asarray(V.indices, np.int32).tobytes())
    return h.hexdigest()


def one(size: float, mode: str, dask_workers: int, solvers: list[str], budget: int | None) -> dict:
    """Run the stages of one warehouse size in this process; return the measurements."""
    from camplace.spec.builtin import resolve_scene
    from camplace.cameras.models import camera_from_spec
    from camplace.cameras.candidates import build_candidates
    from camplace.metrics.coverage import compute_metrics
    from camplace.workflows.run import problem_from_visibility
    from camplace.scene.build import build_scene
    from camplace.solvers import SOLVERS, solve
    from camplace.targets.build import build_targets
    from camplace.visibility.voxel import compute_visibility, drop_blind_candidates

    out: dict = {"size_m2": size, "mode": mode, "stages": {}, "load_avg_start": os.getloadavg()[0]}
    st = out["stages"]

    def stage(name, t0):
        st[name] = {"s": time.perf_counter() - t0, "peak_rss_mib": _rss_peak_mib()}

    t = time.perf_counter()
    spec, _, _ = resolve_scene(f"warehouse:{size:g}")
    sc = build_scene(spec)
    stage("scene", t)
    t = time.perf_counter()
    targets = build_targets(sc)
    stage("targets", t)
    t = time.perf_counter()
    cands = build_candidates(sc, {c.name: camera_from_spec(c) for c in spec.cameras})
    stage("candidates", t)
    out.update(N_g=len(cands), N_p=len(targets), occupancy_cells=int(np.prod(sc.occupancy.shape)))
    executor = None
    if mode == "dask":
        from dask.distributed import Client, LocalCluster

        from camplace.visibility.executors import DaskExecutor

        t = time.perf_counter()
        cluster = LocalCluster(n_workers=dask_workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, memory_limit=0)
        client = Client(cluster, set_as_default=False)
        executor = DaskExecutor(client=client, threads_per_task=1)
        out["dask_startup_s"] = time.perf_counter() - t
    t = time.perf_counter()
    vis = compute_visibility(sc.occupancy, targets, cands, executor=executor)
    stage("visibility", t)
    out.update(nnz=int(vis.V.nnz), V_hash=_v_hash(vis.V), V_mib=(vis.V.data.nbytes + vis.V.indices.nbytes
                                                                  + vis.V.indptr.nbytes) / 2**20)
    if executor is not None:
        executor.client.close()
        cluster.close()
        return out
    t = time.perf_counter()
    vis = drop_blind_candidates(vis)
    b = spec.placement.budget if budget is None else budget
    problem = problem_from_visibility(vis, b)
    stage("problem", t)
    out["budget"] = b
    out["solvers"] = {}
    for name in solvers:
        if name not in SOLVERS:
            continue
        t = time.perf_counter()
        p = solve(problem, name)
        stage(f"solve:{name}", t)
        t = time.perf_counter()
        m = compute_metrics(problem, p.selected, vis.targets.region_ids, vis.targets.region_names)
        stage(f"metrics:{name}", t)
        out["solvers"][name] = {"objective": p.objective, "coverage_gap": m.coverage_gap,
                                "cameras": int(len(p.selected)),
                                "reduction_s": p.info.get("reduction", {}).get("seconds"),
                                "order_hash": hashlib.blake2b(np.asarray(p.info.get("order", []), np.int64).tobytes(),
                                                              digest_size=8).hexdigest(),
                                "selected_hash": hashlib.blake2b(
                                    np.asarray(p.selected, np.int64).tobytes(), digest_size=8).hexdigest()}
    return out


def _fit(x: list[float], y: list[float]) -> float | None:
    """Least-squares slope of log y against log x (None with fewer than 2 distinct x)."""
    x, y = np.log(np.asarray(x, float)), np.log(np.asarray(y, float))
    if len(x) < 2 or np.ptp(x) == 0:
        return None
    return float(np.polyfit(x, y, 1)[0])


def table(results: list[dict]) -> str:
    loc = [r for r in results if r["mode"] == "local"]
    dsk = {r["size_m2"]: r for r in results if r["mode"] == "dask"}
    lines = ["| floor m² | N_g | N_p | nnz(V) | V MiB | scene+targets+cand. s | visibility s | "
             "solve s (greedy / greedy-fast) | peak RSS MiB | Dask 2w visibility s (+start) | speed-up | same V |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in loc:
        s = r["stages"]
        prep = s["scene"]["s"] + s["targets"]["s"] + s["candidates"]["s"]
        solves = " / ".join(f"{s[k]['s']:.1f}" for k in ("solve:greedy", "solve:greedy-fast") if k in s)
        peak = max(v["peak_rss_mib"] for v in s.values())
        d = dsk.get(r["size_m2"])
        if d:
            dv = d["stages"]["visibility"]["s"]
            dcol = f"{dv:.1f} (+{d['dask_startup_s']:.1f})"
            spd = f"{s['visibility']['s'] / dv:.2f}×"
            same = "yes" if d["V_hash"] == r["V_hash"] else "NO"
        else:
            dcol = spd = same = "-"
        lines.append(f"| {r['size_m2']:,.0f} | {r['N_g']:,} | {r['N_p']:,} | {r['nnz']:,} | {r['V_mib']:.0f} | "
                     f"{prep:.1f} | {s['visibility']['s']:.1f} | {solves} | {peak:,.0f} | {dcol} | {spd} | {same} |")
    if len(loc) >= 2:
        vt = [r["stages"]["visibility"]["s"] for r in loc]
        fits = [f"visibility time ∝ nnz^{_fit([r['nnz'] for r in loc], vt):.2f}",
                f"∝ N_g^{_fit([r['N_g'] for r in loc], vt):.2f}",
                f"∝ N_p^{_fit([r['N_p'] for r in loc], vt):.2f}",
                f"(N_g·N_p)^{_fit([r['N_g'] * r['N_p'] for r in loc], vt):.2f}",
                f"nnz ∝ N_g^{_fit([r['N_g'] for r in loc], [r['nnz'] for r in loc]):.2f}"]
        for k in ("solve:greedy", "solve:greedy-fast"):
            if all(k in r["stages"] for r in loc):
                fits.append(f"{k.split(':')[1]} time ∝ nnz^{_fit([r['nnz'] for r in loc], [r['stages'][k]['s'] for r in loc]):.2f}")
        fits.append(f"peak RSS ∝ nnz^{_fit([r['nnz'] for r in loc], [max(v['peak_rss_mib'] for v in r['stages'].values()) for r in loc]):.2f}")
        lines.append("")
        lines.append("Log-log fits over the sizes: " + ", ".join(fits) + ".")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=float, nargs="+", default=[1000, 5000, 10000])
    ap.add_argument("--dask-workers", type=int, default=2, help="0 = skip the Dask runs")
    ap.add_argument("--solvers", nargs="+", default=["greedy", "greedy-fast"])
    ap.add_argument("--budget", type=int, default=None, help="default: the scene's (area / 25 m²)")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--one", type=float, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--mode", default="local", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one is not None:
        print(json.dumps(one(a.one, a.mode, a.dask_workers, a.solvers, a.budget)))
        return
    results = []
    for size in a.sizes:
        for mode in ("local", "dask") if a.dask_workers > 0 else ("local",):
            cmd = [sys.executable, __file__, "--one", str(size), "--mode", mode, "--dask-workers",
                   str(a.dask_workers), "--solvers", *a.solvers] + (["--budget", str(a.budget)] if a.budget else [])
            print(f"# {' '.join(cmd[1:])}", file=sys.stderr, flush=True)
            p = subprocess.run(cmd, capture_output=True, text=True)
            if p.returncode != 0:
                print(p.stderr[-3000:], file=sys.stderr)
                raise SystemExit(p.returncode)
            r = json.loads(p.stdout.strip().splitlines()[-1])
            print(json.dumps(r), file=sys.stderr, flush=True)
            results.append(r)
    meta = {"cpu_count": os.cpu_count(), "load_avg_end": os.getloadavg(), "when": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    if a.out:
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(json.dumps({"meta": meta, "results": results}, indent=1))
    print(table(results))
    print(f"\n{meta}")


if __name__ == "__main__":
    main()
