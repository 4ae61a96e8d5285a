"""Site-scale benchmark (issues 7, 21): time and peak memory of each stage on the procedural
warehouse at several floor areas, locally and with a local Dask cluster, and the
log-log growth exponents of the cost in N_g, N_p and nnz(V).

``--run`` (issue 21) measures instead the whole pipeline as ``camplace run`` does it
(camplace.workflows.run.run with the block cache, out-of-core V, then every output file
with the report and the plan set): per stage the wall time and the peak resident memory
(VmRSS, and its anonymous part RssAnon: the memory-mapped V is file-backed page cache that
the kernel can drop) sampled every 50 ms from /proc/self/status, plus VmHWM at the end.

    python benchmarks/scale.py --run --sizes 10000 30000 100000 --solvers greedy-fast \
        --out benchmarks/results/scale_run.json

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
import contextlib
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


def _v_hash(V, chunk: int = 1 << 26) -> str:
    """BLAKE2b-64 of V's indptr (int64) and indices (int32), fed in slices without a copy of
    a memory-mapped V (its pages released after each slice): the hash of the whole bytes,
    without the benchmark itself raising the run's peak memory (issue 37)."""
    from camplace.core.memory import release_pages

    h = hashlib.blake2b(digest_size=8)
    for a in (np.asarray(V.indptr, np.int64), np.asarray(V.indices, np.int32)):
        a = np.ascontiguousarray(a)
        for i in range(0, len(a), chunk):
            h.update(memoryview(a[i:i + chunk]).cast("B"))
            release_pages(a)
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

        from camplace.core.executors import DaskExecutor

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


def _proc_status() -> dict[str, float]:
    """VmRSS, RssAnon, RssFile, VmHWM of this process in MiB (Linux /proc/self/status)."""
    out = {}
    try:
        with open("/proc/self/status") as f:
            for line in f:
                k, _, v = line.partition(":")
                if k in ("VmRSS", "RssAnon", "RssFile", "VmHWM"):
                    out[k] = float(v.split()[0]) / 1024.0
    except OSError:
        pass
    return out


class StageSampler:
    """Wall time and peak memory per pipeline stage: ``progress(stage, done, total)`` marks
    the current stage; a thread samples /proc/self/status every ``every_s`` seconds."""

    def __init__(self, every_s: float = 0.05) -> None:
        import threading

        self.stage = "start"
        self.stages: dict[str, dict] = {}
        self._t = time.perf_counter()
        self._enter("start")
        self._stop = threading.Event()
        self._th = threading.Thread(target=self._loop, args=(every_s,), daemon=True)
        self._th.start()

    def _enter(self, name: str) -> None:
        now = time.perf_counter()
        if self.stage in self.stages:
            self.stages[self.stage]["s"] += now - self._t
        self._t = now
        self.stage = name
        self.stages.setdefault(name, {"s": 0.0, "peak_rss_mib": 0.0, "peak_anon_mib": 0.0})
        self._sample()

    def _sample(self) -> None:
        m = _proc_status()
        st = self.stages[self.stage]
        st["peak_rss_mib"] = max(st["peak_rss_mib"], m.get("VmRSS", 0.0))
        st["peak_anon_mib"] = max(st["peak_anon_mib"], m.get("RssAnon", 0.0))

    def _loop(self, every_s: float) -> None:
        while not self._stop.wait(every_s):
            self._sample()

    def __call__(self, stage: str, done: int, total: int) -> None:
        name = {"greedy": "solve", "tabu": "solve", "mip": "solve"}.get(stage, stage)
        if name != self.stage:
            self._enter(name)

    def close(self) -> dict:
        self._enter("end")
        self._stop.set()
        self._th.join()
        self.stages.pop("end", None)
        return self.stages


@contextlib.contextmanager
def timed_output_parts(parts: dict[str, float]):
    """Inside the block, the seconds of each part of write_outputs go into ``parts``: the
    contract's visibility.npz (AtomicBatch.stage_savez) and each part of the report set
    (ReportParts.run: exports, figures, plan set, report.html). Issue 37."""
    from camplace.core.files import AtomicBatch
    from camplace.outputs.write import ReportParts

    savez, run_part = AtomicBatch.stage_savez, ReportParts.run

    def timed(name, f, *a, **k):
        t = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            parts[name] = parts.get(name, 0.0) + time.perf_counter() - t

    AtomicBatch.stage_savez = lambda self, path, **k: timed(Path(path).name, savez, self, path, **k)
    ReportParts.run = lambda self, name, write: timed(name, run_part, self, name, write)
    try:
        yield parts
    finally:
        AtomicBatch.stage_savez, ReportParts.run = savez, run_part


