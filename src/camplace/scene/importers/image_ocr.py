"""Plan images: the text on the sheet read by OCR (Tesseract through pytesseract, an
optional dependency: ``pip install camplace[ocr]`` plus the tesseract program).

Text is found without OCR first: ink marks the size of a character (8-connected pieces
no taller than twice the sheet's typical character and not framing other marks: the
circle around a room number is left out) merged into lines. Each line is cut out of
the grey sheet and prepared as a tile (image_text: own marks only, stretched, scaled up
3-4x, binarised, padded); all tiles are read by one Tesseract call as single lines (the
pages of one TIFF), so each line keeps its place on the sheet and the whole sheet costs
one engine start.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from camplace.scene.importers.area_text import is_tatami
from camplace.scene.importers.image_text import line_tile, restore_point
from camplace.scene.importers.image_walls import EIGHT

FRAGMENT = 0.6  # lines lower than this many character heights are fragments (a point, a hatch's dash)
MIN_CONF = 50  # Tesseract word confidence (0..100) below which a word is not used
WORD_CONF = 70  # ... and below which it does not name a room (numbers need MIN_CONF)
AREA_RE = re.compile(r"^(\d{1,4})(?:[.,]\s?(\d{1,2})|\s(\d{2}))"  # '14,43', '14.4'; '14 43' (the comma lost)
                     r"(?:\s*([mм]2|[mм][^\s\d]{0,3}|sq\.?\s*m|sqm|qm|²)|\s*(\S{1,3}))?$",  # unit; misread
                     re.IGNORECASE)
UNITS = {"m", "mm", "cm", "m2", "m²", "м", "м2", "м²", "sqm", "qm"}
JUNK = " .,:;|_-—'\"“”‘’()[]{}«»~°*"  # around a label: the rest of a ring, a stray mark
CASELESS = "cosvwxz"  # letters whose capital has the same shape
LANGUAGES = ("eng", "deu", "fra", "spa", "ita", "por", "nld")  # Tesseract models used when installed
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
        installed = set(pytesseract.get_languages(config=""))
    except Exception:  # noqa: BLE001 - TesseractNotFoundError and OS errors alike
        return None, "the tesseract program is not installed (e.g. apt install tesseract-ocr)"
    if "eng" not in installed:
        return None, "tesseract has no English model (e.g. apt install tesseract-ocr-eng)"
    more = [lang for lang in LANGUAGES if lang in installed]
    return (Tesseract(pytesseract, "+".join(more) if len(more) > 1 else None),
            f"tesseract {version}" + (f" (words again with {'+'.join(more)})" if len(more) > 1 else ""))


@dataclass
class Tesseract:
    """pytesseract, reading with the English model; ``more`` ('eng+deu'): the English model
    and those of LANGUAGES installed beside it (Debian tesseract-ocr-deu, ...), with which
    a word English read badly is read again (read_lines), so a German plan's 'Küche'
    reads whole while numbers stay with English alone (more models misread digits)."""

    module: object
    more: str | None = None

    @property
    def Output(self):  # noqa: N802 - pytesseract's name
        return self.module.Output

    def image_to_data(self, path: str, config: str, output_type, lang: str = "eng"):
        return self.module.image_to_data(path, lang=lang, config=config, output_type=output_type)


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
    """The text of the lines ``wanted`` (labels of ``lines``; fragments lower than
    FRAGMENT ``hc`` are left out), each prepared as a tile (image_text.line_tile) and
    read as a single line of text: one Tesseract call for all the tiles (the pages of
    one TIFF). A decimal point Tesseract dropped from a number is put back
    (image_text.restore_point)."""
    boxes = ndimage.find_objects(lines)
    wanted = [k for k in wanted if boxes[k - 1] is not None and boxes[k - 1][0].stop - boxes[k - 1][0].start
              >= FRAGMENT * hc]
    if not wanted:
        return []
    tiles = [line_tile(dark, ink, lines, k, boxes[k - 1], hc) for k in wanted]
    first = read_pages(engine, [t.image for t in tiles])
    more = getattr(engine, "more", None)
    again = [i for i, (text, conf) in enumerate(first) if conf < WORD_CONF and sum(ch.isalpha() for ch in text) >= 2]
    if more and again:  # words English read badly: once more with the other installed models
        for i, got in zip(again, read_pages(engine, [tiles[i].image for i in again], lang=more)):
            if got[1] > first[i][1]:
                first[i] = got
    out = []
    for k, tile, (text, conf) in zip(wanted, tiles, first):
        b = boxes[k - 1]
        if text:
            out.append(TextLine(restore_point(text.strip(JUNK), tile.grey) if text.strip(JUNK).isdigit() else text,
                                conf, (b[0].start, b[1].start, b[0].stop, b[1].stop), b[0].stop - b[0].start,
                                dimension_row(ink, b, hc) is not None))
    return out


def read_pages(engine, tiles: list[np.ndarray], lang: str | None = None) -> list[tuple[str, float]]:
    """(text, mean word confidence 0..100) of each tile, read by one Tesseract call as a
    single line of text (page segmentation mode 7) on the pages of one TIFF."""
    import tempfile
    from pathlib import Path

    from PIL import Image

    config = "--" + "psm 7"  # tesseract's own argument: each page is one line of text
    pages = [Image.fromarray(t) for t in tiles]
    with tempfile.TemporaryDirectory(prefix="camplace-ocr-") as tmp:
        path = Path(tmp) / "lines.tif"
        pages[0].save(path, save_all=True, append_images=pages[1:])
        more = {} if lang is None else {"lang": lang}
        data = engine.image_to_data(str(path), config=config, output_type=engine.Output.DICT, **more)
    words: dict[int, list] = {}
    for page, text, conf, left in zip(data["page_num"], data["text"], data["conf"], data["left"]):
        text = str(text).strip()
        if text and float(conf) >= 0:
            words.setdefault(int(page) - 1, []).append((left, text, float(conf)))
    out = []
    for i in range(len(tiles)):
        got = sorted(words.get(i, []))
        out.append((" ".join(t for _, t, _ in got), float(np.mean([c for *_, c in got])) if got else 0.0))
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
    (a number needs a unit or a decimal comma with two digits to be an area; where the
    comma was not read, '14 43 m²', two digits after the space; with two decimals a
    small 'm²' may be misread, '12 25 4?'); never a tatami count (area_text.is_tatami)."""
    m = AREA_RE.match(text.strip())
    if not m or is_tatami(text):
        return None
    decimals = m.group(2) or m.group(3)
    if not (m.group(4) or len(decimals) == 2):
        return None
    return float(f"{m.group(1)}.{decimals}")


