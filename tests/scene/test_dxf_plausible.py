"""The DXF importer refuses impossible results or corrects them with a note (issue 34;
tests/scene/dxf_sheets.py): layer names by whole words, objects on a wall-like layer
are obstacles, a unit the file's own area texts disprove, open room outlines, printed
areas compared only with area texts."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st
from shapely.geometry import Polygon

pytest.importorskip("ezdxf")

from camplace.core.errors import InputError  # noqa: E402
from camplace.scene.importers import read_plan  # noqa: E402
from camplace.scene.importers.area_text import printed_area  # noqa: E402
from camplace.scene.importers.dxf_layers import layer_role  # noqa: E402
from tests.scene import dxf_sheets as ds  # noqa: E402


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("dxf34")
    return {"art": ds.draw_art_plan(tmp / "art.dxf"), "art named": ds.draw_art_plan(tmp / "wall-art.dxf", "A-WALL-ART"),
            "unit": ds.draw_unit_lie(tmp / "unit.dxf"), "unit bare": ds.draw_unit_lie(tmp / "bare.dxf", texts=False),
            "rooms": ds.draw_rooms_plan(tmp / "rooms.dxf"), "wide gap": ds.draw_rooms_plan(tmp / "gap.dxf", 2.0)}


@pytest.mark.parametrize("name, role", [
    (ds.ART_LAYER, None), ("Murales", None), ("Wallpaper", None), ("MURS_PORTEURS", "wall"), ("MURA", "wall"),
    ("Walls", "wall"), ("TABIQUES", "wall"), ("PARTITIONS", "wall"), ("A-ANNO-TEXT", "annotation"),
    ("DEMOLITION", "annotation"), ("STAIRCASE", "other"), ("HABITACIONES", "room"), ("Colonne", "column"),
    ("A-GLAZ", "window"), ("Einrichtung", "furniture"), ("TITLEBLOCK", "annotation"), ("GRIDLINES", "annotation"),
    ("Schriftfeld", "annotation"), ("Murature portanti", "wall"), ("Tamponamenti", "wall"), ("AREE", "room"),
    ("POTEAUX", "column"), ("CURTAINWALL", "window")])
def test_layer_words_are_whole_words(name, role):
    assert layer_role(name) == role


@pytest.mark.parametrize("which", ["art", "art named"])
def test_objects_on_a_wall_like_layer_are_obstacles_with_their_height(files, which):
    """Three murals (closed 3 x 0.1 m outlines: line pairs like a wall's) and a sculpture
    inserted twice close no room: five 0.9 m obstacles, not walls, on a layer whose name
    holds 'murals' or even says walls; the footprint is the 10 x 6 m room."""
    got = read_plan(files[which], furniture_heights={"*murals": 1.8})
    layer = ds.ART_LAYER if which == "art" else "A-WALL-ART"
    assert got.used["wall layers"].startswith("A-WALL (") and layer not in got.used["wall layers"]
    art = [o for o in got.scene["obstacles"] if o["source"]["layer"] == layer]
    assert len(art) == len(ds.ART_MURALS) + len(ds.ART_SCULPTURES)
    assert {o["prism"]["z"][1] for o in art} == {1.8 if which == "art" else 0.9}
    murals = sorted(Polygon(o["prism"]["polygon"]).area for o in art if "block" not in o["source"])
    assert murals == pytest.approx([0.3] * 3, rel=0.01)
    assert any(n.startswith(f"{layer}: 3 small closed shapes, 2 repeated blocks") for n in got.notes)
    assert Polygon(got.scene["room"]["footprint"]).area == pytest.approx(60.0, rel=0.01)


def test_partitions_drawn_as_closed_boxes_stay_walls(tmp_path):
    """Partitions drawn one closed box per piece (small closed shapes) divide the flat
    into rooms, doorways and all: walls, not objects."""
    from tests.scene.dxf_drawings import draw_latin_plan

    got = read_plan(draw_latin_plan(tmp_path / "fr.dxf", "fr"))
    assert "CLOISONS (4 LWPOLYLINE)" in got.used["wall layers"] and not any("objects" in n for n in got.notes)


def test_unit_the_area_texts_prove_is_used_with_a_note(files):
    """$INSUNITS says mm, the room is drawn in metres: its texts print 28.51 m² three ways
    and its outline measures 28.52 m² in metres only: read in m, said so."""
    got = read_plan(files["unit"])
    assert got.used["units"].startswith("m (from its area texts; the file says mm ($INSUNITS 4))")
    assert any(n.startswith("read in m, not in the file's unit") and "3 area texts" in n for n in got.notes)
    zones = {z["name"]: Polygon(z["polygon"]).area for z in got.scene["zones"]}
    assert zones == {"Soggiorno": pytest.approx(ds.UNIT_ROOM_M2, rel=0.005)}
    assert "room Soggiorno: printed 28.51 m², measured 28.52 m² (+0 %)" in got.notes


def test_unit_given_by_the_user_is_kept_with_a_note(files):
    got = read_plan(files["unit"], units="m")
    assert got.used["units"] == "m (given)" and not any("area texts agree" in n for n in got.notes)
    with pytest.raises(InputError):  # mm given: the texts disagree (a note), and the footprint is a speck
        read_plan(files["unit"], units="mm")


def test_wrong_unit_without_evidence_ends_in_one_line_naming_the_fix(files, tmp_path, monkeypatch, capsys):
    """No area texts: the footprint would measure 0 m² in mm; one line naming the cause and
    '--units m' (an option the user did not give, the one that fixes it), exit 2, nothing written."""
    from tests.conftest import run_cli

    with pytest.raises(InputError) as err:
        read_plan(files["unit bare"])
    assert err.value.option == "units" and "(units=m)" in str(err.value) and "0 m²" in str(err.value)
    code, text = run_cli(["scene", "import", files["unit bare"], "--out", tmp_path / "s.yaml"], monkeypatch, capsys)
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and "(--units m)" in lines[0] and "--storey" not in lines[0], text
    assert "--units:" not in lines[0]  # no prefix as if the user had given --units
    assert not (tmp_path / "s.yaml").exists()
    assert read_plan(files["unit bare"], units="m").used["units"] == "m (given)"


def test_storey_with_no_free_floor_ends_in_one_line(tmp_path):
    """All wall, no floor, and no unit makes it a building: the cause, and the wall layers to name."""
    with pytest.raises(InputError) as err:
        read_plan(ds.draw_solid_block(tmp_path / "block.dxf"))
    assert err.value.option == "wall_layers" and "the walls fill the footprint (36.0 m², 0.0 m² free floor)" in str(
        err.value) and "(wall_layers)" in str(err.value)


def test_open_room_outline_closed_when_the_gap_is_small(files):
    got = read_plan(files["rooms"])
    zones = {z["name"]: Polygon(z["polygon"]).area for z in got.scene["zones"]}
    assert set(zones) == set(ds.ROOMS)
    x0, y0, x1, y1 = ds.ROOMS["Hall"]
    assert zones["Hall"] == pytest.approx((x1 - x0) * (y1 - y0), rel=0.01)
    assert any(n.startswith("closed 1 open room outline") for n in got.notes)


def test_open_room_outline_with_a_wide_gap_is_said(files):
    got = read_plan(files["wide gap"])
    assert "Hall" not in {z["name"] for z in got.scene["zones"]}
    assert got.skipped["open room outlines"] == 1
    assert any(n.startswith("left out 1 open room outline whose ends lie 2.00-2.00 m apart") for n in got.notes)


def test_printed_areas_compared_only_with_area_texts(files):
    """Kitchen prints '17.48 m²', Hall a bare '16.56' beside its name: compared. Bedroom's
    tatami count and the width on its dimension layer are no areas: not compared."""
    got = read_plan(files["rooms"])
    printed = [n for n in got.notes if " printed " in n]
    assert printed == ["room Kitchen: printed 17.48 m², measured 17.48 m² (+0 %)",
                       "room Hall: printed 16.56 m², measured 16.56 m² (+0 %)"]


@pytest.mark.parametrize("text, area", [
    ("28.51 m²", 28.51), ("mq=28.51", 28.51), ("MQ 28,51", 28.51), ("28.5 sqm", 28.5), ("Area: 28.5", 28.5),
    ("NGF=24,35", 24.35), ("Soggiorno mq 28,51", 28.51), ("120 sq ft", 120 * 0.09290304), ("3.60", None),
    ("3600", None), ("6帖", None), ("6畳", None), ("6 jō", None), ("A=3.6", None), ("+0.00", None), ("A101", None),
    ("10.5 m", None)])
def test_printed_area_reads_only_areas(text, area):
    assert printed_area(text) == (pytest.approx(area) if area is not None else None)


@given(st.decimals(min_value="0.5", max_value="9999", places=2),
       st.sampled_from(["帖", "畳", " jō", " JO", " tatami"]))
def test_tatami_counts_are_never_areas(value, suffix):
    """Neither in a DXF's texts nor in a plan image's OCR lines."""
    from camplace.scene.importers import image_ocr

    assert printed_area(f"{value}{suffix}") is None and image_ocr.printed_area(f"{value}{suffix}") is None


@given(st.decimals(min_value="0.5", max_value="9999", places=2),
       st.sampled_from([" m²", "m2", " sqm", " mq", " m2", " sq m"]))
def test_a_number_with_a_unit_of_area_is_that_area(value, unit):
    assert printed_area(f"{value}{unit}") == pytest.approx(float(value))


@given(st.floats(1.0, 500.0), st.floats(0.3, 3.0), st.sampled_from(["mm", "cm", "m", "in", "ft"]))
def test_area_texts_tell_the_unit_the_outline_is_drawn_in(area, aspect, unit):
    """A room of ``area`` m² drawn in ``unit`` (read at 1 m per unit) and two texts printing
    its area: the texts tell that unit, whatever its size and shape."""
    from shapely.geometry import Point, box

    from camplace.scene.importers import UNITS_M
    from camplace.scene.importers.dxf_checks import unit_from_areas
    from camplace.scene.importers.dxf_read import Label

    w = (area * aspect) ** 0.5 / UNITS_M[unit]  # drawing units
    outline = box(0, 0, w, area / (area * aspect) ** 0.5 / UNITS_M[unit])
    labels = [Label(Point(1, 1), text, 0.2, "TEXT", "", 0) for text in (f"{area:.2f} m²", f"mq={area:.2f}")]
    assert unit_from_areas(labels, [outline], 1.0).unit == unit
