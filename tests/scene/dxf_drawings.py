"""Floor plans drawn as CAD offices draw them (ezdxf), for the DXF importer's tests (issue 25):

- ``draw_fm_plan``: a Swiss facility-management ground floor in cm: exterior walls as
  three LINE faces on E41_AUSSENWAENDE with their concrete core hatched, load-bearing
  walls on E61_INNENWAENDE_TRAGEND, partitions on E62_INNENWAENDE_LEICHT (the toilet
  cubicles inside a block drawn on layer 0), door and window blocks, room polygons on
  Z23_NGF-POLYGONE, room stamps (INSERT + ATTRIB: number, name, area) on
  Z21_RAUMSTEMPEL, an axis grid, dimensions, a floor hatch, furniture blocks, and beside
  the building a title block with a key plan of the building drawn on the wall layer.
- ``draw_latin_plan``: a flat with French (``lang='fr'``) or Spanish (``'es'``) layer
  names: walls as closed polylines, room outlines named by TEXT / MTEXT.
- ``draw_unnamed_plan``: walls as LINE pairs on a layer named ``L4``, among layers of
  furniture, stairs, an exploded hatch, door swings and text with meaningless names.
- ``draw_single_line_plan``: a flat in cm drawn as hobby and LibreCAD plans are: every
  wall one LINE on layer 0 (no pairs, no layer names), door swings as ARC + leaf LINE on
  layer 0 too, room names as TEXT, a 0.9 m wide hall.
- ``draw_wc_plan``: a hall with a 1.2 m wide WC whose door swings into it (AIA layers, m).
- ``draw_no_walls``: text, circles and a few loose lines: nothing a wall.
- ``draw_walls_on_door_layer``: a room whose walls are LINE pairs on the door layer
  (as a web planner exports them), with a 1 m stub on A-WALL.

Each returns the file's path; the FM_* and LATIN_* constants are the truths (m).
"""

from __future__ import annotations

import math
from pathlib import Path

FM_OUTER = (3100, 2000)  # cm, outer faces of the exterior walls
FM_EXT, FM_BEARING, FM_PARTITION = 40, 20, 12  # wall thicknesses, cm
FM_OUTLINE_M2 = 3100 * 2000 / 1e4  # the footprint: the outer faces of the exterior walls, m²
# rooms (name, number, x0, y0, x1, y1 in cm, clear sizes); the corridor between y 900 and 1100
FM_ROOMS = [("Büro", "E.01", 40, 40, 794, 880), ("Sitzungszimmer", "E.02", 806, 40, 1494, 880),
            ("Büro", "E.03", 1506, 40, 2294, 880), ("Empfang", "E.04", 2306, 40, 3060, 880),
            ("Korridor", "E.05", 40, 900, 3060, 1100),
            ("Archiv", "E.06", 40, 1120, 694, 1960), ("Teeküche", "E.07", 706, 1120, 1394, 1960),
            ("WC Damen", "E.08", 1406, 1120, 1694, 1960), ("WC Herren", "E.09", 1706, 1120, 1994, 1960),
            ("Technik", "E.10", 2006, 1120, 2394, 1960), ("Büro", "E.11", 2406, 1120, 3060, 1960)]


def _wall(msp, a, b, t, layer, gaps=(), faces=2, caps=True):
    """An axis-parallel wall from a to b (its centre line, drawing units) ``t`` thick,
    as ``faces`` parallel LINEs (2: the faces; 3: with the insulation line) broken at
    ``gaps`` [(s0, s1) along the wall], with end caps at the gaps."""
    (x0, y0), (x1, y1) = a, b
    horiz = y0 == y1
    lo, hi = (min(x0, x1), max(x0, x1)) if horiz else (min(y0, y1), max(y0, y1))
    c = y0 if horiz else x0
    offs = [-t / 2, t / 2] if faces == 2 else [-t / 2, -t / 2 + 0.4 * t, t / 2]
    cuts = [lo, *[v for g in sorted(gaps) for v in g], hi]
    for s0, s1 in zip(cuts[::2], cuts[1::2]):
        for o in offs:
            p, q = ((s0, c + o), (s1, c + o)) if horiz else ((c + o, s0), (c + o, s1))
            msp.add_line(p, q, dxfattribs={"layer": layer})
        for s in (s0, s1):
            if caps and lo < s < hi:
                p, q = ((s, c - t / 2), (s, c + t / 2)) if horiz else ((c - t / 2, s), (c + t / 2, s))
                msp.add_line(p, q, dxfattribs={"layer": layer})


