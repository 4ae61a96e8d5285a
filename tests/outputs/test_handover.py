"""The hand-over plan set read back with real clients: pypdf, pdftoppm, ezdxf, trimesh."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

from camplace.core.errors import InputError
from conftest import box_room

pypdf = pytest.importorskip("pypdf")
ezdxf = pytest.importorskip("ezdxf")


def _spec():
    pillar = {"name": "pillar", "box": {"min": [2.8, 1.8, 0.0], "max": [3.2, 2.2, 3.0]}}
    return box_room(obstacles=[pillar], footprint=[[0, 0], [6, 0], [6, 4], [0, 4]],
                    targets=[{"name": "floor", "kind": "volume", "heights": [1.0, 1.5], "coverage": 2}],
                    cameras=[{"name": "cam", "resolution": [640, 480], "fov_deg": [90, 70], "max_range": 6.0}],
                    mounts=[{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0, "yaw_deg": [0, 90, 180, 270],
                             "pitch_deg": [45]}])


@pytest.fixture(scope="module")
def run_result():
    from camplace.workflows.run import run

    return run(_spec(), budget=4, solver="greedy")


def _write(out, r, **kw):
    from camplace.outputs.write import write_outputs

    return write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                         scene=r.scene, **kw)


@pytest.fixture(scope="module")
def plan_dir(tmp_path_factory, run_result):
    out = tmp_path_factory.mktemp("handover")
    paths = _write(out, run_result, repeatable=True)
    return out, paths


def _cameras(out):
    import json

    return json.loads((out / "placement.json").read_text())["cameras"]


def test_every_file_is_written(plan_dir):
    out, paths = plan_dir
    for name in ("plan.pdf", "plan.svg", "plan.dxf", "scene.glb"):
        assert name in paths and (out / name).stat().st_size > 1000


def test_pdf_pages_and_text(plan_dir):
    out, _ = plan_dir
    cams = _cameras(out)
    reader = pypdf.PdfReader(out / "plan.pdf")
    assert len(reader.pages) == 5
    box = reader.pages[0].mediabox
    assert (round(float(box.width)), round(float(box.height))) == (1191, 842)  # A3 landscape, points
    plan = reader.pages[0].extract_text()
    assert "floor plan" in plan and "scale 1:" in plan and "test-room" in plan and "pillar" in plan
    for k in range(len(cams)):
        assert f"C{k + 1}" in plan
    schedule = reader.pages[2].extract_text(extraction_mode="layout")  # text by position: one line a row
    assert "camera schedule" in schedule
    lines = [" ".join(line.split()) for line in schedule.splitlines()]
    assert any(line.startswith("mark id x (m) y (m) height (m) yaw") for line in lines)
    for k, c in enumerate(cams):  # one row per camera: mark, id, position, height, angles, type, status
        row = (f"C{k + 1} {c['candidate_id']} {c['position'][0]:.2f} {c['position'][1]:.2f} {c['position'][2]:.2f} "
               f"{c['yaw_deg']:.1f} {c['pitch_deg']:.1f} {c['roll_deg']:.1f} {c['camera']} pinhole")
        assert sum(line.startswith(row) and line.endswith(" new") for line in lines) == 1, row
    assert "coverage" in reader.pages[1].extract_text() and "camera views" in reader.pages[3].extract_text()
    assert "bill of materials" in reader.pages[4].extract_text()
    assert "date" not in plan  # repeatable: no date in the title block


def test_every_sheet_carries_its_title_block_and_slice_titles(plan_dir):
    """The title block (figure-level text since issue 37, no axes) on each of the 5 sheets with
    its own sheet number; the coverage sheet titles each target height's slice."""
    out, _ = plan_dir
    pages = [p.extract_text() for p in pypdf.PdfReader(out / "plan.pdf").pages]
    for k, (text, name) in enumerate(zip(pages, ("floor plan", "coverage", "camera schedule", "camera views",
                                                  "bill of materials")), start=1):
        assert "camplace \u2013 camera plan" in text, k
        assert f"sheet {k}: {name}" in text and "test-room" in text and "greedy" in text, k
    for z in ("1.00", "1.50"):
        assert f"z = {z} m:" in pages[1]


