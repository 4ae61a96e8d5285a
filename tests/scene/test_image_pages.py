"""PDF plan sets (issue 33): one storey per page, named by the level the page's text
gives (else page-N), each in its page's coordinates; ``page`` still reads one page."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image
from shapely.geometry import Polygon

from camplace.core.errors import InputError
from camplace.scene.importers import read_plan, read_storey_plans
from camplace.scene.importers.image_pages import level_name, page_of_storey
from tests.scene.poche_drawings import DPI, draw_pdf_levels, draw_pdf_pages, plan_pages

GROUND = [(0.0, 0.0, 6.0, 4.0)]  # one room of 24 m²
UPPER = [(0.0, 0.0, 4.0, 4.0), (4.3, 0.0, 8.0, 4.0)]  # 16 m² and 14.8 m²


def _areas(got) -> list[float]:
    return sorted(round(Polygon(z["polygon"]).area, 1) for z in got.scene["zones"])


@pytest.fixture(scope="module")
def sets(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pages")
    levels = draw_pdf_levels(folder / "levels.pdf", [GROUND, UPPER], ["GROUND FLOOR PLAN", "Level 2"],
                             ["stair up to Level 2", "stair down to Ground floor"])
    return levels, draw_pdf_pages(folder / "pages.pdf", [GROUND, UPPER])


def test_every_page_a_storey_named_by_its_title(sets):
    got = read_storey_plans(sets[0], scale="1:100", ocr=False)
    assert [name for name, _, _ in got] == ["Ground floor", "Level 2"]  # the title, not the 8 pt note
    assert _areas(got[0][1]) == pytest.approx([24.0], abs=0.3)
    assert _areas(got[1][1]) == pytest.approx([14.8, 16.0], abs=0.3)
    assert [elev for _, _, elev in got] == [0.0, 0.0]
    assert [s["name"] for s in got[1][1].storeys] == ["Ground floor", "Level 2"]
    assert [s["chosen"] for s in got[1][1].storeys] == [False, True]


def test_the_scale_printed_on_the_page(tmp_path):
    """No scale given, no OCR: the page's own '1:100' gives it (at 200 dpi: 0.0127 m/px)."""
    pdf = draw_pdf_levels(tmp_path / "set.pdf", [GROUND], ["GROUND FLOOR PLAN 1:100"], ["ramp 1:12"])
    got = read_plan(pdf, ocr=False)
    assert got.used["scale"].startswith("0.0127 m/px (1:100 at 200 dpi: the scale printed on the page")
    assert _areas(got) == pytest.approx([24.0], abs=0.4)
    assert any("printed on the page" in n for n in got.notes)
    two = draw_pdf_levels(tmp_path / "two.pdf", [GROUND], ["PLAN 1:100"], ["DETAIL 1:20"])
    with pytest.raises(InputError) as err:  # two plan scales on the page: not guessed
        read_plan(two, ocr=False)
    assert err.value.option == "scale"


def test_pages_without_text_are_page_n(sets):
    got = read_storey_plans(sets[1], scale="1:100", ocr=False)
    assert [name for name, _, _ in got] == ["page-1", "page-2"]
    assert _areas(got[1][1]) == pytest.approx([14.8, 16.0], abs=0.3)


@pytest.mark.parametrize("options, areas", [({"page": 2}, [14.8, 16.0]), ({"storey": "Level 2"}, [14.8, 16.0]),
                                            ({"storey": "page-1"}, [24.0]), ({}, [24.0])])
def test_one_page_by_page_or_storey(sets, options, areas):
    got = read_plan(sets[0], scale="1:100", ocr=False, **options)
    assert _areas(got) == pytest.approx(areas, abs=0.3)
    assert any("2 pages (Ground floor, Level 2)" in n for n in got.notes) == (options == {})


def test_page_with_one_storey_all_keeps_its_plans(sets):
    got = read_storey_plans(sets[1], scale="1:100", ocr=False, page=2)  # the page's own plans: plan-1 (one)
    assert [name for name, _, _ in got] == ["plan-1"]