def room_name(lines: list[TextLine], hc: float) -> tuple[str | None, float, float | None]:
    """(name, its confidence 0..100, printed area m²) of a room from the text lines
    inside it: words (three letters or more, or two capitals such as 'WC', also when read
    'wc'; confident) before room numbers such as '1.4' or 'B12' (before plain integers); an area such as
    '14,43 m²' is not a name, nor a dimension (a lone number on a dimension line, or four
    digits and more). The tallest, most confident line wins; lines shorter than 0.6
    ``hc`` (the typical character height) are fragments."""
    words, numbers, area = _label_parts(lines, hc)
    pick = sorted(words) or sorted(numbers)
    return (pick[0][-1], -pick[0][-2], area) if pick else (None, 0.0, area)


def room_number(lines: list[TextLine], hc: float) -> str | None:
    """The room number among a room's text lines ('B102', '1.4'; see room_name), or None."""
    numbers = sorted(_label_parts(lines, hc)[1])
    return numbers[0][-1] if numbers else None


def _label_parts(lines: list[TextLine], hc: float) -> tuple[list, list, float | None]:
    """(words, numbers, printed area) of a room's text lines, each word and number with
    its sort key (see room_name)."""
    words, numbers, area = [], [], None
    for ln in lines:
        text = ln.text.strip(JUNK)
        if not text or ln.conf < MIN_CONF or ln.height < FRAGMENT * hc or text.lower() in UNITS:
            continue
        a = printed_area(text)
        if a is not None:
            area = area if area is not None else a
        elif NUMBER_RE.match(text):
            if not ln.dimension and not re.fullmatch(r"\d{4,}", text):
                numbers.append((not re.search(r"\D", text), -ln.height, -ln.conf, text))
        elif ln.conf >= WORD_CONF and sum(ch.isalpha() for ch in text) >= 3:
            words.append((-ln.height, -ln.conf, text))
        elif ln.conf >= WORD_CONF and re.fullmatch(r"[A-Za-z]{2}", text) and all(c.isupper() or c in CASELESS
                                                                                 for c in text):
            words.append((-ln.height, -ln.conf, text.upper()))  # 'wc': Tesseract cannot tell the case
    return words, numbers, area
