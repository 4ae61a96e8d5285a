"""The IFC importer's rules of issue 34, each on a small file written with ifcopenshell.api
whose answer is known by hand: walls found by their shape whatever their class (a Tekla
precast 'WAND' exported as IfcBeam), named by hand with wall_classes; an import that finds
nothing names what it found and the option that fixes it, never one the user did not
give; a footprint under 1 m² names the unit; the ceiling comes from the covering or the
space over the rooms, the roof only where neither says it."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Polygon

pytest.importorskip("ifcopenshell")

from camplace.core.errors import InputError  # noqa: E402
from camplace.scene.importers import UNITS_M, read_plan  # noqa: E402
from camplace.scene.importers.ifc_build import GridBuilding, write_grid_building  # noqa: E402
from camplace.scene.importers.ifc_build_cases import write_beam_walls, write_roofed_house  # noqa: E402
from camplace.scene.importers.ifc_checks import PLAUSIBLE_M2, suggested_unit  # noqa: E402
from camplace.scene.importers.ifc_geometry import Element  # noqa: E402
from camplace.scene.importers.ifc_model import structure  # noqa: E402
from camplace.scene.importers.ifc_walls import storey_walls  # noqa: E402
from tests.conftest import run_cli  # noqa: E402

W, D, T = 6.0, 4.0, 0.2  # the beam-walled storey: centre lines 6 x 4 m, walls 0.2 m
OUTLINE_M2 = (W + T) * (D + T)  # 26.04 m² at the outer faces


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("ifc-rules")
    return {"standing": write_beam_walls(d / "wand.ifc"), "lying": write_beam_walls(d / "beams.ifc", standing=False),
            "proxy": write_beam_walls(d / "proxy.ifc", cls="IfcBuildingElementProxy"),
            # drawn in metres, the file says mm: 6 x 4 units read as 6 x 4 mm
            "tiny beams": write_beam_walls(d / "tiny-beams.ifc", size=(0.006, 0.004), wall=0.0002, height=0.0028,
                                           unit="mm"),
            "tiny walls": write_beam_walls(d / "tiny-walls.ifc", size=(0.006, 0.004), wall=0.0002, height=0.0028,
                                           unit="mm", cls="IfcWall"),
            "tiny grid": write_grid_building(d / "tiny-grid.ifc", GridBuilding(
                room=(0.005, 0.004), wall=0.0002, height=0.003, slab=0.0002, door=(0.001, 0.0021),
                window=(0.0012, 0.0012, 0.0009)), unit="mm")}


@pytest.mark.parametrize("which, cls", [("standing", "IfcBeam"), ("proxy", "IfcBuildingElementProxy")])
def test_beams_shaped_like_walls_are_walls_and_the_summary_says_so(files, which, cls):
    got = read_plan(files[which])
    assert Polygon(got.scene["room"]["footprint"]).area == pytest.approx(OUTLINE_M2, abs=0.05)
    assert got.used["walls"] == f"{cls} 4 (shaped like walls)"
    assert got.scene["room"]["height"] == pytest.approx(2.8)


def test_nothing_wall_shaped_names_wall_classes_not_the_storey_nobody_gave(files):
    with pytest.raises(InputError) as err:
        read_plan(files["lying"])
    msg = str(err.value)
    assert err.value.option == "wall_classes" and "storey 'Undefined'" in msg and "IfcBeam 4" in msg
    assert "wall_classes=IfcBeam" in msg and "(storey)" not in msg


def test_no_free_floor_ends_in_one_line_naming_what_covers_it(tmp_path):
    with pytest.raises(InputError) as err:
        read_plan(write_beam_walls(tmp_path / "mass.ifc", cls="IfcWall", block=True))
    msg = str(err.value)  # the block fills the 5.8 x 3.8 m inside, the walls the rest of 6.2 x 4.2 m
    assert msg.startswith(f"{tmp_path / 'mass.ifc'}: storey 'Undefined': no free floor: obstacles standing on it "
                          "cover 26.0 of its 26.0 m² footprint (IfcBuildingElementProxy 22.0 m², IfcWall 4.2 m²)")
    assert "\n" not in msg and "export its walls, slabs and spaces" in msg and err.value.option is None


def test_a_storey_holding_only_a_small_thing_names_the_storeys_not_the_unit(tmp_path):
    path = write_beam_walls(tmp_path / "chimney.ifc", cls="IfcWall", chimney="Chimney level")
    with pytest.raises(InputError) as err:
        read_plan(path, storey="Chimney level")
    assert str(err.value) == (f"{path}: storey 'Chimney level': its elements' extent is 0.25 m² while the model spans "
                              "26 m²: the storey holds no building to plan; pick another storey (storey): 'Undefined'")
    assert err.value.option == "storey"


def test_wall_classes_names_them_by_hand(files):
    got = read_plan(files["lying"], wall_classes="IfcBeam")
    assert Polygon(got.scene["room"]["footprint"]).area == pytest.approx(OUTLINE_M2, abs=0.05)
    assert got.used["walls"] == "IfcBeam 4 (wall_classes)"
    assert read_plan(files["lying"], wall_classes=["ifcbeam"]).used["walls"] == "IfcBeam 4 (wall_classes)"


@pytest.mark.parametrize("bad", ["IfcFoo", "IfcLabel", "IfcProject"])
def test_wall_classes_refuses_what_is_no_element_class(files, bad):
    with pytest.raises(InputError, match=f"wall_classes: '{bad}' is not an element class of IFC4") as err:
        read_plan(files["lying"], wall_classes=bad)
    assert err.value.option == "wall_classes"


@pytest.mark.parametrize("which, what, area", [("tiny walls", "elements' extent", OUTLINE_M2),
                                               ("tiny beams", "elements' extent", OUTLINE_M2),
                                               ("tiny grid", "elements' extent", 10.2 * 4.2)])
def test_a_footprint_under_1_m2_names_the_unit_that_fits(files, which, what, area):
    with pytest.raises(InputError, match=rf"storey '[^']+': its {what} is [0-9.e-]+ m², too small for a building: "
                                         r"the file's length unit, mm \(IfcUnitAssignment: MILLI METRE\), is likely "
                                         r"wrong; give the unit it is drawn in, units=m$") as err:
        read_plan(files[which])
    assert err.value.option == "units"
    got = read_plan(files[which], units="m")
    assert Polygon(got.scene["room"]["footprint"]).area == pytest.approx(area, abs=0.05)


@given(area=st.floats(PLAUSIBLE_M2[0], PLAUSIBLE_M2[1] / 100), truth=st.sampled_from(["m", "mm", "cm", "ft", "in"]),
       said=st.sampled_from(["m", "mm", "cm", "ft", "in"]))
@settings(max_examples=60, deadline=None)
def test_the_suggested_unit_gives_a_building_its_area(area, truth, said):
    """A building of ``area`` m² drawn in ``truth`` but read in ``said``: the unit suggested
    for the area read makes it a building's area again (the true one or one as plausible)."""
    read = area * (UNITS_M[said] / UNITS_M[truth]) ** 2
    unit = suggested_unit(read, UNITS_M[said])
    if unit is not None:
        assert PLAUSIBLE_M2[0] <= read * (UNITS_M[unit] / UNITS_M[said]) ** 2 <= PLAUSIBLE_M2[1]
        assert unit != said
    if truth != said and not PLAUSIBLE_M2[0] <= read <= PLAUSIBLE_M2[1]:
        assert unit is not None


