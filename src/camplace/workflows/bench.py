"""The paper's experiments (Tables I/II, Figs. 4/5): several solvers on the same V.

``run_bench`` computes visibility once, then for every budget N_s runs each method on
the same PlacementProblem and records the coverage optimality gap (paper eq. 8), the
share of non-triangulatable targets (seen by < 2 cameras), the solve time, the status
and the proven gap. ``write_bench`` writes bench.csv, bench.md (tables beside the
paper's numbers) and bench.png (gap and % non-triangulatable vs budget per method).

By default only volume targets count (targets='volume'), as in the paper, whose
tables cover "only the 3D walkable voxel grid"; targets='all' keeps surfaces too.
"""

from __future__ import annotations

import csv
import io
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from camplace.core.errors import InputError
from camplace.core.files import atomic_write_bytes, atomic_write_text
from camplace.problem.model import PlacementProblem

DEFAULT_METHODS = ("greedy", "mip", "paper-mip", "zhao", "horster")
LABELS = {"certify": "Certified (tabu + bounds)", "greedy": "Proposed Greedy", "mip": "Proposed MIP",
          "paper-mip": "Proposed MIP (paper model, CBC)", "zhao": "Zhao et al.", "horster": "Greedy (Hörster)", "greedy+ls": "Proposed Greedy + 1-swap",
          "greedy-ls": "Proposed Greedy + 1-swap"}
ALIASES = {"greedy+ls": "greedy-ls"}  # earlier method names -> registered solvers

# Coverage optimality gap from the paper (Tables I and II), method -> {N_s: gap}.
PAPER_TABLES: dict[str, dict[str, dict[int, float]]] = {
    "standard-store": {
        "zhao": {80: 0.0, 60: 0.01, 50: 0.03, 40: 0.04, 30: 0.09, 20: 0.23},
        "horster": {80: 0.04, 60: 0.07, 50: 0.13, 40: 0.26, 30: 0.34, 20: 0.47},
        "greedy": {80: 0.0, 60: 0.01, 50: 0.02, 40: 0.04, 30: 0.08, 20: 0.16},
        "mip": {80: 0.0, 60: 0.0, 50: 0.01, 40: 0.04, 30: 0.08, 20: 0.16},
    },
    "store-a": {
        "zhao": {100: 0.0, 80: 0.01, 60: 0.06, 40: 0.13, 20: 0.41},
        "horster": {100: 0.04, 80: 0.12, 60: 0.30, 40: 0.48, 20: 0.64},
        "greedy": {100: 0.0, 80: 0.01, 60: 0.04, 40: 0.12, 20: 0.35},
        "mip": {100: 0.0, 80: 0.01, 60: 0.04, 40: 0.12, 20: 0.34},
    },
}


@dataclass
class BenchRow:
    scene: str
    budget: int
    method: str
    cameras: int
    cost: float
    coverage_gap: float
    non_triangulatable_pct: float
    bound: float | None
    proven_gap: float | None
    status: str
    seconds: float


def restrict_targets(problem: PlacementProblem, keep: np.ndarray) -> PlacementProblem:
    """The same problem on the targets where keep (N_p,) bool is True."""
    cols = np.nonzero(keep)[0]
    tp = None if problem.target_positions is None else np.asarray(problem.target_positions)[cols]
    return replace(problem, V=problem.V[:, cols].tocsr(), gamma=problem.gamma[cols], weights=problem.weights[cols],
                   target_positions=tp)


def method_options(method: str, options: dict | None) -> dict:
    """The part of ``options`` that the solver of ``method`` takes."""
    from camplace.solvers import SOLVERS

    names = SOLVERS[ALIASES.get(method, method)].option_names
    return {k: v for k, v in (options or {}).items() if k in names}


def check_method_options(methods: Sequence[str], options: dict | None) -> None:
    """InputError(option=key) for an option no method takes or a value one of them refuses."""
    from camplace.solvers.registry import build_options, solvers_taking

    for key in options or {}:
        if not any(key in method_options(m, {key: None}) for m in methods):
            takers = solvers_taking(key)
            raise InputError(f"{key}: none of the methods {', '.join(methods)} takes option '{key}'"
                             + (f"; solvers that take it: {', '.join(takers)}" if takers else ""), option=key)
    for m in methods:
        build_options(ALIASES.get(m, m), **method_options(m, options))


