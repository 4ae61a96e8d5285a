"""The hand-over plan set: plan.pdf, plan.svg, plan.dxf and scene.glb, and report.html's plan view.

``write_handover`` writes the four files from one ``PlanData`` (camplace.outputs.plan_data:
viewsheds, schedule rows, DORI distances); ``plan_section`` is the report's section:
the plan page as inline SVG where hovering a camera shows its schedule row. What each
file holds and how to open it: docs/handover.md.
"""

from __future__ import annotations

import html
import re
from pathlib import Path

from camplace.core.files import atomic_write_text
from camplace.outputs.plan_data import SCHEDULE_HEAD, PlanData, check_paper, plan_data  # noqa: F401 (re-exported)
from camplace.outputs.plan_bom import bom_figure
from camplace.outputs.plan_dxf import write_building_dxf, write_plan_dxf
from camplace.outputs.plan_pdf import plan_figure, plan_svg, write_plan_pdf
from camplace.outputs.plan_storeys import building_plans, is_building, write_building_pdf
from camplace.outputs.scene_glb import write_building_glb, write_scene_glb
from camplace.visibility.viewshed import WORKING_HEIGHT

FILES = ("plan.pdf", "plan.svg", "plan.dxf", "scene.glb")


def write_handover(out_dir: str | Path, data: PlanData) -> tuple[dict[str, Path], str]:
    """Write FILES into out_dir. Returns (file name -> path, the plan page's SVG text)."""
    out = Path(out_dir)
    fig = plan_figure(data)  # sheet 1 drawn once for both files
    svg = plan_svg(data, fig)
    paths = {"plan.pdf": write_plan_pdf(out / "plan.pdf", data, fig, [bom_figure(data)]),
             "plan.svg": atomic_write_text(out / "plan.svg", svg),
             "plan.dxf": write_plan_dxf(out / "plan.dxf", data),
             "scene.glb": write_scene_glb(out / "scene.glb", data)}
    return paths, svg


def svg_with_tooltips(svg: str, data: PlanData) -> str:
    """The plan SVG cut to its <svg> element, each camera's symbol group given a <title>
    (its schedule row), so a browser shows the row when the pointer rests on the camera."""
    rows = {r[0]: "; ".join(f"{h}: {v}" for h, v in zip(data.schedule_head, r)) for r in data.schedule_rows()}
    body = svg[svg.index("<svg"):]
    # inline in HTML5 the parser gives <svg> its namespace: drop the xmlns declarations and the
    # RDF metadata, so the page names no URL at all
    body = re.sub(r"<metadata>.*?</metadata>", "", body, count=1, flags=re.S)
    body = re.sub(r'\s+xmlns(?::\w+)?="[^"]*"', "", body)
    body = re.sub(r'<svg([^>]*?)width="[^"]*"\s+height="[^"]*"', r'<svg\1style="width:100%;height:auto"', body,
                  count=1)

    def titled(m: re.Match) -> str:
        return f'{m.group(0)}<title>{html.escape(rows.get(m.group(1), m.group(1)))}</title>'

    return re.sub(r'<g id="camera-(C\d+)(?:-\w+)?">', titled, body)


def plan_section(data: PlanData, svg: str) -> str:
    """report.html's plan section (HTML): the plan page with hover rows and links to the files."""
    links = " \u00b7 ".join(f"<a href='{f}'>{f}</a>" for f in FILES)
    return (f"<section><h2>Plan</h2><p class=note>The floor plan of plan.pdf: each camera's viewshed at "
            f"{data.height:.2f} m (what it sees at that height, stopped by walls and obstacles), filled by the best "
            f"DORI level any camera reaches there. Rest the pointer on a camera for its row of the schedule. "
            f"Hand-over files: {links}.</p><div class='plan' style='max-width:1500px'>{svg_with_tooltips(svg, data)}</div></section>")


def write_building_handover(out_dir: str | Path, scene, whole: PlanData, storeys: list[PlanData]
                            ) -> tuple[dict[str, Path], list[str]]:
    """FILES of a building (camplace.outputs.plan_storeys: ``whole`` and one PlanData per storey):
    plan.pdf with each storey's sheets, plan.svg the first storey's floor plan, plan.dxf one
    layer set per storey at its elevation, scene.glb stacked. Returns (paths, each storey's
    floor plan as SVG text)."""
    out = Path(out_dir)
    figs = [plan_figure(d) for d in storeys]
    svgs = [plan_svg(d, fig) for d, fig in zip(storeys, figs)]
    paths = {"plan.pdf": write_building_pdf(out / "plan.pdf", whole, storeys, figs),
             "plan.svg": atomic_write_text(out / "plan.svg", svgs[0]),
             "plan.dxf": write_building_dxf(out / "plan.dxf", storeys),
             "scene.glb": write_building_glb(out / "scene.glb", scene, storeys)}
    return paths, svgs


def building_plan_section(whole: PlanData, storeys: list[PlanData], svgs: list[str]) -> str:
    """report.html's plan section of a building: each storey's floor plan (hover rows from the
    whole building's schedule)."""
    links = " \u00b7 ".join(f"<a href='{f}'>{f}</a>" for f in FILES)
    plans = "".join(f"<h3>{html.escape(str(d.storey))}</h3><div class='plan' style='max-width:1500px'>"
                    f"{svg_with_tooltips(svg, whole)}</div>" for d, svg in zip(storeys, svgs))
    return (f"<section><h2>Plan, storey by storey</h2><p class=note>The floor plans of plan.pdf, one per storey: each "
            f"camera's viewshed at {whole.height:.2f} m above its storey's floor, filled by the best DORI level any "
            f"camera of that storey reaches there. Rest the pointer on a camera for its row of the schedule. "
            f"Hand-over files: {links} (plan.svg: the first storey).</p>{plans}</section>")


def write_plan_set(out_dir: str | Path, scene, vis, placement: dict, metrics: dict, selected, *, paper: str = "A3",
                   height: float = WORKING_HEIGHT, repeatable: bool = False, input_from_scene=None,
                   people: tuple | None = None) -> tuple[dict[str, Path], str, tuple[list[dict], int]]:
    """The hand-over set of a placement (scene: camplace.scene.build.Scene; vis: Visibility;
    placement / metrics: the placement.json / metrics.json dicts; selected: rows of vis.V).
    The camera views are rendered once (report_html.camera_views, its time budget unless
    ``repeatable``) and returned for report.html; the viewsheds have their own budget
    (plan_data.VIEWSHED_BUDGET_S, none when ``repeatable``). ``input_from_scene`` (4x4):
    plan.dxf in that frame (write_outputs(frame='input')). ``people``: (xy (P, 2), radius, height) m,
    test people drawn into the camera views (issue 36). Returns (paths, plan section HTML, views)."""
    from camplace.outputs.report_html import VIEW_BUDGET_S, camera_views

    views = camera_views(scene, vis, selected, budget_s=float("inf") if repeatable else VIEW_BUDGET_S, people=people)
    if is_building(scene):  # issue 33: one plan sheet per storey
        whole, storeys = building_plans(scene, vis, placement, metrics, selected, height=height, paper=paper,
                                        repeatable=repeatable, views=views[0], input_from_scene=input_from_scene)
        paths, svgs = write_building_handover(out_dir, scene, whole, storeys)
        return paths, building_plan_section(whole, storeys, svgs), views
    data = plan_data(scene, vis, placement, metrics, selected, height=height, paper=paper, repeatable=repeatable,
                     views=views[0], input_from_scene=input_from_scene)
    paths, svg = write_handover(out_dir, data)
    return paths, plan_section(data, svg), views
