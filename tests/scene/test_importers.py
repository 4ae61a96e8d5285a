"""Plans people have (issue 18): prism obstacles, the importer registry, DXF floor
plans and plan images, each generated here with the libraries themselves."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.scene.build import build_scene
from camplace.scene.importers import import_plan, plan_kind, prism_obstacles, read_plan, room_zones
from tests.conftest import box_room

L_WALL = [[1, 1], [3, 1], [3, 3], [2.5, 3], [2.5, 1.5], [1, 1.5]]  # a non-convex (L-shaped) wall in plan


def test_prism_cells_follow_the_polygon_and_z():
    spec = box_room(obstacles=[{"name": "w", "prism": {"polygon": L_WALL, "z": [0, 2]},
                                "source": {"file": "plan.dxf", "layer": "A-WALL", "handle": "1F"}}])
    scene = build_scene(spec)
    pts = np.array([[2.0, 1.2, 1.0],   # in the L's foot
                    [2.7, 2.5, 1.0],   # in the L's leg
                    [2.0, 2.5, 1.0],   # in the L's notch: free
                    [2.0, 1.2, 2.5]])  # above the wall: free
    assert scene.occupancy.is_occupied(pts).tolist() == [True, True, False, False]
    assert set(scene.prisms) == {"w"} and scene.prisms["w"][1:] == (0.0, 2.0)
    res = scene.occupancy.resolution
    cells = scene.occupancy.occupied[:, :, int(1.0 / res)].sum() - build_scene(box_room()).occupancy.occupied[
        :, :, int(1.0 / res)].sum()
    area = 2 * 0.5 + 0.5 * 1.5  # foot + leg, m²
    assert cells * res**2 == pytest.approx(area, rel=0.08)


def test_prism_with_a_hole_leaves_the_hole_free():
    ring = {"polygon": [[1, 1], [3, 1], [3, 3], [1, 3]], "holes": [[[1.5, 1.5], [2.5, 1.5], [2.5, 2.5], [1.5, 2.5]]],
            "z": [0, 3]}
    occ = build_scene(box_room(obstacles=[{"name": "r", "prism": ring}])).occupancy
    assert occ.is_occupied(np.array([[1.2, 2.0, 1.0], [2.0, 2.0, 1.0]])).tolist() == [True, False]


def test_prisms_sharing_a_mitred_edge_leave_no_free_cell_on_the_seam():
    # two walls mitred at 45 degrees (BlenderBIM, ArchiCAD): cell centres lie exactly on
    # the shared diagonal; they were in neither prism and came out free inside the wall
    lower = {"polygon": [[1, 1], [2, 1], [2, 2]], "z": [0, 3]}
    upper = {"polygon": [[1, 1], [2, 2], [1, 2]], "z": [0, 3]}
    occ = build_scene(box_room(obstacles=[{"name": "a", "prism": lower}, {"name": "b", "prism": upper}])).occupancy
    c = np.arange(1.025, 2.0, occ.resolution)
    diagonal = np.c_[c, c, np.full(len(c), 1.0)]
    assert occ.is_occupied(diagonal).all()


@pytest.mark.parametrize("prism, key", [({"polygon": [[0, 0], [1, 0]], "z": [0, 1]}, "polygon"),
                                        ({"polygon": L_WALL, "z": [2, 1]}, "z"),
                                        ({"polygon": [[0, 0], [1, 1], [1, 0], [0, 1]], "z": [0, 1]}, "polygon")])
def test_bad_prisms_are_refused_naming_the_key(prism, key):
    with pytest.raises(Exception, match=key):
        box_room(obstacles=[{"name": "w", "prism": prism}])


def test_prism_and_box_together_are_refused():
    with pytest.raises(Exception, match="exactly one"):
        box_room(obstacles=[{"name": "w", "prism": {"polygon": L_WALL, "z": [0, 1]},
                             "box": {"min": [0, 0, 0], "max": [1, 1, 1]}}])


def test_a_rooms_specks_are_no_zones():
    """A room in two real pieces gives name and name-2; a speck a pinch left beside it
    (0.09 m²) is no zone; a small room of its own (a 0.36 m² shaft) stays a zone."""
    from collections import Counter

    from shapely.geometry import MultiPolygon, box

    skipped = Counter()
    zones = room_zones([("Hall", MultiPolygon([box(0, 0, 4, 3), box(5, 0, 7, 1), box(8, 0, 8.3, 0.3)])),
                        ("Shaft", box(9, 0, 9.6, 0.6))], 1, skipped=skipped)
    assert [z["name"] for z in zones] == ["Hall", "Hall-2", "Shaft"] and skipped["slivers"] == 1


def test_registry_kinds_and_refusals(tmp_path):
    assert [plan_kind(f"a{s}") for s in (".DXF", ".png", ".jpeg", ".tif", ".ifc", ".ply")] == \
        ["dxf", "image", "image", "image", "ifc", None]
    with pytest.raises(InputError, match="file not found"):
        import_plan(tmp_path / "none.dxf")
    with pytest.raises(InputError, match="not a plan"):
        import_plan(tmp_path / "a.ply")


def test_prism_obstacles_keep_holes_and_provenance():
    from shapely.geometry import Polygon

    ring = Polygon([(0, 0), (4, 0), (4, 4), (0, 4)], [[(0.2, 0.2), (3.8, 0.2), (3.8, 3.8), (0.2, 3.8)]])
    (ob,) = prism_obstacles(ring, 0, 2.5, "wall", {"file": "p.dxf", "layer": "A-WALL"})
    assert ob["name"] == "wall-1" and ob["source"]["layer"] == "A-WALL"
    assert len(ob["prism"]["holes"]) == 1 and ob["prism"]["z"] == [0, 2.5]


# ------------------------------------------------------------------ the two-room plan (mm)
# outer walls 10 m x 5 m, 0.2 m thick; an interior wall x 4.9..5.1 m with a 0.9 m door
# (y 2.0..2.9 m); room A "Office" (west), room B "Lab" (east); a 1.2 m x 0.6 m desk in A
WALL_AREA = 50 - 2 * 4.7 * 4.6 - 0.2 * 0.9  # m², all walls
FOOTPRINT_AREA = 10.0 * 5.0  # m², the building's outline: the outer faces of the outer walls
ROOM_A = [(200, 200), (4900, 200), (4900, 4800), (200, 4800)]
ROOM_B = [(5100, 200), (9800, 200), (9800, 4800), (5100, 4800)]


def draw_dxf(path, insunits=4, door_layer="A-DOOR"):
    """The two-room plan as an AIA-layered DXF (double-line walls, door, desk, rooms)."""
    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = insunits
    msp = doc.modelspace()
    w = {"layer": "A-WALL"}
    msp.add_lwpolyline([(0, 0), (10000, 0), (10000, 5000), (0, 5000)], close=True, dxfattribs=w)
    msp.add_lwpolyline([(4900, 2000), (4900, 200), (200, 200), (200, 4800), (4900, 4800), (4900, 2900)],
                       dxfattribs=w)
    msp.add_lwpolyline([(5100, 2900), (5100, 4800), (9800, 4800), (9800, 200), (5100, 200), (5100, 2000)],
                       dxfattribs=w)
    msp.add_line((4900, 2000), (5100, 2000), dxfattribs=w)
    msp.add_line((4900, 2900), (5100, 2900), dxfattribs=w)
    msp.add_line((5100, 2000), (6000, 2000), dxfattribs={"layer": door_layer})  # the leaf, swung open
    msp.add_arc((5100, 2000), 900, 0, 90, dxfattribs={"layer": door_layer})
    desk = doc.blocks.new("DESK")
    desk.add_lwpolyline([(0, 0), (1200, 0), (1200, 600), (0, 600)], close=True)
    msp.add_blockref("DESK", (1500, 3500), dxfattribs={"layer": "A-FURN"})
    for pts, label, at in ((ROOM_A, "Office", (2500, 1000)), (ROOM_B, "Lab", (7500, 2500))):
        msp.add_lwpolyline(pts, close=True, dxfattribs={"layer": "A-AREA"})
        msp.add_mtext(label, dxfattribs={"layer": "A-AREA-IDEN", "insert": at})
    doc.saveas(path)
    return path


def _sees(scene, a, b, n=400) -> bool:
    """True when no occupied cell lies on the segment a -> b (m), ends excluded."""
    t = np.linspace(0.02, 0.98, n)[:, None]
    return not scene.occupancy.is_occupied(np.asarray(a) + t * (np.asarray(b) - np.asarray(a))).any()


def _wall_cells_m2(scene, z=1.0) -> float:
    """Occupied plan area (m²) inside the footprint at height z."""
    import shapely

    occ = scene.occupancy
    k = int((z - occ.origin[2]) / occ.resolution)
    gx, gy = np.meshgrid(occ.cell_centres(0), occ.cell_centres(1), indexing="ij")
    inside = shapely.contains_xy(scene.polygon, gx, gy)
    return float((occ.occupied[:, :, k] & inside).sum() * occ.resolution**2)


def _prism_area(ob) -> float:
    from shapely.geometry import Polygon

    return Polygon(ob["prism"]["polygon"], ob["prism"].get("holes", [])).area


def _scene_of(data):
    from camplace.spec.loading import parse_scene

    return build_scene(parse_scene(data, "plan"))


def test_dxf_two_rooms_known_answers(tmp_path):
    from shapely.geometry import Polygon

    data = import_plan(draw_dxf(tmp_path / "plan.dxf"))
    assert Polygon(data["room"]["footprint"]).area == pytest.approx(FOOTPRINT_AREA, rel=0.01)
    assert {z["name"] for z in data["zones"]} == {"Office", "Lab"}
    office = next(z for z in data["zones"] if z["name"] == "Office")
    assert Polygon(office["polygon"]).area == pytest.approx(4.7 * 4.6, rel=0.01)
    walls = [o for o in data["obstacles"] if o["name"].startswith("wall")]
    assert walls and all(o["source"]["file"] == "plan.dxf" and "A-WALL" in o["source"]["layer"] for o in walls)
    assert sum(_prism_area(o) for o in walls) == pytest.approx(WALL_AREA, rel=0.01)
    (desk,) = [o for o in data["obstacles"] if o["name"].startswith("desk")]
    assert desk["prism"]["z"] == [0.0, 0.9] and desk["source"]["block"] == "DESK"
    assert Polygon(desk["prism"]["polygon"]).area == pytest.approx(0.72, rel=0.01)
    scene = _scene_of(data)
    assert _wall_cells_m2(scene, 1.0) == pytest.approx(WALL_AREA, rel=0.05)  # every wall (inside the footprint)
    assert _wall_cells_m2(scene, 0.5) == pytest.approx(WALL_AREA + 0.72, rel=0.05)  # and the desk
    assert _sees(scene, (2.0, 2.45, 1.5), (8.0, 2.45, 1.0))  # through the open door
    assert not _sees(scene, (2.0, 4.0, 1.5), (8.0, 4.0, 1.0))  # through the interior wall


def test_dxf_closed_door_blocks_the_view_and_units_override(tmp_path):
    data = import_plan(draw_dxf(tmp_path / "plan.dxf"), doors="closed")
    assert any(o["name"].startswith("door") for o in data["obstacles"])
    assert not _sees(_scene_of(data), (2.0, 2.45, 1.5), (8.0, 2.45, 1.0))
    data = import_plan(draw_dxf(tmp_path / "unitless.dxf", insunits=0), units="mm")
    from shapely.geometry import Polygon

    assert Polygon(data["room"]["footprint"]).area == pytest.approx(FOOTPRINT_AREA, rel=0.01)


def test_unitless_dxf_unit_guessed_from_its_walls_and_doors(tmp_path, monkeypatch, capsys):
    from shapely.geometry import Polygon

    from tests.conftest import run_cli

    plan = draw_dxf(tmp_path / "plan.dxf", insunits=0)  # $INSUNITS 0, drawn in mm
    got = read_plan(plan)
    assert got.used["units"].startswith("mm (guessed") and "door swings 0.90 m" in got.used["units"]
    assert any("no drawing unit" in n and "(units)" in n for n in got.notes)
    assert Polygon(got.scene["room"]["footprint"]).area == pytest.approx(FOOTPRINT_AREA, rel=0.01)
    code, text = run_cli(["scene", "import", plan, "--out", tmp_path / "site.yaml"], monkeypatch, capsys)
    assert code == 0 and "guessed" in text and "(--units)" in text, text


def test_cli_run_and_import_dxf(tmp_path, monkeypatch, capsys):
    import json

    import yaml
    from shapely.geometry import Point, Polygon

    from tests.conftest import run_cli

    plan = draw_dxf(tmp_path / "plan.dxf")
    code, text = run_cli(["--quiet", "scene", "import", plan, "--out", tmp_path / "site.yaml"], monkeypatch, capsys)
    assert code == 0, text
    data = yaml.safe_load((tmp_path / "site.yaml").read_text())
    assert [z["name"] for z in data["zones"]] == ["Office", "Lab"]
    scene = _scene_of(data)
    out = tmp_path / "run"
    code, text = run_cli(["--quiet", "run", plan, "--out", out, "--budget", "6", "--grid-only", "--no-plan"],
                         monkeypatch, capsys)
    assert code == 0, text
    cams = np.array([c["position"] for c in json.loads((out / "placement.json").read_text())["cameras"]], float)
    assert len(cams) > 0 and not scene.occupancy.is_occupied(cams).any()
    assert all(scene.polygon.contains(Point(*c[:2])) for c in cams)
    rooms = {z["name"]: Polygon(z["polygon"]) for z in data["zones"]}
    assert {n for n, r in rooms.items() if any(r.contains(Point(*c[:2])) for c in cams)} == {"Office", "Lab"}
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["coverage_gap"] < 1.0


def _bad_dxf(tmp_path, kind):
    import ezdxf

    if kind == "not-dxf":
        p = tmp_path / "plan.dxf"
        p.write_text("this is not a drawing\n")
        return p
    if kind == "no-walls":
        doc = ezdxf.new()
        doc.header["$INSUNITS"] = 4
        doc.modelspace().add_line((0, 0), (1000, 0), dxfattribs={"layer": "A-ANNO"})
        doc.saveas(tmp_path / "plan.dxf")
        return tmp_path / "plan.dxf"
    doc = ezdxf.new()  # unitless, 0.5 units wide: no unit makes it a building
    doc.header["$INSUNITS"] = 0
    doc.modelspace().add_lwpolyline([(0, 0), (0.5, 0), (0.5, 0.3), (0, 0.3)], close=True, dxfattribs={"layer": "A-WALL"})
    doc.saveas(tmp_path / "plan.dxf")
    return tmp_path / "plan.dxf"


@pytest.mark.parametrize("kind, words", [("not-dxf", "not a DXF file"), ("no-walls", "no walls found"),
                                         ("unitless", "--units")])
def test_bad_dxf_exits_2_with_one_line_and_writes_nothing(tmp_path, monkeypatch, capsys, kind, words):
    from tests.conftest import run_cli

    plan = _bad_dxf(tmp_path, kind)
    for args in (["scene", "import", plan, "--out", tmp_path / "site.yaml"], ["run", plan, "--out", tmp_path / "o"]):
        code, text = run_cli(args, monkeypatch, capsys)
        lines = [ln for ln in text.strip().splitlines() if ln.strip()]
        assert code == 2 and len(lines) == 1 and "plan.dxf" in lines[0] and words in lines[0], text
        assert not (tmp_path / "site.yaml").exists() and not (tmp_path / "o").exists()


def test_dxf_coordinates_that_are_no_numbers_are_left_out_without_a_warning(tmp_path):
    import warnings

    import ezdxf

    plan = draw_dxf(tmp_path / "plan.dxf")
    doc = ezdxf.readfile(plan)
    for end in ((float("nan"), 5000), (1e308, 5000)):  # damage: 'nan' and an overflowing number in the file
        doc.modelspace().add_line((0, 0), end, dxfattribs={"layer": "A-WALL"})
    doc.saveas(plan)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # shapely's RuntimeWarnings (invalid value, overflow in buffer) fail
        got = read_plan(plan)
    assert got.skipped["entities with coordinates that are no numbers or over 10,000 km out"] == 2
    assert {z["name"] for z in got.scene["zones"]} == {"Office", "Lab"}


def test_bad_units_option_is_refused(tmp_path, monkeypatch, capsys):
    from tests.conftest import run_cli

    code, text = run_cli(["scene", "import", draw_dxf(tmp_path / "plan.dxf"), "--units", "furlong",
                          "--out", tmp_path / "s.yaml"], monkeypatch, capsys)
    assert code == 2 and "--units" in text and "furlong" in text and not (tmp_path / "s.yaml").exists()


# ------------------------------------------------------------------ the same plan as an image
PX = 0.02  # m per pixel
MARGIN = 20  # white pixels around the building


def draw_png(path, closed=True):
    """The two-room plan drawn with Pillow: 0.2 m black walls, a 0.9 m door gap, thin
    text and a door swing (removed as thinner than a wall); ``closed=False`` opens
    both rooms to the outside (no enclosed room)."""
    from PIL import Image, ImageDraw

    def px(x, y):  # metres (y up) -> pixel (col, row)
        return MARGIN + x / PX, MARGIN + (5.0 - y) / PX

    im = Image.new("L", (int(10 / PX) + 2 * MARGIN, int(5 / PX) + 2 * MARGIN), 255)
    d = ImageDraw.Draw(im)

    def rect(x0, y0, x1, y1, fill=0):
        (c0, r1), (c1, r0) = px(x0, y0), px(x1, y1)
        d.rectangle([c0, r0, c1 - 1, r1 - 1], fill=fill)

    for r in ((0, 0, 10, 0.2), (0, 4.8, 10, 5), (0, 0, 0.2, 5), (9.8, 0, 10, 5), (4.9, 0, 5.1, 2.0), (4.9, 2.9, 5.1, 5)):
        rect(*r)
    if not closed:  # 2 m gaps in the west and east walls: neither room is enclosed
        rect(9.8, 1.0, 10, 3.0, fill=255)
        rect(0, 1.0, 0.2, 3.0, fill=255)
    d.arc([*px(4.2, 2.9), *px(5.8, 1.3)], 270, 360, fill=0, width=1)
    d.text(px(2.0, 2.5), "Office", fill=0)
    im.save(path)
    return path


def test_image_two_rooms_known_answers(tmp_path):
    from shapely.geometry import Polygon

    data = import_plan(draw_png(tmp_path / "plan.png"), scale=PX, ocr=False)  # OCR of labels: test_image_plans.py
    assert Polygon(data["room"]["footprint"]).area == pytest.approx(FOOTPRINT_AREA, rel=0.01)
    assert [z["name"] for z in data["zones"]] == ["room-1", "room-2"]
    assert sorted(Polygon(z["polygon"]).area for z in data["zones"]) == pytest.approx([4.7 * 4.6] * 2, rel=0.03)
    assert all(o["source"]["file"] == "plan.png" for o in data["obstacles"])
    scene = _scene_of(data)
    assert sum(_prism_area(o) for o in data["obstacles"]) == pytest.approx(WALL_AREA, rel=0.03)
    assert _wall_cells_m2(scene, 1.0) == pytest.approx(WALL_AREA, rel=0.08)
    assert _sees(scene, (2.0, 2.45, 1.5), (8.0, 2.45, 1.0))  # through the door gap
    assert not _sees(scene, (2.0, 4.0, 1.5), (8.0, 4.0, 1.0))


def test_image_scale_from_two_reference_points(tmp_path):
    from shapely.geometry import Polygon

    # the outer wall's west and east faces: 500 px apart, 10 m
    data = import_plan(draw_png(tmp_path / "plan.jpg"), ref=(MARGIN, 100, MARGIN + 500, 100, 10.0))
    assert Polygon(data["room"]["footprint"]).area == pytest.approx(FOOTPRINT_AREA, rel=0.02)
    assert len(data["zones"]) == 2


def test_cli_run_png(tmp_path, monkeypatch, capsys):
    import json

    from shapely.geometry import Point

    from tests.conftest import run_cli

    plan = draw_png(tmp_path / "plan.png")
    out = tmp_path / "run"
    code, text = run_cli(["--quiet", "run", plan, "--scale", PX, "--out", out, "--budget", "6", "--grid-only",
                          "--no-plan"], monkeypatch, capsys)
    assert code == 0, text
    scene = _scene_of(import_plan(plan, scale=PX))
    cams = np.array([c["position"] for c in json.loads((out / "placement.json").read_text())["cameras"]], float)
    assert len(cams) > 0 and not scene.occupancy.is_occupied(cams).any()
    assert all(scene.polygon.contains(Point(*c[:2])) for c in cams)
    assert {c[0] < 5 for c in cams} == {True, False}  # cameras in both rooms


@pytest.mark.parametrize("case, words", [("open", "no closed room"), ("noscale", "--scale"),
                                         ("garbage", "not a readable image")])
def test_bad_images_exit_2_with_one_line(tmp_path, monkeypatch, capsys, case, words):
    from tests.conftest import run_cli

    plan = tmp_path / "plan.png"
    if case == "garbage":
        plan.write_bytes(b"not a png at all")
    else:
        draw_png(plan, closed=case != "open")
    scale = [] if case == "noscale" else ["--scale", PX]
    code, text = run_cli(["scene", "import", plan, *scale, "--out", tmp_path / "s.yaml"], monkeypatch, capsys)
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and "plan.png" in lines[0] and words in lines[0], text
    assert not (tmp_path / "s.yaml").exists()


def test_run_on_the_imported_yaml_reproduces_the_run_on_the_dxf(tmp_path, monkeypatch, capsys):
    """camplace run site.yaml (written by scene import plan.dxf) = camplace run plan.dxf:
    the same V (hash of the CSR arrays) and the same placement."""
    import hashlib
    import json

    from tests.conftest import run_cli

    plan = draw_dxf(tmp_path / "plan.dxf")
    site = tmp_path / "site.yaml"
    assert run_cli(["--quiet", "scene", "import", plan, "--out", site], monkeypatch, capsys)[0] == 0
    outs = {}
    for name, src in (("dxf", plan), ("yaml", site)):
        outs[name] = tmp_path / name
        code, text = run_cli(["--quiet", "run", src, "--out", outs[name], "--budget", "4", "--grid-only",
                              "--repeatable", "--no-plan"], monkeypatch, capsys)
        assert code == 0, text

    def v_hash(folder):
        with np.load(folder / "visibility.npz") as z:
            return hashlib.sha256(b"".join(np.ascontiguousarray(z[k]).tobytes() for k in sorted(z.files))).hexdigest()

    def cameras(folder):
        return json.loads((folder / "placement.json").read_text())["cameras"]

    assert v_hash(outs["dxf"]) == v_hash(outs["yaml"])
    assert cameras(outs["dxf"]) == cameras(outs["yaml"]) and cameras(outs["dxf"])


def test_cli_dxf_wall_layers_and_layer_height(tmp_path, monkeypatch, capsys):
    """--wall-layers PATTERNS and --layer-height LAYER=M reach dxf.import_plan's options."""
    import yaml

    from tests.conftest import run_cli

    plan = draw_dxf(tmp_path / "plan.dxf")
    site = tmp_path / "site.yaml"
    code, text = run_cli(["--quiet", "scene", "import", plan, "--out", site, "--layer-height", "A-FURN*=0.75"],
                         monkeypatch, capsys)
    assert code == 0, text
    (desk,) = [o for o in yaml.safe_load(site.read_text())["obstacles"] if o["name"].startswith("desk")]
    assert desk["prism"]["z"] == [0.0, 0.75]
    code, text = run_cli(["scene", "import", plan, "--out", tmp_path / "none.yaml", "--wall-layers", "X-WALL*,PARTN"],
                         monkeypatch, capsys)
    assert code == 2 and "no walls found" in text and "X-WALL*, PARTN" in text, text
    assert not (tmp_path / "none.yaml").exists()
    code, text = run_cli(["scene", "import", plan, "--out", site, "--layer-height", "A-FURN"], monkeypatch, capsys)
    assert code == 2 and "--layer-height" in text and "LAYER=M" in text, text


@pytest.mark.parametrize("name, words", [("plan.dwg", "save it as DXF"), ("house.rvt", "export it as IFC"),
                                         ("office.pln", "save it as IFC")])
def test_tool_native_formats_say_how_to_export(tmp_path, name, words, monkeypatch, capsys):
    """DWG, Revit and ArchiCAD files: one line saying what to export, from Python and the CLI."""
    from tests.conftest import run_cli

    (tmp_path / name).write_bytes(b"AC1032\x00\x00")
    with pytest.raises(InputError, match=words):
        read_plan(tmp_path / name)
    code, text = run_cli(["run", tmp_path / name, "--out", tmp_path / "out"], monkeypatch, capsys)
    assert code == 2 and words in text and len(text.strip().splitlines()) == 1 and not (tmp_path / "out").exists()