def run_one(size: float, solver: str, budget: int | None, cache: Path, out_dir: Path | None,
            time_limit_s: float) -> dict:
    """camplace run warehouse:<size> end to end in this process (cache at ``cache``,
    outputs and plan set into ``out_dir``); per-stage time and memory."""
    from camplace.outputs.write import write_outputs
    from camplace.workflows.run import run

    sampler = StageSampler()
    t0 = time.perf_counter()
    r = run(f"warehouse:{size:g}", budget=budget, solver=solver, progress=sampler, cache_dir=cache,
            time_limit_s=time_limit_s)
    sampler("outputs", 0, 1)
    t = time.perf_counter()
    parts: dict[str, float] = {}
    if out_dir is not None:  # None: --no-outputs
        with timed_output_parts(parts):
            write_outputs(out_dir, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics,
                          r.timings_s, scene=r.scene)
    report_s = time.perf_counter() - t
    total = time.perf_counter() - t0
    st = sampler.close()
    hwm = _proc_status().get("VmHWM")  # the run's peak, before the benchmark hashes V
    red = r.placement.info.get("reduction", {})
    return {"size_m2": size, "mode": "run", "solver": solver, "N_g": int(r.visibility.V.shape[0]),
            "N_p": int(r.visibility.V.shape[1]), "nnz": int(r.visibility.V.nnz), "V_hash": _v_hash(r.visibility.V),
            "cached_chunks": r.visibility.info.get("cached_chunks"), "chunks": r.visibility.info.get("chunks"),
            "stages": st, "timings_s": dict(r.timings_s, report=report_s), "output_parts_s": parts, "total_s": total,
            "reduction_s": red.get("seconds"), "nnz_reduced": red.get("nonzeros_after"),
            "objective": r.placement.objective, "coverage_gap": r.metrics.coverage_gap,
            "cameras": int(len(r.placement.selected)), "status": r.placement.status,
            "VmHWM_mib": hwm, "ru_maxrss_mib": _rss_peak_mib(), "load_avg": os.getloadavg()[0]}


