"""Imported walls (prism obstacles of a DXF plan, issue 18) in the hand-over: plan_data's
free floor and the plan cut, plan.dxf's CAMPLACE-WALLS, plan.pdf page 1, the report's
slices (walls by provenance label, rooms by name)."""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

ezdxf = pytest.importorskip("ezdxf")

from camplace.outputs.walls import label_colours, obstacle_label, plan_cut, scene_walls  # noqa: E402
from camplace.scene.importers import import_plan  # noqa: E402
from camplace.scene.importers.ifc_build import GridBuilding  # noqa: E402
from camplace.spec.loading import parse_scene  # noqa: E402
from tests.scene.plan_drawings import draw_grid_dxf  # noqa: E402

B = GridBuilding(names=("Office", "Lab"))


@pytest.fixture(scope="module")
def dxf_run(tmp_path_factory):
    from camplace.outputs.write import write_outputs
    from camplace.workflows.run import run

    tmp = tmp_path_factory.mktemp("walls")
    data = import_plan(draw_grid_dxf(tmp / "plan.dxf", B), coverage=1, budget=3)
    r = run(parse_scene(data, "plan.dxf"), budget=3, solver="greedy")
    out = tmp / "out"
    write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                  scene=r.scene, repeatable=True)
    return data, r, out


def _wall_union(data, height=1.5):
    return shapely.union_all([Polygon(o["prism"]["polygon"], o["prism"].get("holes", []))
                              for o in data["obstacles"] if "prism" in o and o["prism"]["z"][0] <= height
                              <= o["prism"]["z"][1]])


def test_plan_cut_holds_the_wall_polygons_of_the_scene(dxf_run):
    data, r, _ = dxf_run
    walls = scene_walls(r.scene)
    assert len(walls) == sum("prism" in o for o in data["obstacles"]) > 0
    cut, below = plan_cut(walls, 1.5)
    assert set(cut) == {"A-WALL"} and below == {}
    assert cut["A-WALL"].symmetric_difference(_wall_union(data)).area < 1e-6
    cut, below = plan_cut(walls, r.scene.height + 1.0)  # above every wall: all of them below the cut
    assert cut == {} and set(below) == {"A-WALL"} and below["A-WALL"].area == pytest.approx(_wall_union(data).area)
    assert plan_cut(walls, -1.0) == ({}, {})  # under the floor: nothing


def test_viewsheds_stop_at_the_walls(dxf_run):
    from camplace.outputs.plan_data import free_floor

    data, r, _ = dxf_run
    floor = free_floor(r.scene, 1.5)
    inner = _wall_union(data).intersection(r.scene.polygon)
    assert inner.area > 0.5 and floor.intersection(inner).area < 1e-6  # the wall at x = 5 between the rooms


def test_plan_dxf_walls_layer_matches_the_walls(dxf_run):
    data, _, out = dxf_run
    doc = ezdxf.readfile(out / "plan.dxf")
    rings = [np.array([p[:2] for p in e.get_points("xy")]) for e in doc.modelspace().query("LWPOLYLINE")
             if e.dxf.layer == "CAMPLACE-WALLS"]
    walls = _wall_union(data)
    lo, hi = np.vstack(rings).min(0), np.vstack(rings).max(0)
    assert lo == pytest.approx(walls.bounds[:2], abs=1e-3) and hi == pytest.approx(walls.bounds[2:], abs=1e-3)
    fp = Polygon(data["room"]["footprint"])
    assert len(rings) >= 3  # the footprint, the walls' outline and their inner rings (rooms)
    areas = [Polygon(r).area for r in rings]  # the outer wall outline is the footprint (the outer faces)
    assert max(areas) == pytest.approx(fp.area, rel=1e-3) and sum(a == pytest.approx(fp.area, rel=1e-3)
                                                                 for a in areas) >= 2


def test_legend_labels_by_provenance():
    assert obstacle_label("Wall 3-z1", {"file": "b.ifc", "class": "IfcWall", "GlobalId": "x"}) == "IfcWall"
    assert obstacle_label("wall-2", {"file": "p.dxf", "layer": "A-WALL,A-WALL-FULL", "handle": "1F"}) == "A-WALL"
    assert obstacle_label("wall-1", {"file": "p.png"}) == "wall"
    colours = label_colours(["IfcWall", "IfcWindow", "IfcFurnishingElement", "IfcColumn", "X-ODD", "Y-ODD"])
    assert len(set(colours.values())) == 6 and colours["IfcWall"] == label_colours(["A-WALL"])["A-WALL"]


