"""Which layers of a DXF plan hold walls (m): by name (dxf_layers) or the given patterns,
else by their geometry (dxf_walls: parallel line pairs a wall's thickness apart, single
lines enclosing rooms); a layer named like walls, or whose line pairs look like walls,
that holds objects instead (dxf_objects.object_layers) is a furniture layer; the summary
lines that list layers with what they hold.
"""

from __future__ import annotations

from collections import Counter, defaultdict
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import LineString

from camplace.core.errors import InputError
from camplace.scene.importers import polygons_of
from camplace.scene.importers.dxf_layers import ROLES, layer_role, matches
from camplace.scene.importers.dxf_objects import DEFAULT_FURNITURE_M, object_layers
from camplace.scene.importers.dxf_read import FILLED, LINEWORK, Drawing, Shape
from camplace.scene.importers.dxf_walls import (MIN_SEGMENT_M, closing_solid, door_leaves, encloses_room, is_wall_fill,
                                                layer_pairs, single_line_rooms, wall_layers_by_geometry)

STRAIGHT = {"LINE", "LWPOLYLINE", "POLYLINE"}  # single-line walls: these, not arcs (door swings) or splines
MIN_NAMED_WALLS_M = 8.0  # less linework than this on the wall layers (a legend's stub): ask the geometry too
ALSO_WALLS_SHARE = 0.2  # wall-like pairs elsewhere, this share of the named walls' linework or more, get a note


def layer_roles(d: Drawing, given: dict, radius: float, single: float) -> tuple[dict[str, str | None], dict[str, str]]:
    """(layer -> role or None, layer -> how the role was found: 'given', 'by name' or
    'by shape'): a layer named like walls that holds objects (dxf_objects.object_layers,
    walls closed with ``radius``, ``single``) is furniture, said in a note."""
    role, how = {}, {}
    for layer in {sh.layer for sh in d.shapes}:
        mine = next((r for r in ROLES if given[r] and matches(layer, given[r])), None)
        if mine is not None:
            role[layer], how[layer] = mine, "given"
            continue
        named = layer_role(layer)
        role[layer] = None if named in ROLES and given[named] else named
        how[layer] = "by name"
    named_walls = {la for la, r in role.items() if r == "wall" and how[la] == "by name"}
    _objects(d, {la: [sh for sh in d.shapes if sh.layer == la] for la in named_walls}, role, how, radius, single)
    return role, how


def _objects(d: Drawing, shapes: dict, role: dict, how: dict, radius: float, single: float,
             around=None) -> set[str]:
    """The layers of ``shapes`` (layer -> its shapes) that hold objects, not walls
    (object_layers; ``around``: the solid of the other walls), made furniture layers
    with a note; their names."""
    found = object_layers(d, shapes, radius, single, around)
    for la, what in found.items():
        role[la], how[la] = "furniture", "by shape"
        d.notes.append(f"{la}: {what} that close no room: objects, not walls (furniture_heights gives their "
                       f"height, default {DEFAULT_FURNITURE_M:g} m; wall_layers names the walls)")
    return set(found)


def lines_fills(shapes: list[Shape]) -> tuple[list, list]:
    """(LineStrings, filled Polygons) of shapes, m."""
    lines = [sh.geom for sh in shapes if isinstance(sh.geom, LineString)]
    fills = [q for sh in shapes if not isinstance(sh.geom, LineString) for q in polygons_of(sh.geom)]
    return lines, fills


