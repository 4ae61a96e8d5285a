"""The hand-over plan set: plan.pdf, plan.svg, plan.dxf and scene.glb, and report.html's plan view.

In three steps: ``prepare_plan_set`` renders the camera views and computes the ``PlanData``
(camplace.outputs.plan_data: viewsheds, schedule rows, DORI distances; numba kernels on
every core); ``plan_file_bytes`` makes plan.pdf, plan.dxf and scene.glb from it (in two forked child
processes beside the rest of the report: ``start_plan_files``, camplace.outputs.background);
``plan_svgs`` draws the floor plan(s) as SVG here, for plan.svg and ``plan_section``, the
report's section (the plan page as inline SVG where hovering a camera shows its schedule
row). ``write_plan_set`` chains them. What each file holds and how to open it: docs/handover.md.
"""

from __future__ import annotations

import html
import re
from dataclasses import dataclass
from pathlib import Path

from camplace.core.files import atomic_write_bytes
from camplace.outputs.background import Forked
from camplace.outputs.plan_data import SCHEDULE_HEAD, PlanData, check_paper, plan_data  # noqa: F401 (re-exported)
from camplace.outputs.plan_bom import bom_figure
from camplace.outputs.plan_dxf import building_dxf, plan_dxf
from camplace.outputs.plan_pdf import plan_figure, plan_pdf_bytes, plan_svg
from camplace.outputs.plan_storeys import building_pdf_bytes, building_plans, is_building
from camplace.outputs.scene_glb import building_glb, scene_glb
from camplace.visibility.viewshed import WORKING_HEIGHT

FILES = ("plan.pdf", "plan.svg", "plan.dxf", "scene.glb")


@dataclass
class PlanSet:
    """What the plan set's files are made from (prepare_plan_set): ``views`` as
    report_html.camera_views returns them, ``data`` the placement's PlanData (a building's
    whole), ``storeys`` one PlanData per storey (empty for one room), ``scene`` the Scene."""

    views: tuple[list[dict], int]
    data: PlanData
    storeys: list[PlanData]
    scene: object
    plans: list | None = None  # the floor plan figures (plan_figure), once drawn: for plan.pdf and plan.svg

    def floor_plans(self) -> list:
        """The floor plan figure of each storey (one room: the one sheet), drawn at the first call."""
        if self.plans is None:
            self.plans = [plan_figure(d) for d in (self.storeys or [self.data])]
        return self.plans


def prepare_plan_set(scene, vis, placement: dict, metrics: dict, selected, *, paper: str = "A3",
                     height: float = WORKING_HEIGHT, repeatable: bool = False, input_from_scene=None,
                     people: tuple | None = None, preload: bool = False) -> PlanSet:
    """The camera views (report_html.camera_views, its time budget unless ``repeatable``) and the
    PlanData (one per storey too for a building, camplace.outputs.plan_storeys); arguments as
    for write_plan_set. ``preload``: the children's modules imported (``preload_modules``) on a
    thread beside the viewsheds' numba kernels (they release the GIL), joined before returning."""
    import threading

    from camplace.outputs.report_html import VIEW_BUDGET_S, camera_views

    views = camera_views(scene, vis, selected, budget_s=float("inf") if repeatable else VIEW_BUDGET_S, people=people)
    imports = threading.Thread(target=preload_modules, name="camplace-preload", daemon=True) if preload else None
    if imports is not None:
        imports.start()
    try:
        if is_building(scene):  # issue 33: one plan sheet per storey
            whole, storeys = building_plans(scene, vis, placement, metrics, selected, height=height, paper=paper,
                                            repeatable=repeatable, views=views[0], input_from_scene=input_from_scene)
            return PlanSet(views, whole, storeys, scene)
        data = plan_data(scene, vis, placement, metrics, selected, height=height, paper=paper, repeatable=repeatable,
                         views=views[0], input_from_scene=input_from_scene)
        return PlanSet(views, data, [], scene)
    finally:
        if imports is not None:
            imports.join()  # before any fork: a child must not inherit an import in progress