def _door_block(doc, name, w):
    """A door leaf and its swing, hinge at the origin, opening along +x, swinging to +y."""
    blk = doc.blocks.new(name)
    blk.add_lwpolyline([(0, 0), (4, 0), (4, w), (0, w)], close=True)
    blk.add_arc((0, 0), w, 0, 90)
    return name


def draw_fm_plan(path: str | Path) -> Path:
    """The Swiss FM ground floor (see the module docstring); truth FM_OUTLINE_M2, FM_ROOMS."""
    import ezdxf
    from ezdxf.enums import TextEntityAlignment

    doc = ezdxf.new("R2018")
    doc.header["$INSUNITS"] = 5
    msp = doc.modelspace()
    W, H = FM_OUTER
    e, ext = FM_EXT / 2, "E41_AUSSENWAENDE"
    south_gaps = [(300, 420), (1050, 1170), (1800, 1920), (2500, 2680), (2750, 2870)]  # windows; 2500-2680 entrance
    north_gaps = [(300, 420), (950, 1070), (2700, 2820)]
    _wall(msp, (0, e), (W, e), FM_EXT, ext, south_gaps, faces=3)
    _wall(msp, (0, H - e), (W, H - e), FM_EXT, ext, north_gaps, faces=3)
    _wall(msp, (e, 0), (e, H), FM_EXT, ext, faces=3)
    _wall(msp, (W - e, 0), (W - e, H), FM_EXT, ext, [(1400, 1520)], faces=3)
    for x0, y0, x1, y1 in ((16, 0, 40, H), (W - 40, 0, W - 16, 1400), (W - 40, 1520, W - 16, H)):
        hatch = msp.add_hatch(dxfattribs={"layer": "E41_AUSSENWAENDE_SCHRAFFUR"})  # concrete cores
        hatch.set_pattern_fill("ANSI31", scale=5)
        hatch.paths.add_polyline_path([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], is_closed=True)
    bear = "E61_INNENWAENDE_TRAGEND"
    doors_s = [(300, 390), (1100, 1190), (1900, 1990), (2600, 2690)]
    doors_n = [(200, 290), (900, 990), (1500, 1590), (1800, 1890), (2100, 2190), (2600, 2690)]
    _wall(msp, (40, 890), (3060, 890), FM_BEARING, bear, doors_s)
    _wall(msp, (40, 1110), (3060, 1110), FM_BEARING, bear, doors_n)
    part = "E62_INNENWAENDE_LEICHT"
    for x in (800, 1500, 2300):
        _wall(msp, (x, 40), (x, 880), FM_PARTITION, part)
    for x in (700, 2000, 2400):
        _wall(msp, (x, 1120), (x, 1960), FM_PARTITION, part)
    wc = doc.blocks.new("WC_ANLAGE")  # the toilet walls on layer 0 in a block, nested in the core's block
    for x in (0, 300, 600):
        _wall(wc, (x, 0), (x, 840), FM_PARTITION, "0")
    doc.blocks.new("KERN").add_blockref("WC_ANLAGE", (0, 0))
    msp.add_blockref("KERN", (1400, 1120), dxfattribs={"layer": part})
    _door_block(doc, "TUER_90", 90)
    for x0, _ in doors_s:
        msp.add_blockref("TUER_90", (x0, 880), dxfattribs={"layer": "E63_TUEREN", "xscale": 1, "yscale": -1})
    for x0, _ in doors_n:
        msp.add_blockref("TUER_90", (x0, 1120), dxfattribs={"layer": "E63_TUEREN"})
    win = doc.blocks.new("FENSTER_120")
    for y in (0, 16, 20, 40):
        win.add_line((0, y), (120, y))
    for gaps, y in ((south_gaps, 0), (north_gaps, H - 40)):
        for x0, x1 in gaps:
            if x1 - x0 == 120:
                msp.add_blockref("FENSTER_120", (x0, y), dxfattribs={"layer": "E51_FENSTER"})
    stamp = doc.blocks.new("RAUMSTEMPEL")
    stamp.add_lwpolyline([(0, 0), (220, 0), (220, 90), (0, 90)], close=True)
    for k, tag in enumerate(("RAUMNUMMER", "RAUMNAME", "NGF")):
        stamp.add_attdef(tag, (10, 65 - 28 * k), dxfattribs={"height": 18 if tag == "RAUMNAME" else 12})
    for name, number, x0, y0, x1, y1 in FM_ROOMS:
        msp.add_lwpolyline([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], close=True,
                           dxfattribs={"layer": "Z23_NGF-POLYGONE"})
        area = (x1 - x0) * (y1 - y0) / 1e4
        at = ((x0 + x1) / 2 - 110, (y0 + y1) / 2 - 45)
        ref = msp.add_blockref("RAUMSTEMPEL", at, dxfattribs={"layer": "Z21_RAUMSTEMPEL"})
        ref.add_auto_attribs({"RAUMNUMMER": number, "RAUMNAME": name, "NGF": f"{area:.2f} m²"})
    desk = doc.blocks.new("PULT_160")
    desk.add_lwpolyline([(0, 0), (160, 0), (160, 80), (0, 80)], close=True)
    for at in ((150, 150), (450, 150), (1650, 150), (2500, 1500)):
        msp.add_blockref("PULT_160", at, dxfattribs={"layer": "M10_MOEBEL"})
    floor = msp.add_hatch(dxfattribs={"layer": "Z30_BODENBELAG"})  # the corridor's floor finish
    floor.set_pattern_fill("NET", scale=20)
    floor.paths.add_polyline_path([(40, 900), (3060, 900), (3060, 1100), (40, 1100)], is_closed=True)
    for k, x in enumerate((0, 800, 1500, 2300, 3100)):  # the axis grid, past the building on both sides
        msp.add_line((x, -400), (x, H + 400), dxfattribs={"layer": "Z05_ACHSEN"})
        msp.add_circle((x, -460), 60, dxfattribs={"layer": "Z05_ACHSEN"})
        msp.add_text(str(k + 1), height=50, dxfattribs={"layer": "Z05_ACHSEN"}).set_placement(
            (x, -460), align=TextEntityAlignment.MIDDLE_CENTER)
    for a, b, base in (((0, 0), (W, 0), (0, -200)), ((0, 0), (0, H), (-200, 0))):
        dim = msp.add_aligned_dim(p1=a, p2=b, distance=-200 if a[1] == b[1] else 200,
                                  dxfattribs={"layer": "Z10_MASSLINIEN"})
        dim.render()
    _title_block(doc, msp, (W + 600, -600))
    msp.add_text("Grundriss Erdgeschoss 1:100", height=60, dxfattribs={"layer": "Z02_TEXT"}).set_placement((0, -800))
    doc.saveas(path)
    return Path(path)


