"""The plotly figure specs of report.html, as plain JSON-ready dicts built from arrays.

``view3d_figure``: room, obstacle boxes, target voxels by coverage class, camera frusta;
``slice_figure``: coverage per target height; ``histogram_figure``: targets per achieved
coverage. Used by camplace.outputs.report_html.
"""

from __future__ import annotations

import html

import numpy as np

from camplace.outputs.figures import (COVERAGE_CLASSES, REGION_COLOURS, CoverageSlice, SceneView, coverage_class,
                                      label_point)
from camplace.outputs.walls import label_colours, prism_mesh, svg_path

MAX_POINTS = 60_000  # target markers drawn in the 3D view at most (uniform subsample above)
MAX_FRUSTA = 300  # camera frusta drawn at most (an even sample above); above it ids show on hover only


def _r(a, nd: int = 3) -> list:
    """Rounded floats for JSON; None (line breaks) and NaN come out as null."""
    v = np.round(np.asarray(a, float), nd)
    if np.isnan(v).any():
        return [None if x != x else x for x in v.tolist()]
    return v.tolist()


def _nan_to_none(grid: np.ndarray) -> list:
    """Integer grid for JSON, NaN -> null (heatmap gaps)."""
    g = np.asarray(grid, float)
    return np.where(np.isnan(g), None, np.nan_to_num(g).astype(np.int64).astype(object)).tolist()


# ----------------------------------------------------------------------------- 3D view
def _room_lines(view: SceneView) -> dict:
    fp = np.asarray(view.footprint, float)
    ring = np.vstack([fp, fp[:1]])
    xs, ys, zs = [], [], []
    for z in (0.0, view.height):
        xs += ring[:, 0].tolist() + [None]
        ys += ring[:, 1].tolist() + [None]
        zs += [z] * len(ring) + [None]
    for x, y in fp:
        xs += [x, x, None]
        ys += [y, y, None]
        zs += [0.0, view.height, None]
    return {"type": "scatter3d", "mode": "lines", "x": xs, "y": ys, "z": zs, "name": "room",
            "line": {"color": "#888888", "width": 2}, "hoverinfo": "skip"}


_BOX_TRI = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                     [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])
_BOX_EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)]


def _box_corners(bmin, bmax, height: float) -> np.ndarray:
    (x0, y0, z0), (x1, y1, z1) = np.asarray(bmin, float), np.asarray(bmax, float)
    z0, z1 = max(z0, 0.0), min(z1, height)
    return np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                     [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]])


def _wall_traces(view: SceneView) -> list[dict]:
    """One mesh3d per provenance label of the prism obstacles (imported walls, ...)."""
    groups: dict[str, tuple[list, list]] = {}
    for w in view.walls:
        v, t = prism_mesh(w, view.height)
        vs, ts = groups.setdefault(w.label, ([], []))
        ts.append(t + sum(len(a) for a in vs))
        vs.append(v)
    colours = label_colours(groups)
    out = []
    for label, (vs, ts) in groups.items():
        v, t = np.vstack(vs), np.vstack(ts)
        if not len(t):
            continue
        out.append({"type": "mesh3d", "x": _r(v[:, 0]), "y": _r(v[:, 1]), "z": _r(v[:, 2]), "i": t[:, 0].tolist(),
                    "j": t[:, 1].tolist(), "k": t[:, 2].tolist(), "color": colours[label], "opacity": 0.3,
                    "flatshading": True, "name": label, "showlegend": True,
                    "hovertemplate": f"{html.escape(label)}<extra>wall</extra>"})
    return out


def _obstacle_traces(view: SceneView) -> list[dict]:
    if not view.boxes:
        return _wall_traces(view)
    verts, tris, names = [], [], []
    ex, ey, ez = [], [], []
    for k, (name, (bmin, bmax)) in enumerate(view.boxes.items()):
        c = _box_corners(bmin, bmax, view.height)
        verts.append(c)
        tris.append(_BOX_TRI + 8 * k)
        names += [name] * 8
        for a, b in _BOX_EDGES:
            ex += [c[a, 0], c[b, 0], None]
            ey += [c[a, 1], c[b, 1], None]
            ez += [c[a, 2], c[b, 2], None]
    v, t = np.vstack(verts), np.vstack(tris)
    mesh = {"type": "mesh3d", "x": _r(v[:, 0]), "y": _r(v[:, 1]), "z": _r(v[:, 2]),
            "i": t[:, 0].tolist(), "j": t[:, 1].tolist(), "k": t[:, 2].tolist(), "text": names,
            "color": "#a1887f", "opacity": 0.35, "flatshading": True, "name": "obstacles", "showlegend": True,
            "hovertemplate": "%{text}<extra>obstacle</extra>"}
    edges = {"type": "scatter3d", "mode": "lines", "x": _r(ex), "y": _r(ey), "z": _r(ez), "name": "obstacle edges",
             "line": {"color": "#5d4037", "width": 2}, "hoverinfo": "skip", "showlegend": False}
    return [mesh, edges, *_wall_traces(view)]


