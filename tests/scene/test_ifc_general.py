"""The IFC importer on the ways real files differ from the tidy case (issue 25), each on a
small two-storey building written with ifcopenshell.api: spaces aggregated to the building
instead of their storey and with only a FootPrint curve (no body), storeys without
Elevation or placement, a length-unit override; and the pieces of the footprint rule
(separate blocks joined by seams)."""

from __future__ import annotations

import pytest
from shapely.geometry import Polygon, box

pytest.importorskip("ifcopenshell")

from camplace.scene.importers import read_plan, read_storey_plans  # noqa: E402
from camplace.scene.importers.ifc_build import GridBuilding, write_grid_building, write_ring_room  # noqa: E402
from camplace.scene.importers.ifc_model import unique_names  # noqa: E402
from camplace.scene.importers.ifc_storey import join_pieces  # noqa: E402
from camplace.spec.loading import parse_scene  # noqa: E402

B = GridBuilding(names=("Office", "Lab"))
FLOORS = ("Ground Floor", "First Floor")
UP = B.height + B.slab  # the first floor's elevation


def _check(path, **options):
    """Both floors with storey 'all': names, elevations, rooms and footprint as the tidy file's."""
    got = read_storey_plans(path, **options)
    assert [(n, e) for n, _, e in got] == [("Ground Floor", 0.0), ("First Floor", pytest.approx(UP))]
    for name, g, _ in got:
        parse_scene(g.scene, name)
        assert [z["name"] for z in g.scene["zones"]] == ["Office", "Lab"], name
        assert Polygon(g.scene["room"]["footprint"]).area == pytest.approx(B.outline_area(), rel=0.01), name
        assert g.scene["room"]["height"] == pytest.approx(B.height), name
    return got


def test_spaces_in_the_building_with_only_a_footprint_curve(tmp_path):
    path = write_grid_building(tmp_path / "b.ifc", B, unit="mm", floors=FLOORS, spaces_in="building",
                               space_body="footprint")
    _check(path)


def test_storeys_without_elevation_take_their_spaces_level(tmp_path):
    got = _check(write_grid_building(tmp_path / "b.ifc", B, floors=FLOORS, storey_levels=False))
    assert any("no floor level" in note and "lowest point of its spaces" in note for note in got[1][1].notes)


def test_units_override_scales_the_building(tmp_path):
    path = write_grid_building(tmp_path / "b.ifc", B, unit="mm")
    g = read_plan(path, units="cm")  # a file wrongly saying mm: 10 x the size
    rooms = [Polygon(z["polygon"]).area for z in g.scene["zones"]]
    assert rooms == pytest.approx([100 * 4.8 * 3.8] * 2, rel=0.01)  # the 2 m wall between them: two pieces
    assert g.scene["room"]["height"] == pytest.approx(10 * B.height)
    assert g.used["units"].startswith("cm (units option")


def test_walls_of_a_room_as_one_element_keep_the_room_free(tmp_path):
    """One IfcWall whose profile is a ring (the room's four walls in one element): its
    prism keeps the hole (the room is not a wall), and the ceiling grid has mounts."""
    g = read_plan(write_ring_room(tmp_path / "ring.ifc", (4.0, 3.0), 0.2))
    walls = [Polygon(o["prism"]["polygon"], o["prism"].get("holes", [])) for o in g.scene["obstacles"]]
    assert sum(q.area for q in walls) == pytest.approx(4 * 3 - 3.6 * 2.6, rel=0.01)
    assert Polygon(g.scene["room"]["footprint"]).area == pytest.approx(12.0, rel=0.01)


def test_a_level_holding_only_the_roof_is_no_storey_to_plan(tmp_path):
    """Revit's 'Level 1' holding only the roof (no walls, no slab, a name not saying roof):
    storey 'all' imports the storey with the walls and says why the roof level was left out."""
    path = write_ring_room(tmp_path / "ring.ifc", (4.0, 3.0), 0.2, roof_level="Level 1")
    got = read_storey_plans(path)
    assert [n for n, _, _ in got] == ["Ground Floor"]
    assert any("'Level 1' no rooms (no walls, no floor slab)" in note for note in got[0][1].notes)
    assert got[0][1].scene["room"]["height"] == pytest.approx(3.0)  # the roof's underside


def test_separate_blocks_join_into_one_simple_polygon_with_a_thin_seam():
    a, b = box(0, 0, 4, 4), box(7, 1, 10, 3)
    outline, seam = join_pieces([a, b], width=0.1)
    assert outline.is_valid and not outline.interiors and outline.contains(a) and outline.contains(b)
    assert seam.area == pytest.approx(3 * 0.1, rel=0.01)  # 3 m between the blocks, 0.1 m wide
    assert outline.area == pytest.approx(a.area + b.area + seam.area, rel=1e-3)
    assert seam.intersection(a).area < 1e-9 and seam.intersection(b).area < 1e-9


def test_storey_names_of_two_buildings_stay_apart():
    assert unique_names(["Level 1", "Level 1", "Roof", "X", "X"], ["North", "South", "North", "", ""]) == [
        "Level 1 (North)", "Level 1 (South)", "Roof", "X", "X #2"]
