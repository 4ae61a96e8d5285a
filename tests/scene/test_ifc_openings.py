"""Where an IFC storey's floor is open to the storey below (issue 33), on two-storey
grid buildings written with ifcopenshell.api whose answer is known by hand: an
IfcOpeningElement voiding the first floor's slab, a stair flight of the ground floor rising
to it, a ground-floor space two storeys high under no slab; and the frame those polygons
are in: the IFC's world x, y, the storeys at their world z (storey_elevations)."""

from __future__ import annotations

import pytest
from shapely.geometry import Polygon, box

pytest.importorskip("ifcopenshell")

from camplace.scene.importers import read_storey_plans  # noqa: E402
from camplace.scene.importers.ifc import storey_elevations  # noqa: E402
from camplace.scene.importers.ifc_build import GridBuilding  # noqa: E402
from camplace.scene.importers.ifc_build_cases import write_open_floors  # noqa: E402

B = GridBuilding()  # two 5 x 4 m rooms side by side, 0.2 m walls, 3 m storeys on 0.2 m slabs
UP = B.height + B.slab


def _openings(path) -> dict:
    return {name: (got, elev) for name, got, elev in read_storey_plans(path)}


def _one(got) -> Polygon:
    assert len(got.floor_openings) == 1, got.floor_openings
    return Polygon(got.floor_openings[0])


@pytest.mark.parametrize("kw, expect, kind", [
    ({"opening": (1.0, 1.0, 2.0, 3.0)}, box(1.0, 1.0, 2.0, 3.0), "slab openings 1"),
    ({"stair": (6.0, 1.0, 7.0, 3.5)}, box(6.0, 1.0, 7.0, 3.5), "stair voids 1"),
    # the atrium: room 2's clear inside (x 5.1-9.9, y 0.1-3.9), where the first floor has no slab
    ({"atrium": True}, box(5.1, 0.1, 9.9, 3.9), "atria 1"),
    ({"void": "Luftraum"}, box(5.1, 0.1, 9.9, 3.9), "void spaces 1"),  # a space of the first floor named so
])
def test_the_first_floor_is_open_where_the_model_opens_it(tmp_path, kw, expect, kind):
    got = _openings(write_open_floors(tmp_path / "b.ifc", B, **kw))
    assert got["Ground Floor"][0].floor_openings == []
    assert got["Ground Floor"][0].used["floor openings"] == "none: the lowest storey"
    first = got["First Floor"][0]
    assert _one(first).symmetric_difference(expect).area < 1e-3
    assert first.used["floor openings"] == f"1 open to the storey below ({kind})"


def test_a_closed_floor_has_no_opening_and_storeys_stand_at_their_world_z(tmp_path):
    path = write_open_floors(tmp_path / "b.ifc", B)
    got = _openings(path)
    assert got["First Floor"][0].floor_openings == []
    assert got["First Floor"][0].used["floor openings"] == "0 open to the storey below"
    # storey_elevations and read_storey_plans: each floor's world z in metres; plans in world x, y (the same frame)
    assert storey_elevations(path) == {"Ground Floor": 0.0, "First Floor": pytest.approx(UP)}
    assert [e for _, e in got.values()] == [0.0, pytest.approx(UP)]
    walls = box(-B.wall / 2, -B.wall / 2, 2 * B.room[0] + B.wall / 2, B.room[1] + B.wall / 2)
    for name, (g, _) in got.items():
        assert Polygon(g.scene["room"]["footprint"]).symmetric_difference(walls).area < 1e-3, name


def test_openings_in_a_file_in_mm_are_in_metres(tmp_path):
    """The same opening through a file in mm: polygons in m, the first floor at 3.2 m."""
    path = write_open_floors(tmp_path / "b.ifc", B, opening=(1.0, 1.0, 2.0, 3.0), unit="mm")
    assert "MILLI" in path.read_text()
    got = _openings(path)
    assert got["First Floor"][1] == pytest.approx(UP)
    assert _one(got["First Floor"][0]).bounds == pytest.approx((1.0, 1.0, 2.0, 3.0))


def _everything_on(m, xyz):
    """A new IfcLocalPlacement at ``xyz`` (m) that every placement of model ``m`` without a
    parent is made relative to (the whole model moves by ``xyz``)."""
    at = m.createIfcLocalPlacement(None, m.createIfcAxis2Placement3D(m.createIfcCartesianPoint(xyz), None, None))
    for lp in m.by_type("IfcLocalPlacement"):
        if lp.PlacementRelTo is None and lp != at:
            lp.PlacementRelTo = at
    return at


def test_a_site_placed_away_from_the_origin_moves_plans_and_elevations_with_it(tmp_path):
    """Every placement made relative to an IfcSite at (100, 50, 10) m: the storeys stand at
    world z 10 and 13.2 m, the footprint and the floor opening lie at world x + 100, y + 50
    (the IFC's own coordinates, the same frame for every storey), the heights unchanged."""
    import ifcopenshell

    path = write_open_floors(tmp_path / "b.ifc", B, opening=(1.0, 1.0, 2.0, 3.0))
    m = ifcopenshell.open(str(path))
    m.by_type("IfcSite")[0].ObjectPlacement = _everything_on(m, (100.0, 50.0, 10.0))
    m.write(str(path))
    assert storey_elevations(path) == {"Ground Floor": pytest.approx(10.0), "First Floor": pytest.approx(10.0 + UP)}
    got = _openings(path)
    for name, (g, _) in got.items():
        assert Polygon(g.scene["room"]["footprint"]).bounds == pytest.approx((99.9, 49.9, 110.1, 54.1)), name
        assert g.scene["room"]["height"] == pytest.approx(B.height), name
    assert _one(got["First Floor"][0]).bounds == pytest.approx((101.0, 51.0, 102.0, 53.0))


def test_storeys_placed_alike_take_their_elevation_above_the_building(tmp_path):
    """Both storeys placed at the building's origin, 10 m up, their Elevation 0 and 3.2 m:
    the floors stand at world z 10 and 13.2 m, where the geometry is."""
    import ifcopenshell

    path = write_open_floors(tmp_path / "b.ifc", B)
    m = ifcopenshell.open(str(path))
    at = _everything_on(m, (0.0, 0.0, 10.0))
    m.by_type("IfcBuilding")[0].ObjectPlacement = at
    for st in m.by_type("IfcBuildingStorey"):
        st.ObjectPlacement = at
    m.write(str(path))
    assert storey_elevations(path) == {"Ground Floor": pytest.approx(10.0), "First Floor": pytest.approx(10.0 + UP)}
    got = _openings(path)
    assert got["First Floor"][0].used["storey"].startswith("First Floor (floor at +13.20 m, from its Elevation")
    assert got["First Floor"][0].scene["room"]["height"] == pytest.approx(B.height)