def _target_traces(positions: np.ndarray, coverage: np.ndarray, gamma: np.ndarray, region_ids: np.ndarray,
                   region_names, max_points: int) -> tuple[list[dict], int]:
    n = len(positions)
    idx = np.arange(n)
    if n > max_points:
        idx = np.sort(np.random.default_rng(0).choice(n, max_points, replace=False))
    cls = coverage_class(coverage)
    names = np.asarray([str(r) for r in region_names], dtype=object)
    traces = []
    for c, (label, colour) in enumerate(COVERAGE_CLASSES):
        sel = idx[cls[idx] == c]
        total = int((cls == c).sum())
        traces.append({
            "type": "scatter3d", "mode": "markers", "name": f"targets seen by {label} ({total})",
            "x": _r(positions[sel, 0]), "y": _r(positions[sel, 1]), "z": _r(positions[sel, 2]),
            "marker": {"size": 2.5, "color": colour, "opacity": 0.85 if c == 0 else 0.6},
            "customdata": np.c_[coverage[sel], gamma[sel]].astype(int).tolist(),
            "text": names[region_ids[sel]].tolist(),
            "hovertemplate": "%{text}: coverage %{customdata[0]} of \u0393 %{customdata[1]}"
                             "<br>(%{x}, %{y}, %{z}) m<extra></extra>",
        })
    return traces, len(idx)


def frustum_depth(view: SceneView) -> float:
    """Drawn depth of the camera frusta (m): 8 % of the larger room side, in [0.3, 1.5]."""
    fp = np.asarray(view.footprint, float)
    return float(np.clip(0.08 * max(np.ptp(fp[:, 0]), np.ptp(fp[:, 1]), view.height), 0.3, 1.5))


def _corner_rays(intr: dict) -> np.ndarray:
    """(4, 3) camera-frame rays through the image corners, z = 1 where possible; through the
    lens model (camplace.cameras.models) so distorted and fisheye lenses get their true extent."""
    W, H = intr["width"], intr["height"]
    uv = np.array([[-0.5, -0.5], [W - 0.5, -0.5], [W - 0.5, H - 0.5], [-0.5, H - 0.5]])
    pinhole = np.c_[(uv[:, 0] - intr["cx"]) / intr["fx"], (uv[:, 1] - intr["cy"]) / intr["fy"], np.ones(4)]
    if intr.get("model", "pinhole") == "pinhole" or not intr.get("distortion"):
        return pinhole
    try:
        from camplace.cameras.models import CameraModel

        cam = CameraModel("frustum", intr["model"], int(W), int(H), intr["fx"], intr["fy"], intr["cx"], intr["cy"],
                          distortion=tuple(intr.get("distortion", ())))
        rays = np.asarray(cam.unproject(uv), float)
    except Exception:  # noqa: BLE001 - a lens this version cannot invert: draw the pinhole extent
        return pinhole
    z = rays[:, 2:3]
    return np.where(z > 0.2, rays / np.maximum(z, 1e-9), rays * 1.5)  # very wide lenses: unit-ish rays


def frustum_corners(cam: dict, depth: float) -> np.ndarray:
    """(5, 3) world points: camera centre and the 4 image corners at ``depth`` (m)."""
    R = np.asarray(cam["rotation"], float)
    C = np.asarray(cam["position"], float)
    d = _corner_rays(cam["intrinsics"]) * depth
    return np.vstack([C, C + d @ R.T])


def shown_frusta(n: int) -> np.ndarray:
    """Indices of the cameras whose frusta are drawn: all up to MAX_FRUSTA, else an even sample of that many."""
    return np.arange(n) if n <= MAX_FRUSTA else np.unique(np.linspace(0, n - 1, MAX_FRUSTA).round().astype(int))