def bench_problem(problem: PlacementProblem, budget: int, method: str, *, time_limit_s: float | None = None,
                  threads: int | None = None, should_stop: Callable[[], bool] | None = None,
                  scene: str = "", options: dict | None = None) -> BenchRow:
    """Run one registered solver (or an alias, ALIASES: 'greedy+ls' = 'greedy-ls') at one budget
    with the part of ``options`` it takes; score it."""
    from camplace.metrics.coverage import compute_metrics
    from camplace.solvers import solve

    p = replace(problem, budget=int(budget))
    own = {k: v for k, v in method_options(method, options).items() if k not in ("time_limit_s", "threads")}
    pl = solve(p, ALIASES.get(method, method), time_limit_s=time_limit_s, threads=threads, should_stop=should_stop,
               **own)
    m = compute_metrics(p, pl.selected)
    return BenchRow(scene, int(budget), method, int(len(pl.selected)), float(pl.objective), float(m.coverage_gap),
                    float(m.non_triangulatable_pct), pl.bound, pl.gap, pl.status, float(pl.seconds))


def run_bench(scene: str | Path, budgets: Sequence[int], methods: Sequence[str] = DEFAULT_METHODS, *,
              time_limit_s: float | None = 60.0, threads: int | None = None, targets: str = "volume",
              progress: Callable[[str, int, int], None] | None = None,
              should_stop: Callable[[], bool] | None = None,
              on_row: Callable[[list[BenchRow]], None] | None = None,
              certify_s: float | None = None, options: dict | None = None) -> tuple[str, dict, list[BenchRow]]:
    """Every method at every budget on one V. Returns (scene name, instance info, rows).
    on_row(rows so far) is called after each run (e.g. to save partial results).
    certify_s: also run the 'certify' solver (tabu + proven bounds) for that many seconds
    per budget (its row carries the bound and proven gap). options: solver options, each
    given to the methods that take it (one no method takes is an InputError)."""
    from camplace.workflows.run import prepare, problem_from_visibility
    from camplace.solvers import SOLVERS

    if certify_s is not None:
        if not certify_s > 0:
            raise InputError(f"certify_s: expected seconds > 0, got {certify_s}", option="certify_s")
        methods = [m for m in methods if m != "certify"] + ["certify"]
    for m in methods:
        if ALIASES.get(m, m) not in SOLVERS:
            raise InputError(f"methods: unknown method '{m}'; expected some of {', '.join(sorted(SOLVERS))}",
                             option="methods")
    if targets not in ("volume", "all"):
        raise InputError(f"targets: expected 'volume' or 'all', got '{targets}'", option="targets")
    check_method_options(methods, options)
    sc, vis = prepare(scene, progress)
    problem = problem_from_visibility(vis, max(budgets))
    t = vis.targets
    if targets == "volume":
        volume_regions = [r for r, k in enumerate(t.region_kinds) if k == "volume"]
        problem = restrict_targets(problem, np.isin(t.region_ids, volume_regions))
    info = {"scene": sc.name, "candidates": problem.n_candidates, "targets": problem.n_targets,
            "nonzeros": int(problem.V.nnz), "locations": int(len(np.unique(problem.location_ids))),
            "target_set": targets, "time_limit_s": time_limit_s, "threads": threads}
    rows: list[BenchRow] = []
    total = len(budgets) * len(methods)
    for b in budgets:
        for m in methods:
            if should_stop is not None and should_stop():
                return sc.name, info, rows
            if progress:
                progress("bench", len(rows), total)
            limit = certify_s if (m == "certify" and certify_s is not None) else time_limit_s
            rows.append(bench_problem(problem, b, m, time_limit_s=limit, threads=threads,
                                      should_stop=should_stop, scene=sc.name, options=options))
            if on_row:
                on_row(rows)
    if progress:
        progress("bench", len(rows), total)
    return sc.name, info, rows


def rows_csv(rows: list[BenchRow]) -> str:
    buf = io.StringIO()
    fields = list(BenchRow.__dataclass_fields__)
    w = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: ("" if v is None else (f"{v:.6g}" if isinstance(v, float) else v)) for k, v in asdict(r).items()})
    return buf.getvalue()


def _fmt(x: float | None, nd: int = 3) -> str:
    return "–" if x is None else f"{x:.{nd}f}"


