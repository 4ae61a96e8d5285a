"""A realistic apartment plan sheet drawn with Pillow, for the plan-image tests (issue 25):
outer walls as outlines filled with a diagonal hatch, inner walls solid, windows as white
gaps with thin glazing lines, doors as gaps with a leaf and a swing arc, five rooms
labelled in a real TTF font (name and area), dimension lines with ticks and numbers in
mm, a scale bar, a north arrow and a title block with a frame around the sheet."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

PX = 0.02  # m per pixel (1:50 at 127 dpi)
OUTER = 0.3  # outer wall thickness, m
INNER = 0.12  # inner wall thickness, m
W, D = 10.0, 7.0  # clear inside of the outer walls, m
# the rooms' clear rectangles (x0, y0, x1, y1, m; y up from the inner face of the south wall)
ROOMS = {
    "Living": (0.0, 3.06, 5.44, 7.0),
    "Bedroom": (5.56, 3.56, 10.0, 7.0),
    "Kitchen": (0.0, 0.0, 2.94, 2.94),
    "Bathroom": (3.06, 0.0, 5.44, 2.94),
    "Office": (5.56, 0.0, 10.0, 3.44),
}


def room_area(name: str) -> float:
    x0, y0, x1, y1 = ROOMS[name]
    return (x1 - x0) * (y1 - y0)


@dataclass
class Sheet:
    """Where the plan lies on the sheet: ``origin`` the pixel (col, row) of the inside
    corner x = 0, y = 0 (south-west), ``size`` the image (width, height) in pixels."""

    path: Path
    origin: tuple[int, int]
    size: tuple[int, int]


def font(size: int, bold: bool = False):
    import matplotlib
    from PIL import ImageFont

    name = "DejaVuSans-Bold.ttf" if bold else "DejaVuSans.ttf"
    return ImageFont.truetype(str(Path(matplotlib.__file__).parent / "mpl-data" / "fonts" / "ttf" / name), size)


def draw_apartment(path: str | Path, *, jpeg_quality: int | None = None, noise: float = 0.0, seed: int = 0,
                   labels: bool = True, hatch: bool = True, furniture: bool = False,
                   label_px: tuple[int, int] = (18, 14), names: dict[str, str] | None = None,
                   dimensions: bool = True, numbers: dict[str, str] | None = None) -> Sheet:
    """The apartment sheet as PNG (or JPEG with ``jpeg_quality``; ``noise``: the grey
    level std of a scan's noise on a slightly grey paper; ``hatch=False``: the outer
    walls as two lines with paper between them, as many CAD exports draw them;
    ``furniture``: a bed, a sofa, a table with chairs, a kitchen counter with a sink, a
    bathtub and a desk drawn in outline; ``label_px``: the font sizes (px) of the room
    names (bold at the default size, regular below it) and areas; ``names``: the printed
    name of a room of ROOMS, where it differs from its key)."""
    import numpy as np
    from PIL import Image, ImageDraw

    margin, title_h = 120, 130
    ox, oy = margin + round(OUTER / PX), margin + round((D + OUTER) / PX)  # pixel of inside (0, 0)
    width = round((W + 2 * OUTER) / PX) + 2 * margin + 220
    height = round((D + 2 * OUTER) / PX) + 2 * margin + title_h
    im = Image.new("RGB", (width, height), "white")
    d = ImageDraw.Draw(im)

    def p(x: float, y: float) -> tuple[int, int]:
        return ox + round(x / PX), oy - round(y / PX)

    def box(x0, y0, x1, y1, **kw):
        (c0, r1), (c1, r0) = p(x0, y0), p(x1, y1)
        d.rectangle([min(c0, c1), min(r0, r1), max(c0, c1) - 1, max(r0, r1) - 1], **kw)

    # outer walls: outline + 45° hatch, then the openings cut white
    t = OUTER
    ring = [(-t, -t, W + t, 0), (-t, D, W + t, D + t), (-t, -t, 0, D + t), (W, -t, W + t, D + t)]
    for r in ring:
        box(*r, fill="white")
    hatch_lines = Image.new("L", im.size, 0)
    hd = ImageDraw.Draw(hatch_lines)
    for k in range(-height, width, 6):
        hd.line([(k, height), (k + height, 0)], fill=255, width=1)
    mask = Image.new("L", im.size, 0)
    md = ImageDraw.Draw(mask)
    for x0, y0, x1, y1 in ring:
        (c0, r1), (c1, r0) = p(x0, y0), p(x1, y1)
        md.rectangle([c0, r0, c1 - 1, r1 - 1], fill=255)
    if hatch:
        im.paste((0, 0, 0), (0, 0), Image.fromarray(np.minimum(np.asarray(hatch_lines), np.asarray(mask))))
    d.rectangle([*p(-t, D + t), *p(W + t, -t)], outline="black", width=2)
    d.rectangle([*p(0, D), *p(W, 0)], outline="black", width=2)
    # inner walls (solid), door gaps cut later
    inner = [(5.44, 0.0, 5.56, 7.0), (0.0, 2.94, 5.44, 3.06), (2.94, 0.0, 3.06, 2.94), (5.56, 3.44, 10.0, 3.56)]
    for r in inner:
        box(*r, fill="black")
    # windows: gaps through the outer wall (north and west with two glazing lines) (side, span)
    windows = [("s", 0.8, 2.2), ("s", 6.5, 8.2), ("n", 1.0, 2.6), ("n", 3.2, 4.6), ("n", 6.6, 8.4), ("w", 4.0, 5.6),
               ("e", 4.6, 6.2), ("e", 1.0, 2.4)]
    for side, a, b in windows:
        c0, c1 = {"s": (-t, 0), "n": (D, D + t), "w": (-t, 0), "e": (W, W + t)}[side]

        def xy(u, v, side=side):  # along the wall u, across it v -> (x, y)
            return (u, v) if side in "sn" else (v, u)

        box(*xy(a, c0 - 0.02), *xy(b, c1 + 0.02), fill="white")
        if side in "se":  # south and east windows: plain white gaps (no glazing drawn)
            continue
        for f in (0.33, 0.67):
            d.line([p(*xy(a, c0 + f * t)), p(*xy(b, c0 + f * t))], fill="black", width=1)
        for u in (a, b):
            d.line([p(*xy(u, c0)), p(*xy(u, c1))], fill="black", width=1)
    # doors: gap, leaf and swing arc (hinge, leaf direction, gap span)
    doors = [("v", 5.44, 5.56, 4.2, 5.1), ("v", 5.44, 5.56, 1.2, 2.1), ("h", 3.06, 2.94, 1.4, 2.3),
             ("h", 3.56, 3.44, 7.0, 7.9), ("v", 2.94, 3.06, 0.15, 0.95)]
    for kind, a, b, lo, hi in doors:
        if kind == "v":
            box(min(a, b), lo, max(a, b), hi, fill="white")
            hinge = p(max(a, b), lo)
            r = round((hi - lo) / PX)
            d.line([hinge, (hinge[0] + r, hinge[1])], fill="black", width=2)
            d.arc([hinge[0] - r, hinge[1] - r, hinge[0] + r, hinge[1] + r], 270, 360, fill="black", width=1)
        else:
            box(lo, min(a, b), hi, max(a, b), fill="white")
            hinge = p(lo, min(a, b))
            r = round((hi - lo) / PX)
            d.line([hinge, (hinge[0], hinge[1] + r)], fill="black", width=2)
            d.arc([hinge[0] - r, hinge[1] - r, hinge[0] + r, hinge[1] + r], 0, 90, fill="black", width=1)
    box(9.0, -t - 0.02, 9.95, 0.02, fill="white")  # entrance door in the south wall
    d.line([p(9.0, 0), p(9.0, -0.9)], fill="black", width=2)
    # dimension lines (mm) outside and one inside the living room, 0.45 m from its north wall
    f_dim = font(12)

    def dim_h(x0, x1, y, text):
        d.line([p(x0, y), p(x1, y)], fill="black", width=1)
        for x in (x0, x1):
            c, r = p(x, y)
            d.line([(c - 4, r + 4), (c + 4, r - 4)], fill="black", width=2)
            d.line([(c, r - 10), (c, r + 6)], fill="black", width=1)
        c, r = p((x0 + x1) / 2, y)
        d.text((c, r - 3), text, font=f_dim, fill="black", anchor="mb")

    def dim_v(x, y0, y1, text):
        d.line([p(x, y0), p(x, y1)], fill="black", width=1)
        for y in (y0, y1):
            c, r = p(x, y)
            d.line([(c - 4, r + 4), (c + 4, r - 4)], fill="black", width=2)
            d.line([(c - 6, r), (c + 10, r)], fill="black", width=1)
        label = Image.new("L", (60, 16), 0)
        ImageDraw.Draw(label).text((30, 8), text, font=f_dim, fill=255, anchor="mm")
        label = label.rotate(90, expand=True)
        c, r = p(x, (y0 + y1) / 2)
        im.paste((0, 0, 0), (c - 18, r - 30), label)

    if dimensions:
        dim_h(-t, W + t, D + t + 0.9, f"{round((W + 2 * t) * 1000)}")
        dim_h(0, 5.44, D + t + 0.45, "5440")
        dim_h(5.56, W, D + t + 0.45, "4440")
        dim_v(-t - 0.9, -t, D + t, f"{round((D + 2 * t) * 1000)}")
        dim_h(0.0, 5.44, D - 0.45, "5440")
    if furniture:
        _furniture(d, p)
    # room labels: name (bold) and area in m² below it
    if labels:
        f_name, f_area = font(label_px[0], bold=label_px[0] >= 18), font(label_px[1])
        for name, (x0, y0, x1, y1) in ROOMS.items():
            c, r = p((x0 + x1) / 2, (y0 + y1) / 2)
            d.text((c, r - 2), (names or {}).get(name, name), font=f_name, fill="black", anchor="mb")
            d.text((c, r + 4), f"{room_area(name):.2f} m²".replace(".", ","), font=f_area, fill="black", anchor="mt")
            if name in (numbers or {}):
                d.text((c, r + 8 + label_px[1]), numbers[name], font=f_area, fill="black", anchor="mt")
    # scale bar: 0-1-2-3-4-5 m, alternating blocks, under the plan
    c0, r0 = p(0, -t - 1.6)
    step = round(1.0 / PX)
    for k in range(5):
        d.rectangle([c0 + k * step, r0, c0 + (k + 1) * step - 1, r0 + 8], fill="black" if k % 2 == 0 else "white",
                    outline="black")
        d.text((c0 + k * step, r0 + 12), str(k), font=f_dim, fill="black", anchor="mt")
    d.text((c0 + 5 * step, r0 + 12), "5 m", font=f_dim, fill="black", anchor="mt")
    # north arrow
    cx, cy = width - 90, 80
    d.polygon([(cx, cy - 40), (cx - 14, cy + 10), (cx, cy), (cx + 14, cy + 10)], outline="black", fill="black")
    d.text((cx, cy + 14), "N", font=font(16, bold=True), fill="black", anchor="mt")
    # title block and sheet frame
    d.rectangle([8, 8, width - 9, height - 9], outline="black", width=2)
    tx0, ty0 = width - 380, height - title_h
    d.rectangle([tx0, ty0, width - 9, height - 9], outline="black", width=2)
    for k in (1, 2, 3):
        y = ty0 + k * (title_h - 9) // 4
        d.line([(tx0, y), (width - 9, y)], fill="black", width=1)
    d.line([(tx0 + 150, ty0), (tx0 + 150, height - 9)], fill="black", width=1)
    f_tb = font(13)
    rows = [("Project", "Apartment 3B"), ("Drawing", "Floor plan"), ("Scale", "1:50"), ("Date", "2026-03-01")]
    for k, (a, b) in enumerate(rows):
        y = ty0 + k * (title_h - 9) // 4 + 8
        d.text((tx0 + 8, y), a, font=f_tb, fill="black")
        d.text((tx0 + 158, y), b, font=f_tb, fill="black")
    a = np.asarray(im).astype(np.float64)
    if noise:
        rng = np.random.default_rng(seed)
        a = a * 0.93 + 6 + rng.normal(0, noise, a.shape[:2])[..., None]  # slightly grey paper, noise
    out = Image.fromarray(np.clip(a, 0, 255).astype(np.uint8))
    path = Path(path)
    if jpeg_quality:
        out.save(path, quality=jpeg_quality)
    else:
        out.save(path)
    return Sheet(path, (ox, oy), (width, height))


def _furniture(d, p) -> None:
    """Furniture in outline (2 px; cushions, pillows, a sink, chairs inside or beside it)."""
    def rect(x0, y0, x1, y1, width=2):
        (c0, r1), (c1, r0) = p(x0, y0), p(x1, y1)
        d.rectangle([c0, r0, c1, r1], outline="black", width=width)

    def circle(x, y, r):
        (c0, r1), (c1, r0) = p(x - r, y - r), p(x + r, y + r)
        d.ellipse([c0, r0, c1, r1], outline="black", width=1)

    rect(8.2, 4.2, 9.8, 6.2)  # bed with two pillows
    for x0 in (8.3, 9.05):
        rect(x0, 5.7, x0 + 0.65, 6.1, 1)
    rect(0.4, 6.0, 2.8, 6.9)  # sofa with armrests
    for x0 in (0.4, 2.6):
        rect(x0, 6.0, x0 + 0.2, 6.9, 1)
    rect(3.6, 3.6, 4.8, 4.4)  # table and four chairs
    for x, y in ((3.35, 4.0), (5.05, 4.0), (4.2, 3.35), (4.2, 4.65)):
        circle(x, y, 0.2)
    rect(0.0, 0.0, 0.6, 2.9)  # kitchen counter and sink
    circle(0.3, 1.4, 0.2)
    rect(4.6, 0.05, 5.4, 1.75)  # bathtub
    rect(4.7, 0.15, 5.3, 1.65, 1)
    rect(8.0, 2.7, 9.9, 3.35)  # desk


def inside(sheet: Sheet, x: float, y: float) -> bool:
    """True when (x, y) m of the importer's frame lies inside the apartment's clear area:
    the importer puts pixel (c, r) at x = (c + 0.5) s, y = (H - r - 0.5) s."""
    c = x / PX - 0.5
    r = sheet.size[1] - y / PX - 0.5
    px, py = (c - sheet.origin[0]) * PX, (sheet.origin[1] - r) * PX
    return -1e-6 <= px <= W and -1e-6 <= py <= D and not math.isnan(px)



def _draw_walls(path: str | Path, px: float, size: tuple[float, float], walls: list, cuts: list) -> Path:
    """A plan of solid black wall rectangles with white ``cuts`` (doors, windows) at ``px``
    m per pixel: rectangles (x0, y0, x1, y1) in m, y up, on a sheet ``size`` m with 1.2 m
    of paper around it."""
    from PIL import Image, ImageDraw

    margin = round(1.2 / px)
    height = round(size[1] / px) + 2 * margin
    im = Image.new("RGB", (round(size[0] / px) + 2 * margin, height), "white")
    d = ImageDraw.Draw(im)
    for rects, fill in ((walls, "black"), (cuts, "white")):
        for x0, y0, x1, y1 in rects:
            d.rectangle([margin + round(x0 / px), height - margin - round(y1 / px),
                         margin + round(x1 / px) - 1, height - margin - round(y0 / px) - 1], fill=fill)
    im.save(path)
    return Path(path)


def draw_u_plan(path: str | Path, px: float = PX, court: float = 2.4, window: float = 1.2) -> Path:
    """A U-shaped one-storey plan (0.3 m walls), 12.6 x 11.6 m: a hall along the south and
    two wings with a room each, a ``court`` wide (clear) between them, open to the north.
    The south wall and the wall between the court and the hall each have a ``window`` wide
    window in the middle, so the two halves of the building meet only across those window
    gaps (columns with no wall from top to bottom): the hall spans them. Rooms: the hall
    and the two wing rooms."""
    t, cx0, cx1 = 0.3, 6.3 - court / 2, 6.3 + court / 2
    walls = [(0, 0, 12.6, t), (0, 0, t, 11.6), (12.6 - t, 0, 12.6, 11.6), (0, 5.0, 12.6, 5.0 + t),
             (0, 11.6 - t, cx0, 11.6), (cx1, 11.6 - t, 12.6, 11.6), (cx0 - t, 5.0, cx0, 11.6), (cx1, 5.0, cx1 + t, 11.6)]
    doors = [(x - 0.45, 5.0, x + 0.45, 5.0 + t) for x in (cx0 / 2, (cx1 + 12.6) / 2)]
    return _draw_walls(path, px, (12.6, 11.6), walls, doors + [(6.3 - window / 2, -0.01, 6.3 + window / 2, 5.0 + t + 0.01)])


def draw_two_blocks(path: str | Path, gap: float, px: float = PX) -> Path:
    """Two storey plans of a 9 x 7 m house (0.3 m walls, two rooms, a door between them,
    windows 0.3 m from the corners of the walls facing each other) side by side on one
    sheet, ``gap`` m of paper between them, their north and south walls in line."""
    t, w, h = 0.3, 9.0, 7.0
    walls, cuts = [], []
    for x in (0.0, w + gap):
        walls += [(x, 0, x + w, t), (x, h - t, x + w, h), (x, 0, x + t, h), (x + w - t, 0, x + w, h),
                  (x + 4.5, 0, x + 4.5 + t, h)]
        cuts += [(x + 4.5, 2.0, x + 4.5 + t, 2.9)]  # the door between the rooms
        cuts += [(x + side, y0, x + side + t, y1) for side in (0.0, w - t) for y0, y1 in ((0.6, 2.2), (4.8, 6.4))]
    return _draw_walls(path, px, (2 * w + gap, h), walls, cuts)



def draw_line_plan(path: str | Path, px: float = PX, pen="black") -> Sheet:
    """The apartment of ROOMS drawn in hairlines, as many CAD exports and sketches are: every
    wall one 1 px line at its centre (the outer walls 0.05 m outside the clear rectangle,
    the inner walls between the rooms), doors as gaps with a leaf line and a swing arc,
    windows as gaps with a glazing line just outside (the west one a plain gap), room
    names, one dimension line, a sheet frame and a title block. Sheet.origin: the pixel of x = 0, y = 0.
    ``pen``: the colour of the walls, doors and windows (a CAD plot's layer colour; the
    text, dimension line and frame stay black)."""
    from PIL import Image, ImageDraw

    margin = 100
    width, height = round((W + 0.1) / px) + 2 * margin + 200, round((D + 0.1) / px) + 2 * margin + 100
    ox, oy = margin, margin + round(D / px)
    im = Image.new("RGB", (width, height), "white")
    d = ImageDraw.Draw(im)

    def p(x: float, y: float) -> tuple[int, int]:
        return ox + round(x / px), oy - round(y / px)

    def run(a, b, openings=()):  # a wall line from a to b (m) with gaps (lo, hi) along it
        (x0, y0), (x1, y1) = a, b
        length = math.hypot(x1 - x0, y1 - y0)
        cuts = [0.0] + [v for lo, hi in sorted(openings) for v in (lo, hi)] + [length]
        for s0, s1 in zip(cuts[::2], cuts[1::2]):
            f0, f1 = s0 / length, s1 / length
            d.line([p(x0 + f0 * (x1 - x0), y0 + f0 * (y1 - y0)), p(x0 + f1 * (x1 - x0), y0 + f1 * (y1 - y0))],
                   fill=pen, width=1)

    e = 0.05
    run((-e, -e), (W + e, -e), [(0.8, 2.2), (6.5, 8.2), (9.0, 9.9)])  # south: two windows, the entrance
    run((-e, D + e), (W + e, D + e), [(1.0, 2.6), (3.2, 4.6), (6.6, 8.4)])
    run((-e, -e), (-e, D + e), [(4.0, 5.6)])  # west: a window drawn as a plain gap
    run((W + e, -e), (W + e, D + e), [(1.0, 2.4), (4.6, 6.2)])
    for (x0, y0), (x1, y1) in (((0.8, -0.09), (2.2, -0.09)), ((6.5, -0.09), (8.2, -0.09)), ((1.0, D + 0.09),
                               (2.6, D + 0.09)), ((3.2, D + 0.09), (4.6, D + 0.09)), ((6.6, D + 0.09), (8.4, D + 0.09)),
                               ((W + 0.09, 1.0), (W + 0.09, 2.4)), ((W + 0.09, 4.6), (W + 0.09, 6.2))):
        d.line([p(x0 - e, y0), p(x1 - e, y1)] if y0 == y1 else [p(x0, y0 - e), p(x1, y1 - e)], fill=pen,
               width=1)  # the other windows' glazing, just outside the wall line
    run((5.5, 0.0), (5.5, D), [(1.2, 2.1), (4.2, 5.1)])
    run((0.0, 3.0), (5.5, 3.0), [(1.4, 2.3)])
    run((3.0, 0.0), (3.0, 3.0), [(0.15, 0.95)])
    run((5.5, 3.5), (W, 3.5), [(1.5, 2.4)])
    for (hx, hy), (lx, ly), start in (((5.5, 1.2), (6.4, 1.2), 270), ((5.5, 4.2), (6.4, 4.2), 270),
                                      ((1.4, 3.0), (1.4, 2.1), 0), ((7.0, 3.5), (7.0, 2.6), 0),
                                      ((3.0, 0.15), (3.8, 0.15), 270)):
        d.line([p(hx, hy), p(lx, ly)], fill=pen, width=1)  # the leaf, open
        r = round(math.hypot(lx - hx, ly - hy) / px)
        c, rr = p(hx, hy)
        d.arc([c - r, rr - r, c + r, rr + r], start, start + 90, fill=pen, width=1)
    f = font(18, bold=True)
    for name, (x0, y0, x1, y1) in ROOMS.items():
        d.text(p((x0 + x1) / 2, (y0 + y1) / 2), name, font=f, fill="black", anchor="mm")
    c0, r0 = p(0, D + 0.6)
    c1, _ = p(W, D + 0.6)
    d.line([(c0, r0), (c1, r0)], fill="black", width=1)
    d.text(((c0 + c1) // 2, r0 - 3), f"{round(W * 1000)}", font=font(12), fill="black", anchor="mb")
    d.rectangle([8, 8, width - 9, height - 9], outline="black", width=2)
    d.rectangle([width - 300, height - 80, width - 9, height - 9], outline="black", width=2)
    d.text((width - 290, height - 70), "Floor plan 1:50", font=font(13), fill="black")
    im.save(path)
    return Sheet(Path(path), (ox, oy), (width, height))


def draw_hollow_walls(path: str | Path, t: float = 0.42, px: float = PX) -> Path:
    """A 9 x 6 m (outside) two-room plan whose walls are drawn as outlines with nothing
    inside (many CAD exports), each wall piece between openings a closed outline: outer
    walls ``t`` thick, the wall between the rooms 0.15 m at x = 4.5 m with a 0.9 m door,
    a 1.2 m window in the middle of the south wall of each room."""
    from PIL import Image, ImageDraw

    margin, w, h = round(1.2 / px), 9.0, 6.0
    size = (round(w / px) + 2 * margin, round(h / px) + 2 * margin)
    im = Image.new("RGB", size, "white")
    d = ImageDraw.Draw(im)

    def outline(x0, y0, x1, y1):
        d.rectangle([margin + round(x0 / px), size[1] - margin - round(y1 / px),
                     margin + round(x1 / px) - 1, size[1] - margin - round(y0 / px) - 1], outline="black", width=2)

    c0, c1 = (4.5 - 0.075 + t) / 2, (4.5 + 0.075 + w - t) / 2  # the rooms' middles along x
    for x0, x1 in ((0, c0 - 0.6), (c0 + 0.6, c1 - 0.6), (c1 + 0.6, w)):
        outline(x0, 0, x1, t)  # the south wall, parted by the windows
    outline(0, h - t, w, h)
    outline(0, t, t, h - t)
    outline(w - t, t, w, h - t)
    outline(4.425, t, 4.575, 2.0)
    outline(4.425, 2.9, 4.575, h - t)
    for x0, x1 in ((c0 - 0.6, c0 + 0.6), (c1 - 0.6, c1 + 0.6)):  # glazing across each window
        d.line([(margin + round(x0 / px), size[1] - margin - round(t / 2 / px)),
                (margin + round(x1 / px), size[1] - margin - round(t / 2 / px))], fill="black", width=1)
    im.save(path)
    return Path(path)