def tiled_one(size: float, copies: int, solver: str, cache: Path, work: Path, time_limit_s: float) -> dict:
    """The stages after visibility on ``copies`` side-by-side copies of warehouse:<size>'s V
    (block diagonal: a floor ``copies`` times larger, with that many independent halls),
    V memory-mapped from files written block by block; per-stage time and memory.
    Measures the out-of-core stages at a size whose raycasting is too slow for this box."""
    import scipy.sparse as sp

    from camplace.metrics.coverage import compute_metrics
    from camplace.metrics.triangulation import well_triangulated_of_selection
    from camplace.problem.feasibility import check_feasibility
    from camplace.problem.model import PlacementProblem
    from camplace.solvers import solve
    from camplace.workflows.run import prepare

    sampler = StageSampler()
    sampler("prepare (cached V)", 0, 1)
    _, vis = prepare(f"warehouse:{size:g}", cache_dir=cache)
    V1, t1, c1 = vis.V, vis.targets, vis.candidates
    n1, m1, z1 = V1.shape[0], V1.shape[1], int(V1.nnz)
    sampler("tile V to disk", 0, 1)
    work.mkdir(parents=True, exist_ok=True)
    fmt = np.lib.format
    indices = fmt.open_memmap(work / "indices.npy", mode="w+", dtype=np.int32, shape=(z1 * copies,))
    data = fmt.open_memmap(work / "data.npy", mode="w+", dtype=np.uint8, shape=(z1 * copies,))
    base_ptr = np.asarray(V1.indptr, np.int64)
    indptr = np.concatenate([base_ptr[:-1] + k * z1 for k in range(copies)] + [[z1 * copies]])
    for k in range(copies):
        indices[k * z1:(k + 1) * z1] = np.asarray(V1.indices) + k * m1
        data[k * z1:(k + 1) * z1] = 1
    indices.flush()
    data.flush()
    del indices, data
    V = sp.csr_matrix((np.load(work / "data.npy", mmap_mode="r"), np.load(work / "indices.npy", mmap_mode="r"),
                       indptr), shape=(n1 * copies, m1 * copies), copy=False)
    width = float(np.ptp(c1.positions[:, 0])) + 20.0
    shift = lambda p, k: p + np.array([k * width, 0.0, 0.0])  # noqa: E731
    cand_pos = np.concatenate([shift(c1.positions, k) for k in range(copies)])
    targ_pos = np.concatenate([shift(t1.positions, k) for k in range(copies)])
    gamma, weights = np.tile(t1.gamma, copies), np.tile(t1.weights, copies)
    loc = np.concatenate([c1.location_ids + k * (int(c1.location_ids.max()) + 1) for k in range(copies)])
    regions = np.tile(t1.region_ids, copies)
    sampler("feasibility", 0, 1)
    check_feasibility(V, gamma, loc, regions, t1.region_names)
    budget = 400 * copies if size == 10000 else int(round(size * copies / 25.0))
    problem = PlacementProblem(V, gamma, weights, budget, loc, np.ones(V.shape[0]), None,
                               candidate_positions=cand_pos, target_positions=targ_pos)
    sampler("solve", 0, 1)
    p = solve(problem, solver, time_limit_s=time_limit_s)
    sampler("metrics", 0, 1)
    well = well_triangulated_of_selection(V, cand_pos, targ_pos, p.selected)
    m = compute_metrics(problem, p.selected, regions, t1.region_names, well_triangulated=well)
    sampler("visibility.npz", 0, 1)
    from camplace.core.files import atomic_savez

    atomic_savez(work / "visibility.npz", data=V.data, indices=V.indices, indptr=V.indptr)
    st = sampler.close()
    red = p.info.get("reduction", {})
    return {"size_m2": size * copies, "mode": "tiled", "tiles_of": size, "copies": copies, "solver": solver,
            "N_g": int(V.shape[0]), "N_p": int(V.shape[1]), "nnz": int(V.nnz), "stages": st,
            "reduction_s": red.get("seconds"), "nnz_reduced": red.get("nonzeros_after"),
            "objective": p.objective, "coverage_gap": m.coverage_gap,
            "cameras": int(len(p.selected)), "total_s": sum(v["s"] for v in st.values()),
            "VmHWM_mib": _proc_status().get("VmHWM"), "load_avg": os.getloadavg()[0]}


def run_table(results: list[dict]) -> str:
    """Markdown: per size, each stage's seconds and peak RSS / anonymous MiB; then log-log fits."""
    names = []
    for r in results:
        names += [k for k in r["stages"] if k not in names and k != "start"]
    head = "| floor m² | nnz(V) | " + " | ".join(names) + " | total s | VmHWM MiB |"
    lines = ["Each stage: seconds / peak RSS MiB / peak anonymous MiB.", "", head, "|" + "---|" * (len(names) + 4)]
    for r in results:
        cells = []
        for k in names:
            v = r["stages"].get(k)
            cells.append("-" if v is None else f"{v['s']:.1f} s / {v['peak_rss_mib']:,.0f} / {v['peak_anon_mib']:,.0f}")
        lines.append(f"| {r['size_m2']:,.0f} | {r['nnz']:,} | " + " | ".join(cells)
                     + f" | {r['total_s']:.0f} | {r['VmHWM_mib']:,.0f} |")
    if len(results) >= 2:
        nnz = [r["nnz"] for r in results]
        fits = []
        for k in names:
            if all(k in r["stages"] and r["stages"][k]["s"] > 0 for r in results):
                e_t = _fit(nnz, [r["stages"][k]["s"] for r in results])
                e_m = _fit(nnz, [max(r["stages"][k]["peak_anon_mib"], 1.0) for r in results])
                fits.append(f"{k}: time ∝ nnz^{e_t:.2f}, anon. memory ∝ nnz^{e_m:.2f}")
        fits.append(f"total: time ∝ nnz^{_fit(nnz, [r['total_s'] for r in results]):.2f}, "
                    f"VmHWM ∝ nnz^{_fit(nnz, [r['VmHWM_mib'] for r in results]):.2f}")
        lines += ["", "Log-log fits over the sizes: " + "; ".join(fits) + "."]
    return "\n".join(lines)


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


