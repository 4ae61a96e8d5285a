"""report.html of a building (issue 33): the 3D view storey by storey, with a storey selector,
and the coverage slices of each storey.

Each storey is drawn from its own scene (floor at z = 0: its room, obstacles and walls,
its targets and cameras moved to local z) by the single-room figure builders of
camplace.outputs.report_figures, then raised to its elevation, so the building stands
stacked in building z. The selector (plotly ``updatemenus`` buttons) shows every storey or
one of them; each slice is titled with its storey and its height above that storey's floor.
"""

from __future__ import annotations

import numpy as np

from camplace.outputs.figures import SceneView, coverage_slices
from camplace.outputs.plan_storeys import local_camera, storey_targets
from camplace.outputs.report_figures import MAX_POINTS, slice_figure, view3d_figure
from camplace.scene.build import storey_index


def raise_trace(trace: dict, dz: float, storey: str) -> dict:
    """A plotly 3D trace moved up by ``dz`` m (its z values; None kept), named and grouped by ``storey``."""
    out = dict(trace, name=f"{storey}: {trace.get('name', '')}", legendgroup=storey)
    if "z" in trace:
        out["z"] = [None if v is None else round(float(v) + dz, 3) for v in trace["z"]]
    return out


def storey_buttons(names: list[str], groups: list[str]) -> dict:
    """The 3D view's storey selector: plotly updatemenus buttons 'all storeys' and one per
    storey, each showing only its traces (``groups``: the storey of each trace)."""
    idx = list(range(len(groups)))  # traces added after these (a crowd) keep their own visibility
    buttons = [{"label": "all storeys", "method": "restyle", "args": [{"visible": [True] * len(groups)}, idx]}]
    buttons += [{"label": n, "method": "restyle", "args": [{"visible": [g == n for g in groups]}, idx]}
                for n in names]
    return {"type": "buttons", "direction": "right", "x": 0.0, "xanchor": "left", "y": 1.06, "yanchor": "bottom",
            "showactive": True, "active": 0, "buttons": buttons, "name": "storey"}


def building_figures(scene, targets, coverage: np.ndarray, cameras: list[dict], max_points: int = MAX_POINTS
                     ) -> tuple[tuple[dict, int], list[dict]]:
    """((the 3D view spec with its storey selector, target markers drawn), the coverage slice
    specs of every storey, lowest first) of a building scene (camplace.scene.build.Scene with
    storeys); ``targets`` (Targets, building z), ``coverage`` (N_p,), ``cameras``: placement.json
    camera objects carrying ``storey``."""
    storeys = scene.storeys
    where = storey_index(storeys, targets.positions[:, 2]) if len(targets) else np.zeros(0, np.int64)
    share = max(1, max_points // len(storeys))
    data, groups, slices, shown, layout = [], [], [], 0, {}
    for k, st in enumerate(storeys):
        view = SceneView.from_scene(st.scene)
        t = storey_targets(targets, where == k, st.elevation)
        cov = np.asarray(coverage)[where == k]
        cams = [local_camera(c, st.elevation) for c in cameras if c.get("storey") == st.name]
        fig, n = view3d_figure(view, t.positions, cov, t.gamma, t.region_ids, t.region_names, cams, share)
        shown += n
        layout = layout or fig["layout"]
        data += [raise_trace(tr, st.elevation, st.name) for tr in fig["data"]]
        groups += [st.name] * len(fig["data"])
        for sl in coverage_slices(view, t.positions, t.is_surface, cov):
            spec = slice_figure(sl, view, cams)
            spec["layout"]["title"]["text"] = (f"{st.name}: coverage {sl.height:.2f} m above its floor "
                                               f"(z = {sl.height + st.elevation:.2f} m)")
            slices.append(spec)
    layout = dict(layout, updatemenus=[storey_buttons([st.name for st in storeys], groups)],
                  margin={**layout.get("margin", {}), "t": 60})
    return ({"data": data, "layout": layout}, shown), slices
