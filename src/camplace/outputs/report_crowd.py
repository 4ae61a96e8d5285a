"""report.html's crowd part (issue 28): the placement in held-out crowds.

- ``crowd_traces``: one sampled crowd in the 3D view (each person a cylinder);
- ``crowd_map_figure``: at one target height, the share of the held-out crowds in which
  a person standing at each spot is seen by ≥ 2 cameras (issue 36; without it: the spot
  itself), a heatmap over the coverage slice's layout;
- ``crowd_section``: the figures of metrics.json ``crowd`` (mean ± std over the samples,
  overall and per region) beside the empty-store ones.
"""

from __future__ import annotations

import html
from dataclasses import dataclass, field

import numpy as np

from camplace.outputs.figures import SceneView, coverage_slices
from camplace.outputs.report_figures import slice_figure

SIDES = 12  # facets of a drawn person
PERSON_COLOUR = "#8d6e63"
P2_SCALE = [[0.0, "#d62728"], [0.5, "#ffdd57"], [1.0, "#2ca02c"]]


def cylinder_mesh(xy: np.ndarray, radius: float, height: float, sides: int = SIDES) -> tuple[np.ndarray, np.ndarray]:
    """Closed cylinders standing on z = 0 at centres xy (n, 2): (vertices (n·(2k+2), 3), triangles (n·4k, 3))."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    a = 2 * np.pi * np.arange(sides) / sides
    ring = np.c_[np.cos(a), np.sin(a)] * radius
    one = np.r_[np.c_[ring, np.zeros(sides)], np.c_[ring, np.full(sides, height)], [[0, 0, 0], [0, 0, height]]]
    k = np.arange(sides)
    nxt = (k + 1) % sides
    bc, tc = 2 * sides, 2 * sides + 1
    tri = np.r_[np.c_[k, nxt, sides + k], np.c_[nxt, sides + nxt, sides + k],
                np.c_[np.full(sides, bc), nxt, k], np.c_[np.full(sides, tc), sides + k, sides + nxt]]
    n, m = len(xy), len(one)
    verts = (one[None, :, :] + np.c_[xy, np.zeros(n)][:, None, :]).reshape(-1, 3)
    tris = (tri[None, :, :] + (np.arange(n) * m)[:, None, None]).reshape(-1, 3)
    return verts, tris


def crowd_traces(shown: np.ndarray, radius: float, height: float) -> list[dict]:
    """The 3D view's trace of one sampled crowd (empty list when nobody is in it)."""
    if len(shown) == 0:
        return []
    v, t = cylinder_mesh(shown, radius, height)
    return [{"type": "mesh3d", "x": np.round(v[:, 0], 3).tolist(), "y": np.round(v[:, 1], 3).tolist(),
             "z": np.round(v[:, 2], 3).tolist(), "i": t[:, 0].tolist(), "j": t[:, 1].tolist(), "k": t[:, 2].tolist(),
             "color": PERSON_COLOUR, "opacity": 0.55, "flatshading": True, "showlegend": True,
             "name": f"people (one crowd sample, {len(shown)})", "hoverinfo": "name"}]


def crowd_map_figure(view: SceneView, positions: np.ndarray, is_surface: np.ndarray, p2: np.ndarray,
                     height: float, cameras: list[dict], person: bool = False) -> dict | None:
    """Heatmap of p2 (N_p,) share of crowds in which each target is seen by ≥ 2 cameras, at
    the volume targets of ``height`` (m); None without volume targets there. ``person``: p2
    is the chance that a person standing at each spot is seen by ≥ 2 (triangulatable)."""
    sl = next((s for s in coverage_slices(view, positions, is_surface, p2) if abs(s.height - height) < 1e-6), None)
    if sl is None:
        return None
    fig = slice_figure(sl, view, cameras)
    z = [[None if v != v else round(float(v), 4) for v in row] for row in sl.coverage]
    fig["data"][0] = {"type": "heatmap", "x": np.round(sl.x, 3).tolist(), "y": np.round(sl.y, 3).tolist(), "z": z,
                      "zmin": 0.0, "zmax": 1.0, "colorscale": P2_SCALE, "hoverongaps": False,
                      "colorbar": {"title": {"text": "P(seen by \u2265 2)"}, "tickformat": ".0%", "len": 0.8},
                      "hovertemplate": "(%{x}, %{y}) m: seen by \u2265 2 cameras in %{z:.0%} of the crowds"
                                       "<extra></extra>"}
    fig["layout"]["title"]["text"] = (
        "chance that a person standing here is triangulatable (each of its points seen by \u2265 2 cameras) in the "
        "crowd" if person else f"chance of being seen by \u2265 2 cameras in the crowd, z = {height:.2f} m")
    if person:
        fig["data"][0]["hovertemplate"] = ("(%{x}, %{y}) m: a person here is seen by \u2265 2 cameras in %{z:.0%} of "
                                           "the crowds<extra></extra>")
    return fig