@pytest.mark.skipif(shutil.which("pdftoppm") is None, reason="pdftoppm (poppler-utils) not installed")
def test_plan_pdf_page_1_is_dark_on_the_inner_wall(dxf_run, tmp_path):
    from PIL import Image

    from camplace.outputs.plan_data import plan_data
    from camplace.outputs.plan_pdf import plan_figure

    _, r, out = dxf_run
    subprocess.run(["pdftoppm", "-r", "60", "-f", "1", "-l", "1", "-png", str(out / "plan.pdf"), str(tmp_path / "p")],
                   check=True)
    img = np.asarray(Image.open(next(tmp_path.glob("p*.png"))).convert("RGB"), float)
    placement = json.loads((out / "placement.json").read_text())
    fig = plan_figure(plan_data(r.scene, r.visibility, placement, {}, r.placement.selected, repeatable=True))
    ax = fig.axes[0]
    h, w = img.shape[:2]

    def pixel(x, y):
        fx, fy = fig.transFigure.inverted().transform(ax.transData.transform((x, y)))
        return int(round((1 - fy) * h)), int(round(fx * w))

    def grey(x, y):  # the wall fill: dark grey (viewsheds are orange/red, the floor near white)
        r_, g, b = img[pixel(x, y)]
        return max(r_, g, b) < 110 and max(r_, g, b) - min(r_, g, b) < 20

    assert all(grey(5.0, y) for y in (0.6, 1.0, 3.0, 3.4))  # the inner wall, away from its door
    assert grey(2.5, -0.02) and grey(10.02, 2.0)  # the outer walls (inside the footprint, its edge their outer face)
    assert not any(grey(x, y) for x, y in ((2.5, 2.0), (7.5, 2.0), (5.0, 2.0)))  # rooms and the open door


def test_report_slices_draw_walls_and_room_names(dxf_run):
    from camplace.outputs.figures import SceneView, coverage_slices
    from camplace.outputs.report_figures import slice_figure

    _, r, _ = dxf_run
    view = SceneView.from_scene(r.scene)
    t = r.visibility.targets
    cov = np.zeros(len(t.positions))
    sl = coverage_slices(view, t.positions, t.is_surface, cov)[0]
    assert set(sl.walls) == {"A-WALL"}
    fig = slice_figure(sl, view, [])
    names = [s.get("name") for s in fig["layout"]["shapes"]]
    assert "A-WALL" in names and {"Office", "Lab"} <= set(names)
    assert {a["text"] for a in fig["layout"]["annotations"]} == {"<i>Office</i>", "<i>Lab</i>"}


def test_prism_mesh_is_closed_with_the_prism_volume():
    trimesh = pytest.importorskip("trimesh")
    from camplace.outputs.walls import Wall, prism_mesh

    ring = Polygon([(0, 0), (0, 4), (4, 4), (4, 0)], [[(1, 1), (3, 1), (3, 3), (1, 3)]])  # clockwise outside
    v, t = prism_mesh(Wall("w", "IfcWall", ring, -0.5, 2.0), height=1.5)  # clipped to the room: 0..1.5 m
    m = trimesh.Trimesh(v, t)
    m.merge_vertices()
    assert m.is_watertight and m.is_winding_consistent and m.volume == pytest.approx(12 * 1.5)
    assert prism_mesh(Wall("w", "x", ring, 2.0, 3.0), height=1.5)[1].shape == (0, 3)  # above the ceiling


def test_report_3d_view_has_the_walls_by_label(dxf_run):
    from camplace.outputs.figures import SceneView
    from camplace.outputs.report_figures import view3d_figure

    _, r, _ = dxf_run
    t = r.visibility.targets
    n = len(t.positions)
    fig, _ = view3d_figure(SceneView.from_scene(r.scene), t.positions, np.zeros(n), np.ones(n, int), t.region_ids,
                           t.region_names, [])
    walls = [d for d in fig["data"] if d.get("name") == "A-WALL"]
    assert len(walls) == 1 and walls[0]["type"] == "mesh3d" and max(walls[0]["z"]) == pytest.approx(r.scene.height)