def wall_linework(path: Path, d: Drawing, parts: dict, role: dict, how: dict, given, radius: float,
                   single: float) -> tuple[tuple, dict]:
    """((wall lines, wall fills), layer -> how found) by name or given patterns, else by
    geometry; where the named walls (closed into solids: closing_solid with ``radius``,
    ``single``) close no room, the single-line wall layers around them too (a renovation
    plan's new walls named, the building's walls on a layer no name explains); InputError
    listing the layers with linework when there are none."""
    lines, fills = lines_fills(parts["wall"])
    thin = [q for q in fills if is_wall_fill(q)]
    if len(fills) > len(thin):
        d.skipped["filled areas on wall layers too wide to be walls"] += len(fills) - len(thin)
    named = sum(ln.length for ln in lines) + sum(q.length / 2 for q in thin)
    found = layers_of(parts["wall"], how)
    if given is None and named < MIN_NAMED_WALLS_M:  # nothing, or a legend's stub: what does the geometry say?
        geo = _walls_by_geometry(d, parts, role, radius, single)
        if geo is not None and sum(ln.length for ln in geo[0]) > 2 * named:
            d.notes.append(f"{'no layer is named like walls' if not named else 'little on the wall layers'}; took "
                           f"{', '.join(geo[2])} by their geometry ({geo[3]}); if that is wrong, name "
                           "the wall layers (wall_layers)")
            for n in geo[2]:
                role[n] = "wall"
            return (lines + geo[0], thin + geo[1]), {**found, **{n: f"by geometry: {geo[3]}"
                                                               for n in geo[2]}}
    if lines or thin:
        if given is None:  # walls on a layer no name explains besides the named ones? say so, take nothing
            geo = _walls_by_geometry(d, parts, role, radius, single)
            around = _enclosing(geo[4], closing_solid(lines, thin, radius, single)) if geo else []
            if around:
                d.notes.append(f"the named wall layers close no room; took {', '.join(around)} too: single lines "
                               "enclosing rooms around them; if that is wrong, name the wall layers (wall_layers)")
                for n in around:
                    role[n] = "wall"
                return (lines + [ln for n in around for ln in geo[4][n]], thin), {
                    **found, **{n: "by geometry: single lines enclosing rooms around the named walls" for n in around}}
            extra = sum(ln.length for ln in geo[0]) if geo else 0.0
            if extra >= ALSO_WALLS_SHARE * named:
                d.notes.append(f"{', '.join(geo[2])} also hold{'s' if len(geo[2]) == 1 else ''} {geo[3]} like walls "
                               f"({extra:.0f} m); if they are walls, name every wall layer "
                               "(wall_layers)")
        return (lines, thin), found
    raise InputError(_no_walls_message(path, d, given), option="wall_layers")


def _walls_by_geometry(d: Drawing, parts: dict, role: dict, radius: float, single: float) -> tuple | None:
    """(wall lines, wall-thin fills, layers, what they hold: 'parallel line pairs 0.25 m
    apart' / 'single lines enclosing rooms', the single-line layers -> their straight
    lines) of the layers no name explains whose linework looks like walls
    (dxf_walls.wall_layers_by_geometry: of a layer of pairs its wall faces, of a layer of
    single-line walls its straight lines); None when there are none."""
    by_line, by_fill, straight = defaultdict(list), defaultdict(list), defaultdict(list)
    arcs = [sh.geom for got in parts.values() for sh in got if sh.kind == "ARC" and isinstance(sh.geom, LineString)]
    for sh in parts.get("none", []) + parts.get("other", []):
        if role.get(sh.layer) == "furniture":  # objects (a layer found to hold them)
            continue
        if not isinstance(sh.geom, LineString):
            by_fill[sh.layer] += polygons_of(sh.geom)
        elif role.get(sh.layer) in (None, "door"):  # a door layer's lines here are longer than a door
            by_line[sh.layer].append(sh.geom)
            if sh.kind in STRAIGHT and sh.geom.length >= MIN_SEGMENT_M:
                straight[sh.layer].append(sh.geom)
    for n, ls in straight.items():  # door leaves drawn as lines are no single-line walls
        leaf = door_leaves(ls, arcs)
        straight[n] = [ln for ln, x in zip(ls, leaf) if not x]
        if leaf.any():
            d.skipped["door leaves drawn as a line from a swing's centre (no wall)"] += int(leaf.sum())
    stats = layer_pairs(by_line, by_fill)
    chosen = wall_layers_by_geometry(stats, {n: single_line_rooms(ls) for n, ls in straight.items()})
    things = [sh for sh in parts.get("none", []) + parts.get("other", []) if sh.layer in chosen]
    named = closing_solid(*lines_fills(parts.get("wall", [])), radius, single)
    for n in _objects(d, {n: [sh for sh in things if sh.layer == n] for n in chosen}, role, {}, radius, single,
                      named):
        del chosen[n]
    if not chosen:
        return None
    what = []
    paired = [n for n, m in chosen.items() if m == "pairs"]
    gaps = np.concatenate([stats[n].gaps for n in paired] or [np.zeros(0)])
    if len(gaps):
        lo, hi = np.percentile(gaps, [10, 90])
        what.append(f"parallel line pairs {lo:.2f} m apart" if hi - lo < 0.005 else
                    f"parallel line pairs {lo:.2f}-{hi:.2f} m apart")
    if len(paired) < len(chosen):
        what.append("single lines enclosing rooms")
    lines = [ln for n, m in chosen.items() for ln in (stats[n].lines if m == "pairs" else straight[n])]
    return (lines, [q for n in chosen for q in by_fill.get(n, []) if is_wall_fill(q)], list(chosen),
            "; ".join(what) or "wall-thin filled areas", {n: straight[n] for n, m in chosen.items() if m == "single"})


