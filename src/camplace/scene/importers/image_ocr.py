"""Plan images: the text on the sheet read by OCR (Tesseract through pytesseract, an
optional dependency: ``pip install camplace[ocr]`` plus the tesseract program).

Text is found without OCR first: ink marks the size of a character (8-connected pieces
no taller than twice the sheet's typical character and not framing other marks: the
circle around a room number is left out) merged into lines. Each line is cut out and
the lines are stacked into one mosaic image, read by one Tesseract call (block mode),
and every word goes back to its line, so the words keep their place on the sheet.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from camplace.scene.importers.image_walls import EIGHT

OCR_HEIGHT_PX = 32  # character height Tesseract reads best (lines are scaled up to it, at most 4x)
MIN_CONF = 50  # Tesseract word confidence (0..100) below which a word is not used
WORD_CONF = 70  # ... and below which it does not name a room (numbers need MIN_CONF)
AREA_RE = re.compile(r"^(\d{1,4})(?:[.,]\s?|\s)(\d{1,2})(?:\s*([mм]2|[mм][^\s\d]{0,3}|sq\.?\s*m|sqm|qm|[^\s\d]{1,3}))?$",
                     re.IGNORECASE)
UNITS = {"m", "mm", "cm", "m2", "m²", "м", "м2", "м²", "sqm", "qm"}
NUMBER_RE = re.compile(r"^[A-Za-z]{0,2}\d{1,4}([.\-/]\d{1,3}){0,2}[A-Za-z]?$")


@dataclass
class TextLine:
    """One line of text on the sheet: ``text`` as read, ``conf`` (mean word confidence
    0..100), ``box`` (row0, col0, row1, col1) in sheet pixels, ``height`` (pixels),
    ``dimension``: a line of ink longer than the text runs just above or below it."""

    text: str
    conf: float
    box: tuple[int, int, int, int]
    height: int
    dimension: bool = False

    @property
    def centre(self) -> tuple[float, float]:
        return (self.box[0] + self.box[2]) / 2, (self.box[1] + self.box[3]) / 2


def ocr_engine() -> tuple[object | None, str]:
    """(pytesseract module, 'tesseract X.Y') when OCR can run; (None, why not) otherwise."""
    try:
        import pytesseract
    except ImportError:
        return None, "pytesseract is not installed (pip install camplace[ocr])"
    try:
        version = pytesseract.get_tesseract_version()
    except Exception:  # noqa: BLE001 - TesseractNotFoundError and OS errors alike
        return None, "the tesseract program is not installed (e.g. apt install tesseract-ocr)"
    return pytesseract, f"tesseract {version}"


def text_lines_mask(ink: np.ndarray) -> tuple[np.ndarray, int, float]:
    """(labels, n, char_px): the lines of text of the ink mask (H, W) labelled 1..n and
    the sheet's typical character height in pixels (0 when no text is seen)."""
    lab, n = ndimage.label(ink, EIGHT)
    if n == 0:
        return np.zeros(ink.shape, np.int32), 0, 0.0
    boxes = ndimage.find_objects(lab)
    r0, r1 = np.array([b[0].start for b in boxes]), np.array([b[0].stop for b in boxes])
    c0, c1 = np.array([b[1].start for b in boxes]), np.array([b[1].stop for b in boxes])
    h, w = r1 - r0, c1 - c0
    plausible = (h >= 5) & (h <= 60) & (w >= 2) & (w <= 60)
    if np.count_nonzero(plausible) < 3:
        return np.zeros(ink.shape, np.int32), 0, 0.0
    hc = float(np.median(h[plausible]))
    char = (h <= 2 * hc) & (w <= 3 * hc)
    frames = np.flatnonzero(char & (h >= 1.3 * hc))  # circles and boxes around text
    small = np.flatnonzero(char & (h < 1.3 * hc))
    text = np.r_[False, char][lab]
    if len(frames) and len(small):
        cy, cx = (r0[small] + r1[small]) / 2, (c0[small] + c1[small]) / 2
        holds = ((cy[None] > r0[frames, None]) & (cy[None] < r1[frames, None]) & (cx[None] > c0[frames, None])
                 & (cx[None] < c1[frames, None])).any(axis=1)
        for f in frames[holds]:  # the ring goes, the digits touching it inside stay
            b = (slice(r0[f], r1[f]), slice(c0[f], c1[f]))
            rr, cc = np.ogrid[r0[f]:r1[f], c0[f]:c1[f]]
            ring = np.hypot((rr - (r0[f] + r1[f] - 1) / 2) / (r1[f] - r0[f]),
                            (cc - (c0[f] + c1[f] - 1) / 2) / (c1[f] - c0[f])) >= 0.36
            text[b] &= ~((lab[b] == f + 1) & ring)
    joined = ndimage.maximum_filter(text.astype(np.uint8), size=(max(1, int(hc // 4)), max(3, int(hc))))
    lines, m = ndimage.label(joined, EIGHT)
    return np.where(text, lines, 0), m, hc


def read_lines(engine, dark: np.ndarray, ink: np.ndarray, lines: np.ndarray, wanted: list[int],
               hc: float) -> list[TextLine]:
    """The text of the lines ``wanted`` (labels of ``lines``), read by one Tesseract call
    on a mosaic of the lines stacked top to bottom (each scaled to OCR_HEIGHT_PX; grey
    levels of ``dark`` kept around the line's marks, everything else white)."""
    from PIL import Image

    if not wanted:
        return []
    boxes = ndimage.find_objects(lines)
    up = int(min(4, max(1, round(OCR_HEIGHT_PX / max(hc, 1)))))
    pad = int(max(2, hc // 2))
    tiles, rows, y = [], [], 0
    for k in wanted:
        b = boxes[k - 1]
        near = ndimage.binary_dilation(lines[b] == k, EIGHT)
        tile = np.where(near, dark[b], 255).astype(np.uint8)
        tile = np.pad(tile, pad, constant_values=255)
        tiles.append((y, tile))
        rows.append((y, y + tile.shape[0], k, b))
        y += tile.shape[0] + pad
    width = max(t.shape[1] for _, t in tiles)
    mosaic = np.full((y, width), 255, np.uint8)
    for y0, tile in tiles:
        mosaic[y0:y0 + tile.shape[0], :tile.shape[1]] = tile
    img = Image.fromarray(mosaic).resize((width * up, y * up), Image.BICUBIC)
    data = engine.image_to_data(img, config="--" + "psm 6", output_type=engine.Output.DICT)  # tesseract's argument
    words: dict[int, list] = {}
    for text, conf, top, hgt, left in zip(data["text"], data["conf"], data["top"], data["height"], data["left"]):
        text = str(text).strip()
        if not text or float(conf) < 0:
            continue
        mid = (top + hgt / 2) / up
        for y0, y1, k, _ in rows:
            if y0 <= mid < y1:
                words.setdefault(k, []).append((left, text, float(conf)))
                break
    out = []
    for y0, y1, k, b in rows:
        got = sorted(words.get(k, []))
        if got:
            out.append(TextLine(" ".join(t for _, t, _ in got), float(np.mean([c for _, _, c in got])),
                                (b[0].start, b[1].start, b[0].stop, b[1].stop), b[0].stop - b[0].start,
                                dimension_row(ink, b, hc) is not None))
    return out


def dimension_row(ink: np.ndarray, b: tuple[slice, slice], hc: float) -> int | None:
    """The row of a line of ink just below or above the text box ``b`` running along most
    of it (a dimension line, or an underline); None when there is none."""
    reach = max(2, int(hc * 0.6))
    c0, c1 = max(0, b[1].start - 2), min(ink.shape[1], b[1].stop + 2)
    for r0, r1 in ((b[0].stop, b[0].stop + reach), (b[0].start - reach, b[0].start)):
        r0, r1 = max(0, r0), min(ink.shape[0], max(0, r1))
        rows = ink[r0:r1, c0:c1]
        if rows.size and (rows.mean(axis=1) >= 0.8).any():
            return r0 + int(np.argmax(rows.mean(axis=1)))
    return None


def printed_area(text: str) -> float | None:
    """The area (m²) a label like '14,43 m²', '14.4 m2' or '25,50' states; None otherwise
    (a number needs a unit or a decimal comma with two digits to be an area)."""
    m = AREA_RE.match(text.strip())
    if not m or not m.group(2) or not (m.group(3) or len(m.group(2)) == 2):
        return None
    return float(f"{m.group(1)}.{m.group(2)}")


def room_name(lines: list[TextLine], hc: float) -> tuple[str | None, float | None]:
    """(name, printed area m²) of a room from the text lines inside it: words (three
    letters or more, confident) before room numbers such as '1.4' or 'B12' (before plain
    integers); an area such
    as '14,43 m²' is not a name, nor a dimension (a lone number on a dimension line, or
    four digits and more). The tallest, most confident line wins; lines shorter than
    0.6 ``hc`` (the typical character height) are fragments."""
    words, numbers, area = [], [], None
    for ln in lines:
        text = ln.text.strip(" .,:;|_-—'\"“”‘’()[]{}«»~")
        if not text or ln.conf < MIN_CONF or ln.height < 0.6 * hc or text.lower() in UNITS:
            continue
        a = printed_area(text)
        if a is not None:
            area = area if area is not None else a
        elif NUMBER_RE.match(text):
            if not ln.dimension and not re.fullmatch(r"\d{4,}", text):
                numbers.append((not re.search(r"\D", text), -ln.height, -ln.conf, text))
        elif sum(ch.isalpha() for ch in text) >= 3 and ln.conf >= WORD_CONF:
            words.append((-ln.height, -ln.conf, text))
    pick = sorted(words) or sorted(numbers)
    return (pick[0][-1] if pick else None), area
