"""The first run after an install: `pip install -e . && camplace demo` on a fresh clone.

Clones the repository (its HEAD) into a temporary folder, makes a fresh virtual
environment, installs the clone into it (timed), then runs `camplace demo` twice with
empty caches (numba's cache beside the fresh sources, an empty visibility cache, an empty
matplotlib cache): the first run is what a new user waits for, the second the same run
once everything is compiled and cached. Each run's wall time (and the CPU time of its
processes, which a busy machine stretches far less) is split by the stage lines
camplace prints when stderr is not a terminal (start-up = until the first stage). The load
average is recorded with the numbers: on a shared machine they move with it.

    python benchmarks/first_run.py                       # the full measurement (install from the index)
    python benchmarks/first_run.py --system-site-packages --no-deps   # quick: reuse the installed dependencies
    python benchmarks/first_run.py --out benchmarks/results/first_run.jsonl

Prints a table and (``--out``) appends one JSON line.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def load() -> list[float]:
    return [round(x, 2) for x in os.getloadavg()]


def cpu_children() -> float:
    """CPU seconds (user + system) of the finished child processes so far (their children included)."""
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(cmd: list[str], env: dict, cwd: Path, log: Path) -> tuple[float, list[tuple[float, str]], int]:
    """(wall seconds, [(seconds since start, stage name)], exit code) of ``cmd``."""
    t0 = time.perf_counter()
    stages: list[tuple[float, str]] = []
    with open(log, "w") as f:
        proc = subprocess.Popen(cmd, env=env, cwd=cwd, stdout=f, stderr=subprocess.PIPE, text=True)

        def read() -> None:
            for line in proc.stderr:
                f.write(line)
                if line.startswith("stage: "):
                    stages.append((time.perf_counter() - t0, line[7:].strip()))

        th = threading.Thread(target=read, daemon=True)
        th.start()
        rc = proc.wait()
        th.join()
    return time.perf_counter() - t0, stages, rc


def stage_seconds(wall: float, stages: list[tuple[float, str]]) -> dict[str, float]:
    """Seconds per stage from the stage lines: 'start-up' until the first, each stage until the
    next, the last one (outputs) until the process ends."""
    out = {"start-up": round(stages[0][0], 2) if stages else round(wall, 2)}
    for (t, name), nxt in zip(stages, [*stages[1:], (wall, "")]):
        out[name] = round(out.get(name, 0.0) + nxt[0] - t, 2)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repo", type=Path, default=REPO, help="repository to clone (default: this one)")
    ap.add_argument("--work", type=Path, default=None, help="folder for the clone and the venv (default: a temp dir)")
    ap.add_argument("--system-site-packages", action="store_true", help="venv sees the installed dependencies")
    ap.add_argument("--no-deps", action="store_true", help="pip install --no-deps (with --system-site-packages)")
    ap.add_argument("--keep", action="store_true", help="keep the clone and the venv")
    ap.add_argument("--out", type=Path, default=None, help="append the result as a JSON line")
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="camplace-first-run-")) if args.work is None else args.work
    work.mkdir(parents=True, exist_ok=True)
    clone, venv = work / "clone", work / "venv"
    result: dict = {"repo": str(args.repo), "cores": os.cpu_count(), "load_before": load(),
                    "mode": "system-site-packages" if args.system_site_packages else "fresh venv"}
    try:
        subprocess.run(["git", "clone", "-q", "--no-hardlinks", str(args.repo), str(clone)], check=True)
        result["commit"] = subprocess.run(["git", "-C", str(clone), "rev-parse", "--short", "HEAD"],
                                          capture_output=True, text=True).stdout.strip()
        subprocess.run([sys.executable, "-m", "venv", *(["--system-site-packages"] if args.system_site_packages
                                                         else []), str(venv)], check=True)
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR", "VIRTUAL_ENV")}
        env.update(PATH=f"{venv / 'bin'}:{env.get('PATH', '')}", CAMPLACE_CACHE=str(work / "camplace-cache"),
                   MPLCONFIGDIR=str(work / "matplotlib"), HOME=env.get("HOME", str(work)))
        t = time.perf_counter()
        pip = [str(venv / "bin" / "pip"), "install", "-q", *(["--no-deps"] if args.no_deps else []), "-e", str(clone)]
        subprocess.run(pip, check=True, env=env, cwd=work, stdout=subprocess.DEVNULL)
        result["install_s"] = round(time.perf_counter() - t, 1)
        for run in ("first", "second"):
            cmd = [str(venv / "bin" / "camplace"), "demo", "--out", str(work / f"out-{run}")]
            c0 = cpu_children()
            wall, stages, rc = timed(cmd, env, work, work / f"{run}.log")
            cpu = cpu_children() - c0
            if rc != 0:
                raise SystemExit(f"{run} demo failed (exit {rc}); see {work / f'{run}.log'}")
            metrics = json.loads((work / f"out-{run}" / "metrics.json").read_text())
            result[run] = {"wall_s": round(wall, 1), "cpu_s": round(cpu, 1), "stages_s": stage_seconds(wall, stages),
                           "timings_s": {k: round(v, 2) for k, v in metrics["timings_s"].items()}}
        result["load_after"] = load()
    finally:
        if not args.keep and args.work is None:
            shutil.rmtree(work, ignore_errors=True)
    print(f"commit {result.get('commit')} ({result['mode']}), {result['cores']} cores, load {result['load_before']} "
          f"-> {result.get('load_after')}; install {result.get('install_s')} s")
    for run in ("first", "second"):
        if run in result:
            parts = ", ".join(f"{k} {v}" for k, v in result[run]["stages_s"].items())
            print(f"{run:6s} demo {result[run]['wall_s']:6.1f} s ({result[run]['cpu_s']:.1f} CPU s): {parts}")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        with open(args.out, "a") as f:
            f.write(json.dumps(result) + "\n")


if __name__ == "__main__":
    main()