def _pm(d: dict, nd: int, unit: str = "") -> str:
    return f"{d['mean']:.{nd}f}{unit} \u00b1 {d['std']:.{nd}f}"


def _rows(crowd: dict, metrics: dict) -> str:
    regions = metrics.get("regions") or {}
    body = ""
    for name, c, m in [("all targets", crowd, metrics)] + [(n, r, regions.get(n, {}))
                                                           for n, r in (crowd.get("regions") or {}).items()]:
        empty_tri = 100.0 - float(m.get("non_triangulatable_pct", 0.0))
        body += (f"<tr><td>{html.escape(str(name))}</td>"
                 f"<td class=num>{_pm(c['coverage_gap'], 4)}</td><td class=num>{m.get('coverage_gap', 0.0):.4f}</td>"
                 f"<td class=num>{_pm(c['triangulatable_pct'], 1, ' %')}</td><td class=num>{empty_tri:.1f} %</td>"
                 f"<td class=num>{_pm(c['seen_by_gamma_pct'], 1, ' %')}</td></tr>")
    head = ("<tr><th>region</th><th>crowd coverage gap</th><th>empty store</th><th>triangulatable (\u2265 2) in "
            "the crowd</th><th>empty store</th><th>seen by \u2265 \u0393 in the crowd</th></tr>")
    ppl = crowd.get("people")
    if ppl:  # issue 36: the people themselves
        g = ppl["gamma"]
        prow = "".join(f"<tr><td>{html.escape(str(n))}</td><td class=num>{_pm(r['seen_by_2_pct'], 1, ' %')}</td>"
                       f"<td class=num>{_pm(r['seen_by_gamma_pct'], 1, ' %')}</td></tr>"
                       for n, r in [("all people", ppl)] + list((ppl.get("regions") or {}).items()))
        body_p = (f"<table><tr><th>people in</th><th>seen by \u2265 2 cameras</th><th>seen by \u2265 {g}</th></tr>"
                  f"{prow}</table>")
        return f"<table>{head}{body}</table>{body_p}"
    return f"<table>{head}{body}</table>"


def crowd_section(crowd: dict, metrics: dict, map_id: str | None) -> str:
    """The report's crowd section (HTML): the crowd figures, and the map's div when drawn."""
    zones = ", ".join(f"{html.escape(k)} {v:g}" for k, v in (crowd.get("zones") or {}).items())
    opt = crowd.get("optimisation") or {}
    how = (f"This placement was optimised for crowds: the average crowd cost over {opt.get('samples')} other "
           f"crowds of the same model (seed {opt.get('seed')})." if crowd.get("optimised")
           else "This placement was optimised for the empty store.")
    note = (f"People are cylinders of radius {crowd['radius']:g} m and height {crowd['height']:g} m standing on the "
            f"walkable floor at {crowd['density']:g} persons/m\u00b2{' (zones: ' + zones + ')' if zones else ''}; "
            f"figures are the mean \u00b1 standard deviation over {crowd['samples']} held-out random crowds of "
            f"{crowd['persons']['mean']:.0f} people (seed {crowd['seed']}). A person blocks a sight line that "
            f"passes through them; the person standing at a target is the one to be seen. {how} The 3D view "
            f"shows one of these crowds.")
    div = f"<div id='{map_id}' class='plot'></div>" if map_id else "<p class=note>no volume targets to map</p>"
    return (f"<section><h2>In a crowd</h2><p class=note>{html.escape(note)}</p><div class='grid'>"
            f"<div>{_rows(crowd, metrics)}</div><div>{div}</div></div></section>")


@dataclass(frozen=True)
class CrowdReport:
    """What report.html adds for a crowd: 3D traces, figures by div id, the section's HTML."""

    traces: list = field(default_factory=list)
    figures: dict = field(default_factory=dict)
    section: str = ""


def crowd_report(view: SceneView, targets, crowd_metrics, metrics: dict, cameras: list[dict]) -> CrowdReport:
    """The crowd part of report.html from a camplace.metrics.crowd.CrowdMetrics and the
    metrics.json dict (its empty-store figures beside the crowd ones)."""
    cm = crowd_metrics
    figs = {}
    if cm.report_height is not None:
        person = getattr(cm, "p_person", None) is not None  # issue 36: a person standing there, not the air
        fig = crowd_map_figure(view, targets.positions, targets.is_surface,
                               cm.p_person if person else cm.p_triangulatable, cm.report_height, cameras,
                               person=person)
        if fig is not None:
            figs["crowdmap"] = fig
    section = crowd_section(cm.to_dict(), metrics, "crowdmap" if figs else None)
    return CrowdReport(crowd_traces(cm.shown, cm.radius, cm.height), figs, section)