def _enclosing(singles: dict[str, list], named) -> list[str]:
    """The single-line wall layers (layer -> straight lines, m) whose lines span the
    ``named`` wall solid (90 % of it within their hull grown by 0.5 m), where those named
    walls close no room; [] where they do."""
    if not singles or named.is_empty or encloses_room(named):
        return []
    return [n for n, ls in singles.items()
            if shapely.union_all(ls).convex_hull.buffer(0.5).intersection(named).area >= 0.9 * named.area]


def _no_walls_message(path: Path, d: Drawing, given) -> str:
    per = defaultdict(Counter)
    for (layer, kind), n in d.inventory.items():
        if kind in LINEWORK or kind in FILLED or kind == "MLINE":
            per[layer][kind] += n
    ranked = sorted(per, key=lambda la: -sum(per[la].values()))
    listing = ", ".join(f"{la} ({', '.join(f'{n} {k}' for k, n in per[la].most_common())})" for la in ranked[:12])
    listing += f" and {len(ranked) - 12} more" if len(ranked) > 12 else ""
    where = (f"on the layers {', '.join(given)}" if given else
             "(no layer is named like walls - WALL, WAND, MUR, MURO, PARED, PAREDE, PARETE, A-WALL, ... - and none "
             "holds parallel line pairs 5-60 cm apart or single lines enclosing rooms)")
    have = f"the layers with linework are {listing}" if ranked else "the drawing has no linework"
    return f"{path}: no walls found {where}; {have}; name the wall layers (wall_layers)"


def layers_of(shapes: list[Shape], how: dict) -> dict[str, str]:
    return {sh.layer: how.get(sh.layer, "by name") for sh in shapes}


def listing(d: Drawing, layers: dict[str, str], counts: bool = True, most: int = 8) -> str:
    """'E41_AUSSENWAENDE (212 LINE, 4 HATCH), E61_INNENWAENDE (80 LINE) (by name)'."""
    per = defaultdict(Counter)
    for (layer, kind), n in d.inventory.items():
        if layer in layers and (kind in LINEWORK or kind in FILLED):
            per[layer][kind] += n
    names = sorted(layers, key=lambda la: -sum(per[la].values()))
    text = ", ".join(f"{la} ({', '.join(f'{n} {k}' for k, n in per[la].most_common(3))})" if counts and per[la]
                     else la for la in names[:most])
    text += f" and {len(names) - most} more" if len(names) > most else ""
    hows = sorted(set(layers.values()))
    return f"{text} ({'; '.join(hows)})" if hows else text
