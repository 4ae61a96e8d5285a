"""Plausibility before success (issue 34): what a DXF plan says about itself, checked
against what was read of it (m).

- Area texts (``28.51 m²``, ``mq=28.51``, ``NGF: 24,35``, ``120 sq ft``) are printed
  areas; dimension strings and tatami counts (``6帖``, ``6畳``, ``6 jō``) never are
  (area_text.printed_area). A bare number counts only beside a room's name
  (room_printed_areas).
- Those texts against the closed outlines of the drawing tell its unit
  (unit_from_areas): a file whose $INSUNITS says mm but that is drawn in metres is read
  in metres, with a note, when two texts or more agree with the outlines in one unit
  only.
- Open room outlines are closed when the gap is at most a wall's thickness, else said
  (close_outlines).
- A footprint under MIN_FOOTPRINT_M2 or a storey with no free floor ends in one line
  naming the cause and the option that fixes it (check_floor).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon

from camplace.core.errors import InputError
from camplace.scene.importers import UNITS_M, polygons_of
from camplace.scene.importers.area_text import printed_area

MIN_FOOTPRINT_M2 = 1.0  # a footprint smaller than this is no building: wrong units or no walls
MIN_FREE_M2 = 1.0  # a storey needs at least this much floor the walls leave free
AREA_MATCH = (0.02, 0.05)  # a printed area and an outline agree within 2 % or 0.05 m²
MIN_TEXTS = 2  # texts agreeing with outlines in one unit (and none in another) that prove the unit
NEAR_NAME = 4.0  # a bare number names a room's area within this many text heights of its name
_BARE = re.compile(r"^\d{1,4}[.,]\d{1,2}$")


@dataclass
class UnitEvidence:
    """What the area texts say of the drawing's unit: ``unit`` (None: no one unit),
    ``texts`` agreeing with outlines in it, ``example`` ('mq=28.51: an outline of
    28.52 m²'), ``by_unit`` (unit -> texts agreeing)."""

    unit: str | None
    texts: int
    example: str
    by_unit: dict


def unit_from_areas(labels: list, outlines, scale: float) -> UnitEvidence:
    """The unit in which the drawing's closed ``outlines`` (m at ``scale`` m per drawing
    unit; a list, or a callable giving it, called only when there are area texts) measure
    what its area texts (``labels``) print: the one unit in which MIN_TEXTS texts or
    more agree with an outline (AREA_MATCH) and in which no other does."""
    printed = [(lb.text, a) for lb in labels if (a := printed_area(lb.text)) is not None and a > 0]
    outlines = (outlines() if callable(outlines) else outlines) if printed else []
    by_unit, example = {}, {}
    if printed and outlines:
        units2 = np.sort(np.asarray([q.area for q in outlines])) / scale ** 2  # drawing units², sorted
        value = np.asarray([a for _, a in printed])
        for unit, metres in UNITS_M.items():
            area = units2 * metres ** 2
            near = _nearest(area, value)
            ok = np.abs(area[near] - value) <= np.maximum(AREA_MATCH[0] * value, AREA_MATCH[1])
            if ok.any():
                by_unit[unit] = int(ok.sum())
                k = int(np.argmax(ok))
                example[unit] = f"{printed[k][0]}: an outline of {area[near[k]]:.2f} m²"
    agree = [u for u, n in by_unit.items() if n >= MIN_TEXTS]
    if len(by_unit) == 1 and agree:
        return UnitEvidence(agree[0], by_unit[agree[0]], example[agree[0]], by_unit)
    return UnitEvidence(None, 0, "", by_unit)


def _nearest(ordered: np.ndarray, values: np.ndarray) -> np.ndarray:
    """For each of ``values``, the index of the nearest entry of the sorted ``ordered``."""
    hi = np.clip(np.searchsorted(ordered, values), 0, len(ordered) - 1)
    lo = np.maximum(hi - 1, 0)
    return np.where(np.abs(ordered[lo] - values) < np.abs(ordered[hi] - values), lo, hi)


def close_outlines(shapes: list, gap: float) -> tuple[list[Polygon], int, list[float]]:
    """(polygons, how many were closed, the gaps m of those left open) of the open
    polylines among ``shapes`` (room outlines not closed): joined end to end where they
    meet, each closed when its ends lie at most ``gap`` m apart."""
    lines = [sh.geom for sh in shapes if isinstance(sh.geom, LineString) and not sh.closed
             and len(sh.geom.coords) >= 2]
    if not lines:
        return [], 0, []
    merged = shapely.line_merge(shapely.union_all([shapely.set_precision(ln, 1e-4) for ln in lines]))
    out, closed, left = [], 0, []
    for ln in getattr(merged, "geoms", [merged]):
        if ln.is_ring or len(ln.coords) < 3:
            if ln.is_ring:
                out += polygons_of(shapely.make_valid(Polygon(ln.coords)))
                closed += 1
            continue
        a, b = np.asarray(ln.coords[0]), np.asarray(ln.coords[-1])
        d = float(np.hypot(*(b - a)))
        if d <= gap:
            out += polygons_of(shapely.make_valid(Polygon(ln.coords)))
            closed += 1
        elif Polygon(ln.coords).area > 1.0:  # an outline left open, not a stroke
            left.append(d)
    return out, closed, left


def room_printed_areas(rooms: list[Polygon], names: list[str], labels: list) -> list[str]:
    """Notes comparing each room's area (m²) with the area printed in it: an area text
    (printed_area), or a bare number with decimals beside the room's name (on its layer,
    within NEAR_NAME text heights of it); never dimensions or tatami counts."""
    notes = []
    if not rooms or not labels:
        return notes
    pts = np.asarray([lb.point for lb in labels], dtype=object)
    li, ri = shapely.STRtree(np.asarray(rooms, dtype=object)).query(pts, predicate="within")
    inside: dict[int, list] = {}
    for a, b in zip(li.tolist(), ri.tolist()):
        inside.setdefault(b, []).append(labels[a])
    for k, found in sorted(inside.items()):
        got = next((a for lb in found if (a := printed_area(lb.text)) is not None), None)
        if got is None:
            name = next((lb for lb in found if lb.text == names[k] or names[k].startswith(lb.text + " ")), None)
            got = next((float(lb.text.replace(",", ".")) for lb in found if name is not None and lb is not name
                        and lb.layer == name.layer and _BARE.match(lb.text)
                        and lb.point.distance(name.point) <= NEAR_NAME * max(name.height, lb.height, 1e-3)), None)
        if got is not None and got > 0:
            area = rooms[k].area
            notes.append(f"room {names[k]}: printed {got:g} m², measured {area:.2f} m² "
                         f"({round(100 * (area - got) / got):+d} %)")
    return notes


def check_floor(path, footprint: Polygon, solids, units: str, span_units: float) -> None:
    """InputError naming the cause and the fix when the footprint (m) is under
    MIN_FOOTPRINT_M2 or the ``solids`` (walls, glass, columns) leave less than
    MIN_FREE_M2 of it free; ``units`` how the unit was found, ``span_units`` the walls'
    larger side in drawing units (what other units would make of it)."""
    area = footprint.area
    free = footprint.difference(solids).area if solids is not None else area
    if area >= MIN_FOOTPRINT_M2 and free >= MIN_FREE_M2:
        return
    fits = {u: span_units * s for u, s in UNITS_M.items() if 5.0 <= span_units * s <= 500.0}
    best = min(fits, key=lambda u: abs(np.log10(fits[u] / 30.0))) if fits else None
    what = (f"the footprint measures {area:.2g} m²" if area < MIN_FOOTPRINT_M2 else
            f"the walls fill the footprint ({area:.1f} m², {free:.1f} m² free floor)")
    if best is not None and UNITS_M[best] != _unit_m(units):
        raise InputError(f"{path}: {what} read in {units}: the drawing unit is wrong; in {best} the walls span "
                         f"{fits[best]:.1f} m; give the unit (units={best})", option="units")
    raise InputError(f"{path}: {what} read in {units}: no floor to place cameras over; name the wall layers "
                     "(wall_layers) or check the drawing", option="wall_layers")


def _unit_m(units: str) -> float | None:
    """Metres per unit of a ``Drawing.units`` text ('mm ($INSUNITS 4)'), None when unknown."""
    return UNITS_M.get(units.split(" ", 1)[0])