def _camera_traces(cameras: list[dict], depth: float) -> list[dict]:
    if not cameras:
        return []
    xs, ys, zs = [], [], []
    drawn = shown_frusta(len(cameras))
    for cam in (cameras[int(k)] for k in drawn):
        p = frustum_corners(cam, depth)
        for a, b in ((0, 1), (0, 2), (0, 3), (0, 4), (1, 2), (2, 3), (3, 4), (4, 1)):
            xs += [p[a, 0], p[b, 0], None]
            ys += [p[a, 1], p[b, 1], None]
            zs += [p[a, 2], p[b, 2], None]
    pos = np.array([c["position"] for c in cameras], float)
    ids = [str(c.get("candidate_id")) for c in cameras]
    hover = [f"camera {c.get('candidate_id')} ({html.escape(str(c.get('camera', '')))})<br>"
             f"yaw {c['yaw_deg']:.1f}\u00b0 pitch {c['pitch_deg']:.1f}\u00b0 roll {c['roll_deg']:.1f}\u00b0"
             for c in cameras]
    few = len(cameras) <= MAX_FRUSTA
    return [
        {"type": "scatter3d", "mode": "lines", "x": _r(xs), "y": _r(ys), "z": _r(zs),
         "name": "camera frusta" if few else f"camera frusta (showing {len(drawn)} of {len(cameras)})",
         "line": {"color": "#000000", "width": 3}, "hoverinfo": "skip"},
        {"type": "scatter3d", "mode": "markers+text" if few else "markers", "x": _r(pos[:, 0]), "y": _r(pos[:, 1]),
         "z": _r(pos[:, 2]),
         "text": ids, "textposition": "top center", "textfont": {"size": 10, "color": "#000000"},
         "marker": {"size": 4, "color": "#000000", "symbol": "diamond"}, "name": f"cameras ({len(cameras)})",
         "hovertext": hover, "hovertemplate": "%{hovertext}<br>(%{x}, %{y}, %{z}) m<extra></extra>"},
    ]


def view3d_figure(view: SceneView, positions: np.ndarray, coverage: np.ndarray, gamma: np.ndarray,
                  region_ids: np.ndarray, region_names, cameras: list[dict],
                  max_points: int = MAX_POINTS) -> tuple[dict, int]:
    """Plotly spec of the 3D view and the number of target markers drawn."""
    targets, shown = _target_traces(np.asarray(positions, float), np.asarray(coverage, np.int64),
                                    np.asarray(gamma, np.int64), np.asarray(region_ids, np.int64), region_names,
                                    max_points)
    data = [_room_lines(view), *_obstacle_traces(view), *targets, *_camera_traces(cameras, frustum_depth(view))]
    axis = {"showbackground": False, "gridcolor": "#dddddd", "zerolinecolor": "#bbbbbb"}
    layout = {"height": 720, "margin": {"l": 0, "r": 0, "t": 30, "b": 0}, "uirevision": "keep",
              "legend": {"itemsizing": "constant", "x": 0.0, "y": 1.0, "bgcolor": "rgba(255,255,255,0.8)"},
              "scene": {"aspectmode": "data", "xaxis": {**axis, "title": {"text": "x (m)"}},
                        "yaxis": {**axis, "title": {"text": "y (m)"}}, "zaxis": {**axis, "title": {"text": "z (m)"}},
                        "camera": {"eye": {"x": -1.3, "y": -1.75, "z": 1.35}}}}
    return {"data": data, "layout": layout}, shown


# ----------------------------------------------------------------------------- 2D figures
def _discrete_colourscale() -> list:
    out = []
    for k, (_, colour) in enumerate(COVERAGE_CLASSES):
        out += [[k / 4, colour], [(k + 1) / 4, colour]]
    return out


