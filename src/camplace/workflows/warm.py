"""Warm numba's on-disk cache in the background on a fresh install.

The first ``camplace run`` after an install compiles every numba kernel it meets: the
visibility kernel first (≈ 9 CPU s), then, once V exists, the solver's, the reduction's,
the metrics' and the report's (ray caster, viewsheds) — and matplotlib builds its font
cache. Only the first is needed at once. So while the run compiles the visibility kernel,
a second process (``python -m camplace.workflows.warm SOLVER``) runs every stage after
visibility on the built-in ``demo`` scene with a stand-in V (the same code paths and array
types), and those kernels are in the cache when the run reaches them: on two cores the
compiling happens side by side (docs/benchmarks.md, first run). It is started only when
the cache looks cold and the machine has a second core; the run stops it when it ends.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

import numpy as np
import scipy.sparse as sp


def cache_is_cold() -> bool:
    """True when the report's ray caster has no numba cache index yet (a fresh install or
    an empty NUMBA_CACHE_DIR); False when it has one, or when that cannot be told."""
    try:
        from camplace.visibility.raywalk import _cast_rays_kernel

        return not os.path.exists(_cast_rays_kernel._cache._cache_file._index_path)
    except Exception:  # noqa: BLE001 - numba's cache internals: when in doubt, do nothing
        return False


def start(solver: str | None) -> subprocess.Popen | None:
    """The background warm-up for ``solver`` (default greedy), or None when the cache is warm
    or there is one core only. Its output goes nowhere; Ctrl-C does not reach it."""
    if (os.cpu_count() or 1) < 2 or not cache_is_cold():
        return None
    try:
        return subprocess.Popen([sys.executable, "-m", "camplace.workflows.warm", solver or "greedy"],
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)
    except OSError:
        return None


def stop(proc: subprocess.Popen | None) -> None:
    """End the warm-up if it still runs (what it compiled stays cached: numba writes atomically)."""
    if proc is not None and proc.poll() is None:
        proc.kill()
        proc.wait()


def warm(solver: str) -> None:
    """The visibility kernel's line-of-sight walk and pixel density first (numba's cache serves
    a kernel's callees too: the run, compiling the kernel's own code meanwhile, loads them),
    then every stage after visibility on the demo scene with a stand-in V: the solver (its
    dry run included), the metrics and the whole report set, written to a temporary folder."""
    from camplace.cameras.models import N_PARAMS, px_per_m_nb

    px_per_m_nb(np.zeros(N_PARAMS), 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
    from camplace.visibility.raywalk import segment_clear

    segment_clear(np.zeros((1, 1, 1), np.uint8), 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.5)
    from camplace.cameras.candidates import build_candidates
    from camplace.outputs.write import write_outputs
    from camplace.problem.feasibility import check_feasibility
    from camplace.visibility.engine import Visibility, drop_blind_candidates
    from camplace.solvers import solve
    from camplace.workflows.run import placement_metrics, problem_from_visibility, scene_inputs

    sc, targets, cameras, _ = scene_inputs("demo")
    cands = build_candidates(sc, cameras)
    V = sp.random(len(cands), len(targets), density=0.05, format="csr", random_state=0)
    V = sp.csr_matrix((np.ones(V.nnz, np.uint8), V.indices, V.indptr), shape=V.shape)
    V.indices.flags.writeable = V.data.flags.writeable = False  # as the visibility cache's memory maps: numba
    # compiles a read-only array's kernels apart from a writable one's (a run without the cache compiles its own)
    vis = drop_blind_candidates(Visibility(V, cands, targets))
    tg = vis.targets
    check_feasibility(vis.V, tg.gamma, vis.candidates.location_ids, tg.region_ids, tg.region_names)
    problem = problem_from_visibility(vis, 4)
    placement = solve(problem, solver, time_limit_s=1.0)
    metrics = placement_metrics(vis, problem, placement.selected)
    with tempfile.TemporaryDirectory(prefix="camplace-warm-") as out:
        write_outputs(out, "demo", vis, placement, 4, metrics, {}, scene=sc, problem=problem)


if __name__ == "__main__":
    warm(sys.argv[1] if len(sys.argv) > 1 else "greedy")