@pytest.mark.skipif(shutil.which("pdftoppm") is None, reason="pdftoppm (poppler-utils) not installed")
def test_first_page_renders_with_ink_at_the_cameras(plan_dir, run_result, tmp_path):
    from PIL import Image

    from camplace.outputs.plan_data import plan_data
    from camplace.outputs.plan_pdf import plan_figure
    from camplace.outputs.write import placement_dict

    out, _ = plan_dir
    dpi = 60
    subprocess.run(["pdftoppm", "-png", "-r", str(dpi), "-f", "1", "-l", "1", str(out / "plan.pdf"),
                    str(tmp_path / "page")], check=True)
    png = next(tmp_path.glob("page*.png"))
    img = np.asarray(Image.open(png).convert("L"), float)
    assert img.std() > 5  # not blank
    r = run_result
    pd = placement_dict(r.scene.name, r.placement, r.problem.budget, r.visibility.candidates)
    fig = plan_figure(plan_data(r.scene, r.visibility, pd, r.metrics.to_dict(), r.placement.selected,
                                repeatable=True))
    fig.set_dpi(dpi)
    ax = fig.axes[0]
    h = img.shape[0]
    for c in _cameras(out):
        x, y = ax.transData.transform(c["position"][:2])
        px, py = int(round(x)), int(round(h - y))
        win = img[max(py - 4, 0):py + 5, max(px - 4, 0):px + 5]
        assert win.min() < 140, (c["candidate_id"], px, py)  # the camera symbol's dark outline is there
    # far outside the room (the bottom-left page margin) the page is white
    assert img[-5:, :5].min() > 250


def test_dxf_layers_and_camera_blocks(plan_dir):
    out, _ = plan_dir
    cams = _cameras(out)
    doc = ezdxf.readfile(out / "plan.dxf")
    names = {layer.dxf.name for layer in doc.layers}
    for layer in ("CAMPLACE-CAMERAS", "CAMPLACE-FOV", "CAMPLACE-ZONES", "CAMPLACE-WALLS", "CAMPLACE-DORI-DETECT",
                  "CAMPLACE-DORI-IDENTIFY"):
        assert layer in names
    refs = doc.modelspace().query('INSERT[name=="CAMPLACE_CAMERA"]')
    assert len(refs) == len(cams)
    by_id = {ref.get_attrib_text("ID"): ref for ref in refs}
    for c in cams:
        ref = by_id[str(c["candidate_id"])]
        assert ref.dxf.layer == "CAMPLACE-CAMERAS"
        assert np.allclose(tuple(ref.dxf.insert), c["position"], atol=1e-9)
        assert ref.get_attrib_text("TYPE") == c["camera"]
        assert float(ref.get_attrib_text("HEIGHT")) == pytest.approx(c["position"][2], abs=1e-3)
        assert float(ref.get_attrib_text("YAW")) == pytest.approx(c["yaw_deg"], abs=0.01)
        assert float(ref.get_attrib_text("PITCH")) == pytest.approx(c["pitch_deg"], abs=0.01)
        assert ref.dxf.rotation == pytest.approx(c["yaw_deg"])
    assert len(doc.modelspace().query('LWPOLYLINE[layer=="CAMPLACE-FOV"]')) >= len(cams)


def test_glb_cameras_and_bounds(plan_dir, run_result):
    import trimesh

    out, _ = plan_dir
    cams = _cameras(out)
    scene = trimesh.load(out / "scene.glb")
    nodes = [n for n in scene.graph.nodes_geometry if n.startswith("camera ")]
    assert len(nodes) == len(cams)
    assert {n.split(" id ")[1] for n in nodes} == {str(c["candidate_id"]) for c in cams}
    sc = run_result.scene
    fp = np.asarray(sc.footprint, float)
    assert np.allclose(scene.bounds, [[*fp.min(0), 0.0], [*fp.max(0), sc.height]], atol=1e-6)
    assert "coverage" in scene.graph.nodes_geometry and "obstacles" in scene.graph.nodes_geometry


def test_report_shows_the_plan_with_hover_rows(plan_dir):
    out, _ = plan_dir
    text = (out / "report.html").read_text()
    assert "<h2>Plan</h2>" in text and "<svg" in text
    assert text.count('<g id="camera-C1-symbol"><title>mark: C1; id: ') == 1


def test_no_plan_and_paper(tmp_path, run_result):
    paths = _write(tmp_path / "a", run_result, plan=False)
    assert not any((tmp_path / "a" / n).exists() for n in ("plan.pdf", "plan.svg", "plan.dxf", "scene.glb"))
    assert "report.html" in paths and "<h2>Plan</h2>" not in (tmp_path / "a" / "report.html").read_text()
    _write(tmp_path / "b", run_result, paper="a4")
    box = pypdf.PdfReader(tmp_path / "b" / "plan.pdf").pages[0].mediabox
    assert (round(float(box.width)), round(float(box.height))) == (842, 595)
    with pytest.raises(InputError, match="paper: expected one of A4, A3, letter") as err:
        _write(tmp_path / "c", run_result, paper="B5")
    assert err.value.option == "paper"


