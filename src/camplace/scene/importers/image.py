"""Plan images (PNG/JPG/TIFF: CAD exports, scans, coloured sheets) -> a scene mapping and
what was understood of them (camplace.scene.importers.read_plan).

Scale from ``scale`` (m per pixel) or ``ref`` (two pixel points and their distance in
m). Step by step (image_walls, image_rooms, image_ocr, image_text):

1. Ink: pixels darker than ``threshold`` in their brightest channel (Otsu unless given;
   flat colour room fills are light there, and fills darker than the split are split off).
2. Walls: the ink closed over ``hatch_spacing`` (outlines with a hatch, walls drawn as two
   lines become solid; broad textured areas such as stair treads are given back), strokes
   thinner than ``min_wall_thickness`` opened away (text, dimension lines, door swings).
   When no such stroke encloses a room, the plan is drawn in single lines (hairlines):
   the straight lines are the walls, drawn LINE_WALL_M thick (image_walls.line_walls).
3. Plans: the drawn wall pieces joined across their openings form a plan, not across a
   gutter no room spans (image_walls.gutter_bridges); marks off the plans (title block,
   legend, scale bar, key plan) and text blocks are dropped. Several plans side by side
   (storeys on one sheet) are ``storeys``; the default is the one with most rooms.
4. Each plan (image_poche.settle): lines running past the building (grid, dimension
   lines) are not walls; a closed door-less strip up to a wall thick is a wall's inside,
   or in a plan of solid walls a counter or piece of furniture (an obstacle FURNITURE_M high).
5. Rooms: door and window gaps up to ``max_opening`` between walls in line are bridged
   (for the rooms only: the walls keep their openings); the enclosed free regions of at
   least ``min_room_area`` are the rooms, named by the text OCR reads inside them.

A PDF of several pages is a plan set: read_storeys gives one storey per page
(image_pages: named by the level its text gives, else page-N).
"""

from __future__ import annotations

import math
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import shapely
from scipy import ndimage

from camplace.core.errors import InputError
from camplace.scene.importers import (DEFAULT_CEILING_M, PlanImport, clean_polygons, plan_scene, polygons_of,
                                      prism_obstacles, room_zones, rooms_footprint)
from camplace.scene.importers.image_names import name_rooms
from camplace.scene.importers.image_ocr import ocr_engine
from camplace.scene.importers.image_poche import FURNITURE_M, settle
from camplace.scene.importers.image_pages import is_pdf, page_count, page_names, page_of_storey, printed_scale
from camplace.scene.importers.image_read import metres_per_pixel, read_sheet
from camplace.scene.importers.image_rooms import colour_rooms, free_regions, mask_polygons
from camplace.scene.importers.image_scale import scale_from_sheet
from camplace.scene.importers.image_walls import (EIGHT, HOLLOW_WALL_M, LINE_WALL_M, REACH_M,
                                                  brightness, colour_lines, find_plans, ink_threshold, line_walls,
                                                  otsu_threshold, solid_walls)

HOLLOW_GAIN = 1.25  # the walls read as empty outlines are taken when their rooms are this much larger
PLAN_RE = re.compile(r"plan-\d+")  # a plan of a sheet, as storeys names it
WORK_M_PER_PX = 0.01  # images finer than this are read at an integer fraction of their pixels
OPTIONS = ("scale", "ref", "threshold", "storey", "min_wall_thickness", "max_wall_thickness", "hatch_spacing",
           "max_opening", "min_room_area", "ocr", "page")


