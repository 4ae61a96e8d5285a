"""report.html: one self-contained page that shows a placement (opens offline, no CDN).

plotly.js is embedded in the page (the bundle of plotly's offline mode, as with
``include_plotlyjs=True``); the figures are plain plotly JSON specs built here from
arrays in camplace.outputs.report_figures (no plotly Python object validation, so the
page is written in well under a second for a store). Sections: summary, interactive 3D view (room, obstacle boxes,
target voxels coloured by achieved coverage class 0 / 1 / 2 / >= 3 with one trace per
class, selected cameras as frusta with ids), coverage slices per target height,
coverage histogram, per-region table, mount list, links to the other outputs.

``write_report`` writes the whole report set: exports (OpenCV YAML, COLMAP), PNG
figures and report.html.
"""

from __future__ import annotations

import html
import json
import time
from pathlib import Path

import numpy as np

from camplace.core.files import atomic_write_text
from camplace.outputs.figures import COVERAGE_CLASSES, CoverageSlice, SceneView, coverage_class, coverage_slices
from camplace.outputs.writers import file_list
from camplace.outputs.report_figures import (MAX_POINTS, frustum_depth, histogram_figure, shown_frusta, slice_figure,
                                             view3d_figure)

_PLOTLY_JS: str | None = None


def plotly_js() -> str:
    """The plotly.js bundle shipped with the plotly package (cached)."""
    global _PLOTLY_JS
    if _PLOTLY_JS is None:
        from plotly.offline import get_plotlyjs

        _PLOTLY_JS = get_plotlyjs()
    return _PLOTLY_JS



# ----------------------------------------------------------------------------- camera views
VIEW_WIDTH = 240  # pixels of each rendered camera view in the report
VIEW_BUDGET_S = 1.0  # rendering stops after this many seconds (the rest: `camplace render`)
VIEW_MAX_CELLS = 80_000_000  # occupancy cells above which no view is rendered (preparing the grids alone
#                             takes longer than the report's budget: ~10 s per 70 M cells on 2 cores)


def camera_views(scene, vis, selected: np.ndarray, width: int = VIEW_WIDTH,
                 budget_s: float = VIEW_BUDGET_S, people: tuple | None = None) -> tuple[list[dict], int]:
    """What each selected camera sees (camplace.outputs.render: rays through its lens model into
    the occupancy grid), with the targets it covers as dots coloured by their coverage
    class; ``people`` (xy (P, 2), radius, height) m: test people drawn in (issue 36,
    camplace.outputs.render_people). Returns ([{id, caption, uri}], number not rendered within ``budget_s``)."""
    import base64
    import io

    from PIL import Image

    from camplace.outputs.render import covered_pixels, render_view, scene_grids

    t0 = time.perf_counter()
    sel = np.asarray(selected, np.int64)
    if np.isfinite(budget_s) and int(np.prod(scene.occupancy.occupied.shape)) > VIEW_MAX_CELLS:
        return [], len(sel)  # a site-scale scene: the page says none of them is shown
    cov = np.bincount(vis.V[sel].indices, minlength=vis.V.shape[1]) if len(sel) else np.zeros(vis.V.shape[1], int)
    cls = coverage_class(cov)
    colours = np.array([[int(c[1:3], 16), int(c[3:5], 16), int(c[5:7], 16)] for _, c in COVERAGE_CLASSES], np.uint8)
    labels, dist = scene_grids(scene)  # once per report: both grids are the same for every view
    c = vis.candidates
    out = []
    for n, i in enumerate(sel):
        if out and time.perf_counter() - t0 > budget_s:
            return out, len(sel) - n
        cam = c.cameras[int(c.camera_ids[i])]
        rv = render_view(scene, cam, c.positions[i], c.rotations[i], width, labels, dist)
        grey = np.clip(rv.rgb, 0, 1) @ np.array([0.299, 0.587, 0.114])  # grey scene: the coloured dots stand out
        img = np.repeat((40 + 200 * grey)[:, :, None], 3, axis=2).astype(np.uint8)
        if people is not None:  # in their own colour over the grey scene
            from camplace.outputs.render_people import draw_people

            drawn = draw_people(rv, cam, c.positions[i], c.rotations[i], *people)
            near = drawn.depth < rv.depth
            img[near] = (255 * np.clip(drawn.rgb[near], 0, 1)).astype(np.uint8)
        seen = vis.V.indices[vis.V.indptr[i]:vis.V.indptr[i + 1]]
        uv, ok = covered_pixels(cam, c.positions[i], c.rotations[i], vis.targets.positions[seen], rv.scale)
        h, w = img.shape[:2]
        px = np.rint(uv[ok]).astype(np.int64)
        for dx in (0, 1):
            for dy in (0, 1):
                x, y = px[:, 0] + dx, px[:, 1] + dy
                m = (x >= 0) & (x < w) & (y >= 0) & (y < h)
                img[y[m], x[m]] = colours[cls[seen[ok]][m]]
        buf = io.BytesIO()
        Image.fromarray(img).save(buf, format="JPEG", quality=85)
        yaw, pitch, roll = c.angles_deg[i]
        out.append({"id": int(i), "uri": "data:image/jpeg;base64," + base64.b64encode(buf.getvalue()).decode(),
                    "caption": f"camera {int(i)} ({cam.name}): yaw {yaw:.0f}\u00b0, pitch {pitch:.0f}\u00b0, "
                               f"roll {roll:.0f}\u00b0; sees {len(seen)} targets"})
    return out, 0


