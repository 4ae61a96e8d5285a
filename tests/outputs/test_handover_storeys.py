"""A building's hand-over set (issue 33) read back with real clients: pypdf, ezdxf, trimesh,
and report.html's storey selector. One generated two-storey building, run once."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from conftest import two_storeys

pypdf = pytest.importorskip("pypdf")
ezdxf = pytest.importorskip("ezdxf")
trimesh = pytest.importorskip("trimesh")

E1 = 3.5  # the upper storey's floor (m)


@pytest.fixture(scope="module")
def building_dir(tmp_path_factory):
    from camplace.outputs.write import write_outputs
    from camplace.workflows.run import run

    r = run(two_storeys(E1), budget=4, solver="greedy")
    out = tmp_path_factory.mktemp("building")
    paths = write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                          scene=r.scene, repeatable=True)
    return out, paths, json.loads((out / "placement.json").read_text())


def test_both_storeys_have_cameras(building_dir):
    _, _, p = building_dir
    assert sorted({c["storey"] for c in p["cameras"]}) == ["Ground", "Level 1"]


def test_pdf_one_plan_and_coverage_sheet_per_storey_then_the_building(building_dir):
    out, _, p = building_dir
    pages = [pg.extract_text() for pg in pypdf.PdfReader(out / "plan.pdf").pages]
    assert len(pages) == 2 * 2 + 3  # per storey: plan, coverage; then schedule, views, bill of materials
    for k, name in enumerate(("Ground", "Level 1")):
        assert f"storey {name}: floor plan" in pages[2 * k] and f"sheet {2 * k + 1}: floor plan, {name}" in pages[2 * k]
        assert f"sheet {2 * k + 2}: coverage, {name}" in pages[2 * k + 1]
    assert "open to below" in pages[2] and "open to below" not in pages[0]  # Level 1's floor opening
    assert "sheet 5: camera schedule" in pages[4] and "storey" in pages[4]
    assert "sheet 7: bill of materials" in pages[6]
    n_ground = sum(c["storey"] == "Ground" for c in p["cameras"])
    assert f"floor plan, {n_ground} cameras" in pages[0]
    assert f"{n_ground} here, {len(p['cameras'])} in all (budget 4)" in pages[0]


def test_schedule_heights_are_above_the_storey_floor(building_dir):
    from camplace.outputs.plan_storeys import building_plans  # noqa: F401 (the module the rows come from)
    from camplace.outputs.plan_data import PlanData

    _, _, p = building_dir
    cams = p["cameras"]
    data = PlanData(None, p, {}, cams, [f"C{k + 1}" for k in range(len(cams))], [], [{}] * len(cams),
                    [0.0] * len(cams), [{}] * len(cams), None, np.zeros(0))
    head = data.schedule_head
    assert head[2] == "storey"
    for c, row in zip(cams, (dict(zip(head, r)) for r in _rows(data))):
        floor = E1 if c["storey"] == "Level 1" else 0.0
        assert row["storey"] == c["storey"]
        assert float(row["height (m)"]) == pytest.approx(c["position"][2] - floor, abs=0.006)


def _rows(data):
    from dataclasses import replace

    dori = {name: 1.0 for name in ("identify", "recognise", "observe", "detect")}
    return replace(data, dori=[dori] * len(data.cameras)).schedule_rows()


def test_svg_is_the_first_storey(building_dir):
    out, _, p = building_dir
    svg = (out / "plan.svg").read_text()
    assert "storey Ground" in svg and "storey Level 1" not in svg
    first = [k + 1 for k, c in enumerate(p["cameras"]) if c["storey"] == "Ground"]
    assert all(f'id="camera-C{k}-symbol"' in svg for k in first)


def test_dxf_one_layer_set_per_storey_at_its_elevation(building_dir):
    out, _, p = building_dir
    doc = ezdxf.readfile(out / "plan.dxf")
    layers = {lay.dxf.name for lay in doc.layers}
    for name in ("Ground", "Level 1"):
        assert {f"{name}-CAMERAS", f"{name}-WALLS", f"{name}-FOV", f"{name}-DORI-IDENTIFY"} <= layers
    assert not any(lay.startswith("CAMPLACE-") for lay in layers)
    msp = doc.modelspace()
    for name, floor in (("Ground", 0.0), ("Level 1", E1)):
        walls = msp.query(f'LWPOLYLINE[layer=="{name}-WALLS"]')
        assert len(walls) and all(w.dxf.elevation == pytest.approx(floor) for w in walls)
        inserts = msp.query(f'INSERT[layer=="{name}-CAMERAS"]')
        want = sorted(round(c["position"][2], 3) for c in p["cameras"] if c["storey"] == name)
        assert sorted(round(i.dxf.insert[2], 3) for i in inserts) == want
        assert all(floor < z <= floor + 3.0 for z in want)


def test_glb_holds_both_storeys_stacked(building_dir):
    out, _, p = building_dir
    sc = trimesh.load(out / "scene.glb", force="scene")
    geo = sc.geometry
    assert np.allclose(geo["Ground/room"].bounds, [[0, 0, 0], [8, 6, 3.0]])
    assert np.allclose(geo["Level 1/room"].bounds, [[0, 0, E1], [6, 6, E1 + 3.0]])
    assert np.allclose(geo["Level 1/obstacles"].bounds, [[4, 4, E1], [5, 5, E1 + 1.0]])
    # the upper slab is open where its floor opening is: no floor triangle covers (2.5, 2.5)
    room = geo["Level 1/room"]
    floor = room.triangles[np.all(np.abs(room.triangles[:, :, 2] - E1) < 1e-9, axis=1)]
    assert len(floor) and not any(trimesh.triangles.points_to_barycentric(t[None], [[2.5, 2.5, E1]]).min() > 0
                                  for t in floor)
    frusta = {k: g for k, g in geo.items() if "/camera " in k}
    assert len(frusta) == len(p["cameras"])
    for c in p["cameras"]:
        g = next(g for k, g in frusta.items() if k.startswith(f"{c['storey']}/") and k.endswith(f"id {c['candidate_id']}"))
        assert np.allclose(g.vertices[0], c["position"])
    assert geo["Level 1/coverage"].vertices[:, 2] == pytest.approx(E1 + 1.0)


def test_report_has_a_storey_selector_and_slices_per_storey(building_dir):
    out, _, _ = building_dir
    page = (out / "report.html").read_text()
    figs = json.loads(page.split("var figs = ", 1)[1].split(";\n", 1)[0])
    menu = figs["view3d"]["layout"]["updatemenus"][0]
    assert [b["label"] for b in menu["buttons"]] == ["all storeys", "Ground", "Level 1"]
    names = [t["name"] for t in figs["view3d"]["data"]]
    upper = menu["buttons"][2]["args"][0]["visible"]
    assert len(upper) == len(names) and all(v == n.startswith("Level 1:") for v, n in zip(upper, names))
    zs = [z for t in figs["view3d"]["data"] if t["name"].startswith("Level 1: targets") for z in t["z"]]
    assert zs and min(zs) == pytest.approx(E1 + 1.0)
    titles = [f["layout"]["title"]["text"] for k, f in figs.items() if k.startswith("slice")]
    assert titles == ["Ground: coverage 1.00 m above its floor (z = 1.00 m)",
                      "Level 1: coverage 1.00 m above its floor (z = 4.50 m)"]
    assert "Plan, storey by storey" in page
    assert "<th>storey</th>" in page.split("<h2>Mount list</h2>", 1)[1]


def test_storey_layer_names():
    from camplace.outputs.plan_dxf import storey_layer

    assert storey_layer("Level 1", "CAMPLACE-CAMERAS") == "Level 1-CAMERAS"
    assert storey_layer("A/B: 2", "CAMPLACE-DORI-DETECT") == "A_B_ 2-DORI-DETECT"


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 4), min_size=1, max_size=30), st.data())
def test_storey_targets_keep_each_targets_region(ids, data):
    from camplace.outputs.plan_storeys import storey_targets
    from camplace.targets.build import Targets

    n = len(ids)
    mask = np.array(data.draw(st.lists(st.booleans(), min_size=n, max_size=n)))
    names = tuple(f"S/r{k}" for k in range(5))
    t = Targets(np.c_[np.zeros((n, 2)), np.arange(n, dtype=float) + 3.0], np.zeros((n, 3)), np.ones(n, np.int64),
                np.ones(n), np.array(ids, np.int32), names, ("volume",) * 5, np.full(5, 90.0))
    sub = storey_targets(t, mask, 3.0)
    assert [sub.region_names[r] for r in sub.region_ids] == [names[r] for r in np.array(ids)[mask]]
    assert set(sub.region_names) == {names[r] for r in np.array(ids)[mask]}
    assert np.allclose(sub.positions[:, 2], t.positions[mask, 2] - 3.0)
