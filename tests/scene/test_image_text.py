"""Small text prepared for OCR (importers.image_text, no OCR engine needed): a room number
'1.5' 8 px high in a ring on a coloured fill, drawn anti-aliased, becomes a tile with its
three marks and no ring, scaled up 3-4x; the decimal point Tesseract drops is put back
only where the line shows one between two glyphs; what a printed area looks like."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from camplace.scene.importers.image_ocr import printed_area, text_lines_mask
from camplace.scene.importers.image_text import line_tile, restore_point
from camplace.scene.importers.image_walls import EIGHT
from tests.scene.image_drawings import font


def _glyphs(marks: list[tuple[int, int, int, int]], shape=(16, 24)) -> np.ndarray:
    """A stretched grey line (1 paper, 0 ink) with the boxes (r0, r1, c0, c1) inked."""
    grey = np.ones(shape, np.float32)
    for r0, r1, c0, c1 in marks:
        grey[r0:r1, c0:c1] = 0.0
    return grey


TWO, FIVE = (3, 11, 2, 7), (3, 11, 11, 16)


@pytest.mark.parametrize("text, marks, expected", [
    ("25", [TWO, FIVE, (9, 11, 8, 10)], "2.5"),  # a point on the baseline
    ("25", [TWO, FIVE, (9, 13, 8, 10)], "2,5"),  # a comma reaches below it
    ("25", [TWO, FIVE], "25"),  # no mark: nothing added
    ("25", [TWO, FIVE, (5, 7, 8, 10)], "25"),  # a mark up in the line is no point
    ("25", [TWO, FIVE, (9, 11, 18, 20)], "25"),  # after the last glyph
    ("255", [TWO, FIVE, (9, 11, 8, 10)], "255"),  # three digits read, two glyphs seen
    ("2.5", [TWO, FIVE, (9, 11, 8, 10)], "2.5"),  # not digits only: as read
])
def test_restore_point(text, marks, expected):
    assert restore_point(text, _glyphs(marks)) == expected


def test_a_ringed_room_number_becomes_a_clean_tile():
    from PIL import Image, ImageDraw

    im = Image.new("RGB", (60, 40), (200, 160, 140))  # a brown room fill
    d = ImageDraw.Draw(im)
    d.ellipse([18, 8, 40, 30], outline=(40, 40, 40), width=1)
    d.text((29, 19), "1.5", font=font(11), fill=(30, 30, 30), anchor="mm")
    dark = np.asarray(im).max(axis=2)
    ink = dark < 100
    lines, n, hc = text_lines_mask(ink)
    assert n >= 1
    k = max(range(1, n + 1), key=lambda j: np.count_nonzero(lines == j))
    box = ndimage.find_objects(lines)[k - 1]
    tile = line_tile(dark, ink, lines, k, box, hc)
    assert 3 * (box[0].stop - box[0].start) <= tile.image.shape[0] - 32  # scaled up at least 3x, padded
    marks, m = ndimage.label(tile.image == 0, EIGHT)
    heights = [b[0].stop - b[0].start for b in ndimage.find_objects(marks)]
    assert m == 3 and max(heights) < 0.5 * tile.image.shape[0], heights  # '1', '.', '5'; no ring
    assert restore_point("15", tile.grey) == "1.5"


@pytest.mark.parametrize("text, area", [
    ("14,43 m²", 14.43), ("14.4 m2", 14.4), ("25,50", 25.5), ("14 43 m²", 14.43),  # the comma not read
    ("12 25 4?", 12.25),  # a small 'm²' misread, two decimals
    ("1.4", None), ("1,4", None), ("3900", None), ("378 4?", None), ("1.4 Bad", None),  # numbers, names
])
def test_printed_area(text, area):
    assert printed_area(text) == area
