"""The end of a run or an evaluation: write the outputs, show the log, and print the
summary (a rich table, the folder with --quiet, or a JSON document with --json)."""

from __future__ import annotations

import json
import time
from pathlib import Path

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from camplace.cli.common import console, state
from camplace.outputs.writers import file_list


def json_summary(result, out_dir: Path, paths: dict, plan: dict | None = None) -> dict:
    """The --json summary: the placement's headline figures, every metrics.json figure as
    written, where the files are, and a plan's import summary (``plan``, when given)."""
    p = result.placement
    metrics = json.loads(Path(paths["metrics.json"]).read_text())
    return {"scene": result.scene.name, "solver": p.solver, "status": p.status, "budget": int(result.problem.budget),
            "n_cameras": int(len(p.selected)), "objective": float(p.objective),
            "bound": None if p.bound is None else float(p.bound), "gap": p.gap, **metrics,
            "out_dir": str(out_dir), "files": {k: str(v) for k, v in sorted(paths.items())},
            **({"plan": plan} if plan is not None else {})}


def _show_log(result, paths: dict, out_dir: Path) -> None:
    """Warnings always; the pipeline log unless --quiet; solver info and files with --verbose."""
    for line in result.log:
        if line.startswith("warning:"):
            console.print(f"[yellow]{escape(line)}[/yellow]", soft_wrap=True)
        elif not state["quiet"]:
            console.print(f"[dim]{escape(line)}[/dim]")
    if not state["verbose"]:
        return
    for k, v in result.placement.info.items():
        if isinstance(v, (int, float, str, bool)) or v is None:
            console.print(f"[dim]solver {escape(str(k))}: {escape(str(v))}[/dim]")
    groups: dict[str, list[str]] = {}
    for name in sorted(paths):
        groups.setdefault(name.split("/")[0] + "/" if "/" in name else name, []).append(name)
    for key, names in groups.items():
        where = out_dir / key if key.endswith("/") else paths[key]
        more = f" ({len(names)} files)" if key.endswith("/") else ""
        console.print(f"[dim]wrote {escape(str(where))}{more}[/dim]")


def _table(result, out_dir: Path, paths: dict, skipped: list[str] = ()) -> Table:
    p, m = result.placement, result.metrics
    t = Table(title=f"camplace - {result.scene.name}", show_header=False)
    t.add_row("solver / status", f"{p.solver} / {p.status}")
    t.add_row("cameras (budget)", f"{len(p.selected)} ({result.problem.budget})")
    grid = getattr(m, "grid_cost", None)
    t.add_row("cost", f"{p.objective:.6g}" + (f"  (grid {grid:.6g}, before refine)" if grid is not None
                                               and abs(grid - p.objective) > 1e-9 else ""))
    t.add_row("bound", "-" if p.bound is None else f"{p.bound:.6g} (gap {100 * (p.gap or 0):.2f} %)")
    t.add_row("coverage gap (eq. 8)", f"{m.coverage_gap:.4f}")
    t.add_row("non-triangulatable", f"{m.non_triangulatable_pct:.2f} %")
    if m.well_triangulated_pct is not None:
        t.add_row("well triangulated", f"{m.well_triangulated_pct:.2f} % (rays meet at a usable angle)")
    for st in getattr(m, "storeys", None) or []:  # a building (issue 33): one row per storey
        cap = "" if st["budget"] is None else f" (at most {st['budget']})"
        t.add_row(f"  storey {st['storey']}", f"{st['cameras']} cameras{cap}, floor at {st['elevation_m']:g} m, "
                                             f"{st['targets']} targets, gap {st['coverage_gap']:.4f}")
    for name, r in m.regions.items():
        t.add_row(f"  region {name}", f"{r['targets']} targets, gap {r['coverage_gap']:.4f}, "
                                     f"non-tri {r['non_triangulatable_pct']:.1f} %")
    for label, value in crowd_rows(m):
        t.add_row(label, value)
    t.add_row("timings (s)", ", ".join(f"{k} {v:.2f}" for k, v in result.timings_s.items()))
    t.add_row("outputs", str(out_dir))
    t.add_row("files", ", ".join(file_list(paths)))  # what the writers returned (camplace.outputs.writers)
    if "report.html" in paths:
        t.add_row("report", str(paths["report.html"]))
    if "preview.png" in paths:
        t.add_row("plan preview", str(paths["preview.png"]))
    if skipped:
        t.add_row("skipped (interrupted)", ", ".join(skipped))
    return t