def _box(cls: str, lo, hi, eid: int) -> Element:
    """An Element whose body is the box lo..hi (m): 8 vertices, 12 triangles."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = np.array([[x, y, z] for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)], float)
    f = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7],
                  [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]])
    return Element(f"g{eid}", cls, f"{cls} {eid}", v, f, eid)


def test_wall_shape_by_hand():
    """Five 0.2 m proxies closing a 6 x 4 m room (two panels with a 1 m door gap between them)
    are walls; a tall cabinet 0.6 x 2 m standing alone, a 0.3 x 0.3 m pillar, a proxy hanging
    from 1 m up and a sloping stringer are not."""
    ring = [_box("IfcBuildingElementProxy", lo, hi, k + 1) for k, (lo, hi) in enumerate([
        ((-0.1, -0.1, 0), (2.5, 0.1, 2.8)), ((3.5, -0.1, 0), (6.1, 0.1, 2.8)), ((-0.1, 3.9, 0), (6.1, 4.1, 2.8)),
        ((-0.1, -0.1, 0), (0.1, 4.1, 2.8)), ((5.9, -0.1, 0), (6.1, 4.1, 2.8))])]
    others = [_box("IfcBuildingElementProxy", (10, 0, 0), (12, 0.6, 2.1), 9),
              _box("IfcBuildingElementProxy", (2, 2, 0), (2.3, 2.3, 2.8), 6),
              _box("IfcBuildingElementProxy", (1, 1, 1.0), (4, 1.2, 2.8), 7)]
    v = np.array([[0, 5, 0], [3, 5, 2.8], [3, 5.1, 2.8], [0, 5.1, 0], [0, 5, 0.3], [3, 5, 3.1], [3, 5.1, 3.1],
                  [0, 5.1, 0.3]], float)
    f = np.array([[0, 1, 5], [0, 5, 4], [3, 7, 6], [3, 6, 2], [0, 3, 2], [0, 2, 1], [4, 5, 6], [4, 6, 7],
                  [0, 4, 7], [0, 7, 3], [1, 2, 6], [1, 6, 5]])
    stringer = Element("g8", "IfcMember", "stringer", v, f, 8)
    els = ring + others + [stringer]
    kinds = {e.eid: (e.ifc_class, "", ()) for e in els}
    walls, hand, shaped = storey_walls(els, kinds, 0.0, 0.6, (), [], {e.eid for e in els})
    assert [e.eid for e in walls] == [1, 2, 3, 4, 5] and shaped == {"IfcBuildingElementProxy": 5} and not hand
    walls, hand, _ = storey_walls(els, {**kinds, 6: ("IfcBuildingElementProxy", "", ("IfcBuildingElementProxy",))},
                                  0.0, 0.6, ("IfcBuildingElementProxy",), [], {e.eid for e in els})
    assert 6 in [e.eid for e in walls] and hand == {"IfcBuildingElementProxy": 1}


@pytest.mark.parametrize("kw, height, words", [
    ({}, 2.2, "IfcCovering underside"),  # the suspended ceiling, not the roof's 1.74 m eave
    ({"covering": None, "space_height": 2.4}, 2.4, "top of the spaces, not the roof"),
    ({"covering": 2.2, "space_height": 2.4}, 2.2, "IfcCovering underside over the rooms"),
    ({"covering": 2.2, "space_height": 2.4, "covering_type": "ROOFING"}, 2.4, "top of the spaces, not the roof"),
    ({"covering": None}, 1.74, "IfcRoof underside: a roof, as no ceiling covering or space says the height"),
])
def test_ceiling_from_the_covering_or_the_space_the_roof_only_where_neither_says(tmp_path, kw, height, words):
    got = read_plan(write_roofed_house(tmp_path / "house.ifc", **kw))
    assert got.scene["room"]["height"] == pytest.approx(height, abs=1e-3)
    assert words in got.used["ceiling"] and got.used["ceiling"].startswith(f"{height:.2f} m")


def test_a_covering_of_a_space_belongs_to_the_space_s_storey(tmp_path):
    """IFC4's IfcRelCoversSpaces, not a containment: the covering is the storey's, and its ceiling."""
    import ifcopenshell

    path = write_roofed_house(tmp_path / "house.ifc", space_height=2.4, covers_space=True)
    m = ifcopenshell.open(str(path))
    s = structure(m, 1.0)
    cover, = m.by_type("IfcCovering")
    assert not cover.ContainedInStructure and s.storey_key(cover.id()) == m.by_type("IfcBuildingStorey")[0].id()
    assert read_plan(path).used["ceiling"] == "2.20 m (IfcCovering underside over the rooms)"


def test_cli_names_the_flag_that_fixes_it_and_takes_wall_classes(files, tmp_path, monkeypatch, capsys):
    out = tmp_path / "site.yaml"
    code, text = run_cli(["scene", "import", files["lying"], "--out", out], monkeypatch, capsys)
    assert code == 2 and "(--wall-classes), e.g. --wall-classes IfcBeam" in text and "--storey" not in text
    assert "Traceback" not in text and not out.exists()
    code, text = run_cli(["scene", "import", files["lying"], "--wall-classes", "IfcBeam", "--out", out],
                         monkeypatch, capsys)
    assert code == 0, text
    assert Polygon(yaml.safe_load(out.read_text())["room"]["footprint"]).area == pytest.approx(OUTLINE_M2, abs=0.05)
