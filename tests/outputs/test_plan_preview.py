"""The plan preview (issue 25): what an importer understood, drawn: walls in their label's
colour, openings, rooms named with their areas inside them, the surviving mount grid;
empty fields drawn without failing; labels that do not fit become key numbers."""

from __future__ import annotations

import io
from collections import Counter

import numpy as np
import pytest
from shapely.geometry import Polygon, box

from camplace.outputs.plan_preview import (DPI, MOUNT_COLOUR, OPENING_FILL, ROOM_FILLS, RC, preview_figure,
                                           render_preview, room_areas, room_labels)
from camplace.outputs.walls import LABEL_COLOURS, WALL_COLOUR
from camplace.scene.importers import PlanImport, plan_scene, prism_obstacles, room_zones

ROOMS = [("Office", box(0.1, 0.1, 4.9, 3.9)), ("Lab", box(5.1, 0.1, 7.9, 3.9))]  # 18.24 and 10.64 m²


def two_rooms(with_rooms: bool = True) -> PlanImport:
    """A hand-made import: an 8 x 4 m footprint, a wall between the rooms (IfcWall), a window
    box in it (IfcWindow), a door opening, two named rooms."""
    walls = prism_obstacles(box(4.9, 0.1, 5.1, 3.9).difference(box(4.8, 1.5, 5.2, 2.5)), 0.0, 3.0, "wall",
                            {"class": "IfcWall"})
    window = prism_obstacles(box(4.9, 2.6, 5.1, 3.4), 0.9, 2.1, "window", {"class": "IfcWindow"})
    zones = room_zones(ROOMS, 1) if with_rooms else []
    data = plan_scene("two-rooms", box(0, 0, 8, 4), 3.0, walls + window, zones)
    return PlanImport(data, "ifc", used={"classes": "IfcWall, IfcWindow"}, skipped=Counter({"slivers": 2}),
                      openings=[[[4.9, 1.5], [5.1, 1.5], [5.1, 2.5], [4.9, 2.5]]] if with_rooms else [],
                      notes=["a note to read"] if with_rooms else [])


@pytest.fixture(scope="module")
def drawn():
    """(figure, summary, PNG pixels (H, W, 3) uint8) of two_rooms()."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    with matplotlib.rc_context(RC):
        fig, summary = preview_figure(two_rooms(), "two-rooms.ifc")
        FigureCanvasAgg(fig)
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=DPI)
    return fig, summary, np.asarray(Image.open(io.BytesIO(buf.getvalue())).convert("RGB"))


def _rgb(hex_colour: str) -> np.ndarray:
    return np.array([int(hex_colour[k:k + 2], 16) for k in (1, 3, 5)])


def _count(pixels: np.ndarray, colour: str, tol: int = 6) -> int:
    return int((np.abs(pixels.astype(int) - _rgb(colour)).max(axis=2) <= tol).sum())


def test_summary_of_what_was_understood(drawn):
    _, s, _ = drawn
    assert [(r["name"], r["area_m2"]) for r in s["rooms"]] == [("Office", pytest.approx(18.24)),
                                                                ("Lab", pytest.approx(10.64))]
    assert s["footprint_m2"] == 32.0 and s["walls"] == 3 and s["openings"] == 1  # the wall in two pieces, the window
    assert s["used"] == {"classes": "IfcWall, IfcWindow"} and s["skipped"] == {"slivers": 2}
    # the 1 m grid inside the 8 x 4 m footprint less its edge: x 1..7, y 1..3; (5, 1) and (5, 3) in the wall,
    # (5, 2) in the door 0.5 m from its jambs, 0.8 m above the window
    assert s["mount_positions"] == 19 and s["mount_positions_dropped"] == {"inside": 2, "clearance": 0}


def test_walls_openings_rooms_and_mounts_are_drawn(drawn):
    _, _, px = drawn
    for colour in (WALL_COLOUR, LABEL_COLOURS["window"], OPENING_FILL, ROOM_FILLS[0], ROOM_FILLS[1]):
        assert _count(px, colour) > 50, colour
    assert _count(px, MOUNT_COLOUR, tol=40) > 19 * 4  # 19 '+' marks


def test_each_room_label_lies_in_its_room_and_is_drawn(drawn):
    fig, _, px = drawn
    ax = fig.axes[0]
    renderer = fig.canvas.get_renderer()
    height = px.shape[0]
    for name, poly in ROOMS:
        text = next(t for t in ax.texts if t.get_text().startswith(name))
        assert f"{poly.area:.1f} m\u00b2" in text.get_text()
        bb = text.get_window_extent(renderer)
        (x0, y0), (x1, y1) = ax.transData.transform(np.reshape(poly.bounds, (2, 2)))
        assert x0 <= bb.x0 and bb.x1 <= x1 and y0 <= bb.y0 and bb.y1 <= y1, name  # inside the room
        region = px[int(height - bb.y1):int(height - bb.y0), int(bb.x0):int(bb.x1)]
        assert (region.max(axis=2) < 90).sum() > 20, name  # dark glyph pixels where the label is


def test_svg_keeps_the_names_as_text_and_empty_fields_draw():
    full = render_preview(two_rooms(), "two-rooms.ifc")
    svg = full.svg.decode()
    assert "Office" in svg and "Lab" in svg and "18.2 m\u00b2" in svg and "IfcWindow (1)" in svg
    assert full.png[:8] == b"\x89PNG\r\n\x1a\n"
    bare = PlanImport(plan_scene("bare", box(0, 0, 3, 3), 3.0, [], []), "image")  # nothing found but a footprint
    got = render_preview(bare, "bare.png")
    assert got.summary["rooms"] == [] and got.summary["walls"] == 0 and got.summary["mount_positions"] == 4
    assert b"bare.png" in got.svg


def test_a_room_too_small_for_its_label_gets_a_key_number():
    rooms = room_areas({"zones": room_zones([("Conference hall", box(0, 0, 12, 8)), ("Store", box(12, 0, 12.6, 0.6)),
                                             ("Big", box(0, 8, 12, 16))], 1)})
    labels = room_labels(rooms, m_per_pt=0.04)
    assert [lab.key for lab in labels] == [None, 1, None]
    assert labels[0].text == "Conference hall\n96.0 m\u00b2" and labels[1].text == "1"
    assert all(Polygon(rooms[k][2]).contains(Polygon(box(*np.r_[labels[k].anchor, labels[k].anchor]).buffer(1e-3)))
               for k in range(3))
