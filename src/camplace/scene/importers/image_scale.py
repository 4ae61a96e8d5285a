"""Plan images: the scale read from the sheet when neither ``scale`` nor ``ref`` is given:
from its dimension lines (OCR of each number standing on a horizontal dimension line, and
the line's length in pixels), else from a scale bar (a row of numbers such as 0 1 2 5 m
along a bar, spaced in proportion to their values). Always reported, so the user can
check it."""

from __future__ import annotations

import re

import numpy as np
from scipy import ndimage

from camplace.scene.importers.image_ocr import MIN_CONF, dimension_row, read_lines, text_lines_mask

AGREE = 0.03  # dimension lines within 3 % of the median scale agree
BAR_FIT = 0.02  # a scale bar's numbers lie within this share of its length of a straight line (value -> column)
FEET_RE = re.compile(r"(\d{1,3})\s*['’′`]\s*-?\s*(?:(\d{1,2})(?:\s+(\d)/(\d{1,2}))?\s*(?:\"|”|″|''|'’)?)?")
BAR_UNITS = {"": 1.0, "m": 1.0, "cm": 0.01, "mm": 0.001, "ft": 0.3048, "'": 0.3048}
BAR_RE = re.compile(r"^(\d{1,3}(?:[.,]\d{1,2})?)\s*(m|cm|mm|ft|')?$", re.IGNORECASE)


def dimension_value_m(text: str) -> float | None:
    """The length (m) a dimension text states: whole millimetres ('10700', 3 to 6
    digits), metres with decimals ('3.90', '10,70'), or feet and inches as US plans write
    them ('12\'-6"', '12\' 6 1/2"', '8\'', with any of the quote marks OCR gives);
    None for anything else."""
    feet = FEET_RE.fullmatch(text.strip(" .,:;|_"))
    if feet:
        inches = float(feet.group(2) or 0) + (float(feet.group(3)) / float(feet.group(4)) if feet.group(3) else 0.0)
        return None if inches >= 12 else float(feet.group(1)) * 0.3048 + inches * 0.0254
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


def scale_from_sheet(engine, dark: np.ndarray, ink: np.ndarray) -> tuple[float, str] | None:
    """(m per pixel, how) from the dimension lines, else from a scale bar (the sheet's text
    lines found once for both); None when neither gives it."""
    text = text_lines_mask(ink)
    if text[1] == 0:
        return None
    return scale_from_dimensions(engine, dark, ink, text) or scale_from_bar(engine, dark, ink, text)


def scale_from_dimensions(engine, dark: np.ndarray, ink: np.ndarray, text=None) -> tuple[float, str] | None:
    """(m per pixel, how) from the numbers on horizontal dimension lines: each number's
    length over the length between the marks around it; the scale most numbers agree on
    (within AGREE: each number votes for its candidate spans), when at least two do;
    None otherwise. ``text``: text_lines_mask(ink) when already found."""
    lines, n, hc = text if text is not None else text_lines_mask(ink)
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


def scale_from_bar(engine, dark: np.ndarray, ink: np.ndarray, text=None) -> tuple[float, str] | None:
    """(m per pixel, how) from a scale bar: at least three short numbers (an optional unit
    m, cm, mm, ft on one of them; metres otherwise) side by side on one text row, with
    different values, whose columns are a straight, increasing function of their values
    (within BAR_FIT of the bar's length), along a bar: a row of ink just above or below
    them covering most of the way from the first to the last. None when there is none.
    ``text``: text_lines_mask(ink) when already found."""
    lines, n, hc = text if text is not None else text_lines_mask(ink)
    if n == 0:
        return None
    boxes = ndimage.find_objects(lines)
    short = [k for k, b in enumerate(boxes, 1) if b is not None and b[1].stop - b[1].start <= 4 * hc]
    marks = []  # (row centre, column centre, value, unit, text, box)
    for ln in read_lines(engine, dark, ink, lines, short, hc):
        m = BAR_RE.match(ln.text.strip(" .|_-\"“”"))
        if m and ln.conf >= MIN_CONF:
            r, c = ln.centre
            value = float(m.group(1).replace(",", "."))
            marks.append((r, c, value, (m.group(2) or "").lower(), ln.text.strip(), ln.box))
    best = None
    for row in _rows(marks, 0.6 * hc):
        got = _bar(row, ink, hc)
        if got is not None and (best is None or got[1] > best[1]):
            best = got
    if best is None:
        return None
    s, span, row = best
    return s, (f"read from the scale bar '{row[0][4]} ... {row[-1][4]}' ({len(row)} numbers over {span:.0f} px); "
               "check it")


def _rows(marks: list, tol: float) -> list[list]:
    """The marks grouped into rows (centres within ``tol`` pixels), each sorted left to right."""
    rows: list[list] = []
    for mk in sorted(marks):
        if rows and abs(mk[0] - rows[-1][-1][0]) <= tol:
            rows[-1].append(mk)
        else:
            rows.append([mk])
    return [sorted(r, key=lambda mk: mk[1]) for r in rows if len(r) >= 3]


def _bar(row: list, ink: np.ndarray, hc: float) -> tuple[float, float, list] | None:
    """(m per pixel, span px, the row) when ``row`` reads as a scale bar, else None."""
    values = np.array([mk[2] for mk in row])
    cols = np.array([mk[1] for mk in row])
    if len(set(values)) < 3 or not np.all(np.diff(values) > 0):
        return None
    slope, at = np.polyfit(values, cols, 1)
    span = cols[-1] - cols[0]
    if slope <= 0 or span < 5 * hc or np.abs(cols - (at + slope * values)).max() > BAR_FIT * span:
        return None
    units = {mk[3] for mk in row if mk[3]}
    if len(units) > 1:
        return None
    c0, c1 = int(round(cols[0])), int(round(cols[-1])) + 1
    top, bottom = min(mk[5][0] for mk in row), max(mk[5][2] for mk in row)
    reach = int(2 * hc)
    near = np.r_[max(0, top - reach):top, bottom:min(ink.shape[0], bottom + reach)]
    if not len(near) or ink[near, c0:c1].mean(axis=1).max() < 0.8:
        return None
    return float(BAR_UNITS[units.pop() if units else ""] / slope), float(span), row