def _title_block(doc, msp, at):
    """A title block 2000 x 1400 cm (20 x 14 cm on the sheet at 1:100) at ``at``: frame,
    rows, texts, and a key plan of the building at 1:1000 drawn on the wall layer."""
    x, y = at
    blk = doc.blocks.new("PLANKOPF")
    blk.add_lwpolyline([(0, 0), (2000, 0), (2000, 1400), (0, 1400)], close=True)
    blk.add_lwpolyline([(30, 30), (1970, 30), (1970, 1370), (30, 1370)], close=True)
    for k in range(1, 9):
        blk.add_line((30, 30 + 70 * k), (1970, 30 + 70 * k))
    for k, text in enumerate(("Bauherrschaft: Kanton", "Objekt: Verwaltungsgebäude", "Plan: Grundriss EG",
                              "Massstab 1:100", "Datum 12.03.2021", "Gezeichnet: FM")):
        blk.add_text(text, height=40, dxfattribs={"insert": (60, 50 + 70 * k)})
    msp.add_blockref("PLANKOPF", (x, y), dxfattribs={"layer": "Z01_PLANKOPF"})
    kx, ky = x + 300, y + 750  # the key plan: the building at 1:1000 (3.1 x 2.0 m), walls on the wall layer
    _wall(msp, (kx, ky), (kx + 310, ky), 4, "E41_AUSSENWAENDE")
    _wall(msp, (kx, ky + 200), (kx + 310, ky + 200), 4, "E41_AUSSENWAENDE")
    _wall(msp, (kx, ky), (kx, ky + 200), 4, "E41_AUSSENWAENDE")
    _wall(msp, (kx + 310, ky), (kx + 310, ky + 200), 4, "E41_AUSSENWAENDE")