def test_repeatable_plan_set_is_byte_identical(tmp_path, run_result, plan_dir):
    first, _ = plan_dir  # the module's repeatable write is the first of the two
    _write(tmp_path / "b", run_result, repeatable=True)
    for name in ("plan.pdf", "plan.svg", "plan.dxf", "scene.glb"):
        assert (first / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


def test_report_set_made_in_this_process_is_the_same_bytes(tmp_path, run_result, plan_dir, monkeypatch):
    """plan.pdf, plan.dxf and scene.glb come from forked children (camplace.outputs.background);
    without fork they are made here: the same files in the same order, the same bytes."""
    from camplace.outputs import background

    monkeypatch.setattr(background, "FORK", False)
    first, paths = plan_dir
    again = _write(tmp_path / "here", run_result, repeatable=True)
    assert list(again) == list(paths) and "plan.pdf" in paths
    for name in paths:
        assert (first / name).read_bytes() == (tmp_path / "here" / name).read_bytes(), name


def test_voxel_surface_keeps_only_exposed_faces():
    from camplace.outputs.scene_glb import voxel_surface

    mask = np.zeros((3, 3, 3), bool)
    mask[1, 1, 1] = True
    one = voxel_surface(mask, np.zeros(3), 0.5)
    assert len(one.faces) == 12 and np.allclose(one.bounds, [[0.5] * 3, [1.0] * 3])
    mask[2, 1, 1] = True  # two cells side by side: the shared face is inside, not drawn
    two = voxel_surface(mask, np.zeros(3), 0.5)
    assert len(two.faces) == 20 and np.isclose(two.area, 10 * 0.25)
    assert voxel_surface(np.zeros((2, 2, 2), bool), np.zeros(3), 1.0) is None


PRIVACY = [[0, 0], [4, 0], [4, 4], [0, 4]]
AISLE = [[6.5, 1.5], [7.5, 1.5], [7.5, 2.5], [6.5, 2.5]]
FORBID = [[4.5, 0], [5.5, 0], [5.5, 4], [4.5, 4]]
SITE = {  # tests/workflows/test_sites.py's room: a restroom (privacy) behind a doorway, an aisle zone
    "name": "site", "voxel_size": 0.5, "occupancy_resolution": 0.1,
    "room": {"footprint": [[0, 0], [8, 0], [8, 4], [0, 4]], "height": 3.0},
    "obstacles": [{"name": "wall-s", "box": {"min": [4.0, 0.0, 0.0], "max": [4.2, 1.5, 3.0]}},
                  {"name": "wall-n", "box": {"min": [4.0, 2.5, 0.0], "max": [4.2, 4.0, 3.0]}}],
    "targets": [{"name": "walk", "kind": "volume", "heights": [1.0], "coverage": 1}],
    "cameras": [{"name": "cam", "resolution": [64, 48], "fov_deg": [90, 70], "max_range": 10.0}],
    "mounts": [{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0, "yaw_deg": [0, 90, 180, 270],
                "pitch_deg": [45]}],
    "zones": [{"name": "restroom", "polygon": PRIVACY, "privacy": True},
              {"name": "aisle", "polygon": AISLE, "coverage": 2}],
    "mount_rules": {"forbid": [FORBID]},
    "existing": [{"id": "E1", "camera": "cam", "position": [7.5, 2.0, 2.9], "yaw_deg": 180, "pitch_deg": 45}],
}


@pytest.fixture(scope="module")
def site_dir(tmp_path_factory):
    from camplace.spec.loading import parse_scene
    from camplace.workflows.run import run

    r = run(parse_scene(SITE), budget=2, solver="greedy")
    out = tmp_path_factory.mktemp("site")
    _write(out, r, repeatable=True)
    return out


def _polylines(doc, layer):
    return [np.asarray(e.get_points("xy")) for e in doc.modelspace().query(f'LWPOLYLINE[layer=="{layer}"]')]


def _same_ring(a, b) -> bool:
    return len(a) == len(b) and any(np.allclose(np.roll(a, k, axis=0), b, atol=1e-9) for k in range(len(a)))


def test_zones_privacy_and_forbidden_areas_in_the_dxf_and_pdf(site_dir):
    doc = ezdxf.readfile(site_dir / "plan.dxf")
    zones = _polylines(doc, "CAMPLACE-ZONES")
    assert sum(_same_ring(z, np.asarray(AISLE, float)) for z in zones) == 1
    assert all(e.closed for e in doc.modelspace().query('LWPOLYLINE[layer=="CAMPLACE-ZONES-PRIVACY"]'))
    privacy = _polylines(doc, "CAMPLACE-ZONES-PRIVACY")
    assert len(privacy) == 1 and _same_ring(privacy[0], np.asarray(PRIVACY, float))
    forbid = _polylines(doc, "CAMPLACE-MOUNT-FORBID")
    assert len(forbid) == 1 and _same_ring(forbid[0], np.asarray(FORBID, float))
    assert not any(_same_ring(z, np.asarray(PRIVACY, float)) for z in zones)  # privacy only on its own layer
    texts = {t.dxf.text: t.dxf.layer for t in doc.modelspace().query("TEXT")}
    assert texts["restroom"] == "CAMPLACE-ZONES-PRIVACY" and texts["aisle"] == "CAMPLACE-ZONES"
    existing = doc.modelspace().query('INSERT[layer=="CAMPLACE-CAMERAS-EXISTING"]')
    assert [(r.get_attrib_text("ID"), r.get_attrib_text("STATUS")) for r in existing] == [("E1", "existing")]
    assert np.allclose(tuple(existing[0].dxf.insert), SITE["existing"][0]["position"])
    new = doc.modelspace().query('INSERT[layer=="CAMPLACE-CAMERAS"]')
    assert new and all(r.get_attrib_text("STATUS") == "new" for r in new)
    plan = pypdf.PdfReader(site_dir / "plan.pdf").pages[0].extract_text()
    for word in ("restroom", "aisle", "forbid 1", "privacy zone", "no camera mounted here", "existing camera"):
        assert word in plan, word
    svg = (site_dir / "plan.svg").read_text()
    assert "restroom" in svg and "aisle" in svg


def test_dxf_in_the_input_frame(tmp_path, run_result):
    import dataclasses
    import json

    a = np.radians(30.0)
    T = np.eye(4)
    T[:2, :2] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
    T[:3, 3] = [100.0, -20.0, 0.5]
    r = run_result
    scene = dataclasses.replace(r.scene, input_from_scene=T)
    from camplace.outputs.write import write_outputs

    write_outputs(tmp_path, scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                  scene=scene, repeatable=True, frame="input")
    cams = json.loads((tmp_path / "placement.json").read_text())["cameras"]  # input frame
    doc = ezdxf.readfile(tmp_path / "plan.dxf")
    refs = {ref.get_attrib_text("ID"): ref for ref in doc.modelspace().query('INSERT[name=="CAMPLACE_CAMERA"]')}
    assert len(refs) == len(cams)
    for c in cams:
        ref = refs[str(c["candidate_id"])]
        assert np.allclose(tuple(ref.dxf.insert), c["position"], atol=1e-9)
        assert float(ref.get_attrib_text("YAW")) == pytest.approx(c["yaw_deg"], abs=0.01)
        assert float(ref.get_attrib_text("HEIGHT")) == pytest.approx(c["position"][2], abs=1e-3)
        assert (ref.dxf.rotation - c["yaw_deg"] + 180.0) % 360.0 == pytest.approx(180.0)
    fp = np.asarray(r.scene.footprint, float)
    walls = _polylines(doc, "CAMPLACE-WALLS")
    assert any(_same_ring(w, fp @ T[:2, :2].T + T[:2, 3]) for w in walls)


def test_viewshed_budget_leaves_markers_and_a_note(tmp_path, run_result):
    from camplace.outputs.plan_data import plan_data
    from camplace.outputs.plan_pdf import write_plan_pdf
    from camplace.outputs.write import placement_dict

    r = run_result
    pd = placement_dict(r.scene.name, r.placement, r.problem.budget, r.visibility.candidates)
    data = plan_data(r.scene, r.visibility, pd, r.metrics.to_dict(), r.placement.selected, budget_s=0.0)
    assert data.skipped == len(data.cameras) and all(v.polygon.is_empty for v in data.shed)
    write_plan_pdf(tmp_path / "plan.pdf", data)
    text = pypdf.PdfReader(tmp_path / "plan.pdf").pages[0].extract_text()
    assert f"{len(data.cameras)} viewsheds not computed within the time budget" in text
    assert all(m in text for m in data.marks)  # the cameras are still drawn
    full = plan_data(r.scene, r.visibility, pd, r.metrics.to_dict(), r.placement.selected, budget_s=0.0,
                     repeatable=True)  # repeatable: no budget
    assert full.skipped == 0
