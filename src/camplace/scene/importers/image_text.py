"""Plan images: small text made readable for OCR (pure numpy and Pillow, no engine).

A sheet-wide ink threshold loses the thin anti-aliased strokes and the points of 8 px
text (the '1' and the '.' of a room number '1.5' on a coloured fill). So each line of
text is prepared the classic way: cut out of the grey sheet with a margin; the marks that
are not the line's own (the ring around a room number, a wall, a dimension line, a
neighbouring label) laid to paper; grey levels stretched from the line's darkest ink (0)
to its paper (1); marks not touching the line's own dropped; scaled up with Lanczos so a
character is about OCR_HEIGHT_PX high (at most MAX_UPSCALE times); binarised at
INK_LEVEL (thin strokes are kept); padded with paper.

Tesseract at this size still drops a decimal point now and then ('2.5' read '25');
:func:`restore_point` puts it back where the tile shows a point between the digits.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from camplace.scene.importers.image_walls import EIGHT

OCR_HEIGHT_PX = 32  # height of a line (px) in a tile: capitals Tesseract reads well
MAX_UPSCALE = 4
INK_LEVEL = 0.8  # stretched grey (0 ink .. 1 paper) below which a pixel is ink
POINT_LEVEL = 0.9  # ... and below which a mark near the line is kept (a faint point, a thin stroke's edge)


def upscale_for(height_px: float) -> int:
    """The whole factor (1..MAX_UPSCALE) that brings a line ``height_px`` high near OCR_HEIGHT_PX."""
    return int(np.clip(round(OCR_HEIGHT_PX / max(height_px, 1.0)), 1, MAX_UPSCALE))


@dataclass
class LineTile:
    """A line of text prepared for OCR: ``image`` (h, w) uint8, 0 ink and 255 paper,
    scaled up and padded; ``grey`` the line's window at the sheet's scale, stretched
    from ink (0) to paper (1), with only the line's own marks left."""

    image: np.ndarray
    grey: np.ndarray


def line_tile(dark: np.ndarray, ink: np.ndarray, lines: np.ndarray, k: int, box: tuple[slice, slice],
              hc: float) -> LineTile:
    """The tile of line ``k`` of the labelled ``lines`` (int, the sheet's shape; its marks
    lie in ``box``, rows and cols slices): ``dark`` the grey sheet, ``ink`` its ink
    mask, ``hc`` the sheet's character height (px)."""
    from PIL import Image

    height, width = dark.shape
    my, mx = max(2, round(0.4 * hc)), max(2, round(0.6 * hc))
    win = (slice(max(0, box[0].start - my), min(height, box[0].stop + my)),
           slice(max(0, box[1].start - mx), min(width, box[1].stop + mx)))
    grey = dark[win].astype(np.float32)
    mine, marks = lines[win] == k, ink[win]
    foreign = ndimage.binary_dilation(marks & ~mine, EIGHT) & ~ndimage.binary_dilation(mine, EIGHT)
    paper_px = ~ndimage.binary_dilation(marks, EIGHT)
    paper = float(np.median(grey[paper_px])) if paper_px.any() else 255.0
    darkest = float(grey[mine].min()) if mine.any() else 0.0
    x = np.clip((grey - darkest) / max(paper - darkest, 1.0), 0.0, 1.0)
    x[foreign] = 1.0
    strokes, _ = ndimage.label(x < POINT_LEVEL, EIGHT)
    near = ndimage.binary_dilation(mine, EIGHT, iterations=max(1, round(hc / 4)))
    x[(strokes > 0) & ~np.isin(strokes, np.unique(strokes[near & (strokes > 0)]))] = 1.0
    up = upscale_for(box[0].stop - box[0].start)
    small = Image.fromarray(np.round(x * 255).astype(np.uint8))
    big = np.asarray(small.resize((small.width * up, small.height * up), Image.LANCZOS))
    tile = np.where(big < 255 * INK_LEVEL, 0, 255).astype(np.uint8)
    return LineTile(np.pad(tile, max(8, OCR_HEIGHT_PX // 2), constant_values=255), x)


def restore_point(text: str, grey: np.ndarray) -> str:
    """``text`` (as read from a line, ``grey`` its LineTile.grey) with the decimal point
    or comma put back: when the text is digits only, one digit per glyph (the marks
    darker than INK_LEVEL, grouped by the columns they cover) and the line shows one
    small mark on the baseline between two glyphs: '.' when it stays on the baseline,
    ',' when it reaches below. Anything else is returned as it is."""
    if not text.isdigit():
        return text
    lab, n = ndimage.label(grey < INK_LEVEL, EIGHT)
    groups: list[list[int]] = []  # [c0, c1, r0, r1] of marks sharing columns
    for box in sorted(ndimage.find_objects(lab), key=lambda b: b[1].start):
        c0, c1, r0, r1 = box[1].start, box[1].stop, box[0].start, box[0].stop
        if groups and c0 < groups[-1][1]:
            g = groups[-1]
            g[1], g[2], g[3] = max(g[1], c1), min(g[2], r0), max(g[3], r1)
        else:
            groups.append([c0, c1, r0, r1])
    size = max((g[3] - g[2] for g in groups), default=0)
    glyphs = [g for g in groups if g[3] - g[2] >= 0.6 * size]
    if size < 4 or len(glyphs) != len(text):
        return text
    base = float(np.median([g[3] for g in glyphs]))
    between = []
    for c0, c1, r0, r1 in groups:
        i = sum(g[1] <= c0 for g in glyphs)  # glyphs wholly left of the mark
        if (0 < i < len(glyphs) and c1 <= glyphs[i][0] and r1 - r0 <= 0.5 * size and c1 - c0 <= 0.4 * size
                and abs(r1 - base) <= 0.3 * size):
            between.append((i, "," if r1 - base > 0.15 * size else "."))
    if len(between) != 1:
        return text
    i, point = between[0]
    return text[:i] + point + text[i:]
