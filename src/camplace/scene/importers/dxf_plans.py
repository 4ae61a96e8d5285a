"""Several plans on one DXF sheet (issue 33): a ground floor and a first floor drawn side
by side become one storey each. The walls, glass and columns cluster into buildings
(dxf_walls.building_clusters); every cluster with walls whose extent (its pieces grown
by half the gap, holes filled) is at least PLAN_SHARE of the largest one's and a
building's size is a plan (a title block's key plan, a legend or a detail is not). Plans are ordered left to right, then top to bottom (rows of plans
whose heights overlap), named plan-1..n, or by the level a text near them names
("Ground floor", "Erdgeschoss", "Piano terra", "Level 1", ...).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon

from camplace.core.errors import InputError
from camplace.scene.importers.dxf_layers import normalise
from camplace.scene.importers.dxf_walls import building_clusters, span

PLAN_SHARE = 0.25  # a cluster with at least this share of the largest one's extent (m²) is a plan of its own
MIN_PLAN_M = 3.0  # ... and at least this wide (m)
NEAR_SHARE = 0.2  # a text names a plan's level within this share of the plan's size (at least NEAR_M) of it
NEAR_M = 3.0
# the words of a level name (normalised: upper case, accents dropped); the match is the storey's name
_ORD = (r"(?:FIRST|SECOND|THIRD|FOURTH|FIFTH|\d+(?:ST|ND|RD|TH)|UPPER|LOWER|TOP|GROUND|BASEMENT|MEZZANINE|ATTIC|"
        r"PRIMO|SECONDO|TERZO|PRIMERA|SEGUNDA|TERCERA|PRIMER|SEGUNDO)")
LEVEL = re.compile("|".join([
    rf"(?<![A-Z]){_ORD}\s+(?:FLOOR|STOREY|STORY|LEVEL|PIANO|PLANTA)(?![A-Z])",
    r"(?<![A-Z])(?:LEVEL|FLOOR|STOREY|STORY|NIVEAU|LIVELLO|ETAGE|PLANTA|PIANO)\s+(?:[-+]?\d+|[A-Z]{1,2}\d?|"
    r"TERRA|PRIMO|SECONDO|TERZO|INTERRATO|SEMINTERRATO|BAJA|ALTA|PRIMERA|SEGUNDA|SOTANO)(?![A-Z0-9])",
    r"(?<![A-Z])(?:BASEMENT|MEZZANINE|ATTIC|LOFT|ERDGESCHOSS|OBERGESCHOSS|\d+\.\s*OBERGESCHOSS|UNTERGESCHOSS|"
    r"KELLERGESCHOSS|DACHGESCHOSS|SOUTERRAIN|REZ[- ]DE[- ]CHAUSSEE|SOUS[- ]SOL|SEMINTERRATO|SOTTOTETTO|"
    r"SOTANO|BEGANE GROND|\d+E? VERDIEPING|\d+(?:ER|E|EME)\s+ETAGE)(?![A-Z])",
    r"(?<![A-Z0-9])(?:\d\.?\s?)?(?:EG|OG|UG|DG|KG|RDC)(?![A-Z0-9])",
]))


@dataclass
class Plan:
    """One plan on the sheet: its ``name`` (plan-N or the level a text names), ``region``
    (m, the cluster grown by half the building gap, holes filled), ``kept`` (which of
    the wall, glass and column pieces it holds), ``walls_m2`` (its wall area)."""

    name: str
    region: Polygon
    kept: np.ndarray
    walls_m2: float


def find_plans(pieces: list, weights: list[float], labels: list) -> list[Plan]:
    """The plans on the sheet (pieces: wall, glass and column polygons, m; ``weights``:
    their wall area; ``labels``: the sheet's texts) in reading order, named."""
    blobs, blob_of, total = building_clusters(pieces, weights)
    if not blobs:
        return []
    size = np.array([Polygon(b.exterior).area for b in blobs])  # a plan's extent, not its ink
    keep = [k for k in range(len(blobs)) if total[k] > 0 and size[k] >= PLAN_SHARE * size[total > 0].max()
            and span(blobs[k]) >= MIN_PLAN_M]
    keep = keep or [int(np.argmax(total))]
    regions = [Polygon(blobs[k].exterior) for k in keep]
    order = reading_order([r.bounds for r in regions])
    plans = [Plan(f"plan-{i + 1}", regions[k], blob_of == keep[k], float(total[keep[k]])) for i, k in enumerate(order)]
    if len(plans) > 1:
        _name_levels(plans, labels)
    return plans


def reading_order(boxes: list[tuple]) -> list[int]:
    """Indices of boxes (x0, y0, x1, y1) left to right, then top to bottom: rows of boxes
    whose heights overlap, the top row first."""
    idx = sorted(range(len(boxes)), key=lambda i: -boxes[i][3])
    rows: list[list[int]] = []
    for i in idx:
        row = next((r for r in rows if boxes[i][3] > min(boxes[j][1] for j in r)
                    and boxes[i][1] < max(boxes[j][3] for j in r)), None)
        if row is None:
            rows.append([i])
        else:
            row.append(i)
    return [i for r in rows for i in sorted(r, key=lambda i: boxes[i][0])]


def level_name(text: str) -> str | None:
    """The level a text names ('Grundriss Erdgeschoss 1:100' -> 'Erdgeschoss', 'FIRST
    FLOOR PLAN' -> 'FIRST FLOOR'), as written; None when it names none."""
    n = normalise(text)
    m = LEVEL.search(n)
    if not m:
        return None
    got = text[m.start():m.end()] if len(n) == len(text) else m.group(0).title()
    return " ".join(got.split())


def _name_levels(plans: list[Plan], labels: list) -> None:
    """Each plan named by the level a text near it names (no plan nearer to it; a title
    outside the plan before a text inside it, a taller text first, then the nearer),
    unless two plans would share a name."""
    if not labels:
        return
    pts = np.asarray([lb.point for lb in labels], dtype=object)
    dist = np.array([shapely.distance(p.region, pts) for p in plans])  # plans x labels
    near = np.array([max(NEAR_M, NEAR_SHARE * span(p.region)) for p in plans])
    names: list[str | None] = []
    for i, p in enumerate(plans):
        ranked = sorted((j for j in range(len(labels)) if dist[i, j] <= near[i] and dist[:, j].argmin() == i),
                        key=lambda j: (dist[i, j] == 0, -labels[j].height, dist[i, j]))
        names.append(next((nm for j in ranked if (nm := level_name(labels[j].text))), None))
    for p, nm in zip(plans, names):
        if nm and sum(1 for x in names if x and x.upper() == nm.upper()) == 1:
            p.name = nm


def choose(plans: list[Plan], storey: str | None, path) -> tuple[int, str]:
    """(index, why) of the plan ``storey`` names ('plan-N' or a plan's name, case does
    not matter), else of the plan with most wall area; InputError listing the plans."""
    if storey is None:
        best = max(range(len(plans)), key=lambda i: plans[i].walls_m2)
        return best, "the only plan on the sheet" if len(plans) == 1 else "most walls"
    names = [p.name.upper() for p in plans]
    if storey.upper() in names:
        return names.index(storey.upper()), "chosen"
    m = re.fullmatch(r"plan-(\d+)", storey.strip().lower())
    if m and 1 <= int(m.group(1)) <= len(plans):
        return int(m.group(1)) - 1, "chosen"
    have = ", ".join(f"{p.name}" + (f" (plan-{i + 1})" if p.name != f"plan-{i + 1}" else "")
                     for i, p in enumerate(plans))
    raise InputError(f"storey: {path.name} has no plan '{storey}'; it has {have} (or 'all')", option="storey")
