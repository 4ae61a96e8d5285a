"""What the hand-over plan set draws, gathered once: cameras, viewsheds, schedule rows.

``PlanData`` holds the scene, the placement.json dict (scene frame), metrics, each
selected camera's viewshed at the working height (camplace.visibility.viewshed), its
DORI distances, price and the regions it serves, so plan.pdf / plan.svg / plan.dxf /
scene.glb and report.html's plan view all show the same numbers. Cameras are marked
C1..Cn in candidate-id order (the order of placement.json).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import shapely

from camplace.core.errors import InputError
from camplace.visibility.viewshed import DORI_LEVELS, STEP, WORKING_HEIGHT, Viewshed, dori_distances, viewsheds

VIEWSHED_BUDGET_S = 1.5  # viewsheds stop after this many seconds (the rest: camera symbols only)

PAPERS_MM: dict[str, tuple[float, float]] = {"A4": (297.0, 210.0), "A3": (420.0, 297.0), "letter": (279.4, 215.9)}
DORI_COLOURS = {"detect": "#fef0d9", "observe": "#fdcc8a", "recognise": "#fc8d59", "identify": "#d7301f"}
SCHEDULE_HEAD = ("mark", "id", "x (m)", "y (m)", "height (m)", "yaw (\u00b0)", "pitch (\u00b0)", "roll (\u00b0)",
                 "type", "lens", "price", "DORI I/R/O/D (m)", "serves", "status")


def check_paper(paper: str) -> str:
    """The paper name as PAPERS_MM spells it (case-insensitive), else InputError(option='paper')."""
    for name in PAPERS_MM:
        if str(paper).lower() == name.lower():
            return name
    raise InputError(f"paper: expected one of {', '.join(PAPERS_MM)}, got {paper!r}", option="paper")


@dataclass(frozen=True)
class PlanData:
    """Inputs of every hand-over file. cameras: placement.json camera objects (scene
    frame); marks: 'C1'..; shed: one Viewshed per camera; dori: level -> m per camera;
    price: per camera; served: region -> targets seen, per camera; coverage: (N_p,)
    achieved coverage; dated: the date line of the title block (None: repeatable)."""

    scene: object  # camplace.scene.build.Scene
    placement: dict
    metrics: dict
    cameras: list[dict]
    marks: list[str]
    shed: list[Viewshed]
    dori: list[dict[str, float]]
    price: list[float]
    served: list[dict[str, int]]
    targets: object  # camplace.targets.build.Targets
    coverage: np.ndarray
    height: float = WORKING_HEIGHT
    paper: str = "A3"
    dated: str | None = None
    views: list[dict] = field(default_factory=list)  # report_html.camera_views cards (may be fewer than cameras)
    input_from_scene: np.ndarray | None = None  # 4x4: plan.dxf drawn in the input file's frame; None: scene frame
    models: list = field(default_factory=list)  # camplace.cameras.models.CameraModel per camera (issue 27: BOM sheet)
    storey: str | None = None  # a building's storey (issue 33): its sheets carry the name; None: the whole scene
    sheet_offset: int = 0  # added to the sheet numbers (a building: the storey sheets come first)
    openings: tuple = ()  # a storey's floor openings (shapely polygons, m): drawn as open to the storey below

    def sheet(self, n: int, what: str) -> str:
        """The title block's sheet label: 'sheet n: what' (numbers moved by sheet_offset; a
        storey's sheets end with its name)."""
        return f"sheet {n + self.sheet_offset}: {what}" + (f", {self.storey}" if self.storey else "")

    @property
    def schedule_head(self) -> tuple[str, ...]:
        """SCHEDULE_HEAD, with a 'storey' column after 'id' when the cameras name their storey."""
        if not any("storey" in c for c in self.cameras):
            return SCHEDULE_HEAD
        return (*SCHEDULE_HEAD[:2], "storey", *SCHEDULE_HEAD[2:])

    @property
    def skipped(self) -> int:
        """How many viewsheds the time budget left uncomputed."""
        return sum(not v.computed for v in self.shed)

    @property
    def areas(self) -> list[tuple[str, str, np.ndarray]]:
        """site_areas of the scene."""
        return site_areas(self.scene)

    @property
    def title_pairs(self) -> list[tuple[str, str]]:
        """The title block: (label, value) lines."""
        p, m = self.placement, self.metrics
        bound = p.get("bound")
        out = [("scene", str(p.get("scene", self.scene.name))), ("solver", f"{p.get('solver')} ({p.get('status')})"),
               ("cameras", f"{len(self.cameras)}" + (f" here, {len(p.get('cameras', []))} in all" if self.storey else "")
                + f" (budget {p.get('budget')})"),
               ("cost", f"{float(m.get('cost', p.get('objective', 0.0))):.6g}"),
               ("coverage gap", f"{float(m.get('coverage_gap', 0.0)):.4f}"),
               ("bound", "\u2013" if bound is None else f"{float(bound):.6g}"),
               ("working height", f"{self.height:.2f} m")]
        if self.storey:
            floor = {st.get("name"): st.get("elevation_m") for st in p.get("storeys", [])}.get(self.storey)
            out.insert(1, ("storey", self.storey + ("" if floor is None else f" (floor at {float(floor):.2f} m)")))
        elif p.get("storeys"):
            out.insert(1, ("storeys", ", ".join(str(st.get("name")) for st in p["storeys"])))
        if self.dated:
            out.append(("date", self.dated))
        return out

    def schedule_rows(self) -> list[tuple[str, ...]]:
        """One row of schedule_head per camera (strings); a building's heights are above the
        camera's storey floor (placement.json ``storeys``), its storey in its own column."""
        rows = []
        floors = {st.get("name"): float(st.get("elevation_m", 0.0)) for st in self.placement.get("storeys", [])}
        for c, mark, d, price, served in zip(self.cameras, self.marks, self.dori, self.price, self.served):
            x, y, z = c["position"]
            z -= floors.get(c.get("storey"), 0.0) if self.storey is None else 0.0  # a storey's own cameras: local z
            k = c.get("intrinsics", {})
            lens = f"{k.get('model', '')} {k.get('width', '')}x{k.get('height', '')} f {float(k.get('fx', 0)):.0f}"
            if c.get("focal_mm") is not None:  # a lens as sold (issue 27): the focal length it is set to
                lens += f" ({float(c['focal_mm']):.1f} mm)"
            dori = "/".join(f"{d[n]:.1f}" for n, _ in reversed(DORI_LEVELS))
            serves = ", ".join(f"{r} ({n})" for r, n in served.items()) or "\u2013"
            storey = (str(c["storey"]),) if "storey" in c else ()
            rows.append((mark, camera_id(c), *storey, f"{x:.2f}", f"{y:.2f}", f"{z:.2f}",
                         f"{c['yaw_deg']:.1f}", f"{c['pitch_deg']:.1f}", f"{c['roll_deg']:.1f}", str(c["camera"]),
                         lens, f"{price:g}", dori, serves, "existing" if c.get("existing") else "new"))
        return rows


