"""The drawing unit of a DXF plan: the ``units`` option, else the header's $INSUNITS, else
(a file that says none: $INSUNITS 0, very common; R12 files, which cannot say it; a code
no building is drawn in) guessed from the geometry: of mm, cm, m, in and ft, the units in
which the drawing's extent is a building's (PLAUSIBLE_M), then the one in which its door
swings (quarter arcs) are doors' leaves (DOOR_RADIUS_M), then in which its lines pair up
like wall faces (5-60 cm apart), then the one that makes its extent nearest a typical
building's. The guess is said in a note with how to override it. Also the notes when a
declared unit makes no sense (check_span).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import LineString

from camplace.core.errors import InputError
from camplace.scene.importers import UNITS_M, unit_scale
from camplace.scene.importers.dxf_read import Drawing, read_drawing
from camplace.scene.importers.dxf_walls import MIN_SEGMENT_M, pair_sides, segments

INSUNITS = {1: ("in", 0.0254), 2: ("ft", 0.3048), 4: ("mm", 0.001), 5: ("cm", 0.01), 6: ("m", 1.0),
            10: ("yd", 0.9144), 14: ("dm", 0.1)}  # $INSUNITS code -> (unit, m per unit)
PLAUSIBLE_M = (3.0, 500.0)  # the span of a building plan that makes sense, m
TYPICAL_SPAN_M = 30.0  # of several units that fit, the guess makes the drawing's span nearest this
DOOR_RADIUS_M = (0.6, 1.3)  # the radius of a door swing (its leaf's width) that makes sense, m
QUARTER_ARC = (1.09, 1.13)  # arc length / chord of a door swing: a quarter circle's is pi / (2 sqrt 2) = 1.111
MIN_WALL_SHARE = 0.2  # at least this share of the straight linework paired like wall faces says walls
MAX_SEGMENTS = 20_000  # the longest straight pieces weighed for walls (a guard on huge drawings)


def read_in_units(doc, path: Path, units: str | None) -> Drawing:
    """The modelspace of ``doc`` in metres, in ``units`` if given, else in the header's
    $INSUNITS, else in the unit its geometry suggests (guess_unit: ``Drawing.units`` says
    it was guessed and a note how to override it); InputError naming the file when no
    unit makes the drawing a building."""
    if units is not None:
        return read_drawing(doc, unit_scale(units), f"{units} (given)")
    code = int(doc.header.get("$INSUNITS", 0) or 0)
    if code in INSUNITS:
        name, metres = INSUNITS[code]
        return read_drawing(doc, metres, f"{name} ($INSUNITS {code})")
    said = f"$INSUNITS {code}" if "$INSUNITS" in doc.header else "no $INSUNITS: R12 cannot say it"
    first = _span_units(doc)
    provisional = UNITS_M[_typical(first)] if first > 0 else 1.0  # read once at about the right detail
    d = read_drawing(doc, provisional, "")
    guess = guess_unit(d)
    if guess is None:
        span = _span_m(d) / provisional
        hint = f"; its linework spans {span:,.4g} units ({unit_hint(span)})" if span > 0 else "; it has no linework"
        raise InputError(f"{path}: the drawing units are unknown ({said}) and no unit makes the drawing a "
                         f"building{hint}; expected mm, cm, m, in or ft (units)", option="units")
    name, why = guess
    text = f"{name} (guessed: the file says no unit, {said}; {why})"
    if UNITS_M[name] != provisional:
        d = read_drawing(doc, UNITS_M[name], text)
    d.units = text
    d.notes.append(f"the file says no drawing unit ({said}): read in {name}, guessed from its geometry ({why}); "
                   "if that is wrong, give the unit (units)")
    return d


def guess_unit(d: Drawing) -> tuple[str, str] | None:
    """(unit, why) of a drawing read at ``d.scale`` m per unit whose file says no unit:
    among the units that make its extent PLAUSIBLE_M, the one whose door swings measure
    DOOR_RADIUS_M, then whose lines pair like wall faces (MIN_WALL_SHARE), then whose
    extent is nearest TYPICAL_SPAN_M; None when no unit makes its extent a building's."""
    span0 = _span_m(d)
    if span0 <= 0:
        return None
    p0, p1, _ = segments([sh.geom for sh in d.shapes if isinstance(sh.geom, LineString)])
    length = np.hypot(*(p1 - p0).T) if len(p0) else np.zeros(0)
    longest = np.argsort(-length)[:MAX_SEGMENTS]
    p0, p1, length = p0[longest], p1[longest], length[longest]
    swings = _door_radii(d)
    best, best_key = None, None
    for unit, metres in UNITS_M.items():
        k = metres / d.scale
        span = span0 * k
        if not PLAUSIBLE_M[0] <= span <= PLAUSIBLE_M[1]:
            continue
        door = float(np.median(swings)) * k if len(swings) else 0.0
        share, gap = _wall_pairs(p0 * k, p1 * k, length * k)
        key = (DOOR_RADIUS_M[0] <= door <= DOOR_RADIUS_M[1], share >= MIN_WALL_SHARE,
               -abs(math.log10(span / TYPICAL_SPAN_M)))
        if best_key is None or key > best_key:
            why = [f"it spans {span:,.1f} m"]
            why += [f"door swings {door:.2f} m"] if key[0] else []
            why += [f"{share:.0%} of its lines pair like wall faces {gap:.2f} m apart"] if key[1] else []
            best, best_key = (unit, ", ".join(why)), key
    return best


