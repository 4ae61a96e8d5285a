"""Generated plans for issues 34 (image part) and 33 (PDF plan sets), each with an answer
known by hand: walls drawn as stippled poché, grid and dimension lines running past the
building, a kitchen counter, and plan sets of several PDF pages. Lengths in m, y up;
the sheets have PX m per pixel and 1.5 m of paper around the drawing."""

from __future__ import annotations

from pathlib import Path

import numpy as np

PX = 0.02  # m per pixel (1:100 at 127 dpi)
DPI = 127
MARGIN = 3.0  # paper around the drawing, m


def _canvas(size: tuple[float, float]):
    """(image, draw, to-pixel function) of a white sheet for a drawing ``size`` m."""
    from PIL import Image, ImageDraw

    w, h = round((size[0] + 2 * MARGIN) / PX), round((size[1] + 2 * MARGIN) / PX)
    im = Image.new("RGB", (w, h), "white")

    def p(x: float, y: float) -> tuple[int, int]:
        return round((x + MARGIN) / PX), h - round((y + MARGIN) / PX)

    return im, ImageDraw.Draw(im), p


def _rect(d, p, x0, y0, x1, y1, **kw) -> None:
    (c0, r1), (c1, r0) = p(x0, y0), p(x1, y1)
    d.rectangle([c0, r0, c1 - 1, r1 - 1], **kw)


def box_walls(w: float, h: float, t: float, door: tuple[float, float] | None = None) -> list:
    """The four walls (x0, y0, x1, y1) of a box w x h m outside with walls ``t`` thick; a
    door (x from, x to) in the south wall."""
    south = [(0, 0, w, t)] if door is None else [(0, 0, door[0], t), (door[1], 0, w, t)]
    return south + [(0, h - t, w, h), (0, t, t, h - t), (w - t, t, w, h - t)]


def draw_stippled(path: str | Path, t: float = 0.7, w: float = 9.0, h: float = 7.0, seed: int = 0,
                  dots: bool = True, solid: bool = False) -> Path:
    """A room w x h m outside whose walls, ``t`` thick, are drawn as masonry poché: a
    thin outline (1 px) round each wall filled with a random stipple of 1-2 px dots (no
    hatch lines; ``dots`` False: empty outlines; ``solid``: filled black), closed at a 0.9 m
    door in the south wall. The room's clear area is (w - 2t) x (h - 2t)."""
    rng = np.random.default_rng(seed)
    im, d, p = _canvas((w, h))
    for x0, y0, x1, y1 in box_walls(w, h, t, door=(w / 2 - 0.45, w / 2 + 0.45)):
        _rect(d, p, x0, y0, x1, y1, outline="black", width=1, **({"fill": "black"} if solid else {}))
        n = int((x1 - x0) * (y1 - y0) / 0.004) if dots else 0  # one dot per 40 cm²
        for x, y in zip(rng.uniform(x0 + 0.04, x1 - 0.04, n), rng.uniform(y0 + 0.04, y1 - 0.04, n)):
            c, r = p(x, y)
            d.rectangle([c, r, c + int(rng.integers(0, 2)), r], fill="black")
    im.save(path, dpi=(DPI, DPI))
    return Path(path)


def draw_grid_lines(path: str | Path, w: float = 10.0, h: float = 8.0, t: float = 0.3) -> Path:
    """A room w x h m outside (solid walls ``t``, a 0.9 m door south) crossed by column
    grid lines 0.12 m wide (6 px: as a photo thickens them), two each way, running 2.5 m
    past the building to a grid bubble, and a dimension line 1 m south of the building
    with extension lines from the wall: none of them is a wall, the room is one."""
    im, d, p = _canvas((w, h))
    for x0, y0, x1, y1 in box_walls(w, h, t, door=(2.0, 2.9)):
        _rect(d, p, x0, y0, x1, y1, fill="black")
    g = 0.12
    for x in (w / 3, 2 * w / 3):
        _rect(d, p, x - g / 2, -2.5, x + g / 2, h + 2.5, fill="black")
        d.ellipse([*(np.array(p(x - 0.35, h + 3.2))), *(np.array(p(x + 0.35, h + 2.5)))], outline="black", width=4)
    for y in (h / 3, 2 * h / 3):
        _rect(d, p, -2.5, y - g / 2, w + 2.5, y + g / 2, fill="black")
        d.ellipse([*(np.array(p(-3.2 + 0.0, y + 0.35))), *(np.array(p(-2.5, y - 0.35)))], outline="black", width=4)
    _rect(d, p, 0, -1.06, w, -0.94, fill="black")  # the dimension line ...
    for x in (0.0, w):
        _rect(d, p, x - 0.06, -1.3, x + 0.06, -0.05, fill="black")  # ... and its extension lines
    im.save(path, dpi=(DPI, DPI))
    return Path(path)


def draw_counter(path: str | Path, w: float = 8.0, h: float = 6.0, t: float = 0.3) -> Path:
    """A kitchen w x h m outside (solid walls ``t``, a door south) with a counter 0.6 m
    deep along the north wall from x = 1 to 5 m, and an island 2.0 x 0.9 m in the room,
    each drawn as a 0.12 m outline (as a photo thickens furniture lines): one room of
    (w - 2t) x (h - 2t), the counter and island obstacles, not walls."""
    im, d, p = _canvas((w, h))
    for x0, y0, x1, y1 in box_walls(w, h, t, door=(2.0, 2.9)):
        _rect(d, p, x0, y0, x1, y1, fill="black")
    for x0, y0, x1, y1 in ((1.0, h - t - 0.6, 5.0, h - t), (3.0, 2.0, 5.0, 2.9)):
        _rect(d, p, x0, y0, x1, y1, outline="black", width=6)
    im.save(path, dpi=(DPI, DPI))
    return Path(path)


