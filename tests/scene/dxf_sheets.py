"""DXF plans for the importer's plausibility rules and sheets of several plans (issues 34
and 33), drawn with ezdxf; every answer known by hand (m):

- ``draw_art_plan``: a 10 x 6 m room on A-WALL with murals (closed 3 x 0.1 m outlines)
  and a sculpture block inserted twice on a layer whose name holds 'murals' or says walls.
- ``draw_unit_lie``: a room drawn in metres whose $INSUNITS says mm; its outline is
  UNIT_ROOM_M2 and its texts print that area ('mq=28.51', '28.5 m²') unless ``texts`` is off.
- ``draw_rooms_plan``: three rooms on A-AREA, the hall's outline left open ``hall_gap``
  m; an area text, a tatami count and a dimension string, a bare number beside a name.
- ``draw_solid_block``: a 6 x 6 m block all wall (lines 0.5 m apart on A-WALL): no free floor.
- ``draw_two_storeys``: a ground floor and a first floor side by side, each under a
  title naming its level (``titles``), 10 m apart.
"""

from __future__ import annotations

from pathlib import Path

from tests.scene.dxf_drawings import _wall

ART_LAYER = "A786g - Works of Art - sculpture-murals"
ART_MURALS = [(1.0, 0.5, 4.0, 0.6), (5.0, 0.5, 8.0, 0.6), (1.0, 5.4, 4.0, 5.5)]  # x0, y0, x1, y1 of each mural
ART_SCULPTURES = [(3.0, 3.0), (6.0, 3.0)]  # where the 0.8 x 0.8 m sculpture block stands
UNIT_ROOM = (0.2, 0.2, 5.8, 5.293)  # the room's outline (m): 5.6 x 5.093 = 28.52 m²
UNIT_ROOM_M2 = 5.6 * 5.093
ROOMS = {"Kitchen": (0.2, 0.2, 4.0, 4.8), "Bedroom": (4.2, 0.2, 8.0, 4.8), "Hall": (8.2, 0.2, 11.8, 4.8)}
TWO_SIZE = (10.0, 8.0)  # each storey's outer faces, m; the first floor starts at x = 20
TWO_FIRST_X = 20.0


def _new(units: int):
    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = units
    return doc, doc.modelspace()


def _box(msp, x0, y0, x1, y1, layer, close=True):
    msp.add_lwpolyline([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], close=close, dxfattribs={"layer": layer})


def _outer_walls(msp, x0, y0, w, h, t=0.2, layer="A-WALL", door=None):
    """The four walls of a w x h box from (x0, y0) to its outer faces, LINE pairs on ``layer``;
    ``door``: a gap (s0, s1) in the bottom wall, from x0."""
    _wall(msp, (x0, y0 + t / 2), (x0 + w, y0 + t / 2), t, layer, [(x0 + door[0], x0 + door[1])] if door else [])
    _wall(msp, (x0, y0 + h - t / 2), (x0 + w, y0 + h - t / 2), t, layer)
    _wall(msp, (x0 + t / 2, y0), (x0 + t / 2, y0 + h), t, layer)
    _wall(msp, (x0 + w - t / 2, y0), (x0 + w - t / 2, y0 + h), t, layer)


def draw_art_plan(path: str | Path, layer: str = ART_LAYER) -> Path:
    """A 10 x 6 m room in m (walls on A-WALL, a 1 m door gap), three murals drawn as
    closed 3 x 0.1 m outlines and a 0.8 x 0.8 m sculpture block inserted twice, all on
    ``layer``."""
    doc, msp = _new(6)
    _outer_walls(msp, 0, 0, 10, 6, door=(4.5, 5.5))
    for x0, y0, x1, y1 in ART_MURALS:
        _box(msp, x0, y0, x1, y1, layer)
    blk = doc.blocks.new("SCULPTURE")
    blk.add_lwpolyline([(0, 0), (0.8, 0), (0.8, 0.8), (0, 0.8)], close=True)
    blk.add_circle((0.4, 0.4), 0.3)
    for at in ART_SCULPTURES:
        msp.add_blockref("SCULPTURE", at, dxfattribs={"layer": layer})
    doc.saveas(path)
    return Path(path)