def plan_file_bytes(ps: PlanSet, names: tuple[str, ...] = ("plan.pdf", "plan.dxf", "scene.glb")
                    ) -> dict[str, bytes]:
    """The files ``names`` (of plan.pdf, plan.dxf, scene.glb) of a prepared plan set, name ->
    bytes; no file is written and no thread used, so this may run in a forked child
    (camplace.outputs.background). A building's plan.pdf holds each storey's sheets, plan.dxf
    one layer set per storey at its elevation, scene.glb the storeys stacked."""
    if ps.storeys:
        make = {"plan.pdf": lambda: building_pdf_bytes(ps.data, ps.storeys, ps.floor_plans()),
                "plan.dxf": lambda: building_dxf(ps.storeys).encode("utf-8"),
                "scene.glb": lambda: building_glb(ps.scene, ps.storeys)}
    else:
        make = {"plan.pdf": lambda: plan_pdf_bytes(ps.data, ps.floor_plans()[0], lambda: [bom_figure(ps.data)]),
                "plan.dxf": lambda: plan_dxf(ps.data).encode("utf-8"),
                "scene.glb": lambda: scene_glb(ps.data)}
    return {name: make[name]() for name in names}


CHILD_FILES = (("plan.pdf",), ("plan.dxf", "scene.glb"))  # made by two children (plan.pdf alone: the longest)


def start_plan_files(ps: PlanSet) -> list[Forked]:
    """plan.pdf, plan.dxf and scene.glb of ``ps`` (plan_file_bytes) started in forked children
    (CHILD_FILES; camplace.outputs.background): made beside the rest of the report set, and
    matplotlib's PDF writer, ezdxf and trimesh off this process. The floor plans are drawn
    first, here: the PDF's child inherits them and plan_svgs writes them as SVG."""
    ps.floor_plans()
    jobs: list[Forked] = []
    try:
        for names in CHILD_FILES:
            jobs.append(Forked(lambda names=names: plan_file_bytes(ps, names)))
    except BaseException:  # a Ctrl-C between two forks: no child left behind
        for job in jobs:
            job.cancel()
        raise
    return jobs


def preload_modules() -> None:
    """Import what plan_file_bytes uses (once per process; ≈ 0.6 CPU s, trimesh most of it) so
    that each report's children inherit the modules instead of importing them again."""
    import ezdxf  # noqa: F401
    import trimesh  # noqa: F401
    from matplotlib.backends import backend_pdf  # noqa: F401


def plan_svgs(ps: PlanSet) -> list[str]:
    """The floor plan sheet of each storey (one room: the one sheet) as SVG text."""
    return [plan_svg(d, fig) for d, fig in zip(ps.storeys or [ps.data], ps.floor_plans())]


def plan_set_section(ps: PlanSet, svgs: list[str]) -> str:
    """report.html's plan section of a prepared plan set (plan_section / building_plan_section)."""
    return building_plan_section(ps.data, ps.storeys, svgs) if ps.storeys else plan_section(ps.data, svgs[0])


def write_plan_files(out_dir: str | Path, made: dict[str, bytes], svgs: list[str]) -> dict[str, Path]:
    """Write FILES (``made``: plan_file_bytes' result; plan.svg: the first of ``svgs``), each
    atomically, in FILES order; name -> path."""
    out = Path(out_dir)
    files = {**made, "plan.svg": svgs[0].encode("utf-8")}
    return {name: atomic_write_bytes(out / name, files[name]) for name in FILES}


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
                   people: tuple | None = None, prepared: PlanSet | None = None,
                   made: list[Forked] | None = None) -> tuple[dict[str, Path], str, tuple[list[dict], int]]:
    """The hand-over set of a placement (scene: camplace.scene.build.Scene; vis: Visibility;
    placement / metrics: the placement.json / metrics.json dicts; selected: rows of vis.V).
    The camera views are rendered once (report_html.camera_views, its time budget unless
    ``repeatable``) and returned for report.html; the viewsheds have their own budget
    (plan_data.VIEWSHED_BUDGET_S, none when ``repeatable``). ``input_from_scene`` (4x4):
    plan.dxf in that frame (write_outputs(frame='input')). ``people``: (xy (P, 2), radius, height) m,
    test people drawn into the camera views (issue 36). ``prepared`` / ``made``: prepare_plan_set's
    result and start_plan_files' on it (camplace.outputs.write starts both before the rest of
    the report set). plan.pdf, plan.dxf and scene.glb are made in forked children while plan.svg
    is drawn here. Returns (paths, plan section HTML, views)."""
    ps = prepared or prepare_plan_set(scene, vis, placement, metrics, selected, paper=paper, height=height,
                                      repeatable=repeatable, input_from_scene=input_from_scene, people=people)
    made = made or start_plan_files(ps)
    try:
        svgs = plan_svgs(ps)
        paths = write_plan_files(out_dir, {k: v for job in made for k, v in job.result().items()}, svgs)
    finally:
        for job in made:
            job.cancel()
    return paths, plan_set_section(ps, svgs), ps.views