def slice_figure(sl: CoverageSlice, view: SceneView, cameras: list[dict]) -> dict:
    """Plotly spec of one coverage slice (heatmap of classes, obstacles, cameras)."""
    cls = np.where(np.isnan(sl.coverage), np.nan, np.minimum(sl.coverage, 3))
    data = [{"type": "heatmap", "x": _r(sl.x), "y": _r(sl.y), "z": _nan_to_none(cls),
             "customdata": _nan_to_none(sl.coverage), "zmin": -0.5, "zmax": 3.5, "colorscale": _discrete_colourscale(),
             "showscale": False, "hoverongaps": False, "name": f"z = {sl.height:.2f} m",
             "hovertemplate": "(%{x}, %{y}) m: seen by %{customdata} cameras<extra></extra>"}]
    if cameras:
        pos = np.array([c["position"] for c in cameras], float)
        data.append({"type": "scatter", "mode": "markers+text" if len(cameras) <= MAX_FRUSTA else "markers",
                     "x": _r(pos[:, 0]), "y": _r(pos[:, 1]),
                     "text": [str(c.get("candidate_id")) for c in cameras], "textposition": "top center",
                     "textfont": {"size": 9}, "marker": {"color": "#000000", "size": 5}, "name": "cameras",
                     "hovertemplate": "camera %{text}<extra></extra>", "showlegend": False})
    fp = np.asarray(view.footprint, float)
    path = "M " + " L ".join(f"{x:.3f},{y:.3f}" for x, y in fp) + " Z"
    shapes = [{"type": "path", "path": path, "line": {"color": "#000000", "width": 1.5}}]
    for _, x0, y0, x1, y1 in sl.boxes:
        shapes.append({"type": "rect", "x0": x0, "y0": y0, "x1": x1, "y1": y1, "fillcolor": "#9e9e9e",
                       "opacity": 0.8, "line": {"color": "#424242", "width": 1}, "layer": "below"})
    colours = label_colours(sl.walls)
    for label, geom in sl.walls.items():  # imported walls (prisms) cut at this height, by provenance label
        shapes.append({"type": "path", "path": svg_path(geom), "fillcolor": colours[label], "fillrule": "evenodd",
                       "opacity": 0.9, "line": {"color": "#000000", "width": 0.5}, "name": label})
    for name, corners in view.zones:  # rooms: outline and name
        shapes.append({"type": "path", "path": "M " + " L ".join(f"{x:.3f},{y:.3f}" for x, y in corners) + " Z",
                       "line": {"color": "#1b7837", "width": 1}, "name": name})
    annotations = [{"x": x, "y": y, "text": f"<i>{html.escape(name)}</i>", "showarrow": False,
                    "font": {"size": 10, "color": "#1b7837"}, "bgcolor": "rgba(255,255,255,0.75)"} for name, c in view.zones for x, y in [label_point(c)]]
    w, h = np.ptp(fp[:, 0]), np.ptp(fp[:, 1])
    layout = {"title": {"text": f"coverage at z = {sl.height:.2f} m", "font": {"size": 14}, "x": 0.01,
                        "xanchor": "left"},
              "height": int(np.clip(80 + 520 * h / max(w, 1e-9), 260, 760)), "margin": {"l": 50, "r": 10, "t": 40, "b": 40},
              "xaxis": {"title": {"text": "x (m)"}, "constrain": "domain"},
              "yaxis": {"title": {"text": "y (m)"}, "scaleanchor": "x", "scaleratio": 1, "constrain": "domain"},
              "shapes": shapes, "annotations": annotations, "plot_bgcolor": "#ffffff"}
    return {"data": data, "layout": layout}


def histogram_figure(histograms: dict[str, dict[str, int]], gammas: dict[str, int]) -> dict:
    """Plotly spec of the coverage histogram, stacked by region, Γ per region dashed."""
    kmax = max([int(k) for h in histograms.values() for k in h] + [0])
    ks = list(range(kmax + 1))
    data, shapes = [], []
    for n, (name, hist) in enumerate(histograms.items()):
        colour = REGION_COLOURS[n % len(REGION_COLOURS)]
        data.append({"type": "bar", "x": ks, "y": [int(hist.get(str(k), 0)) for k in ks], "name": str(name),
                     "marker": {"color": colour},
                     "hovertemplate": f"{html.escape(str(name))}: %{{y}} targets seen by %{{x}} cameras<extra></extra>"})
        if name in gammas:
            shapes.append({"type": "line", "xref": "x", "yref": "paper", "x0": gammas[name] - 0.5,
                           "x1": gammas[name] - 0.5, "y0": 0, "y1": 1, "line": {"color": colour, "dash": "dash"}})
    layout = {"barmode": "stack", "height": 380, "margin": {"l": 60, "r": 10, "t": 40, "b": 50}, "shapes": shapes,
              "title": {"text": "targets per achieved coverage (dashed: required \u0393)", "font": {"size": 14},
                        "x": 0.01, "xanchor": "left"},
              "xaxis": {"title": {"text": "cameras seeing the target"}, "dtick": 1},
              "yaxis": {"title": {"text": "targets"}}}
    return {"data": data, "layout": layout}