def crowd_rows(m) -> list[tuple[str, str]]:
    """The summary's rows about the crowd (none without one): mean ± std over the held-out samples."""
    c = m.crowd.to_dict() if getattr(m, "crowd", None) is not None else None
    if c is None:
        return []
    pm = lambda d, nd, unit="": f"{d['mean']:.{nd}f}{unit} ± {d['std']:.{nd}f}"  # noqa: E731
    head = (f"{c['samples']} held-out crowds of {c['persons']['mean']:.0f} people ({c['density']:g} /m²"
            + (", optimised for" if c.get("optimised") else "") + ")")
    rows = [("in a crowd", head), ("  crowd coverage gap", pm(c["coverage_gap"], 4)),
            ("  seen by ≥ Γ in the crowd", pm(c["seen_by_gamma_pct"], 1, " %")),
            ("  triangulatable in the crowd", pm(c["triangulatable_pct"], 1, " %"))]
    ppl = c.get("people")
    if ppl:  # issue 36: the people themselves
        g = ppl["gamma"]
        rows.append(("  people seen by ≥ 2 cameras", pm(ppl["seen_by_2_pct"], 1, " %")))
        if g != 2:
            rows.append((f"  people seen by ≥ {g} cameras", pm(ppl["seen_by_gamma_pct"], 1, " %")))
        rows += [(f"    people in {name}", f"seen by ≥ 2 {r['seen_by_2_pct']['mean']:.1f} %"
                                          + (f", ≥ {g} {r['seen_by_gamma_pct']['mean']:.1f} %" if g != 2 else ""))
                 for name, r in ppl.get("regions", {}).items()]
    for name, r in c.get("regions", {}).items():
        rows.append((f"    region {name}", f"gap {r['coverage_gap']['mean']:.4f}, seen ≥ Γ "
                                             f"{r['seen_by_gamma_pct']['mean']:.1f} %, triangulatable "
                                             f"{r['triangulatable_pct']['mean']:.1f} %"))
    return rows


def write_and_summarise(result, out_dir: Path, repeatable: bool = False, frame: str = "scene", plan: bool = True,
                        paper: str = "A3", extra: dict | None = None, stop=None) -> None:
    """Write every output of ``result`` into ``out_dir`` (poses in ``frame``; the plan set on
    ``paper`` unless not ``plan``) and print the summary; ``extra``: files written besides
    ({'files': {name: path}, 'plan': a plan's import summary}, camplace.cli.plan_preview.run_extra).
    ``stop`` (camplace.cli.common.StopFlag): after a Ctrl-C the contract files come first and
    fast, then the report set as far as it fits the time after the interrupt (the parts left
    out are listed as skipped)."""
    from camplace.outputs.write import write_outputs

    p = result.placement
    t0 = time.perf_counter()
    skipped: list[str] = []
    watch = {} if stop is None else {"compressed": not stop(), "on_contract": stop.contract_written,
                                     "deadline": stop.report_deadline, "skipped": skipped}
    paths = write_outputs(out_dir, result.scene.name, result.visibility, p, result.problem.budget, result.metrics,
                          result.timings_s, repeatable=repeatable, scene=result.scene, frame=frame, plan=plan,
                          paper=paper, problem=result.problem, **watch)
    if stop is not None:
        stop.finished()
    result.timings_s["report"] = time.perf_counter() - t0
    paths.update((extra or {}).get("files", {}))
    _show_log(result, paths, out_dir)
    if state["json"]:
        summary = json_summary(result, out_dir, paths, (extra or {}).get("plan"))
        typer.echo(json.dumps(dict(summary, **({"skipped": skipped} if skipped else {})), indent=2))
    elif state["quiet"]:
        typer.echo(str(out_dir))
    else:
        Console().print(_table(result, out_dir, paths, skipped))
