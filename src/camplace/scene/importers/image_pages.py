"""Plan images: the pages of a PDF plan set and the storey each page draws (issue 33).

A plan set handed over as one PDF has one page per floor. Each page becomes a storey
named by the level its own text gives ('Ground floor', 'Level 2', 'Erdgeschoss', '1er
étage' ...: the largest such text on the page, its title) or, without one, ``page-N``.
Pages whose text is only pictures (a scanned set) are ``page-N``.
"""

from __future__ import annotations

import re
from pathlib import Path

from camplace.core.errors import InputError

# a level's name in a title, in the languages OCR reads (English, German, French, Spanish, Italian, Dutch)
_ORD = r"(?:ground|first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|top|upper|lower|\d+\s*(?:st|nd|rd|th)?)"
LEVEL_RE = re.compile("|".join((
    rf"\b{_ORD}[\s-]+(?:floor|storey|story|level)\b",
    r"\b(?:level|floor|storey|story|etage|ebene|niveau|piso|piano|verdieping|geschoss)\s*[-+]?\d+\b",
    r"\b(?:basement|cellar|mezzanine|attic|roof)\s+(?:floor|level|plan|storey|story)\b",
    r"(?:\b\d+\.\s*)?\b(?:erd|ober|unter|keller|dach|sockel|zwischen)geschoss\b|(?-i:\b(?:EG|OG|UG|DG|KG)\s*\d*\b)",
    r"\brez[\s-]de[\s-]chauss[ée]e\b|\b\d+\s*(?:er|re|e|ème|eme)\s+étage\b|\bsous[\s-]sol\b",
    r"\bplanta\s+(?:baja|alta|primera|segunda|tercera|s[óo]tano)\b|\b(?:primera|segunda|tercera)\s+planta\b",
    r"\bpiano\s+(?:terra|primo|secondo|terzo|interrato|seminterrato)\b|\b(?:primo|secondo|terzo)\s+piano\b",
    r"\bbegane\s+grond\b|\b(?:eerste|tweede|derde)\s+verdieping\b|\bkelder\b",
)), re.IGNORECASE)


# a drawing scale printed on a sheet ('1:100', 'M 1:50', 'Scale 1:200'), one of the scales plans are drawn at
SCALE_TEXT_RE = re.compile(r"(?<![\d.:/])1\s*:\s*(\d{2,4})(?![\d:.,])")
PLAN_SCALES = (20, 25, 50, 75, 100, 125, 150, 200, 250, 500, 1000)


def is_pdf(path: Path) -> bool:
    """True for a PDF file (by its suffix, as plan_kind)."""
    return path.suffix.lower() == ".pdf"


def open_pdf(path: Path):
    """The open pypdfium2 document of ``path`` (InputError when it cannot be read; the
    caller closes it)."""
    try:
        import pypdfium2 as pdfium
    except ImportError:  # pragma: no cover - a declared dependency
        raise InputError(f"{path}: reading a PDF needs pypdfium2 (pip install pypdfium2)") from None
    try:
        return pdfium.PdfDocument(str(path))
    except (pdfium.PdfiumError, OSError) as err:
        raise InputError(f"{path}: not a readable PDF ({str(err).splitlines()[0]})") from None


def page_count(path: Path) -> int:
    """The number of pages of a PDF."""
    doc = open_pdf(path)
    try:
        return len(doc)
    finally:
        doc.close()


def level_name(text: str, sizes: dict[str, float] | None = None) -> str | None:
    """The level a page's ``text`` names ('Ground floor', 'Level 2', 'Erdgeschoss'), None
    when it names none. Several: the one printed largest (``sizes``: font size of each
    matched text, pt), else the first. Whitespace is collapsed; text all in capitals is
    given with a capital first letter ('GROUND FLOOR' -> 'Ground floor')."""
    found = [" ".join(m.group(0).split()) for m in LEVEL_RE.finditer(text)]
    if not found:
        return None
    best = max(found, key=lambda f: (sizes or {}).get(f, 0.0)) if sizes else found[0]
    return best.capitalize() if best.isupper() and any(len(w) > 3 for w in best.split()) else best


def printed_scale(path: Path, page: int) -> int | None:
    """N of the drawing scale 1:N printed on page ``page`` (1-based) of a PDF, when its
    text gives one plan scale (PLAN_SCALES) and no other; None otherwise (no text, no
    scale, or a plan at 1:100 beside a detail at 1:20: the dimension lines decide)."""
    doc = open_pdf(path)
    try:
        if not 1 <= page <= len(doc):
            return None
        pg = doc[page - 1]
        textpage = pg.get_textpage()
        try:
            text = textpage.get_text_range()
        finally:
            textpage.close()
            pg.close()
    finally:
        doc.close()
    found = {int(m.group(1)) for m in SCALE_TEXT_RE.finditer(text)} & set(PLAN_SCALES)
    return found.pop() if len(found) == 1 else None


def page_names(path: Path) -> list[str]:
    """One storey name per page of a PDF: the level its text names (level_name, by the
    largest font), else page-N; a name two pages give is made unique by its page
    ('Level 1 (page 3)')."""
    doc = open_pdf(path)
    names = []
    try:
        for i in range(len(doc)):
            page = doc[i]
            textpage = page.get_textpage()
            try:
                text = textpage.get_text_range()
                sizes = {}
                for m in LEVEL_RE.finditer(text):
                    key = " ".join(m.group(0).split())
                    sizes[key] = max(sizes.get(key, 0.0), _printed_size(textpage, m.group(0)))
                names.append(level_name(text, sizes) or f"page-{i + 1}")
            finally:
                textpage.close()
                page.close()
    finally:
        doc.close()
    seen = {n: names.count(n) for n in names}
    return [f"{n} (page {i + 1})" if seen[n] > 1 else n for i, n in enumerate(names)]


def _printed_size(textpage, text: str) -> float:
    """The height (pt) of the first character of ``text`` where it is printed on the page
    (0 when it cannot be found)."""
    searcher = textpage.search(text, match_case=False)
    try:
        hit = searcher.get_next()
        if not hit:
            return 0.0
        _, bottom, _, top = textpage.get_charbox(hit[0])
        return float(top - bottom)
    finally:
        searcher.close()


def page_of_storey(storey: str, names: list[str]) -> int | None:
    """The page (1-based) a storey name chooses: one of ``names`` (page_names; case does
    not matter), or 'page-N'; None when it names no page."""
    low = [n.lower() for n in names]
    if storey.lower() in low:
        return low.index(storey.lower()) + 1
    m = re.fullmatch(r"page-(\d+)", storey.strip(), re.IGNORECASE)
    if m and 1 <= int(m.group(1)) <= len(names):
        return int(m.group(1))
    return None
