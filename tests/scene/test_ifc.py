"""IFC (BIM) import (issue 18): a two-room storey written with ifcopenshell.api (walls
as IfcExtrudedAreaSolid, a door between the rooms, a window in an outer wall, a slab
above on a 'Roof' storey) read back by camplace.scene.importers.ifc."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import yaml
from shapely.geometry import Polygon

pytest.importorskip("ifcopenshell")

from camplace.core.errors import InputError  # noqa: E402
from camplace.scene.build import build_scene  # noqa: E402
from camplace.scene.importers import import_plan  # noqa: E402
from camplace.scene.importers.ifc_build import GridBuilding, write_grid_building  # noqa: E402
from camplace.spec.loading import parse_scene  # noqa: E402
from tests.conftest import run_cli  # noqa: E402

TWO_ROOMS = GridBuilding(names=("Office", "Lab"))  # 5 x 4 m rooms side by side, door in the wall at x = 5


@pytest.fixture(scope="module", params=["mm", "m"])
def building(request, tmp_path_factory):
    return write_grid_building(tmp_path_factory.mktemp(f"ifc-{request.param}") / "building.ifc", TWO_ROOMS,
                               unit=request.param)


def _scene(data):
    return build_scene(parse_scene(data, "<ifc>"))


def _line_free(scene, a, b, n=400) -> bool:
    """True when no occupied cell lies on the segment a-b (m)."""
    t = np.linspace(0, 1, n)[:, None]
    return not scene.occupancy.is_occupied(np.asarray(a) + t * (np.asarray(b) - np.asarray(a))).any()


def test_footprint_zones_and_walls(building):
    data = import_plan(building)
    assert data["room"]["height"] == pytest.approx(TWO_ROOMS.height)  # the roof slab's underside
    assert Polygon(data["room"]["footprint"]).area == pytest.approx(TWO_ROOMS.outline_area(), rel=0.01)
    assert [z["name"] for z in data["zones"]] == ["Office", "Lab"]
    for z, (lo, hi) in zip(data["zones"], TWO_ROOMS.space_boxes()):
        assert Polygon(z["polygon"]).area == pytest.approx((hi[0] - lo[0]) * (hi[1] - lo[1]), rel=0.01)
    classes = {o["source"]["class"] for o in data["obstacles"]}
    assert classes == {"IfcWall", "IfcWindow"}  # the door is open; slabs lie outside the storey's z range
    assert all(o["source"]["file"] == "building.ifc" and o["source"]["GlobalId"] for o in data["obstacles"])
    occ = _scene(data).occupancy
    assert occ.is_occupied(np.array([[5.0, 0.5, 1.0], [5.0, 3.5, 2.5], [5.0, 2.0, 2.5]])).all()  # inner wall
    assert not occ.is_occupied(np.array([[2.5, 2.0, 1.0], [7.5, 2.0, 1.0], [5.0, 2.0, 1.0]])).any()  # rooms, door


def test_open_door_lets_room_a_see_room_b_and_a_closed_one_does_not(building):
    a, b = (2.5, 2.0, 1.2), (7.5, 2.0, 1.2)  # room centres, through the door (1 m wide, 2.1 m high)
    assert _line_free(_scene(import_plan(building)), a, b)
    closed = import_plan(building, doors="closed")
    assert "IfcDoor" in {o["source"]["class"] for o in closed["obstacles"]}
    assert not _line_free(_scene(closed), a, b)


def test_window_occludes_unless_glass_is_transparent(building):
    def classes(**kw):
        return {o["source"]["class"] for o in import_plan(building, **kw)["obstacles"]}

    assert "IfcWindow" in classes() and "IfcWindow" not in classes(glass="transparent")


def test_storey_by_name_and_ceiling_override(building):
    data = import_plan(building, storey="Ground Floor", ceiling_height=2.5, coverage=1, budget=4)
    assert data["room"]["height"] == 2.5 and data["placement"]["budget"] == 4
    assert all(o["prism"]["z"][1] <= 2.5 for o in data["obstacles"])
    assert {z["coverage"] for z in data["zones"]} == {1}


@pytest.mark.parametrize("options, words", [(dict(storey="Level 9"), ["Level 9", "'Ground Floor', 'Roof'"]),
                                            (dict(doors="ajar"), ["doors", "open"]),
                                            (dict(glass="frosted"), ["glass", "transparent"]),
                                            (dict(storey="all"), ["all", "one scene per storey"])])
def test_bad_options_end_in_one_line(building, options, words):
    with pytest.raises(InputError) as err:
        import_plan(building, **options)
    msg = str(err.value)
    assert "\n" not in msg and all(w in msg for w in words), msg


@pytest.mark.parametrize("text, words", [("solid cube\nfacet normal 0 0 1\n", "not an IFC file"),
                                         ("ISO-10303-21;\nHEADER;\nthis is not STEP\n", "not a readable IFC file")])
def test_not_ifc_is_refused(tmp_path, text, words):
    bad = tmp_path / "junk.ifc"
    bad.write_text(text)
    with pytest.raises(InputError, match=f"junk.ifc: {words}"):
        import_plan(bad)


def test_ifczip_reads_as_its_ifc(building, tmp_path):
    """An .ifczip (Revit's and ArchiCAD's compressed IFC) reads as the .ifc it holds; a file
    so named that is no zip is one line."""
    import zipfile

    with zipfile.ZipFile(tmp_path / "building.ifczip", "w", zipfile.ZIP_DEFLATED) as zf:
        zf.write(building, "model/building.ifc")
    zipped, plain = import_plan(tmp_path / "building.ifczip"), import_plan(building)
    assert zipped["room"] == plain["room"] and zipped["zones"] == plain["zones"]
    assert [o.get("prism") for o in zipped["obstacles"]] == [o.get("prism") for o in plain["obstacles"]]
    assert zipped["obstacles"][0]["source"]["file"] == "building.ifczip"
    (tmp_path / "junk.ifczip").write_text("ISO-10303-21;\n")
    with pytest.raises(InputError, match="junk.ifczip: not an .ifczip file"):
        import_plan(tmp_path / "junk.ifczip")


def test_cli_scene_import_bad_storey_exits_2_and_writes_nothing(building, tmp_path, monkeypatch, capsys):
    out = tmp_path / "site.yaml"
    code, text = run_cli(["scene", "import", building, "--storey", "Attic", "--out", out], monkeypatch, capsys)
    assert code == 2 and "Attic" in text and "'Ground Floor', 'Roof'" in text and str(building) in text
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_cli_scene_import_writes_an_editable_scene(building, tmp_path, monkeypatch, capsys):
    out = tmp_path / "site.yaml"
    code, text = run_cli(["scene", "import", building, "--out", out], monkeypatch, capsys)
    assert code == 0, text
    data = yaml.safe_load(out.read_text())
    assert [z["name"] for z in data["zones"]] == ["Office", "Lab"] and data == import_plan(building, coverage=2)


def test_cli_run_on_the_ifc_file(tmp_path, monkeypatch, capsys):
    ifc = write_grid_building(tmp_path / "building.ifc", TWO_ROOMS, unit="mm")
    out = tmp_path / "out"
    code, text = run_cli(["run", ifc, "--out", out, "--repeatable", "--no-plan"], monkeypatch, capsys)
    assert code == 0, text
    scene = _scene(import_plan(ifc))
    with open(out / "placement.csv") as f:
        pos = np.array([[float(r["x"]), float(r["y"]), float(r["z"])] for r in csv.DictReader(f)])
    assert len(pos) > 0
    fp = Polygon(scene.footprint)
    assert all(fp.contains(Polygon([(x - 1e-3, y - 1e-3), (x + 1e-3, y - 1e-3), (x, y + 1e-3)])) for x, y in pos[:, :2])
    assert not scene.occupancy.is_occupied(pos).any()  # none inside a wall
    assert not (np.abs(pos[:, 0] - 5.0) <= TWO_ROOMS.wall / 2).any()
    regions = json.loads((out / "metrics.json").read_text())["regions"]
    for room in ("Office", "Lab"):
        hist = regions[room]["coverage_histogram"]
        assert regions[room]["targets"] > 100 and hist.get("0", 0) == 0, (room, hist)
