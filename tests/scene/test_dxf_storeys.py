"""Several plans on one DXF sheet (issue 33; tests/scene/dxf_sheets.py): one storey per
plan, in the sheet's coordinates, left to right then top to bottom, named by the level
their title names, else plan-1..n; --storey chooses one."""

from __future__ import annotations

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st
from shapely.geometry import Polygon

pytest.importorskip("ezdxf")

from camplace.core.errors import InputError  # noqa: E402
from camplace.scene.importers import read_plan, read_storey_plans  # noqa: E402
from camplace.scene.importers.dxf_plans import level_name, reading_order  # noqa: E402
from tests.scene import dxf_sheets as ds  # noqa: E402


@pytest.fixture(scope="module")
def sheets(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("dxf33")
    return {"titled": ds.draw_two_storeys(tmp / "house.dxf"), "bare": ds.draw_two_storeys(tmp / "bare.dxf", ())}


def _box(got):
    return Polygon(got.scene["room"]["footprint"]).bounds


def test_every_plan_is_a_storey_in_the_sheets_coordinates(sheets):
    found = read_storey_plans(sheets["titled"])
    assert [(name, elev) for name, _, elev in found] == [("GROUND FLOOR", 0.0), ("FIRST FLOOR", 0.0)]
    w, h = ds.TWO_SIZE
    for (_, got, _), x0, rooms in zip(found, (0.0, ds.TWO_FIRST_X), (2, 3)):
        assert _box(got) == pytest.approx((x0, 0.0, x0 + w, h), abs=0.01)
        assert Polygon(got.scene["room"]["footprint"]).area == pytest.approx(w * h, rel=0.01)
        assert len(got.scene["zones"]) == rooms


def test_a_title_outside_the_plan_names_it_before_a_room_text_inside(tmp_path):
    import ezdxf

    doc = ezdxf.readfile(ds.draw_two_storeys(tmp_path / "house.dxf"))
    doc.modelspace().add_text("Basement store", height=0.2, dxfattribs={"layer": "A-ANNO-TEXT", "insert": (2, 4)})
    doc.saveas(tmp_path / "store.dxf")
    assert [name for name, _, _ in read_storey_plans(tmp_path / "store.dxf")] == ["GROUND FLOOR", "FIRST FLOOR"]


def test_plans_without_titles_are_plan_1_to_n_left_to_right(sheets):
    found = read_storey_plans(sheets["bare"])
    assert [name for name, _, _ in found] == ["plan-1", "plan-2"]
    assert _box(found[0][1])[0] < _box(found[1][1])[0]


def test_storey_chooses_one_plan_default_the_one_with_most_walls(sheets):
    got = read_plan(sheets["titled"])
    assert _box(got)[0] == pytest.approx(ds.TWO_FIRST_X, abs=0.01) and got.used["plans"].startswith("2 on the sheet")
    assert any("storey='all'" in n for n in got.notes)
    for storey in ("ground floor", "plan-1"):
        assert _box(read_plan(sheets["titled"], storey=storey))[0] == pytest.approx(0.0, abs=0.01)
    with pytest.raises(InputError) as err:
        read_plan(sheets["titled"], storey="plan-3")
    assert err.value.option == "storey" and "GROUND FLOOR (plan-1), FIRST FLOOR (plan-2)" in str(err.value)


def test_storey_all_on_the_command_line(sheets, tmp_path, monkeypatch, capsys):
    from tests.conftest import run_cli

    code, text = run_cli(["--quiet", "scene", "import", sheets["titled"], "--storey", "all", "--out",
                          tmp_path / "house.yaml"], monkeypatch, capsys)
    assert code == 0, text
    assert sorted(p.name for p in tmp_path.glob("*.yaml")) == ["house.yaml"]  # one building (issue 33)
    data = yaml.safe_load((tmp_path / "house.yaml").read_text())
    assert list(data["storeys"]) == ["GROUND FLOOR", "FIRST FLOOR"]
    assert data["storeys"]["FIRST FLOOR"]["elevation"] > data["storeys"]["GROUND FLOOR"]["elevation"]
    ground = [p[0] for p in data["storeys"]["GROUND FLOOR"]["room"]["footprint"]]
    first = [p[0] for p in data["storeys"]["FIRST FLOOR"]["room"]["footprint"]]
    assert min(first) == pytest.approx(min(ground), abs=0.01)  # side by side on the sheet, stacked in the building


@pytest.mark.parametrize("text, name", [
    ("GROUND FLOOR PLAN 1:100", "GROUND FLOOR"), ("Grundriss Erdgeschoss 1:100", "Erdgeschoss"),
    ("Pianta piano terra", "piano terra"), ("Level 1", "Level 1"), ("1. OG", "1. OG"), ("Planta baja", "Planta baja"),
    ("Rez-de-chaussée", "Rez-de-chaussée"), ("Section A-A", None), ("Kitchen", None), ("Legend", None)])
def test_level_names(text, name):
    assert level_name(text) == name


def test_reading_order_rows_top_to_bottom_left_to_right():
    boxes = {"bottom-right": (12, 0, 20, 8), "top-left": (0, 10, 10, 18), "bottom-left": (0, 0, 10, 8),
             "top-right": (12, 11, 20, 17)}
    names = list(boxes)
    assert [names[i] for i in reading_order(list(boxes.values()))] == ["top-left", "top-right", "bottom-left",
                                                                       "bottom-right"]


@given(st.lists(st.tuples(st.floats(-100, 100), st.floats(-100, 100), st.floats(1, 30), st.floats(1, 30)),
                min_size=1, max_size=8))
def test_reading_order_is_a_permutation(rects):
    boxes = [(x, y, x + w, y + h) for x, y, w, h in rects]
    assert sorted(reading_order(boxes)) == list(range(len(boxes)))


def test_a_plan_without_floor_is_left_out_and_said(tmp_path):
    """A block of wall with no floor beside the two storeys (more wall area than either):
    not the default plan, left out of 'all' with a note."""
    import ezdxf

    doc = ezdxf.readfile(ds.draw_two_storeys(tmp_path / "house.dxf"))
    msp = doc.modelspace()
    for k in range(13):
        msp.add_line((50, 0.5 * k), (56, 0.5 * k), dxfattribs={"layer": "A-WALL"})
    for x in (50, 56):
        msp.add_line((x, 0), (x, 6), dxfattribs={"layer": "A-WALL"})
    doc.saveas(tmp_path / "block.dxf")
    got = read_plan(tmp_path / "block.dxf")
    assert _box(got)[0] == pytest.approx(ds.TWO_FIRST_X, abs=0.01) and "plan-3 has none" in got.used["plans"]
    found = read_storey_plans(tmp_path / "block.dxf")
    assert [name for name, _, _ in found] == ["GROUND FLOOR", "FIRST FLOOR"]
    assert any(n.startswith("left out plan-3: the walls fill the footprint") for n in found[0][1].notes)