def test_unknown_page_name_and_blank_pages(sets, tmp_path):
    with pytest.raises(InputError) as err:
        read_plan(sets[0], scale="1:100", ocr=False, storey="Level 7")
    assert err.value.option == "storey" and "Ground floor, Level 2" in str(err.value)
    blank = Image.new("RGB", (400, 300), "white")
    plan_pages([GROUND])[0].save(tmp_path / "cover.pdf", save_all=True, append_images=[blank], resolution=DPI)
    got = read_storey_plans(tmp_path / "cover.pdf", scale="1:100", ocr=False)
    assert [name for name, _, _ in got] == ["page-1"]
    assert any(n.startswith("pages left out: page-2 (no walls found") for n in got[0][1].notes)
    cover = draw_pdf_levels(tmp_path / "cover2.pdf", [GROUND, GROUND], ["COVER SHEET", "GROUND FLOOR PLAN 1:100"])
    got = read_storey_plans(cover, ocr=False)  # no --scale: page 2 prints its 1:100, page 1 no scale
    assert [name for name, _, _ in got] == ["Ground floor"]
    assert any(n.startswith("pages left out: page-1 (the plan's scale is unknown") for n in got[0][1].notes)
    blank.save(tmp_path / "blank.pdf", save_all=True, append_images=[blank], resolution=DPI)
    with pytest.raises(InputError, match="no page holds a plan with a closed room"):
        read_storey_plans(tmp_path / "blank.pdf", scale="1:100", ocr=False)


@pytest.mark.parametrize("text, name", [
    ("GROUND FLOOR PLAN 1:100", "Ground floor"), ("Kitchen 12 m²\nLevel 2", "Level 2"),
    ("1. Obergeschoss", "1. Obergeschoss"), ("Grundriss Erdgeschoss", "Erdgeschoss"), ("2nd floor", "2nd floor"),
    ("plan du rez-de-chaussée", "rez-de-chaussée"), ("Planta baja", "Planta baja"), ("Køkken og bad", None),
    ("Living room 21 m2", None), ("EG", "EG"),
])
def test_level_names(text, name):
    assert level_name(text) == name


def test_page_of_storey():
    names = ["Ground floor", "Level 2"]
    assert page_of_storey("level 2", names) == 2
    assert page_of_storey("page-1", names) == 1
    assert page_of_storey("page-3", names) is None


@settings(max_examples=60, deadline=None)
@given(st.lists(st.sampled_from(["Kitchen", "12 m²", "Level", "3", "floor", "Ground", "WC", "1:100", "og", "EG",
                                 "Erdgeschoss", "first", "étage", "1er", "\n", "plan"]), max_size=12))
def test_a_level_name_is_text_of_the_page(words):
    """Whatever the page says, the name is None or a piece of its text (spaces collapsed)."""
    text = " ".join(words)
    name = level_name(text)
    assert name is None or name.lower() in " ".join(text.split()).lower()


def test_a_pdf_set_is_one_building(sets, tmp_path, monkeypatch, capsys):
    """issue 33: every page a storey of one building, stacked (3 m apart: a plan set has no
    elevations), planned in one run with one budget."""
    import json

    from tests.conftest import run_cli

    code, text = run_cli(["--quiet", "run", sets[0], "--storey", "all", "--scale", "1:100", "--no-ocr", "--budget",
                          "3", "--grid-only", "--no-plan", "--no-cache", "--out", tmp_path / "o"], monkeypatch, capsys)
    assert code == 0, text
    placement = json.loads((tmp_path / "o" / "placement.json").read_text())
    assert [s["name"] for s in placement["storeys"]] == ["Ground floor", "Level 2"]
    assert [s["elevation_m"] for s in placement["storeys"]] == [0.0, 3.0]
    assert len(placement["cameras"]) <= 3 and all("storey" in c for c in placement["cameras"])