def rows_markdown(scene: str, info: dict, rows: list[BenchRow], paper_key: str | None = None) -> str:
    """Tables like the paper's: one row per method, one column per budget (descending)."""
    budgets = sorted({r.budget for r in rows}, reverse=True)
    methods = list(dict.fromkeys(r.method for r in rows))
    by = {(r.method, r.budget): r for r in rows}
    head = "| method | " + " | ".join(f"N_s={b}" for b in budgets) + " |\n|---|" + "---|" * len(budgets) + "\n"
    out = [f"# camplace bench: {scene}\n",
           f"{info.get('candidates')} candidates on {info.get('locations')} locations, {info.get('targets')} "
           f"targets ({info.get('target_set')}), {info.get('nonzeros')} visible pairs; time limit "
           f"{info.get('time_limit_s')} s per MIP run, threads {info.get('threads') or 'default'}.\n",
           "\n## Coverage optimality gap (paper eq. 8; lower is better)\n\n", head]
    paper = PAPER_TABLES.get(paper_key or scene, {})
    for m in methods:
        out.append(f"| {LABELS.get(m, m)} | " + " | ".join(_fmt(by[m, b].coverage_gap) if (m, b) in by else "" for b in budgets) + " |\n")
    for m, vals in paper.items():
        out.append(f"| *paper: {LABELS.get(m, m)}* | " + " | ".join(_fmt(vals.get(b), 2) if b in vals else "" for b in budgets) + " |\n")
    out += ["\n## Non-triangulatable targets, % (seen by < 2 cameras; lower is better)\n\n", head]
    for m in methods:
        out.append(f"| {LABELS.get(m, m)} | " + " | ".join(_fmt(by[m, b].non_triangulatable_pct, 2) if (m, b) in by else "" for b in budgets) + " |\n")
    out += ["\n## Solve time s / status / proven gap\n\n", head]
    for m in methods:
        cells = []
        for b in budgets:
            r = by.get((m, b))
            cells.append("" if r is None else f"{r.seconds:.1f} / {r.status}" +
                         ("" if r.proven_gap is None else f" / {100 * r.proven_gap:.1f} %"))
        out.append(f"| {LABELS.get(m, m)} | " + " | ".join(cells) + " |\n")
    return "".join(out)


def rows_png(scene: str, rows: list[BenchRow]) -> bytes:
    """PNG: coverage gap and % non-triangulatable vs budget, one line per method."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 4), dpi=110)
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2)
    for m in dict.fromkeys(r.method for r in rows):
        rs = sorted((r for r in rows if r.method == m), key=lambda r: r.budget)
        xs = [r.budget for r in rs]
        axes[0].plot(xs, [r.coverage_gap for r in rs], marker="o", label=LABELS.get(m, m))
        axes[1].plot(xs, [r.non_triangulatable_pct for r in rs], marker="o", label=LABELS.get(m, m))
    axes[0].set(title=f"{scene}: coverage optimality gap", xlabel="cameras N_s", ylabel="gap (eq. 8)")
    axes[1].set(title=f"{scene}: non-triangulatable targets", xlabel="cameras N_s", ylabel="% seen by < 2 cameras")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def write_bench(out_dir: str | Path, scene: str, info: dict, rows: list[BenchRow]) -> dict[str, Path]:
    """Write bench.csv, bench.md and bench.png into out_dir (atomically)."""
    out = Path(out_dir)
    return {"csv": atomic_write_text(out / "bench.csv", rows_csv(rows)),
            "markdown": atomic_write_text(out / "bench.md", rows_markdown(scene, info, rows)),
            "png": atomic_write_bytes(out / "bench.png", rows_png(scene, rows))}


def read_csv(path: str | Path) -> list[BenchRow]:
    """Rows back from a bench.csv (to re-render bench.md / bench.png)."""
    rows = []
    with open(path, newline="") as f:
        for d in csv.DictReader(f):
            opt = {k: (None if d[k] == "" else float(d[k])) for k in ("bound", "proven_gap")}
            rows.append(BenchRow(d["scene"], int(d["budget"]), d["method"], int(d["cameras"]), float(d["cost"]),
                                 float(d["coverage_gap"]), float(d["non_triangulatable_pct"]), opt["bound"],
                                 opt["proven_gap"], d["status"], float(d["seconds"])))
    return rows


def parse_budgets(text: str) -> list[int]:
    """'20,30,40' -> [20, 30, 40]; InputError on anything else."""
    try:
        vals = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise InputError(f"budgets: expected comma-separated integers like 20,30,40, got '{text}'",
                         option="budgets") from None
    if not vals or min(vals) < 0:
        raise InputError(f"budgets: expected non-negative integers like 20,30,40, got '{text}'", option="budgets")
    return vals


__all__ = ["BenchRow", "DEFAULT_METHODS", "PAPER_TABLES", "bench_problem", "parse_budgets", "read_csv", "run_bench",
           "write_bench"]
