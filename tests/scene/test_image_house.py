"""The real plan image of shared/data/plans (SOURCES.md section 5): three storey plans of a
house side by side on one sheet at 32 px/m, walls drawn as outlines with a hatch (dashes
in the basement), rooms in flat colours, labelled '1.4' in a circle and '14,43 m²'."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from shapely.geometry import Point, Polygon

from camplace.scene.importers import read_plan, read_storey_plans
from tests.scene.test_image_plans import need_ocr

HOUSE = Path(__file__).parents[2].parent / "shared" / "data" / "plans" / "TheHouseBuiltByProgrammer_plan.png"
SCALE = 1 / 32  # m per pixel (SOURCES.md: 32 px/m ± 2 %)
PRINTED = {"plan-1": 7, "plan-2": 8, "plan-3": 7}  # rooms printed on the basement, ground and upper floor
NUMBERS = {f"{k}.{i}" for k, n in ((0, 7), (1, 8), (2, 7)) for i in range(1, n + 1)}
LABELS = {  # the middle (col, row px) of the ring around each room number, measured on the sheet
    "0.1": (105, 445), "0.2": (124, 342), "0.3": (116, 258), "0.4": (205, 224), "0.5": (282, 139), "0.6": (272, 249),
    "0.7": (252, 462), "1.1": (454, 380), "1.2": (529, 354), "1.3": (604, 354), "1.4": (578, 254), "1.5": (674, 231),
    "1.6": (740, 230), "1.7": (734, 472), "1.8": (568, 454), "2.1": (970, 436), "2.2": (944, 332), "2.3": (970, 244),
    "2.4": (1065, 219), "2.5": (1166, 252), "2.6": (1058, 335), "2.7": (1126, 444)}
# the ground and upper floor outline: the 10.7 m x 11.45 m block and the 1.35 m deep bay,
# 6.44 m wide with 45° corners (10700 and 12800 from the dimension lines, the bay from the drawing)
OUTLINE_M2 = 10.7 * 11.45 + 6.44 * 1.35 - 1.35 ** 2

pytestmark = pytest.mark.skipif(not HOUSE.is_file(), reason=f"{HOUSE} is absent (shared/data/plans)")


@pytest.fixture(scope="module")
def storeys():
    return {name: got for name, got, _ in read_storey_plans(HOUSE, scale=SCALE)}


def test_three_plans_with_about_the_printed_rooms(storeys):
    assert sorted(storeys) == ["plan-1", "plan-2", "plan-3"]
    for name, got in storeys.items():
        assert abs(len(got.scene["zones"]) - PRINTED[name]) <= 2, (name, [z["name"] for z in got.scene["zones"]])
    assert sum(len(g.scene["zones"]) for g in storeys.values()) == pytest.approx(22, abs=4)


def test_outline_and_footprint(storeys):
    for name in ("plan-2", "plan-3"):
        got = storeys[name]
        row = next(s for s in got.storeys if s["name"] == name)
        assert row["outline_m2"] == pytest.approx(OUTLINE_M2, rel=0.1), name
        footprint = Polygon(got.scene["room"]["footprint"]).area  # the outer faces of the 0.65 m outer walls
        assert footprint == pytest.approx(OUTLINE_M2, rel=0.1), (name, footprint)  # ground floor: + porch room 1.1


def test_default_plan_and_what_was_dropped():
    got = read_plan(HOUSE, scale=SCALE, ocr=False)
    assert [s["name"] for s in got.storeys] == ["plan-1", "plan-2", "plan-3"]
    chosen = [s["name"] for s in got.storeys if s["chosen"]]
    assert len(chosen) == 1 and any("3 plans side by side" in n for n in got.notes)
    assert got.skipped["marks off the plans (title block, legend, scale bar, key plan, text)"] > 0
    assert got.used["scale"] == "0.03125 m/px (given)"


def test_room_numbers_read_by_ocr(storeys):
    """8 px digits in rings ('1.4'): every name is a printed number of its floor, in the
    room that holds it, dot kept; at least 80 % of the ground floor's labelled rooms named."""
    need_ocr()
    named_right = {}
    for plan, got in storeys.items():
        printed = {n for n in NUMBERS if n[0] == str(int(plan[-1]) - 1)}
        zones = [(z["name"], Polygon(z["polygon"])) for z in got.scene["zones"]]
        for name, poly in zones:  # a number read is one printed on this floor, on or beside its zone
            assert re.fullmatch(r"room-\d+", name) or (name in printed and poly.distance(_point(name)) < 0.5), \
                (plan, name)
        labelled = {n for n in printed if any(poly.distance(_point(n)) < 0.5 for _, poly in zones)}
        named_right[plan] = len(labelled & {name for name, _ in zones}) / max(1, len(labelled))
    assert named_right["plan-2"] >= 0.8 and min(named_right.values()) >= 0.6, named_right
    assert any("printed" in n for g in storeys.values() for n in g.notes)


def _point(number: str) -> Point:
    """The middle (m) of the ring around a room number on the sheet (1239 x 609 px)."""
    c, r = LABELS[number]
    return Point((c + 0.5) * SCALE, (609 - r - 0.5) * SCALE)


@pytest.fixture(scope="module")
def rooms_per_plan(storeys):
    return [len(s["rooms"]) for s in storeys["plan-1"].storeys]


def test_same_plans_at_the_scale_read(rooms_per_plan):
    """At 0.0314 m/px (the scale read from the sheet) the ground and upper floors, 1.5 m
    apart with their outer walls in line, stay two plans (once merged into one)."""
    got = read_plan(HOUSE, scale=0.0314, ocr=False)
    assert len(got.storeys) == 3
    assert all(abs(len(s["rooms"]) - k) <= 1 for s, k in zip(got.storeys, rooms_per_plan)), got.storeys


def test_scale_read_from_the_dimension_lines(rooms_per_plan):
    need_ocr()
    got = read_plan(HOUSE, ocr=True)  # neither scale nor ref: '10700', '3900', ... over their lines
    assert float(got.used["scale"].split()[0]) == pytest.approx(SCALE, rel=0.02), got.used["scale"]
    assert len(got.storeys) == 3  # the same plans as with the scale given
    assert all(abs(len(s["rooms"]) - k) <= 1 for s, k in zip(got.storeys, rooms_per_plan)), got.storeys