def _wall_pairs(p0: np.ndarray, p1: np.ndarray, length: np.ndarray) -> tuple[float, float]:
    """(share of the length of the straight pieces at least MIN_SEGMENT_M long that have a
    parallel partner a wall's thickness away, the median gap m) of segments in metres."""
    long = length >= MIN_SEGMENT_M
    if long.sum() < 2:
        return 0.0, 0.0
    left, right, gap = pair_sides(p0[long], p1[long], np.zeros(int(long.sum()), int))
    paired = left | right
    share = float(length[long][paired].sum() / length[long].sum())
    return share, float(np.median(gap[paired])) if paired.any() else 0.0


def _door_radii(d: Drawing) -> np.ndarray:
    """The radii (m at ``d.scale``) of the quarter-circle arcs of the drawing (door swings)."""
    arcs = [sh.geom for sh in d.shapes if sh.kind == "ARC" and isinstance(sh.geom, LineString)]
    if not arcs:
        return np.zeros(0)
    arr = np.asarray(arcs, dtype=object)
    a, b = shapely.get_coordinates(shapely.get_point(arr, 0)), shapely.get_coordinates(shapely.get_point(arr, -1))
    chord = np.hypot(*(b - a).T)
    lengths = shapely.length(arr)
    ratio = lengths / np.maximum(chord, 1e-12)
    quarter = (ratio >= QUARTER_ARC[0]) & (ratio <= QUARTER_ARC[1])
    return lengths[quarter] / (math.pi / 2)


def _span_m(d: Drawing) -> float:
    """The larger side (m at ``d.scale``) of the box around the drawing's shapes."""
    if not d.shapes:
        return 0.0
    b = shapely.bounds(np.asarray([sh.geom for sh in d.shapes], dtype=object))
    return float(max(b[:, 2].max() - b[:, 0].min(), b[:, 3].max() - b[:, 1].min()))


def _typical(span: float) -> str:
    """The unit of mm, cm and m that makes ``span`` drawing units nearest TYPICAL_SPAN_M."""
    return min(("mm", "cm", "m"), key=lambda u: abs(np.log10(span * UNITS_M[u] / TYPICAL_SPAN_M)))


def unit_hint(span: float) -> str:
    """'mm: 24.3 m, cm: 243.0 m' - what a span in drawing units would measure in the
    units that make it a building (PLAUSIBLE_M), else in mm, cm and m."""
    good = [(u, span * s) for u, s in UNITS_M.items() if PLAUSIBLE_M[0] <= span * s <= PLAUSIBLE_M[1] / 3]
    return ", ".join(f"{u}: {m:,.1f} m" for u, m in (good or [(u, span * UNITS_M[u]) for u in ("mm", "cm", "m")]))


def _span_units(doc) -> float:
    """The larger side of the box around the modelspace's LINE and polyline vertices (drawing units)."""
    pts = []
    for e in doc.modelspace().query("LINE LWPOLYLINE POLYLINE"):
        if e.dxftype() == "LINE":
            pts += [(e.dxf.start.x, e.dxf.start.y), (e.dxf.end.x, e.dxf.end.y)]
        elif e.dxftype() == "LWPOLYLINE":
            pts += [p[:2] for p in e.get_points("xy")]
        else:
            pts += [(p.x, p.y) for p in e.points()]
    if not pts:
        return 0.0
    a = np.asarray(pts, float)
    return float((a.max(0) - a.min(0)).max())


def check_span(span_m: float, scale: float, units: str, plausible: tuple = PLAUSIBLE_M,
               what: str = "walls") -> list[str]:
    """Notes when a length (m; ``scale`` m per drawing unit) that should lie in
    ``plausible`` (the walls' larger side, a typical door) makes no sense in the drawing's
    ``units``, with what the other units would make of it."""
    if plausible[0] <= span_m <= plausible[1] or span_m <= 0:
        return []
    span = span_m / scale
    other = ", ".join(f"{u}: {span * s:,.2f} m" for u, s in UNITS_M.items()
                      if plausible[0] <= span * s <= plausible[1]) or "none fits"
    return [f"the {what} measure {span_m:,.2f} m in the drawing's units ({units}): are they right? In other "
            f"units: {other} (units)"]
