"""Plan images as they come (issue 25): a generated apartment sheet (hatched outer walls,
solid inner walls, windows as white gaps, doors with swings, labels in a TTF font,
dimension lines, scale bar, title block, sheet frame) gives its five rooms with their
areas and names, the openings, the scale read from its dimension lines, and a grid-only
run inside the footprint; a scan of it (grey paper, noise, JPEG), a drawing of its
outer walls as two lines and one with furniture give the same rooms; two plans side by
side are two storeys, also 1.2 m apart, and a U-shaped plan is one."""

from __future__ import annotations

import os

import numpy as np
import pytest
from shapely.geometry import Point, Polygon

from camplace.core.errors import InputError
from camplace.scene.importers import read_plan, read_storey_plans
from tests.scene.image_drawings import (PX, ROOMS, D, W, draw_apartment, draw_hollow_walls, draw_line_plan,
                                       draw_two_blocks, draw_u_plan, room_area)


def need_ocr():
    """Skip without Tesseract (pytesseract and the tesseract program), except on CI
    (CI=true), where a missing OCR engine fails the test."""
    from camplace.scene.importers.image_ocr import ocr_engine

    engine, why = ocr_engine()
    if engine is None:
        if os.environ.get("CI") == "true":
            pytest.fail(f"OCR is required on CI: {why}")
        pytest.skip(f"no OCR: {why}")


@pytest.fixture(scope="module")
def apartment(tmp_path_factory):
    sheet = draw_apartment(tmp_path_factory.mktemp("apt") / "apartment.png")
    return sheet, read_plan(sheet.path, scale=PX)


def _zones(got):
    return {z["name"]: Polygon(z["polygon"]) for z in got.scene["zones"]}


def test_five_rooms_with_their_areas(apartment):
    _, got = apartment
    areas = sorted(p.area for p in _zones(got).values())
    assert areas == pytest.approx(sorted(room_area(n) for n in ROOMS), rel=0.1), areas
    assert len(got.storeys) == 1 and got.storeys[0]["chosen"]
    outline = (W + 0.6) * (D + 0.6)  # the outer faces of the 0.3 m outer walls
    assert Polygon(got.scene["room"]["footprint"]).area == pytest.approx(outline, rel=0.05)
    assert got.storeys[0]["outline_m2"] == pytest.approx(outline, rel=0.05)


def test_a_plan_drawn_in_single_lines(tmp_path):
    """Hairline walls (every wall one 1 px line, as CAD exports draw them): no stroke is
    thick enough for solid_walls, so the walls are the straight lines, drawn 0.1 m thick;
    the sheet frame and title block are not the building, the rooms are found (a door's
    swing drawn into a room is left out of it), and OCR names them."""
    sheet = draw_line_plan(tmp_path / "lines.png")
    got = read_plan(sheet.path, scale=PX)
    assert got.used["walls"].endswith("from single lines (no stroke 0.08 m thick encloses a room), drawn 0.1 m thick")
    areas = sorted(p.area for p in _zones(got).values())
    assert areas == pytest.approx(sorted(room_area(n) for n in ROOMS), rel=0.15), areas
    outline = (W + 0.2) * (D + 0.2)  # the outer lines 0.05 m out, drawn 0.1 m thick
    assert Polygon(got.scene["room"]["footprint"]).area == pytest.approx(outline, rel=0.03)
    assert len(got.storeys) == 1
    need_ocr()
    assert sorted(_zones(got)) == sorted(ROOMS)


def test_a_fine_scan_is_read_at_a_coarser_scale(apartment, tmp_path):
    """The sheet at 4x the pixels (0.005 m/px, a 1:50 plan at 500 dpi) is read at 1/2 of
    its pixels, the darkest of each 2 x 2 block: the same rooms."""
    from PIL import Image

    sheet, got = apartment
    with Image.open(sheet.path) as im:
        im.resize((im.width * 4, im.height * 4), Image.LANCZOS).save(tmp_path / "fine.png")
    fine = read_plan(tmp_path / "fine.png", scale=PX / 4, ocr=False)
    assert fine.used["scale"] == f"{PX / 2:g} m/px (given; the image's {PX / 4:g} m/px read at 1/2 of its pixels)"
    areas = sorted(p.area for p in _zones(fine).values())
    assert areas == pytest.approx(sorted(p.area for p in _zones(got).values()), rel=0.03)


def test_walls_drawn_as_empty_outlines(tmp_path):
    """0.42 m outer walls drawn as outlines with nothing inside: the closed strip between
    the two lines is the wall's inside (not a room, as the strip between a wall and its
    dimension line is not a wall: that one is open at its ends)."""
    got = read_plan(draw_hollow_walls(tmp_path / "hollow.png", 0.42), scale=PX, ocr=False)
    areas = sorted(p.area for p in _zones(got).values())
    inside = (4.5 - 0.075 - 0.42) * (6.0 - 2 * 0.42)
    assert areas == pytest.approx([inside, inside], rel=0.02), areas
    assert Polygon(got.scene["room"]["footprint"]).area == pytest.approx(9.0 * 6.0, rel=0.02)