LATIN_LAYERS = {"fr": {"wall": "MURS", "part": "CLOISONS", "door": "PORTES", "window": "FENETRES", "room": "LOCAUX",
                       "text": "TEXTE_LOCAUX", "dim": "COTATION", "title": "CARTOUCHE"},
                "es": {"wall": "MUROS", "part": "TABIQUES", "door": "PUERTAS", "window": "VENTANAS",
                       "room": "RECINTOS", "text": "TEXTOS", "dim": "COTAS", "title": "CAJETIN"}}
LATIN_ROOMS = {"fr": ("Séjour", "Cuisine", "Chambre"), "es": ("Salón", "Cocina", "Dormitorio")}
LATIN_OUTLINE_M2 = 12.0 * 8.0  # the 12 x 8 m flat to the outer faces of its 0.2 m exterior walls


def draw_latin_plan(path: str | Path, lang: str = "fr", version: str = "R2000") -> Path:
    """A 12 x 8 m flat in mm with French or Spanish layers: walls as closed polylines (one
    per wall piece), a door block, a window, three rooms named by TEXT (fr; R12) or MTEXT
    (es). ``version`` 'R12' writes no units (R12 has no $INSUNITS) and 2D POLYLINEs."""
    import ezdxf

    names, rooms = LATIN_LAYERS[lang], LATIN_ROOMS[lang]
    doc = ezdxf.new(version)
    if version != "R12":
        doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()

    def box(x0, y0, x1, y1, layer):
        pts = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
        if version == "R12":
            msp.add_polyline2d(pts, close=True, dxfattribs={"layer": layer})
        else:
            msp.add_lwpolyline(pts, close=True, dxfattribs={"layer": layer})

    W, H, t = 12000, 8000, 200
    box(0, 0, W, t, names["wall"])
    box(0, H - t, 4000, H, names["wall"])  # a window 1.5 m wide between 4.0 and 5.5 m on the north side
    box(5500, H - t, W, H, names["wall"])
    box(0, 0, t, H, names["wall"])
    box(W - t, 0, W, H, names["wall"])
    msp.add_line((4000, H - t / 2), (5500, H - t / 2), dxfattribs={"layer": names["window"]})
    box(6000, t, 6100, 3000, names["part"])  # partition with a 0.9 m door (3.0 .. 3.9 m)
    box(6000, 3900, 6100, H - t, names["part"])
    box(6100, 4500, 7000, 4600, names["part"])  # second partition with a door at 7.0 .. 7.9 m
    box(7900, 4500, W - t, 4600, names["part"])
    door = doc.blocks.new("PORTE_90" if lang == "fr" else "PUERTA_90")
    door.add_line((0, 0), (0, 900))
    door.add_arc((0, 0), 900, 0, 90)
    msp.add_blockref(door.name, (6100, 3000), dxfattribs={"layer": names["door"]})
    for (x0, y0, x1, y1), label in zip(((t, t, 6000, H - t), (6100, t, W - t, 4500), (6100, 4600, W - t, H - t)),
                                       rooms):
        box(x0, y0, x1, y1, names["room"])
        at = ((x0 + x1) / 2, (y0 + y1) / 2)
        if lang == "fr" or version == "R12":
            msp.add_text(label, height=250, dxfattribs={"layer": names["text"], "insert": at})
        else:
            msp.add_mtext(f"{label}\\P{(x1 - x0) * (y1 - y0) / 1e6:.1f} m²", dxfattribs={
                "layer": names["text"], "insert": at, "char_height": 250})
    msp.add_linear_dim(base=(0, -1000), p1=(0, 0), p2=(W, 0), dxfattribs={"layer": names["dim"]}).render()
    box(W + 2000, -3000, W + 12000, 1000, names["title"])
    msp.add_text("PLAN RDC 1:50", height=300, dxfattribs={"layer": names["title"], "insert": (W + 2500, -2000)})
    doc.saveas(path)
    return Path(path)


UNNAMED_OUTLINE_M2 = 20.0 * 10.0  # the 20 x 10 m hall, outer faces of its walls, m²