def darkest_of_blocks(rgb: np.ndarray, f: int) -> np.ndarray:
    """(H // f, W // f, 3) uint8: each channel's darkest value in every f x f block of
    ``rgb`` (H, W, 3), so hairlines and small text stay ink at the coarser scale (the
    last rows and columns that do not fill a block are left out)."""
    h, w = rgb.shape[0] // f * f, rgb.shape[1] // f * f
    return rgb[:h, :w].reshape(h // f, f, w // f, f, 3).min(axis=(1, 3))


@dataclass
class PlanRooms:
    """One plan of the sheet: ``box`` (rows, cols slices of the sheet), its ``walls`` and
    ``bridges`` (bool masks in the box), free-region ``labels`` (int, in the box), the
    labels that are ``rooms`` and their ``names`` (None: not read) and printed areas, the
    pixels of its ``outline``, the ``enclosed`` mask: the free space inside the outer
    walls (rooms, stairs, closets), the ``objects`` mask (counters, furniture: image_poche)
    and its thickest wall (m, at least max_wall_thickness)."""

    box: tuple[slice, slice]
    walls: np.ndarray
    bridges: np.ndarray
    labels: np.ndarray
    rooms: list[int]
    names: dict[int, str] = field(default_factory=dict)
    printed: dict[int, float] = field(default_factory=dict)
    coloured: int = 0
    outline_px: int = 0
    enclosed: np.ndarray | None = None
    objects: np.ndarray | None = None
    max_wall: float = 0.0


@dataclass
class Sheet:
    """What was read of the image: scale ``s`` (m/px) and its source, the ink ``threshold``
    and how it was chosen, the ``plans`` in reading order, the image's ``rows``, the OCR
    line ('tesseract X' or why not), what was ``skipped`` and the thickest wall (m)."""

    s: float
    scale_from: str
    threshold: float
    threshold_from: str
    plans: list[PlanRooms]
    rows: int
    ocr: str
    skipped: Counter
    max_wall: float
    walls_from: str = "strokes"


def analyse(path: Path, scale=None, ref=None, threshold=None, min_wall_thickness=0.08, max_wall_thickness=0.8,
            hatch_spacing=0.3, max_opening=1.8, min_room_area=1.0, ocr=True, page=None) -> Sheet:
    """The plans, walls, openings, rooms and room names of a plan image (or of page ``page``
    of a PDF; ``scale`` m per pixel or a drawing scale '1:N', see image_read)."""
    for key, value in (("min_wall_thickness", min_wall_thickness), ("max_wall_thickness", max_wall_thickness),
                       ("hatch_spacing", hatch_spacing), ("max_opening", max_opening), ("min_room_area", min_room_area)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise InputError(f"{key}: expected a number > 0 ({'m²' if key == 'min_room_area' else 'm'}), got {value}",
                             option=key)
    paper = read_sheet(path, page, scale)
    rgb = paper.rgb
    dark = brightness(rgb)
    engine, ocr_line = ocr_engine() if ocr else (None, "off")
    read = metres_per_pixel(path, paper, scale, ref)
    if read is None:
        if engine is not None:
            read = scale_from_sheet(engine, dark, dark < otsu_threshold(dark))
        if read is None and paper.pdf and (printed := printed_scale(path, page or 1)) is not None:
            s, how = metres_per_pixel(path, paper, f"1:{printed}", None)  # a PDF printed at its drawing scale
            read = s, f"{how}: the scale printed on the page, if the page was printed to scale; check it"
        if read is None:
            why = ("no dimension line nor scale bar could be read" if engine is not None else
                   f"OCR not available: {ocr_line}")
            how = ("its drawing scale 1:N, e.g. 1:100 (scale)" if paper.pdf else "metres per pixel or a drawing scale "
                   "1:N (scale) or two reference points and their distance (ref)")
            raise InputError(f"{path}: the plan's scale is unknown ({why}); give {how}", option="scale")
    s, scale_from = read
    if paper.about:
        scale_from += f"; {paper.about}"
    if s * 2 <= WORK_M_PER_PX:  # a fine scan: read at WORK_M_PER_PX or finer (4x fewer pixels at 1/2)
        f = int(WORK_M_PER_PX // s)
        scale_from += f"; the image's {s:g} m/px read at 1/{f} of its pixels"
        rgb, s = darkest_of_blocks(rgb, f), s * f
        dark = brightness(rgb)
    if threshold is None:
        t, how = ink_threshold(dark, s, max_wall_thickness)
    else:
        if not (isinstance(threshold, (int, float)) and 0 < threshold <= 255):
            raise InputError(f"threshold: expected a grey level > 0 and <= 255, got {threshold}", option="threshold")
        t, how = float(threshold), "given"
    ink = dark < t
    opts = (s, hatch_spacing, min_wall_thickness, max_wall_thickness, max_opening, min_room_area)
    raw_any, plans, skipped, walls_from = _wall_passes(ink, rgb, *opts)
    if not any(p.rooms for p in plans):  # walls drawn in colour (a CAD plot: red, cyan, blue pens)?
        pens = colour_lines(rgb) & ~ink
        if pens.any():
            got = _wall_passes(ink | pens, rgb, *opts)
            if any(p.rooms for p in got[1]):
                raw_any, plans, skipped, walls_from = got
                walls_from += "; coloured lines read as ink"
                ink = ink | pens
    if not raw_any and not plans:
        raise InputError(f"{path}: no walls found (no dark strokes at least {min_wall_thickness} m thick, "
                         f"nor single lines enclosing a room); walls drawn lighter than the ink: give a threshold above "
                         f"{t:g} (threshold); walls thinner: a smaller min_wall_thickness")
    if not any(p.rooms for p in plans):
        raise InputError(f"{path}: no closed room found (no free region of at least {min_room_area} m² "
                         f"enclosed by walls at {s:g} m/px); check the scale (scale), or give a larger max_opening "
                         f"than {max_opening:g} m where a wide opening leaves the rooms open")
    if engine is not None:
        name_rooms(engine, dark, ink, plans)
    return Sheet(s, scale_from, t, how, plans, dark.shape[0], ocr_line, skipped, max_wall_thickness, walls_from)


def _wall_passes(ink: np.ndarray, rgb: np.ndarray, s: float, hatch_spacing: float, min_wall: float,
                 max_wall: float, max_opening: float, min_room_area: float) -> tuple[bool, list, Counter, str]:
    """(any wall found, plans, skipped, how the walls were read) of the ink mask: solid
    strokes; walls drawn as empty outlines when that encloses clearly more room; single
    lines when neither encloses a room."""
    skipped: Counter = Counter()
    hollow_skipped: Counter = Counter()
    raw, hollow = solid_walls(ink, s, hatch_spacing, min_wall, max_wall, skipped, hollow_skipped)
    plans = _plans(raw, ink, rgb, s, max_opening, max_wall, min_room_area, skipped) if raw.any() else []
    walls_from = f"strokes at least {min_wall:g} m thick"
    if hollow is not None and (hollow != raw).any():  # walls drawn as empty outlines: when they enclose clearly more
        hollow_plans = _plans(hollow, ink, rgb, s, max_opening, max_wall, min_room_area, hollow_skipped)
        if _room_px(hollow_plans) > HOLLOW_GAIN * _room_px(plans):
            raw, plans, skipped = hollow, hollow_plans, hollow_skipped
            walls_from += f" and walls drawn as empty outlines up to {HOLLOW_WALL_M:g} m wide"
    if not any(p.rooms for p in plans):  # a plan drawn in single lines (hairlines)?
        lines, line_skipped = line_walls(ink, s, max_opening), Counter()
        line_plans = _plans(lines, lines, rgb, s, max_opening, max_wall, min_room_area, line_skipped,
                            reach=max_opening) if lines.any() else []  # wall pieces between windows join
        if any(p.rooms for p in line_plans):
            plans, skipped = line_plans, line_skipped
            walls_from = f"single lines (no stroke {min_wall:g} m thick encloses a room), drawn {LINE_WALL_M:g} m thick"
    return bool(raw.any()), plans, skipped, walls_from


def _room_px(plans: list[PlanRooms]) -> int:
    """The pixels of all rooms of ``plans``."""
    return sum(int(np.isin(p.labels, p.rooms).sum()) for p in plans if p.rooms)


def _plans(raw: np.ndarray, ink: np.ndarray, rgb: np.ndarray, s: float, max_opening: float, max_wall: float,
           min_room_area: float, skipped: Counter, reach: float = REACH_M) -> list[PlanRooms]:
    """The plans of the wall mask ``raw`` with their openings and rooms (``reach``: m, see find_plans)."""
    found = find_plans(raw, ink, s, max_opening, max_wall, skipped, reach)
    plans = [_plan_rooms(found.plan_of, k, box, s, max_opening, max_wall, min_room_area, skipped, raw)
             for k, box in enumerate(found.plans, 1)]
    for plan in plans:
        _colour_split(plan, rgb, ink, s, min_room_area)
    return plans


def _plan_rooms(plan_of: np.ndarray, k: int, box, s: float, max_opening: float, max_wall: float,
                min_room_area: float, skipped: Counter, raw: np.ndarray) -> PlanRooms:
    """Plan ``k`` in its box (widened by an opening, paper beyond the sheet's edge):
    lines past the building dropped, wall insides and objects told (image_poche.settle,
    ``raw`` the sheet's walls), openings bridged, rooms found."""
    m = int(max_opening / s) + 2
    window = (slice(box[0].start, box[0].stop + 2 * m), slice(box[1].start, box[1].stop + 2 * m))
    walls = np.pad(plan_of == k, m)[window]
    box = (slice(box[0].start - m, box[0].stop + m), slice(box[1].start - m, box[1].stop + m))
    walls, bridges, objects, max_wall = settle(walls, s, max_opening, max_wall, skipped, np.pad(raw, m)[window])
    labels, n, outside = free_regions(walls | bridges)
    idle = _bridges_parting_nothing(bridges, labels)
    if idle.any():  # e.g. from a table drawn as a blot to a wall: the room goes round it
        bridges &= ~idle
        labels, n, outside = free_regions(walls | bridges)
    shape, _ = ndimage.label(~np.isin(labels, np.flatnonzero(outside[1:]) + 1))  # walls and what they enclose
    outline_px = int(np.bincount(shape.ravel())[1:].max(initial=0))
    enclosed = (labels > 0) & ~outside[labels]
    area = np.bincount(labels.ravel(), minlength=n + 1) * s * s
    inside = ~outside
    rooms = [int(r) for r in np.flatnonzero(inside & (area >= min_room_area))]
    small = int(np.count_nonzero(inside & (area < min_room_area) & (area > 0)))
    if small:
        skipped[f"enclosed pieces under {min_room_area:g} m² (not rooms)"] += small
    return PlanRooms(box, walls, bridges, labels, rooms, outline_px=outline_px, enclosed=enclosed, objects=objects,
                     max_wall=max_wall)


def _bridges_parting_nothing(bridges: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """The bridges (pixels) with one and the same free region all around them."""
    blab, nb = ndimage.label(bridges, EIGHT)
    if nb == 0:
        return np.zeros_like(bridges)
    ring = ndimage.maximum_filter(blab, size=3) * (labels > 0)  # free pixels beside a bridge, by bridge
    pairs = np.unique(np.stack([ring[ring > 0], labels[ring > 0]]), axis=1)
    sides = np.bincount(pairs[0], minlength=nb + 1)
    return np.r_[False, sides[1:] == 1][blab]


def _colour_split(plan: PlanRooms, rgb: np.ndarray, ink: np.ndarray, s: float, min_room_area: float) -> None:
    """Rooms told apart by their fill colours where no wall parts them (image_rooms.colour_rooms)."""
    m = plan.walls.shape
    pad = [(max(0, -plan.box[0].start), 0), (max(0, -plan.box[1].start), 0)]
    r0, c0 = max(0, plan.box[0].start), max(0, plan.box[1].start)
    crop = lambda a: np.pad(a[r0:plan.box[0].stop, c0:plan.box[1].stop],  # noqa: E731
                            pad + [(0, 0)] * (a.ndim - 2), mode="edge")
    colours, marks = crop(rgb), crop(ink)
    colours = np.pad(colours, [(0, m[0] - colours.shape[0]), (0, m[1] - colours.shape[1]), (0, 0)], mode="edge")
    marks = np.pad(marks, [(0, m[0] - marks.shape[0]), (0, m[1] - marks.shape[1])], mode="edge")
    plan.labels, plan.rooms, plan.coloured = colour_rooms(colours, marks, plan.walls, plan.labels, plan.rooms, s,
                                                          min_room_area)


def _polygons(plan: PlanRooms, sheet: Sheet, min_area: float):
    """(room (name, polygon) list, wall geometry, opening polygons) of a plan (m)."""
    boxes = ndimage.find_objects(plan.labels)
    at = (plan.box[0].start, plan.box[1].start)
    rooms = []
    for i, k in enumerate(plan.rooms):
        b = boxes[k - 1]
        poly = mask_polygons(plan.labels[b] == k, sheet.s, (at[0] + b[0].start, at[1] + b[1].start), sheet.rows)
        pieces = polygons_of(shapely.make_valid(poly.simplify(sheet.s / 2)))  # the room, not crumbs cut off it
        rooms.append((plan.names.get(k, f"room-{i + 1}"), max(pieces, key=lambda q: q.area) if pieces else poly))
    walls = mask_polygons(plan.walls, sheet.s, at, sheet.rows).simplify(sheet.s / 2)
    blab, nb = ndimage.label(plan.bridges)
    openings = [q for j, b in enumerate(ndimage.find_objects(blab), 1)
                for q in clean_polygons(mask_polygons(blab[b] == j, sheet.s, (at[0] + b[0].start, at[1] + b[1].start),
                                                      sheet.rows), min_area=min_area)]
    return rooms, walls, openings


def _footprint(plan: PlanRooms, sheet: Sheet, source: str):
    """The plan's footprint (m): the free space its walls enclose and its rooms (a porch
    drawn by its colour too) merged with the walls and bridged openings that bound them
    (outline_pieces: the outer face of the outer walls), the largest piece."""
    at = (plan.box[0].start, plan.box[1].start)
    inside = mask_polygons(plan.enclosed | np.isin(plan.labels, plan.rooms), sheet.s, at, sheet.rows)
    walls = mask_polygons(plan.walls | plan.bridges, sheet.s, at, sheet.rows)
    return rooms_footprint(polygons_of(inside.simplify(sheet.s / 2)), walls.simplify(sheet.s / 2),
                           max(sheet.max_wall, plan.max_wall),
                           source)


def _storey_rows(sheet: Sheet) -> list[dict]:
    """PlanImport.storeys: every plan of the sheet with its rooms (name, area m²) and the
    area of its outline (m²: the outer face of its walls, openings bridged)."""
    rows = []
    for i, plan in enumerate(sheet.plans):
        area = np.bincount(plan.labels.ravel()) * sheet.s * sheet.s
        rooms = [[plan.names.get(k, f"room-{j + 1}"), round(float(area[k]), 2)] for j, k in enumerate(plan.rooms)]
        rows.append({"name": f"plan-{i + 1}", "elevation_m": 0.0, "rooms": rooms, "chosen": False,
                     "outline_m2": round(plan.outline_px * sheet.s * sheet.s, 2)})
    return rows


def default_plan(sheet: Sheet) -> tuple[int, str]:
    """(index, why) of the plan a user plans first: the most rooms, then the most room area."""
    score = [(len(p.rooms), float(np.isin(p.labels, p.rooms).sum())) for p in sheet.plans]
    best = max(range(len(score)), key=lambda i: score[i])
    if len(score) == 1:
        return best, "the only plan on the sheet"
    tied = sum(1 for sc in score if sc[0] == score[best][0]) > 1
    return best, "most room area of the plans with most rooms" if tied else "most rooms"


def plan_import(path: Path, sheet: Sheet, index: int, why: str, *, name=None, wall_height=None,
                ceiling_height=None, heights=None, coverage=None, budget=None) -> PlanImport:
    """The scene and summary of plan ``index`` of the sheet."""
    plan = sheet.plans[index]
    if not plan.rooms:
        raise InputError(f"{path}: plan-{index + 1} has no closed room (no free region enclosed by walls)")
    rooms, walls, openings = _polygons(plan, sheet, sheet.s * sheet.s)
    ceiling = float(ceiling_height or DEFAULT_CEILING_M)
    src = {"file": path.name, "entity": "wall pixels", "threshold": f"{sheet.threshold:g}", "m_per_px": f"{sheet.s:g}"}
    skipped = Counter(sheet.skipped)
    obstacles = prism_obstacles(walls, 0.0, min(float(wall_height or ceiling), ceiling), "wall", src, tolerance=0,
                                skipped=skipped)
    n_walls = len(obstacles)
    if plan.objects is not None and plan.objects.any():
        shapes = mask_polygons(plan.objects, sheet.s, (plan.box[0].start, plan.box[1].start), sheet.rows)
        obstacles += prism_obstacles(shapes.simplify(sheet.s / 2), 0.0, min(FURNITURE_M, ceiling - 0.05), "furniture",
                                     dict(src, entity="outlines in rooms (counters, furniture)"), tolerance=0,
                                     skipped=skipped)
    footprint = _footprint(plan, sheet, str(path))
    zones = room_zones(rooms, coverage or 2, skipped=skipped)
    title = name or (path.stem if len(sheet.plans) == 1 else f"{path.stem} plan-{index + 1}")
    scene = plan_scene(title, footprint, ceiling, obstacles, zones, heights=heights, coverage=coverage, budget=budget)
    storeys = _storey_rows(sheet)
    storeys[index]["chosen"] = True
    named = len(plan.names)
    used = {"scale": f"{sheet.s:g} m/px ({sheet.scale_from})",
            "threshold": f"{sheet.threshold:g} of 255, brightest channel ({sheet.threshold_from})",
            "plans": f"{len(sheet.plans)} on the sheet; plan-{index + 1} ({why})",
            "walls": f"{n_walls} wall prisms from {sheet.walls_from}",
            "openings": f"{len(openings)} door and window gaps bridged",
            "ocr": sheet.ocr if not sheet.ocr.startswith("tesseract") else
            f"{sheet.ocr}: {named} of {len(plan.rooms)} rooms named"}
    if len(obstacles) > n_walls:
        used["furniture"] = (f"{len(obstacles) - n_walls} counters and furniture drawn as closed outlines in rooms, "
                             f"{min(FURNITURE_M, ceiling - 0.05):g} m high")
    notes = []
    if sheet.scale_from.startswith("read from") or "printed on the page" in sheet.scale_from:
        notes.append(f"scale {sheet.s:.5g} m/px {sheet.scale_from} against a length you know (or give scale or ref)")
    if len(sheet.plans) > 1:
        notes.append(f"{len(sheet.plans)} plans side by side on the sheet (" + ", ".join(
            f"{s['name']}: {len(s['rooms'])} rooms" for s in storeys) + f"): plan-{index + 1} taken ({why}); "
            "choose another with storey='plan-N', or storey='all' for every plan")
    if not sheet.ocr.startswith("tesseract") and sheet.ocr != "off":
        notes.append(f"OCR not available ({sheet.ocr}): rooms are named room-1..{len(plan.rooms)}")
    area = np.bincount(plan.labels.ravel()) * sheet.s * sheet.s
    for k, printed in plan.printed.items():
        label = plan.names.get(k, f"room-{plan.rooms.index(k) + 1}")
        notes.append(f"room {label}: printed {printed:g} m², measured {area[k]:.2f} m² "
                     f"({100 * (area[k] - printed) / printed:+.0f} %)")
    return PlanImport(scene, "image", used=used, skipped=skipped, openings=[
        [[round(float(x), 4), round(float(y), 4)] for x, y in q.exterior.coords[:-1]] for q in openings],
        storeys=storeys, notes=notes)


def _common(options: dict) -> tuple[dict, dict]:
    """(analysis options, scene options) of read's keyword options."""
    if options.get("units") is not None:
        raise InputError("units: a plan image has no units; give its scale (scale or ref)", option="units")
    scene_keys = ("name", "wall_height", "ceiling_height", "heights", "coverage", "budget")
    scene = {k: options[k] for k in scene_keys if k in options}
    analysis = {k: v for k, v in options.items() if k not in scene_keys and k not in ("units", "storey")}
    return analysis, scene


def read(path: Path, **options) -> PlanImport:
    """What was understood of the plan image (one plan: ``storey`` 'plan-N', else the
    default; of a PDF, ``storey`` may name a page as read_storeys names it)."""
    analysis, scene = _common(options)
    storey = options.get("storey")
    pages = page_names(path) if is_pdf(path) and analysis.get("page") is None else []
    label = None
    if storey is not None and pages and not PLAN_RE.fullmatch(storey):
        page = page_of_storey(storey, pages)
        if page is None:
            raise InputError(f"storey: {path.name} has no page '{storey}'; its pages are {', '.join(pages)} "
                             "(or 'all')", option="storey")
        analysis["page"], label, storey = page, pages[page - 1], None
    sheet = analyse(path, **analysis)
    if storey is None:
        index, why = default_plan(sheet)
    else:
        names = [f"plan-{i + 1}" for i in range(len(sheet.plans))]
        if storey not in names:
            raise InputError(f"storey: {path.name} has no plan '{storey}'; it has {', '.join(names)} "
                             "(or 'all')", option="storey")
        index, why = names.index(storey), "chosen"
    if label is not None:
        scene.setdefault("name", f"{path.stem} {label}")
    got = plan_import(path, sheet, index, why, **scene)
    if len(pages) > 1 and label is None:
        got.notes.append(f"{path.name} has {len(pages)} pages ({', '.join(pages)}): page 1 read; choose one with "
                         "page=N or storey='NAME', or storey='all' for every page")
    return got


def read_storeys(path: Path, **options) -> list[tuple[str, PlanImport]]:
    """(name, what was understood) of every plan with rooms: on a sheet, plan-N; of a PDF
    of several pages (page not given), one storey per page, named by the level its text
    gives or page-N (image_pages.page_names; 'NAME plan-K' for a page holding several plans)."""
    analysis, scene = _common(options)
    if is_pdf(path) and analysis.get("page") is None and page_count(path) > 1:
        return _page_storeys(path, analysis, scene)
    sheet = analyse(path, **analysis)
    return [(f"plan-{i + 1}", plan_import(path, sheet, i, "storey 'all'", **scene))
            for i, p in enumerate(sheet.plans) if p.rooms]


def _page_storeys(path: Path, analysis: dict, scene: dict) -> list[tuple[str, PlanImport]]:
    """One storey per page of a PDF plan set, each in its page's coordinates; a page that
    cannot be read (a cover, a legend, no scale) is left out with a note; none read:
    InputError (the first naming an option, as a scale to give, else one naming the pages)."""
    out, unread, rows, errors = [], [], [], []
    for page, name in enumerate(page_names(path), 1):
        try:
            sheet = analyse(path, **dict(analysis, page=page))
        except InputError as err:  # a cover, a legend, a page with no scale to read
            errors.append(err)
            unread.append((name, str(err).removeprefix(f"{path}: ")))
            continue
        with_rooms = [i for i, p in enumerate(sheet.plans) if p.rooms]
        for i in with_rooms:
            label = name if len(with_rooms) == 1 else f"{name} plan-{i + 1}"
            got = plan_import(path, sheet, i, f"page {page}", **{"name": f"{path.stem} {label}", **scene})
            out.append((label, got))
            rows.append(dict(got.storeys[i], name=label))
    causes: dict[str, list[str]] = {}
    for name, cause in unread:  # pages left out for one cause named together
        causes.setdefault(cause, []).append(name)
    left = [f"{', '.join(names)} ({cause})" for cause, names in causes.items()]
    if not out:
        first = next((e for e in errors if e.option is not None), None)
        if first is not None:  # the same option fails on the pages (a scale to give): its one line
            raise first
        raise InputError(f"{path}: no page holds a plan with a closed room: {'; '.join(left)}")
    for label, got in out:
        got.storeys = [dict(r, chosen=r["name"] == label) for r in rows]
        if left:
            got.notes.append(f"pages left out: {'; '.join(left)}")
    return out


def storey_elevations(path: Path, units=None) -> dict[str, float]:
    """A sheet says no floor levels: every plan at 0 m."""
    return {}


def import_plan(path: Path, **options) -> dict:
    """The scene mapping of a plan image (options as read)."""
    return read(path, **options).scene