@pytest.mark.parametrize("pen", [(220, 30, 30), (0, 200, 220)])  # a CAD plot's red and cyan pens
def test_walls_drawn_in_colour(tmp_path, pen):
    """The hairline plan plotted with its walls, doors and windows in a coloured pen and its
    text, dimension line and frame in black: Otsu parts the black from the paper and the
    bright pen is paper at first; the coloured lines are tried as ink when nothing else
    encloses a room."""
    black = read_plan(draw_line_plan(tmp_path / "black.png").path, scale=PX, ocr=False)
    got = read_plan(draw_line_plan(tmp_path / "pen.png", pen=pen).path, scale=PX, ocr=False)
    assert got.used["walls"].endswith("coloured lines read as ink"), got.used["walls"]
    assert sorted(q.area for q in _zones(got).values()) == pytest.approx(
        sorted(q.area for q in _zones(black).values()), rel=0.02)


def test_thick_walls_are_not_read_as_lines(apartment):
    _, got = apartment
    assert got.used["walls"].endswith("from strokes at least 0.08 m thick")


def test_openings_title_block_and_summary(apartment):
    _, got = apartment
    doors_and_plain_windows = 6 + 3  # five doors and the entrance; the south and east windows
    assert len(got.openings) >= doors_and_plain_windows - 1, got.openings
    assert all(Polygon(o).area < 2.0 for o in got.openings)
    assert got.skipped["marks off the plans (title block, legend, scale bar, key plan, text)"] > 0
    assert got.used["scale"].startswith(f"{PX:g} m/px") and "threshold" in got.used
    walls = [Polygon(o["prism"]["polygon"]) for o in got.scene["obstacles"]]
    assert sum(w.bounds[2] - w.bounds[0] > W for w in walls) >= 1  # the outer walls, not the title block
    assert max(w.bounds[2] for w in walls) < (W + 6.0)  # nothing from the title block at the sheet's right


def test_rooms_named_by_their_labels(apartment):
    need_ocr()
    _, got = apartment
    zones = _zones(got)
    assert set(zones) == set(ROOMS), sorted(zones)
    for name, poly in zones.items():
        assert poly.area == pytest.approx(room_area(name), rel=0.1), name
    assert got.used["ocr"].startswith("tesseract") and "5 of 5 rooms named" in got.used["ocr"]
    printed = [n for n in got.notes if "printed" in n]
    assert len(printed) >= 4, got.notes  # '21,43 m²' read as an area, never as a name


def test_two_rooms_with_one_name(tmp_path):
    """Two rooms labelled alike (two bedrooms, two flats' kitchens) are both named; with
    their room numbers printed, by name and number (as the IFC import names them)."""
    need_ocr()
    sheet = draw_apartment(tmp_path / "twice.png", names={"Office": "Bedroom"})
    zones = _zones(read_plan(sheet.path, scale=PX))
    assert {"Bedroom", "Bedroom-2"} <= set(zones), sorted(zones)
    assert sorted(zones[n].area for n in ("Bedroom", "Bedroom-2")) == pytest.approx(
        sorted(room_area(n) for n in ("Bedroom", "Office")), rel=0.1)
    sheet = draw_apartment(tmp_path / "numbered.png", names={"Office": "Bedroom"},
                           numbers={"Bedroom": "B12", "Office": "B14", "Kitchen": "B11"})
    zones = _zones(read_plan(sheet.path, scale=PX))
    assert zones["Bedroom B12"].area == pytest.approx(room_area("Bedroom"), rel=0.1), sorted(zones)
    assert zones["Bedroom B14"].area == pytest.approx(room_area("Office"), rel=0.1)
    assert "Kitchen" in zones  # a name of its own keeps it


def test_german_labels_with_the_german_model(tmp_path):
    """Words English reads badly ('Küche', 'Büro') are read again with the other installed
    models (.ci/run installs tesseract-ocr-deu); numbers stay with English alone."""
    need_ocr()
    from camplace.scene.importers.image_ocr import ocr_engine

    if "deu" not in (getattr(ocr_engine()[0], "more", None) or ""):
        if os.environ.get("CI") == "true":
            pytest.fail("the German model is required on CI (tesseract-ocr-deu)")
        pytest.skip("no German model for tesseract (tesseract-ocr-deu)")
    names = {"Kitchen": "Küche", "Office": "Büro", "Living": "Wohnzimmer", "Bedroom": "Schlafzimmer", "Bathroom": "Bad"}
    got = read_plan(draw_apartment(tmp_path / "de.png", names=names).path, scale=PX)
    assert sorted(_zones(got)) == sorted(names.values())
    assert "words again with eng+deu" in got.used["ocr"]