def draw_unnamed_plan(path: str | Path) -> Path:
    """A 20 x 10 m hall in metres with no telling layer names: walls as LINE pairs
    0.25 m apart on L4 (a 1 m door gap, an interior wall), desks and 0.4 m deep shelves on
    L7, a stair's treads 0.28 m apart on L5, an exploded 45° hatch on L6, door swings on
    L2, text on L9."""
    import ezdxf
    from shapely.geometry import LineString, box

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    t = 0.25
    _wall(msp, (0, t / 2), (20, t / 2), t, "L4", [(9, 10)])
    _wall(msp, (0, 10 - t / 2), (20, 10 - t / 2), t, "L4")
    _wall(msp, (t / 2, 0), (t / 2, 10), t, "L4")
    _wall(msp, (20 - t / 2, 0), (20 - t / 2, 10), t, "L4")
    _wall(msp, (12, t), (12, 10 - t), t, "L4", [(4, 5)])
    msp.add_arc((9, t), 1.0, 0, 90, dxfattribs={"layer": "L2"})
    msp.add_line((9, t), (9, 1.25), dxfattribs={"layer": "L2"})
    for x in (2.0, 4.5, 7.0):  # desks 1.6 x 0.8
        msp.add_lwpolyline([(x, 3), (x + 1.6, 3), (x + 1.6, 3.8), (x, 3.8)], close=True, dxfattribs={"layer": "L7"})
    msp.add_lwpolyline([(1, 9.35), (6, 9.35), (6, 9.75), (1, 9.75)], close=True, dxfattribs={"layer": "L7"})
    for k in range(14):  # stair treads
        msp.add_line((14, 2 + 0.28 * k), (16, 2 + 0.28 * k), dxfattribs={"layer": "L5"})
    area = box(13, 6, 19, 9)
    for k in range(-30, 60):  # an exploded hatch: 45° lines 0.1 m apart filling 13..19 x 6..9
        c = 0.1 * 1.4142 * k
        piece = area.intersection(LineString([(13 + c - 10, 6 - 10), (13 + c + 10, 6 + 10)]))
        if piece.length > 0:
            msp.add_line(*piece.coords, dxfattribs={"layer": "L6"})
    msp.add_text("HALLE", height=0.5, dxfattribs={"layer": "L9", "insert": (5, 6)})
    doc.saveas(path)
    return Path(path)


SINGLE_OUTER = (1200, 600)  # cm, the outer wall lines of the single-line flat
SINGLE_ROOMS = {"Wohnen": (0, 0, 700, 600), "Flur": (700, 0, 790, 600), "Bad": (790, 0, 1200, 250),
                "Schlafen": (790, 250, 1200, 600)}  # cm, between the wall lines; Flur 0.9 m wide


def draw_single_line_plan(path: str | Path, named_partition: bool = False) -> Path:
    """A 12 x 6 m flat in cm, $INSUNITS 5, everything on layer 0: walls as single LINEs
    (the outline, the walls at x 700 and 790, a wall between Bad and Schlafen), a door
    swing (ARC + leaf LINE) into each room from the 0.9 m hall, the front door's leaf
    drawn open outward (60 degrees into its swing, below the outline), room names as TEXT. With
    ``named_partition`` the wall at x 700 is a new partition instead, a LINE pair 10 cm
    apart on the layer 'Wand neu' (a renovation plan: only the new wall named)."""
    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 5
    msp = doc.modelspace()
    w, h = SINGLE_OUTER
    for a, b in [((0, 0), (w, 0)), ((w, 0), (w, h)), ((w, h), (0, h)), ((0, h), (0, 0)), ((790, 0), (790, h)),
                 ((790, 250), (w, 250))] + ([] if named_partition else [((700, 0), (700, h))]):
        msp.add_line(a, b)
    if named_partition:
        _wall(msp, (700, 0), (700, h), 10, "Wand neu")
    for hinge, start, leaf in [((700, 400), 90, (700, 490)), ((790, 100), 0, (880, 100)),
                               ((790, 400), 0, (880, 400))]:
        msp.add_arc(hinge, 90, start, start + 90)
        msp.add_line(hinge, leaf)
    msp.add_arc((300, 0), 90, 270, 360)  # the front door, open outward
    msp.add_line((300, 0), (300 + 90 * math.cos(math.radians(300)), 90 * math.sin(math.radians(300))))
    for name, (x0, y0, x1, y1) in SINGLE_ROOMS.items():
        msp.add_text(name, height=20, dxfattribs={"insert": ((x0 + x1) / 2 - 20, (y0 + y1) / 2)})
    doc.saveas(path)
    return Path(path)


