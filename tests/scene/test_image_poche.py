"""Plan images (issue 34): poché of every kind is wall fill, lines that run past the
building are not walls, counters and furniture are obstacles with their height. Each
plan is generated (tests/scene/poche_drawings.py) with its answer known by hand."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, Polygon, shape

from camplace.scene.importers import read_plan
from camplace.scene.importers.image_poche import closed_strips, lines_past, thin
from camplace.scene.importers.image_walls import evenly_marked
from tests.scene.poche_drawings import MARGIN, PX, draw_counter, draw_grid_lines, draw_photo_ldk, draw_stippled


def _zones(got) -> list[float]:
    return sorted(Polygon(z["polygon"]).area for z in got.scene["zones"])


def _footprint(got) -> Polygon:
    fp = got.scene["room"]["footprint"]
    return Polygon(fp) if isinstance(fp, list) else shape(fp)


def _prisms(got, prefix: str) -> list:
    return [o for o in got.scene["obstacles"] if o["name"].startswith(prefix)]


def _in_walls(got, x: float, y: float) -> bool:
    """(x, y) m of the drawing (y up from its south-west corner) inside a wall prism."""
    pt = Point(x + MARGIN, y + MARGIN)
    return any(Polygon(o["prism"]["polygon"]).buffer(PX).contains(pt) for o in _prisms(got, "wall"))


@pytest.mark.parametrize("t, dots, solid", [(0.5, True, False), (0.7, True, False), (0.9, True, False),
                                            (0.7, False, False), (0.9, False, False), (0.9, False, True)])
def test_stippled_empty_and_solid_poche_is_wall(tmp_path, t, dots, solid):
    got = read_plan(draw_stippled(tmp_path / "plan.png", t=t, dots=dots, solid=solid), scale=PX, ocr=False)
    clear = (9.0 - 2 * t) * (7.0 - 2 * t)
    zones = _zones(got)
    assert len(zones) == 1  # the room, no room made of a wall's inside
    assert zones[0] == pytest.approx(clear, rel=0.04)  # empty outlines: the 0.1 m single lines take a little
    assert _footprint(got).area == pytest.approx(63.0, rel=0.03)
    for x, y in ((t / 2, 3.5), (9 - t / 2, 3.5), (4.5, 7 - t / 2), (1.5, t / 2)):  # the middle of each wall
        assert _in_walls(got, x, y)
    assert not _in_walls(got, 4.5, 3.5)


def test_grid_and_dimension_lines_past_the_building_are_not_walls(tmp_path):
    got = read_plan(draw_grid_lines(tmp_path / "plan.png"), scale=PX, ocr=False)
    assert _zones(got) == pytest.approx([9.4 * 7.4], rel=0.01)  # one room, not cut into nine
    assert _footprint(got).area == pytest.approx(80.0, rel=0.01)  # not out to the dimension line
    assert got.skipped["lines running past the building (grid, dimension lines)"] >= 4
    assert not _in_walls(got, 10 / 3, 4.0) and not _in_walls(got, 5.0, 8 / 3)  # grid lines in the room
    fp = _footprint(got).buffer(PX)
    assert all(fp.contains(Polygon(o["prism"]["polygon"])) for o in _prisms(got, "wall"))


@pytest.mark.parametrize("dashed", [True, False])
def test_photo_grid_lines_and_counter_leave_the_living_room_whole(tmp_path, dashed):
    """The issue's photo: grid lines and the kitchen counter cut a 51 m² living room to 37."""
    got = read_plan(draw_photo_ldk(tmp_path / "plan.jpg", dashed=dashed), scale=PX, ocr=False)
    assert _zones(got) == pytest.approx([24.7, 65.0], rel=0.02)
    assert _footprint(got).area == pytest.approx(14.6 * 7.1, rel=0.01)
    furniture = _prisms(got, "furniture")
    assert len(furniture) == 1 and furniture[0]["prism"]["z"] == [0.0, 0.9]
    assert Polygon(furniture[0]["prism"]["polygon"]).contains(Point(2.8 + MARGIN, 6.45 + MARGIN))


def test_counter_and_island_are_obstacles_not_dividers(tmp_path):
    got = read_plan(draw_counter(tmp_path / "plan.png"), scale=PX, ocr=False)
    assert _zones(got) == pytest.approx([7.4 * 5.4], rel=0.02)  # one room round the counter and island
    furniture = sorted(_prisms(got, "furniture"), key=lambda o: Polygon(o["prism"]["polygon"]).area)
    assert [o["prism"]["z"] for o in furniture] == [[0.0, 0.9], [0.0, 0.9]]
    island, counter = (Polygon(o["prism"]["polygon"]) for o in furniture)
    assert island.area == pytest.approx(2.0 * 0.9, rel=0.05)
    assert counter.area == pytest.approx(4.0 * 0.6, rel=0.25)  # its back line merges with the wall
    assert island.contains(Point(4.0 + MARGIN, 2.45 + MARGIN))
    assert "counters and furniture" in got.used["furniture"]
    assert not _in_walls(got, 4.0, 2.45)


def test_closed_strips_by_hand():
    labels = np.zeros((60, 60), int)
    labels[5:55, 5:9] = 1  # 4 px wide, 50 long: a wall's inside
    labels[20:40, 20:40] = 2  # a 20 px square: a room
    labels[5:55, 50:54] = 3  # as 1, with a door
    bridges = np.zeros_like(labels, bool)
    bridges[30:33, 54:56] = True
    assert closed_strips(labels, [1, 2, 3], bridges, s=0.1) == [1]  # 0.4 m wide; the room is 2 m
    assert closed_strips(labels, [1], bridges, s=0.5) == []  # 2 m wide: no wall


def test_evenly_marked_stipple_not_text():
    blab = np.zeros((40, 400), int)
    blab[5:35, :] = 1
    stipple = np.zeros_like(blab, bool)
    stipple[6:35:4, ::4] = True
    text = np.zeros_like(blab, bool)
    text[15:25, 180:220] = True  # one number along a 8 m strip
    assert evenly_marked(stipple, blab, 1, 0.02).tolist() == [True]
    assert evenly_marked(text, blab, 1, 0.02).tolist() == [False]


@settings(max_examples=25, deadline=None)
@given(st.integers(10, 60), st.integers(10, 60), st.integers(1, 4), st.integers(0, 3))
def test_lines_past_drops_only_thin_wall_pixels(x0, y0, width, past):
    """Whatever is drawn, what lines_past drops is thin wall pixels, never a solid wall."""
    walls = np.zeros((140, 140), bool)
    walls[x0:x0 + 60, y0:y0 + 8] = walls[x0:x0 + 60, y0 + 52:y0 + 60] = True  # a box of 8 px walls
    walls[x0:x0 + 8, y0:y0 + 60] = walls[x0 + 52:x0 + 60, y0:y0 + 60] = True
    walls[x0 + 30:x0 + 30 + width, max(0, y0 - 10 * past):y0 + 60 + 10 * past] = True  # a line
    drop = lines_past(walls, np.zeros_like(walls), 0.05)
    assert not (drop & ~thin(walls, 0.05)).any()
    solid = walls.copy()
    solid[x0 + 30:x0 + 30 + width] = False
    assert not (drop & solid).any()
    if past >= 2:  # at least 1 m past: dropped inside the box too
        assert drop[x0 + 30, y0 + 30]