def test_small_word_labels(tmp_path):
    """Room names at 10 px (capitals about 7 px, regular weight) and areas at 9 px, as on
    a plan printed small: the words and 'WC' are read (Tesseract alone reads 'WC' as 'wc')."""
    need_ocr()
    printed = {"Bathroom": "WC"}
    sheet = draw_apartment(tmp_path / "small.png", label_px=(10, 9), names=printed)
    names = {z["name"] for z in read_plan(sheet.path, scale=PX).scene["zones"]}
    labels = {printed.get(n, n) for n in ROOMS}
    assert len(names & labels) >= 4 and all(n in labels or n.startswith("room-") for n in names), sorted(names)


def test_without_ocr_rooms_are_numbered_with_a_note(apartment, monkeypatch):
    import camplace.scene.importers.image as image

    monkeypatch.setattr(image, "ocr_engine", lambda: (None, "pytesseract is not installed"))
    got = read_plan(apartment[0].path, scale=PX)
    assert sorted(_zones(got)) == [f"room-{k}" for k in range(1, 6)]
    assert any("OCR not available" in n for n in got.notes)


@pytest.mark.parametrize("name, style, rel", [("scan.jpg", {"jpeg_quality": 70, "noise": 8.0, "seed": 3}, 0.1),
                                              ("two-lines.png", {"hatch": False}, 0.1),
                                              ("furnished.png", {"furniture": True}, 0.3)])
def test_a_scan_unhatched_walls_and_furniture_give_the_same_rooms(tmp_path, name, style, rel):
    sheet = draw_apartment(tmp_path / name, **style)
    got = read_plan(sheet.path, scale=PX, ocr=False)
    areas = sorted(p.area for p in _zones(got).values())
    assert areas == pytest.approx(sorted(room_area(n) for n in ROOMS), rel=rel), areas
    # furnished: the bathtub's double outline is a solid ring (an obstacle), its inside no room: bathroom -25 %


def test_grid_only_run_puts_cameras_inside(apartment):
    import camplace
    from camplace.spec.loading import parse_scene

    sheet, got = apartment
    res = camplace.run(parse_scene(got.scene, str(sheet.path)), budget=4, solver="greedy")
    pos = res.visibility.candidates.positions[res.placement.selected]
    assert len(pos) == 4
    assert not res.scene.occupancy.is_occupied(pos).any()
    footprint = Polygon(got.scene["room"]["footprint"])
    assert all(footprint.contains(Point(*p[:2])) for p in pos)


def test_two_plans_side_by_side_are_two_storeys(tmp_path):
    from PIL import Image

    one = np.asarray(Image.open(draw_apartment(tmp_path / "a.png", labels=False).path))
    sheet = tmp_path / "two.png"
    Image.fromarray(np.concatenate([one, one[:, :700]], axis=1)).save(sheet)
    got = read_plan(sheet, scale=PX, ocr=False)
    assert [s["name"] for s in got.storeys] == ["plan-1", "plan-2"]
    assert [len(s["rooms"]) for s in got.storeys] == [5, 5]
    assert sum(s["chosen"] for s in got.storeys) == 1 and any("2 plans" in n for n in got.notes)
    both = read_storey_plans(sheet, scale=PX, ocr=False)
    assert [name for name, _, _ in both] == ["plan-1", "plan-2"]
    second = read_plan(sheet, scale=PX, ocr=False, storey="plan-2")
    assert second.storeys[1]["chosen"] and len(second.scene["zones"]) == 5
    with pytest.raises(InputError, match="plan-1, plan-2"):
        read_plan(sheet, scale=PX, ocr=False, storey="Level 3")


def test_plans_part_at_gutters_no_room_spans(tmp_path):
    """Two storeys 1.2 m apart with their outer walls in line (the gaps are bridged as
    openings) are two plans; a U whose halves meet only across 1.2 m windows (no wall
    from top to bottom there either) is one, its hall spanning them."""
    two = read_plan(draw_two_blocks(tmp_path / "two.png", gap=1.2), scale=PX, ocr=False)
    assert [len(s["rooms"]) for s in two.storeys] == [2, 2]
    u = read_plan(draw_u_plan(tmp_path / "u.png"), scale=PX, ocr=False)
    assert len(u.storeys) == 1
    assert sorted(a for _, a in u.storeys[0]["rooms"]) == pytest.approx([27.0, 27.0, 12.0 * 4.7], rel=0.03)


def test_scale_read_from_the_scale_bar(tmp_path):
    """No dimension lines: the scale bar under the plan (0 1 2 3 4 5 m) gives the scale."""
    need_ocr()
    sheet = draw_apartment(tmp_path / "bar.png", dimensions=False)
    got = read_plan(sheet.path)
    s = float(got.used["scale"].split()[0])
    assert s == pytest.approx(PX, rel=0.01) and "scale bar" in got.used["scale"], got.used["scale"]
    assert len(got.scene["zones"]) == 5


def test_scale_read_from_the_dimension_lines(apartment):
    need_ocr()
    got = read_plan(apartment[0].path)  # neither scale nor ref
    s = float(got.used["scale"].split()[0])
    assert s == pytest.approx(PX, rel=0.01) and "dimension lines" in got.used["scale"]
    assert any("check it" in n for n in got.notes)
    assert len(got.scene["zones"]) == 5