WC_ROOMS = {"Halle": 4.6 * 3.6 - 1.3 * 1.45, "WC": 1.1 * 1.25}  # m², clear areas (walls 0.2 m thick)
WC_LABELS = {"Halle": (3.0, 1.5), "WC": (0.5, 3.2)}  # m


def draw_wc_plan(path: str | Path) -> Path:
    """A 5 x 4 m plan in m: walls 0.2 m thick as LINE pairs on A-WALL, a 1.2 x 1.4 m WC
    in a corner whose 0.8 m door (leaf LINE + ARC on A-DOOR, hinged on the WC's wall at
    x 1.4) swings into the WC, room names as TEXT."""
    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    t = 0.2
    for a, b, gaps in [((0, 0.1), (5, 0.1), ()), ((0, 3.9), (5, 3.9), ()), ((0.1, 0), (0.1, 4), ()),
                       ((4.9, 0), (4.9, 4), ()), ((0, 2.45), (1.5, 2.45), ()), ((1.4, 2.35), (1.4, 4), [(2.7, 3.5)])]:
        _wall(msp, a, b, t, "A-WALL", gaps)
    msp.add_line((1.3, 2.7), (0.5, 2.7), dxfattribs={"layer": "A-DOOR"})  # the leaf, open into the WC
    msp.add_arc((1.3, 2.7), 0.8, 90, 180, dxfattribs={"layer": "A-DOOR"})
    for name, at in WC_LABELS.items():
        msp.add_text(name, height=0.15, dxfattribs={"insert": at})
    doc.saveas(path)
    return Path(path)


DOOR_LAYER_ROOM = (6.0, 4.0)  # m, the outer faces of the room drawn on the door layer
DOOR_LAYER_TABLE = [(1.0, 1.0), (3.8, 1.0), (3.8, 2.6), (1.0, 2.6)]  # m, a table drawn as a closed polyline


def draw_walls_on_door_layer(path: str | Path) -> Path:
    """A 6 x 4 m room in m whose 0.1 m walls are LINE pairs on A-DOOR-INTERNAL (a 0.9 m
    door gap in the bottom wall, its leaf and swing on the same layer), a 1 m stub on
    A-WALL (the only linework named like walls) and a 2.8 x 1.6 m table drawn as a closed
    LWPOLYLINE on 'Furniture 4' (no block), beside a 0.005 m² speck on that layer."""
    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    w, h = DOOR_LAYER_ROOM
    for a, b, gaps in [((0, 0.05), (w, 0.05), [(4.5, 5.4)]), ((0, h - 0.05), (w, h - 0.05), ()),
                       ((0.05, 0), (0.05, h), ()), ((w - 0.05, 0), (w - 0.05, h), ())]:
        _wall(msp, a, b, 0.1, "A-DOOR-INTERNAL", gaps)
    msp.add_line((4.5, 0.1), (4.5, 1.0), dxfattribs={"layer": "A-DOOR-INTERNAL"})
    msp.add_arc((4.5, 0.1), 0.9, 0, 90, dxfattribs={"layer": "A-DOOR-INTERNAL"})
    msp.add_line((2.0, 2.0), (3.0, 2.0), dxfattribs={"layer": "A-WALL"})
    msp.add_lwpolyline(DOOR_LAYER_TABLE, close=True, dxfattribs={"layer": "Furniture 4"})  # no block
    msp.add_lwpolyline([(1, 3), (1.1, 3), (1.1, 3.1)], close=True, dxfattribs={"layer": "Furniture 4"})  # a speck
    doc.saveas(path)
    return Path(path)


def draw_no_walls(path: str | Path) -> Path:
    """Text, circles and a few loose lines in mm: nothing a wall."""
    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    for k in range(5):
        msp.add_circle((1000 * k, 0), 300, dxfattribs={"layer": "SYMBOLS"})
    msp.add_line((0, 2000), (5000, 2000), dxfattribs={"layer": "SKETCH"})
    msp.add_line((0, 3000), (5000, 3500), dxfattribs={"layer": "SKETCH"})
    msp.add_text("Notes", height=200, dxfattribs={"layer": "NOTES", "insert": (0, 5000)})
    doc.saveas(path)
    return Path(path)