def plan_pages(rooms: list[list[tuple[float, float, float, float]]]) -> list:
    """Pillow images, one page per list of room rectangles (x0, y0, x1, y1 of each room's
    clear area, m), each room walled by 0.3 m solid walls (shared walls drawn twice)."""
    pages = []
    for page in rooms:
        size = (max(r[2] for r in page) + 0.3, max(r[3] for r in page) + 0.3)
        im, d, p = _canvas(size)
        for x0, y0, x1, y1 in page:
            for wx0, wy0, wx1, wy1 in box_walls(x1 - x0 + 0.6, y1 - y0 + 0.6, 0.3):
                _rect(d, p, x0 - 0.3 + wx0, y0 - 0.3 + wy0, x0 - 0.3 + wx1, y0 - 0.3 + wy1, fill="black")
        pages.append(im)
    return pages


def draw_pdf_pages(path: str | Path, rooms: list[list[tuple[float, float, float, float]]]) -> Path:
    """A PDF plan set, one page per list of rooms (plan_pages), at 1:100 (DPI), written by
    Pillow (pages of pixels, no text)."""
    first, *rest = plan_pages(rooms)
    first.save(path, save_all=True, append_images=rest, resolution=DPI)
    return Path(path)


def draw_pdf_levels(path: str | Path, rooms: list[list[tuple[float, float, float, float]]], titles: list[str],
                    extra: list[str] | None = None) -> Path:
    """A vector PDF plan set written by matplotlib at 1:100: one page per list of rooms, the
    walls as 0.3 m filled rectangles, each page's title in 20 pt text and ``extra`` text in
    8 pt (a note that names another level)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    inch_per_m = 1 / 2.54  # 1 m = 1 cm of paper at 1:100
    with PdfPages(path) as pdf:
        for k, page in enumerate(rooms):
            size = (max(r[2] for r in page) + 0.3 + 2 * MARGIN, max(r[3] for r in page) + 0.3 + 2 * MARGIN)
            fig = Figure(figsize=(size[0] * inch_per_m, size[1] * inch_per_m))
            ax = fig.add_axes((0, 0, 1, 1))
            ax.set_xlim(-MARGIN, size[0] - MARGIN)
            ax.set_ylim(-MARGIN, size[1] - MARGIN)
            ax.axis("off")
            for x0, y0, x1, y1 in page:
                for wx0, wy0, wx1, wy1 in box_walls(x1 - x0 + 0.6, y1 - y0 + 0.6, 0.3):
                    ax.add_patch(Rectangle((x0 - 0.3 + wx0, y0 - 0.3 + wy0), wx1 - wx0, wy1 - wy0, color="black",
                                           lw=0))
            ax.text(0, -1.5, titles[k], fontsize=20)
            if extra:
                ax.text(0, -2.5, extra[k], fontsize=8)
            pdf.savefig(fig)
    return Path(path)


def draw_photo_ldk(path: str | Path, dashed: bool = True, seed: int = 0) -> Path:
    """A photo (JPEG: blurred, uneven light, yellowish paper, noise) of a 14.6 x 7.1 m flat
    (outside; solid 0.3 m outer walls, a 0.2 m wall with a door): a living-dining-kitchen
    of 10.0 x 6.5 = 65.0 m² clear and a bedroom of 3.8 x 6.5 = 24.7 m², crossed by column
    grid lines 0.1 m thick (dash-dot when ``dashed``) running 2.5 m past the building each
    way, and a kitchen counter 4.0 x 0.65 m against the north wall drawn as a 0.1 m outline."""
    from PIL import Image, ImageFilter

    w, h, t, g = 14.6, 7.1, 0.3, 0.1
    im, d, p = _canvas((w, h))
    for r in box_walls(w, h, t, door=(2.0, 2.9)) + [(10.3, t, 10.5, 3.0), (10.3, 3.9, 10.5, h - t)]:
        _rect(d, p, *r, fill="black")

    def line(a: tuple[float, float], b: tuple[float, float]) -> None:  # axis-parallel, dash-dot or solid
        (x0, y0), (x1, y1) = a, b
        length, at = max(x1 - x0, y1 - y0), 0.0
        pattern = ((1.2, True), (0.2, False), (0.15, True), (0.2, False)) if dashed else ((length, True),)
        while at < length:
            for piece, ink in pattern:
                end = min(at + piece, length)
                if ink:
                    _rect(d, p, *((x0 - g / 2, y0 + at, x0 + g / 2, y0 + end) if x0 == x1 else
                                  (x0 + at, y0 - g / 2, x0 + end, y0 + g / 2)), fill="black")
                at = end
                if at >= length:
                    break

    for x in (3.5, 7.0):
        line((x, -2.5), (x, h + 2.5))
    line((-2.5, 3.55), (w + 2.5, 3.55))
    _rect(d, p, 0.8, h - t - 0.65, 4.8, h - t, outline="black", width=5)
    rng = np.random.default_rng(seed)
    a = np.asarray(im.filter(ImageFilter.GaussianBlur(1.2))).astype(float)
    yy, xx = np.mgrid[0:a.shape[0], 0:a.shape[1]]
    light = 0.8 + 0.2 * np.cos((xx / a.shape[1] - 0.3) * 2) * np.cos((yy / a.shape[0] - 0.5) * 2)
    a = a * light[..., None] * np.array([1.0, 0.97, 0.9]) + rng.normal(0, 6, a.shape)
    Image.fromarray(np.clip(a, 0, 255).astype(np.uint8)).save(path, quality=80)
    return Path(path)