def _views_section(views: list[dict] | None, skipped: int) -> str:
    if views is None:
        return ""
    cards = "".join(f"<figure><img src='{v['uri']}' alt='view of camera {v['id']}'>"
                    f"<figcaption>{html.escape(v['caption'])}</figcaption></figure>" for v in views)
    shown = len(views)
    why = " (this scene is too large to prepare its grids within it)" if not shown else ""
    more = (f"<p class=note>showing {shown} of {shown + skipped} camera views: {skipped} more views not rendered "
            f"within the report's time budget{why}; <code>camplace render</code> draws any camera.</p>"
            if skipped else "")
    return (f"<section><h2>Camera views</h2><p class=note>What each selected camera sees (rays through its "
            f"lens model into the occupancy grid, in grey, darker beyond range); dots: the targets it covers, "
            f"coloured by how many selected cameras see them.</p><div class='views'>{cards}</div>{more}</section>")


# ----------------------------------------------------------------------------- page
_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:0;color:#212121;background:#fafafa}
header{background:#263238;color:#fff;padding:14px 24px}header h1{margin:0;font-size:22px}
header p{margin:4px 0 0;color:#cfd8dc;font-size:13px}main{padding:12px 24px;max-width:1800px}
section{background:#fff;border:1px solid #e0e0e0;border-radius:6px;margin:14px 0;padding:10px 16px}
h2{font-size:17px;margin:6px 0 10px}table{border-collapse:collapse;font-size:13px}
td,th{border-bottom:1px solid #eeeeee;padding:4px 10px;text-align:left}th{background:#f5f5f5}
td.num{text-align:right;font-variant-numeric:tabular-nums}.grid{display:flex;flex-wrap:wrap;gap:12px}
.grid>div{flex:1 1 520px;min-width:420px}.legend span{display:inline-block;margin-right:14px;font-size:13px}
.legend i{display:inline-block;width:12px;height:12px;margin-right:5px;vertical-align:-1px;border-radius:2px}
.note{color:#616161;font-size:12px}.views{display:flex;flex-wrap:wrap;gap:10px}
.views figure{margin:0;width:244px;font-size:11px;color:#424242}.views img{width:240px;border:1px solid #ccc}.top{display:flex;flex-wrap:wrap;gap:14px;align-items:flex-start}
.top>section{margin:14px 0 0}.summary{flex:0 0 360px}.view{flex:1 1 700px;min-width:600px}.mounts{max-height:420px;overflow:auto}a{color:#1565c0}
"""


def _fmt(v, nd: int = 6) -> str:
    if v is None:
        return "\u2013"
    if isinstance(v, float):
        return f"{v:.{nd}g}"
    return str(v)


def _frusta_note(n: int) -> str:
    """'' or ' (showing N of M frusta; ids on hover)' when the 3D view draws a sample of the cameras."""
    k = len(shown_frusta(n))
    return "" if k == n else f" (showing {k} of {n} camera frusta, an even sample; ids on hover)"


def _rows(pairs) -> str:
    return "".join(f"<tr><th>{html.escape(str(k))}</th><td>{html.escape(str(v))}</td></tr>" for k, v in pairs)


def _summary_pairs(placement: dict, metrics: dict, n_targets: int, n_candidates: int | None) -> list:
    gap = placement.get("gap")
    timings = metrics.get("timings_s") or {}
    return [
        ("scene", placement.get("scene")), ("solver", placement.get("solver")), ("status", placement.get("status")),
        ("cameras placed (budget)", f"{len(placement.get('cameras', []))} ({placement.get('budget')})"),
        ("cost \u03a3 w (\u0393 \u2212 c)\u207a\u00b2", _fmt(metrics.get("cost"))),
        *([("grid cost (before refine)", _fmt(metrics["grid_cost"]))] if "grid_cost" in metrics else []),
        ("coverage gap (paper eq. 8)", _fmt(metrics.get("coverage_gap"), 4)),
        ("lower bound", _fmt(placement.get("bound"))),
        ("proven gap", "\u2013" if gap is None else f"{100 * gap:.2f} %"),
        ("non-triangulatable (< 2 cameras)", f"{metrics.get('non_triangulatable_pct', 0.0):.2f} %"),
        ("targets", n_targets), ("candidate poses", "\u2013" if n_candidates is None else n_candidates),
        ("timings (s)", ", ".join(f"{k} {float(v):.2f}" for k, v in timings.items()) or "\u2013"),
    ]


def _region_table(metrics: dict, region_kinds: dict, gammas: dict) -> str:
    head = ("<tr><th>region</th><th>kind</th><th>targets</th><th>\u0393</th><th>cost</th><th>coverage gap</th>"
            "<th>non-triangulatable</th><th>not seen</th></tr>")
    body = ""
    for name, r in (metrics.get("regions") or {}).items():
        hist = r.get("coverage_histogram", {})
        body += (f"<tr><td>{html.escape(str(name))}</td><td>{html.escape(str(region_kinds.get(name, '')))}</td>"
                 f"<td class=num>{r.get('targets', '')}</td><td class=num>{gammas.get(name, '')}</td>"
                 f"<td class=num>{_fmt(r.get('cost'))}</td><td class=num>{r.get('coverage_gap', 0.0):.4f}</td>"
                 f"<td class=num>{r.get('non_triangulatable_pct', 0.0):.2f} %</td>"
                 f"<td class=num>{hist.get('0', 0)}</td></tr>")
    return f"<table>{head}{body}</table>"


def _mount_table(cameras: list[dict]) -> str:
    src = any("source_id" in c for c in cameras)  # an evaluated file: its own camera ids too
    floor = any("storey" in c for c in cameras)  # a building (issue 33): each camera's storey
    head = ("<tr><th>id</th>" + ("<th>id in file</th>" if src else "") + ("<th>storey</th>" if floor else "")
            + "<th>x (m)</th><th>y (m)</th><th>z (m)</th>"
            "<th>yaw (\u00b0)</th><th>pitch (\u00b0)</th><th>roll (\u00b0)</th><th>lens</th></tr>")
    body = "".join(
        f"<tr><td>{c.get('candidate_id')}</td>"
        + (f"<td>{html.escape(str(c.get('source_id', '')))}</td>" if src else "")
        + (f"<td>{html.escape(str(c.get('storey', '')))}</td>" if floor else "")
        + "".join(f"<td class=num>{v:.3f}</td>" for v in c["position"])
        + "".join(f"<td class=num>{c[k]:.2f}</td>" for k in ("yaw_deg", "pitch_deg", "roll_deg"))
        + f"<td>{html.escape(str(c.get('camera', '')))}</td></tr>" for c in cameras)
    return f"<div class=mounts><table>{head}{body}</table></div>"


def _json(obj) -> str:
    return json.dumps(obj, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")


def render_report(view: SceneView, placement: dict, metrics: dict, positions: np.ndarray, is_surface: np.ndarray,
                  coverage: np.ndarray, gamma: np.ndarray, region_ids: np.ndarray, region_names,
                  region_kinds=(), n_candidates: int | None = None, files: list[str] = (),
                  slices: list[CoverageSlice] | None = None, max_points: int = MAX_POINTS,
                  views: list[dict] | None = None, views_skipped: int = 0, dated: bool = True,
                  extra_html: str = "", extra_figures: dict | None = None, extra_traces: list | None = None,
                  storey_figures: tuple | None = None) -> str:
    """The report page as one HTML string (plotly.js embedded).

    positions: (N_p, 3) m; is_surface, coverage, gamma, region_ids: (N_p,);
    placement / metrics: the placement.json / metrics.json dicts; files: names of
    sibling output files to link; ``dated``: say when the page was written (off for repeatable
    runs, so that the page depends only on the inputs); ``extra_figures``: more plotly specs by the
    id of a div in ``extra_html``; ``extra_traces``: more 3D-view traces (one sampled crowd);
    ``storey_figures``: a building's 3D view and slices (camplace.outputs.report_storeys)."""
    positions = np.asarray(positions, float)
    coverage = np.asarray(coverage, np.int64)
    cameras = placement.get("cameras", [])
    written = f" \u00b7 written {time.strftime('%Y-%m-%d %H:%M:%S')}" if dated else ""
    if slices is None:
        slices = coverage_slices(view, positions, is_surface, coverage)
    region_names = [str(r) for r in region_names]
    gammas = {name: int(np.max(gamma[region_ids == r])) for r, name in enumerate(region_names)
              if np.any(region_ids == r)}
    kinds = dict(zip(region_names, region_kinds))
    if storey_figures is None:
        fig3d, shown = view3d_figure(view, positions, coverage, gamma, region_ids, region_names, cameras, max_points)
        slice_specs = [slice_figure(sl, view, cameras) for sl in slices]
    else:  # a building (issue 33): storey selector, slices per storey
        (fig3d, shown), slice_specs = storey_figures
    fig3d["data"].extend(extra_traces or [])
    figs = {"view3d": fig3d}
    for k, spec in enumerate(slice_specs):
        figs[f"slice{k}"] = spec
    hists = {name: r.get("coverage_histogram", {}) for name, r in (metrics.get("regions") or {}).items()}
    if not hists:
        hists = {"all targets": metrics.get("coverage_histogram", {})}
    figs["histogram"] = histogram_figure(hists, gammas)
    figs.update(extra_figures or {})

    legend = "".join(f"<span><i style='background:{c}'></i>{html.escape(lab)}</span>" for lab, c in COVERAGE_CLASSES)
    sub = (f"showing {shown} of {len(positions)} targets" if shown < len(positions)
           else f"all {len(positions)} targets shown")
    slice_divs = "".join(f"<div id='slice{k}' class='plot'></div>" for k in range(len(slice_specs)))
    slice_divs = slice_divs or "<p class=note>no volume targets</p>"
    links = " \u00b7 ".join(f"<a href='{html.escape(f)}'>{html.escape(f)}</a>" for f in files) or "\u2013"
    title = html.escape(str(placement.get("scene", view.name)))
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>camplace report: {title}</title><style>{_CSS}</style></head>
<body data-plots-total="{len(figs)}">
<header><h1>camplace report: {title}</h1>
<p>{html.escape(str(placement.get('solver')))} placement of {len(cameras)} cameras{written} \u00b7 self-contained, works offline</p></header>
<main>
<div class="top"><section class="summary"><h2>Summary</h2><table>{_rows(_summary_pairs(placement, metrics, len(positions), n_candidates))}</table></section>
<section class="view"><h2>3D view</h2><p class="legend">{legend}</p>
<p class="note">Target voxels coloured by how many selected cameras see them ({sub}); camera frusta drawn {frustum_depth(view):.2f} m deep with candidate ids{_frusta_note(len(cameras))}. Drag to rotate, scroll to zoom, click legend entries to hide a class.{" The buttons above the view show every storey or one storey (its room, targets and cameras)." if storey_figures else ""}</p>
<div id="view3d" class="plot"></div></section></div>
<section><h2>Coverage slices per target height</h2><p class="legend">{legend}</p>
<p class="note">Volume targets at each height; grey boxes: obstacles crossing that height; black dots: cameras (ids).</p>
<div class="grid">{slice_divs}</div></section>
<section><h2>Coverage histogram and regions</h2><div class="grid"><div id="histogram" class="plot"></div>
<div>{_region_table(metrics, kinds, gammas)}</div></div></section>
{extra_html}
{_views_section(views, views_skipped)}
<section><h2>Mount list</h2>{_mount_table(cameras)}</section>
<section><h2>Files</h2><p>{links}</p></section>
</main>
<script type="text/javascript">{plotly_js()}</script>
<script type="text/javascript">
(function(){{
  var figs = {_json(figs)};
  var config = {{"displaylogo": false, "responsive": true}};
  var jobs = Object.keys(figs).map(function(id) {{
    return Plotly.newPlot(id, figs[id].data, figs[id].layout, config);
  }});
  Promise.all(jobs).then(function() {{
    document.body.setAttribute("data-plots-ready", String(jobs.length));
  }}).catch(function(err) {{
    document.body.setAttribute("data-plots-error", String(err));
    console.error("camplace report: plot failed: " + err);
  }});
}})();
</script>
</body></html>
"""
    return page


def write_report(out_dir: str | Path, targets, coverage: np.ndarray, placement: dict, metrics: dict,
                 view: SceneView | None = None, n_candidates: int | None = None,
                 html_report: bool = True, figures: bool = True, exports: bool = True,
                 scene=None, vis=None, selected: np.ndarray | None = None,
                 repeatable: bool = False, extra_html: str = "",
                 rendered_views: tuple[list[dict], int] | None = None, written: tuple[str, ...] = (),
                 extra_figures: dict | None = None, extra_traces: list | None = None) -> dict[str, Path]:
    """Write exports (opencv/, colmap/), PNG figures and report.html into out_dir.

    targets: camplace.targets.build.Targets (N_p); coverage: (N_p,) achieved coverage of the
    placement; placement / metrics: the placement.json / metrics.json dicts. With
    ``scene`` (camplace.scene.build.Scene), ``vis`` (camplace.visibility.engine.Visibility) and
    ``selected`` (rows of vis.V) the page also shows each camera's rendered view (as many as
    fit VIEW_BUDGET_S seconds). ``repeatable``: every view and no date, so that the page
    depends only on the inputs (byte-identical between identical runs). ``extra_html``: sections
    placed before the camera views (the plan view, camplace.outputs.handover); ``rendered_views``:
    camera_views' result when already rendered; ``written``: names of files an earlier call wrote
    (report.html links them too); ``extra_figures`` / ``extra_traces``: as for render_report.
    Returns file name (relative to out_dir) -> path."""
    from camplace.outputs.exports import write_exports
    from camplace.outputs.figures import write_figures

    out = Path(out_dir)
    cameras = placement.get("cameras", [])
    if view is None:
        view = SceneView.from_targets(str(placement.get("scene", "scene")), targets.positions, cameras)
    is_surface = targets.is_surface
    slices = coverage_slices(view, targets.positions, is_surface, coverage)
    paths: dict[str, Path] = {}
    if exports:
        paths.update(write_exports(out, cameras))
    if figures:
        gammas = {name: int(targets.gamma[targets.region_ids == r].max())
                  for r, name in enumerate(targets.region_names) if np.any(targets.region_ids == r)}
        hists = {n: r["coverage_histogram"] for n, r in (metrics.get("regions") or {}).items()}
        paths.update(write_figures(out, view, targets.positions, is_surface, coverage, cameras,
                                   hists or {"all targets": metrics.get("coverage_histogram", {})}, gammas, slices))
    if html_report:
        files = file_list([*written, *paths])  # every file written before the page, as returned
        views, skipped = rendered_views or (None, 0)
        if rendered_views is None and scene is not None and vis is not None and selected is not None:
            views, skipped = camera_views(scene, vis, selected,
                                          budget_s=float("inf") if repeatable else VIEW_BUDGET_S)
        text = render_report(view, placement, metrics, targets.positions, is_surface, coverage, targets.gamma,
                             targets.region_ids, targets.region_names, targets.region_kinds, n_candidates, files,
                             slices, views=views, views_skipped=skipped, dated=not repeatable, extra_html=extra_html,
                             extra_figures=extra_figures, extra_traces=extra_traces,
                             storey_figures=_storey_figures(scene, targets, coverage, cameras))
        paths["report.html"] = atomic_write_text(out / "report.html", text)
    return paths


def _storey_figures(scene, targets, coverage: np.ndarray, cameras: list[dict]) -> tuple | None:
    """A building's 3D view and slices (camplace.outputs.report_storeys); None for one room."""
    if not getattr(scene, "storeys", ()):
        return None
    from camplace.outputs.report_storeys import building_figures

    return building_figures(scene, targets, coverage, cameras)
