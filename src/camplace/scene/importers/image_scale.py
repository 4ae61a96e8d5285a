"""Plan images: the scale read from the sheet's dimension lines when neither ``scale``
nor ``ref`` is given (OCR of each number standing on a horizontal dimension line, and
the line's length in pixels). Always reported, so the user can check it."""

from __future__ import annotations

import re

import numpy as np
from scipy import ndimage

from camplace.scene.importers.image_ocr import MIN_CONF, dimension_row, read_lines, text_lines_mask

AGREE = 0.03  # dimension lines within 3 % of the median scale agree


def dimension_value_m(text: str) -> float | None:
    """The length (m) a dimension text states: whole millimetres ('10700', 3 to 6
    digits) or metres with decimals ('3.90', '10,70'); None for anything else."""
    text = text.strip(" .,:;|_-'\"")
    if re.fullmatch(r"\d{3,6}", text):
        return int(text) / 1000.0
    m = re.fullmatch(r"(\d{1,3})[.,](\d{2,3})", text)
    return float(f"{m.group(1)}.{m.group(2)}") if m else None


def spans_around(ink: np.ndarray, r: int, c0: int, c1: int, most: int = 4) -> list[int]:
    """Candidate lengths (pixels) of the dimension line on row ``r`` whose number spans
    columns c0..c1: between a mark crossing the row (extension line, tick: ink just above
    and below it) left of the number and one right of it, the ``most`` nearest each side,
    along the run of ink through the number's middle."""
    row = ink[r]
    c = (c0 + c1) // 2
    if not row[c]:
        return []
    gaps = np.flatnonzero(~row)
    lo = gaps[gaps < c].max(initial=-1) + 1
    hi = gaps[gaps > c].min(initial=len(row))
    up = ink[max(0, r - 4):r, lo:hi].any(axis=0)
    down = ink[r + 1:r + 5, lo:hi].any(axis=0)
    centres = _run_centres(np.flatnonzero(up & down) + lo)
    left = [x for x in centres if x < c0 - 1][::-1][:most]
    right = [x for x in centres if x > c1 + 1][:most]
    return [int(round(b - a)) for a in left for b in right]


def _run_centres(cols: np.ndarray) -> list[float]:
    """The middles of the runs of consecutive columns in sorted ``cols``."""
    if not len(cols):
        return []
    runs = np.split(cols, np.flatnonzero(np.diff(cols) != 1) + 1)
    return [(run[0] + run[-1]) / 2 for run in runs]


def scale_from_dimensions(engine, dark: np.ndarray, ink: np.ndarray) -> tuple[float, str] | None:
    """(m per pixel, how) from the numbers on horizontal dimension lines: each number's
    length over the length between the marks around it; the scale most numbers agree on
    (within AGREE: each number votes for its candidate spans), when at least two do;
    None otherwise."""
    lines, n, hc = text_lines_mask(ink)
    if n == 0:
        return None
    boxes = ndimage.find_objects(lines)
    rows = {k: dimension_row(ink, b, hc) for k, b in enumerate(boxes, 1)
            if b is not None and b[1].stop - b[1].start > b[0].stop - b[0].start}
    votes = []  # (number, its text, scale, span px)
    for i, ln in enumerate(read_lines(engine, dark, ink, lines, [k for k, r in rows.items() if r is not None], hc)):
        value = dimension_value_m(ln.text)
        if value is None or ln.conf < MIN_CONF:
            continue
        k = int(np.max(lines[ln.box[0]:ln.box[2], ln.box[1]:ln.box[3]]))
        votes += [(i, ln.text, value / px, px) for px in spans_around(ink, rows[k], ln.box[1], ln.box[3])
                  if px > 1.5 * (ln.box[3] - ln.box[1])]
    if not votes:
        return None
    scales = np.array([v[2] for v in votes])
    support = [len({v[0] for v in votes if abs(v[2] - sc) <= AGREE * sc}) for sc in scales]
    best = scales[int(np.argmax(support))]
    agree = {}
    for v in sorted(votes, key=lambda v: abs(v[2] - best)):
        if abs(v[2] - best) <= AGREE * best:
            agree.setdefault(v[0], v)
    if len(agree) < 2:
        return None
    s = float(np.median([v[2] for v in agree.values()]))
    numbers = len({v[0] for v in votes})
    longest = max(agree.values(), key=lambda v: v[3])
    return s, (f"read from {len(agree)} of {numbers} dimension lines, e.g. '{longest[1]}' over {longest[3]} px; "
               "check it")
