"""A building's plan set (issue 33): one PlanData per storey, drawn as that storey's sheets.

A building scene (camplace.scene.build.Scene with ``storeys``) is handed over as one
PlanData for the whole building (the camera schedule, the views, the bill of materials)
and one per storey (``storey_plans``): the storey's own scene (floor at z = 0), its
cameras and targets moved to its local z (z − elevation), their viewsheds at the working
height above that storey's floor (computed in the building's grid, so a camera sees down
through a floor opening as it does in V), and its sheets numbered after the storeys
before it. Cameras keep their building-wide marks C1..Cn.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from camplace.outputs.plan_bom import bom_figure
from camplace.outputs.plan_data import VIEWSHED_BUDGET_S, PlanData, free_floor, plan_data
from camplace.core.files import atomic_write_bytes
from camplace.outputs.plan_pdf import coverage_figure, pdf_pages_bytes, plan_figure, schedule_figures, views_figure
from camplace.scene.build import storey_index
from camplace.visibility.viewshed import STEP, WORKING_HEIGHT, viewsheds

SHEETS_PER_STOREY = 2  # the floor plan and the coverage sheet


def is_building(scene) -> bool:
    """True for a building scene (one with storeys)."""
    return bool(getattr(scene, "storeys", ()))


def local_camera(camera: dict, elevation: float) -> dict:
    """A copy of a placement.json camera object with its position moved down by ``elevation`` m."""
    x, y, z = camera["position"]
    return {**camera, "position": [x, y, z - elevation]}


def storey_targets(targets, mask: np.ndarray, elevation: float):
    """The targets of ``mask`` (N,) bool moved down by ``elevation`` m, with only the regions
    they belong to (camplace.targets.build.Targets)."""
    keep = np.unique(targets.region_ids[mask])
    new_id = np.full(len(targets.region_names), -1, np.int64)
    new_id[keep] = np.arange(len(keep))
    px = targets.min_px_per_m
    return replace(targets, positions=targets.positions[mask] - [0.0, 0.0, elevation],
                   normals=targets.normals[mask], gamma=targets.gamma[mask], weights=targets.weights[mask],
                   region_ids=new_id[targets.region_ids[mask]].astype(targets.region_ids.dtype),
                   region_names=tuple(targets.region_names[r] for r in keep),
                   region_kinds=tuple(targets.region_kinds[r] for r in keep),
                   max_incidence_deg=np.asarray(targets.max_incidence_deg)[keep],
                   min_px_per_m=None if px is None else np.asarray(px)[keep])


def building_plans(scene, vis, placement: dict, metrics: dict, selected: np.ndarray, *,
                   height: float = WORKING_HEIGHT, paper: str = "A3", repeatable: bool = False,
                   views: list[dict] | None = None, input_from_scene: np.ndarray | None = None,
                   step: float = STEP, budget_s: float = VIEWSHED_BUDGET_S) -> tuple[PlanData, list[PlanData]]:
    """(the building's PlanData, one PlanData per storey, lowest first) of a building scene.
    ``height``: the working height above each storey's floor (m); viewsheds for ``budget_s``
    seconds in all (no limit when ``repeatable``)."""
    sel = np.sort(np.asarray(selected, np.int64))
    c = vis.candidates
    storeys = scene.storeys
    where = storey_index(storeys, c.positions[sel, 2]) if len(sel) else np.zeros(0, np.int64)
    shed: list = [None] * len(sel)
    t0, limit = time.perf_counter(), float("inf") if repeatable else budget_s
    for k, st in enumerate(storeys):
        rows = np.nonzero(where == k)[0]
        left = max(limit - (time.perf_counter() - t0), 0.0)
        for r, v in zip(rows, viewsheds(scene.occupancy, c, sel[rows], st.elevation + height, step,
                                        free_floor(st.scene, height), budget_s=left)):
            shed[r] = replace(v, height=float(height))
    whole = plan_data(scene, vis, placement, metrics, sel, height=height, paper=paper, repeatable=repeatable,
                      views=views, input_from_scene=input_from_scene, shed=shed)
    whole = replace(whole, sheet_offset=SHEETS_PER_STOREY * (len(storeys) - 1))
    t = vis.targets
    t_storey = storey_index(storeys, t.positions[:, 2]) if len(t) else np.zeros(0, np.int64)
    out = []
    for k, st in enumerate(storeys):
        rows = np.nonzero(where == k)[0]
        mask = t_storey == k

        def pick(items, rows=rows):
            return [items[int(r)] for r in rows]

        out.append(replace(whole, scene=st.scene, cameras=[local_camera(cam, st.elevation) for cam in pick(whole.cameras)],
                           marks=pick(whole.marks), shed=pick(whole.shed), dori=pick(whole.dori),
                           price=pick(whole.price), served=pick(whole.served), models=pick(whole.models),
                           views=[], targets=storey_targets(t, mask, st.elevation), coverage=whole.coverage[mask],
                           storey=st.name, sheet_offset=SHEETS_PER_STOREY * k, openings=tuple(st.openings)))
    return whole, out


def write_building_pdf(path: str | Path, whole: PlanData, storeys: list[PlanData], plans=None) -> Path:
    """Write plan.pdf of a building (building_pdf_bytes) atomically."""
    return atomic_write_bytes(Path(path), building_pdf_bytes(whole, storeys, plans))


def building_pdf_bytes(whole: PlanData, storeys: list[PlanData], plans=None) -> bytes:
    """plan.pdf of a building: each storey's floor plan and coverage sheets (lowest first),
    then the camera schedule, the views and the bill of materials of the whole building.
    ``plans``: the storeys' floor plan figures when already drawn (plan_figure)."""
    def pages():
        for k, data in enumerate(storeys):
            yield plans[k] if plans is not None else plan_figure(data)
            yield coverage_figure(data)
        yield from schedule_figures(whole)
        yield views_figure(whole)
        yield bom_figure(whole)

    return pdf_pages_bytes(whole, pages)