def camera_id(camera: dict) -> str:
    """The id a placement.json camera object is known by: an existing camera's own ``id``,
    the file's id (``source_id``, evaluate) or the ``candidate_id``."""
    return str(camera.get("id", camera.get("source_id", camera["candidate_id"])))


def site_areas(scene) -> list[tuple[str, str, np.ndarray]]:
    """(kind, name, (K, 2) corners m, scene frame) of the scene's areas (camplace.spec.sites):
    kind 'zone' (a volume zone), 'privacy' (a privacy zone), 'forbid' / 'allow' (mount_rules;
    named 'forbid 1'.., 'allow 1'..)."""
    spec = scene.spec
    out = [("privacy" if z.privacy else "zone", z.name, np.asarray(z.polygon, float))
           for z in getattr(spec, "zones", []) if z.polygon is not None]
    rules = getattr(spec, "mount_rules", None)
    for kind in ("forbid", "allow"):
        polys = getattr(rules, kind, None) or []
        out += [(kind, f"{kind} {k + 1}", np.asarray(p, float)) for k, p in enumerate(polys)]
    return out


def free_floor(scene, height: float):
    """The footprint less the box and prism obstacles (imported walls) that cross
    ``height`` m (a shapely geometry)."""
    from shapely.geometry import box

    from camplace.outputs.walls import plan_cut, scene_walls

    occluding = {o.name for o in scene.spec.obstacles if o.occludes}
    cut = [box(b0[0], b0[1], b1[0], b1[1]) for name, (b0, b1) in scene.boxes.items()
           if name in occluding and b0[2] <= height <= b1[2]]
    cut += list(plan_cut(scene_walls(scene), height)[0].values())
    return scene.polygon.difference(shapely.union_all(cut)) if cut else scene.polygon


def plan_data(scene, vis, placement: dict, metrics: dict, selected: np.ndarray, *, height: float = WORKING_HEIGHT,
              paper: str = "A3", repeatable: bool = False, views: list[dict] | None = None,
              step: float = STEP, budget_s: float = VIEWSHED_BUDGET_S,
              input_from_scene: np.ndarray | None = None, shed: list[Viewshed] | None = None) -> PlanData:
    """PlanData of a placement: ``vis`` (camplace.visibility.engine.Visibility) and
    ``selected`` (rows of vis.V, the cameras of placement['cameras'] in the same order).
    Viewsheds are computed for ``budget_s`` seconds (no limit when ``repeatable``);
    ``input_from_scene`` (4x4) draws plan.dxf in that frame; ``shed``: the viewsheds when
    already computed (a building's, per storey: camplace.outputs.plan_storeys)."""
    if not (np.isfinite(height) and 0.0 <= height <= scene.height):
        raise InputError(f"working height: expected 0..{scene.height:g} m (the room's height), got {height!r}",
                         option="height")
    sel = np.sort(np.asarray(selected, np.int64))
    c, t, V = vis.candidates, vis.targets, vis.V
    cams = [c.cameras[int(c.camera_ids[i])] for i in sel]
    per_model = {id(cam): dori_distances(cam) for cam in cams}  # per model: focal settings share a name
    served = []
    for i in sel:
        seen = V.indices[V.indptr[i]:V.indptr[i + 1]]
        n = np.bincount(t.region_ids[seen], minlength=len(t.region_names))
        served.append({str(t.region_names[r]): int(n[r]) for r in np.nonzero(n)[0]})
    cov = np.bincount(V[sel].indices, minlength=V.shape[1]).astype(np.int64) if len(sel) else np.zeros(V.shape[1], int)
    return PlanData(scene, placement, metrics, list(placement.get("cameras", [])), [f"C{k + 1}" for k in range(len(sel))],
                    shed if shed is not None else
                    viewsheds(scene.occupancy, c, sel, height, step, free_floor(scene, height),
                              budget_s=float("inf") if repeatable else budget_s),
                    [per_model[id(cam)] for cam in cams], [float(cam.cost) for cam in cams], served, t, cov,
                    float(height), check_paper(paper), None if repeatable else time.strftime("%Y-%m-%d %H:%M"),
                    list(views or []), None if input_from_scene is None else np.asarray(input_from_scene, float),
                    cams)