def _child(cmd: list[str]) -> dict:
    """Run one measurement in a fresh process (its own peak memory); its JSON line."""
    print(f"# {' '.join(cmd[1:])}", file=sys.stderr, flush=True)
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        print(p.stderr[-3000:], file=sys.stderr)
        raise SystemExit(p.returncode)
    r = json.loads(p.stdout.strip().splitlines()[-1])
    print(json.dumps(r), file=sys.stderr, flush=True)
    return r


def _save(out: Path | None, results: list[dict]) -> dict:
    """Write {meta, results} to ``out`` (when given) and print the meta line; returns meta."""
    meta = {"cpu_count": os.cpu_count(), "load_avg_end": os.getloadavg(),
            "when": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    if out:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps({"meta": meta, "results": results}, indent=1))
    print(f"{meta}", file=sys.stderr)
    return meta


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=float, nargs="+", default=[1000, 5000, 10000])
    ap.add_argument("--dask-workers", type=int, default=2, help="0 = skip the Dask runs")
    ap.add_argument("--solvers", nargs="+", default=["greedy", "greedy-fast"])
    ap.add_argument("--budget", type=int, default=None, help="default: the scene's (area / 25 m²)")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--run", action="store_true", help="end to end as camplace run (one solver: the first)")
    ap.add_argument("--cache", type=Path, default=None, help="--run: the visibility cache (default a temp folder)")
    ap.add_argument("--outputs", type=Path, default=None, help="--run: where the outputs go (default a temp folder)")
    ap.add_argument("--time-limit", type=float, default=600.0, help="--run: the solver's time limit, s")
    ap.add_argument("--no-outputs", action="store_true", help="--run: stop after the metrics (no files written)")
    ap.add_argument("--tiled", type=int, default=0, metavar="K",
                    help="the stages after visibility on K side-by-side copies of each size's (cached) V")
    ap.add_argument("--one", type=float, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--mode", default="local", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one is not None and a.mode == "tiled":
        print(json.dumps(tiled_one(a.one, a.tiled, a.solvers[0], a.cache, a.outputs, a.time_limit)))
        return
    if a.one is not None and a.mode == "run":
        print(json.dumps(run_one(a.one, a.solvers[0], a.budget, a.cache, None if a.no_outputs else a.outputs,
                                 a.time_limit)))
        return
    if a.one is not None:
        print(json.dumps(one(a.one, a.mode, a.dask_workers, a.solvers, a.budget)))
        return
    if a.tiled:
        import tempfile

        results = []
        for size in a.sizes:
            with tempfile.TemporaryDirectory(prefix="camplace-tiled-", dir=a.outputs) as tmp:
                cmd = [sys.executable, __file__, "--one", str(size), "--mode", "tiled", "--tiled", str(a.tiled),
                       "--solvers", a.solvers[0], "--cache", str(a.cache), "--outputs", tmp,
                       "--time-limit", str(a.time_limit)]
                results.append(_child(cmd))
        _save(a.out, results)
        print(run_table(results))
        return
    if a.run:
        import tempfile

        results = []
        with tempfile.TemporaryDirectory(prefix="camplace-scale-") as tmp:
            for size in a.sizes:
                cache = a.cache or Path(tmp) / "cache"
                outd = (a.outputs or Path(tmp) / "out") / f"warehouse-{size:g}"
                cmd = [sys.executable, __file__, "--one", str(size), "--mode", "run", "--solvers", a.solvers[0],
                       "--cache", str(cache), "--outputs", str(outd), "--time-limit", str(a.time_limit)]
                cmd += (["--budget", str(a.budget)] if a.budget else []) + (["--no-outputs"] if a.no_outputs else [])
                results.append(_child(cmd))
        _save(a.out, results)
        print(run_table(results))
        return
    results = []
    for size in a.sizes:
        for mode in ("local", "dask") if a.dask_workers > 0 else ("local",):
            cmd = [sys.executable, __file__, "--one", str(size), "--mode", mode, "--dask-workers",
                   str(a.dask_workers), "--solvers", *a.solvers] + (["--budget", str(a.budget)] if a.budget else [])
            results.append(_child(cmd))
    _save(a.out, results)
    print(table(results))


if __name__ == "__main__":
    main()
