"""Texts that print an area (m²), for every importer's printed-area check (issue 34): a
number with a unit of area, or after an area word; never a dimension string or a tatami
count (Japanese plans give room sizes in mats: 6帖, 6畳, 6 jō).
"""

from __future__ import annotations

import re

from camplace.scene.importers.dxf_layers import normalise

SQ_FT_M2 = 0.09290304
_NUM = r"(\d{1,6}(?:[.,]\d{1,3})?)"
_M2 = r"(?:M\s?2|SQ\.?\s?M|SQM|MQ|QM|M\.Q\.)"
_FT2 = r"(?:SQ\.?\s?FT|SF|FT\s?2)"
_WORD = r"(?:AREA|SUPERFICIE|SUPERF|SUP|SURFACE|FLAECHE|NGF|NRF|HNF|NF|GFA|NIA|GIA|A|S|F)\.?"
_AREA = re.compile(rf"^(?:(?P<w>{_WORD})\s*[:=]?\s*)?(?:(?P<pre>{_M2}|{_FT2})\s*[:=]?\s*)?{_NUM}\s*"
                   rf"(?P<unit>{_M2}|{_FT2})?\.?$")
_IN_TEXT = re.compile(rf"(?<![\d.,]){_NUM}\s*(?P<unit>{_M2}|{_FT2})(?![A-Z])|(?<![A-Z])(?P<pre>{_M2}|{_FT2})\s*[:=]?\s*"
                      rf"(\d{{1,6}}(?:[.,]\d{{1,3}})?)(?![\d])")
_TATAMI = re.compile(r"帖|畳|疊|(?<![A-Z])JO(?![A-Z])|(?<![A-Z])TATAMI")


def printed_area(text: str) -> float | None:
    """The area (m²) a text states: a number with a unit of area (m², m2, sqm, mq, qm;
    sq ft, sf converted) before or after it, or after an area word ('Area: 28.5',
    'NGF=24,35'); None for anything else: a dimension ('3.60', '3600'), a tatami count
    ('6帖', '6畳', '6 jō'), a level ('+0.00')."""
    t = normalise(text).strip()
    if not t or is_tatami(text):
        return None
    m = _AREA.match(t)
    if m:
        unit, number = m.group("unit") or m.group("pre"), m.group(3)
        if unit is None and (m.group("w") is None or m.group("w").rstrip(".") in ("A", "S", "F")):
            return None  # a bare number, or 'A=3.6': any quantity
    else:  # 'Soggiorno mq 28,51', 'Living 28.5 m²': a number with its unit inside a longer text
        m = _IN_TEXT.search(t)
        if not m:
            return None
        unit, number = m.group("unit") or m.group("pre"), m.group(1) or m.group(4)
    value = float(number.replace(",", "."))
    return value * SQ_FT_M2 if unit is not None and re.fullmatch(_FT2, unit) else value


def is_tatami(text: str) -> bool:
    """True for a tatami count ('6帖', '4.5畳', '6 jō', '8 tatami'): a room size in mats, no area."""
    return bool(_TATAMI.search(normalise(text)) or "帖" in text or "畳" in text)