def draw_unit_lie(path: str | Path, texts: bool = True) -> Path:
    """A 6.0 x 5.493 m room drawn in metres (walls LINE pairs 0.2 m apart on MURI, its
    outline on LOCALI) in a file whose $INSUNITS says mm (4); with ``texts`` its name and
    printed area three ways ('mq=28.51', '28.5 m²', 'sqm 28.52')."""
    doc, msp = _new(4)
    x0, y0, x1, y1 = UNIT_ROOM
    _outer_walls(msp, 0, 0, x1 + 0.2, y1 + 0.2, layer="MURI", door=(2.0, 3.0))
    _box(msp, x0, y0, x1, y1, "LOCALI")
    msp.add_text("Soggiorno", height=0.25, dxfattribs={"layer": "TESTI", "insert": (2.0, 3.0)})
    if texts:
        for k, t in enumerate(("mq=28.51", "28.5 m²", "sqm 28.52")):
            msp.add_text(t, height=0.2, dxfattribs={"layer": "TESTI", "insert": (2.0, 2.6 - 0.3 * k)})
    doc.saveas(path)
    return Path(path)


def draw_rooms_plan(path: str | Path, hall_gap: float = 0.3) -> Path:
    """A 12 x 5 m flat in m: walls on A-WALL (0.2 m, partitions at x 4.1 and 8.1 with
    1 m doors), room outlines on A-AREA (ROOMS), the hall's an open polyline whose ends
    lie ``hall_gap`` m apart; texts: 'Kitchen' with '17.48 m²', 'Bedroom' with a tatami
    count '10.5帖' and its width '3.80' on a dimension layer below its name, 'Hall'
    with a bare '16.56' just below it."""
    doc, msp = _new(6)
    _outer_walls(msp, 0, 0, 12, 5)
    for x in (4.1, 8.1):
        _wall(msp, (x, 0.2), (x, 4.8), 0.2, "A-WALL", [(1.0, 2.0)])
    for name, (x0, y0, x1, y1) in ROOMS.items():
        if name == "Hall":  # open: from the gap's end round to its start
            msp.add_lwpolyline([(x0 + hall_gap, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)],
                               dxfattribs={"layer": "A-AREA"})
        else:
            _box(msp, x0, y0, x1, y1, "A-AREA")
    texts = {"Kitchen": ["Kitchen", "17.48 m²"], "Bedroom": ["Bedroom", "10.5帖"], "Hall": ["Hall", "16.56"]}
    for name, lines in texts.items():
        x0, y0, x1, y1 = ROOMS[name]
        for k, t in enumerate(lines):
            msp.add_text(t, height=0.2, dxfattribs={"layer": "A-ANNO-TEXT", "insert": (x0 + 1.0, 3.0 - 0.35 * k)})
    msp.add_text("3.80", height=0.2, dxfattribs={"layer": "A-ANNO-DIMS", "insert": (5.5, 2.3)})  # the room's width
    doc.saveas(path)
    return Path(path)


def draw_two_storeys(path: str | Path, titles: tuple = ("GROUND FLOOR PLAN 1:100", "FIRST FLOOR PLAN 1:100")
                     ) -> Path:
    """A ground floor (x 0..10: two rooms) and a first floor (x 20..30: three rooms, more
    walls) side by side in m, walls on A-WALL, each with a title 1.5 m below it
    (``titles``; none when empty)."""
    doc, msp = _new(6)
    w, h = TWO_SIZE
    for x0, walls in ((0.0, (5.0,)), (TWO_FIRST_X, (3.3, 6.6))):
        _outer_walls(msp, x0, 0, w, h, door=(1.0, 2.0))
        for x in walls:
            _wall(msp, (x0 + x, 0.2), (x0 + x, h - 0.2), 0.2, "A-WALL", [(1.0, 1.9)])
    for x0, title in zip((0.0, TWO_FIRST_X), titles):
        msp.add_text(title, height=0.4, dxfattribs={"layer": "A-ANNO-TTLB", "insert": (x0, -1.5)})
    doc.saveas(path)
    return Path(path)


def draw_solid_block(path: str | Path) -> Path:
    """A 6 x 6 m block in m on A-WALL: 13 lines 0.5 m apart and its two sides, which the
    wall closing fills whole: walls and no free floor."""
    doc, msp = _new(6)
    for k in range(13):
        msp.add_line((0, 0.5 * k), (6, 0.5 * k), dxfattribs={"layer": "A-WALL"})
    for x in (0, 6):
        msp.add_line((x, 0), (x, 6), dxfattribs={"layer": "A-WALL"})
    doc.saveas(path)
    return Path(path)
