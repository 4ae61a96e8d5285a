"""Plan images: room names and printed areas read by OCR from the text in or beside each
room (image_ocr reads the lines; this module gives each room its name)."""

from __future__ import annotations

from collections import Counter

import numpy as np
from scipy import ndimage

from camplace.scene.importers.image_ocr import NUMBER_RE, read_lines, room_name, room_number, text_lines_mask


def name_rooms(engine, dark: np.ndarray, ink: np.ndarray, plans: list) -> None:
    """Room names and printed areas (``plans``: image.PlanRooms, their ``names`` and
    ``printed`` filled in) from the text lines in or beside each room (a label
    whose middle falls on no room, e.g. inside the ring around a room number, goes to
    the nearest room within 1.5 character heights; none on a wall); one OCR call. A room
    number read for two rooms of a plan stays with the more confident reading (the other is
    misread); a word may name several rooms (two flats' 'Living Room'), each with its room
    number where it has one ('Living Room B102', as the IFC import names them), else the
    zones become 'Living Room', 'Living Room-2'."""
    lines, n, hc = text_lines_mask(ink)
    if n == 0:
        return
    boxes = ndimage.find_objects(lines)
    where: dict[int, tuple[int, int]] = {}
    for i, plan in enumerate(plans):
        room_at = np.where(np.isin(plan.labels, plan.rooms), plan.labels, 0)
        gap, (near_r, near_c) = ndimage.distance_transform_edt(room_at == 0, return_indices=True)
        for k, b in enumerate(boxes, 1):
            if b is None:
                continue
            r, c = (b[0].start + b[0].stop) // 2 - plan.box[0].start, (b[1].start + b[1].stop) // 2 - plan.box[1].start
            if (0 <= r < room_at.shape[0] and 0 <= c < room_at.shape[1] and gap[r, c] <= 1.5 * hc
                    and not plan.walls[r, c]):
                where[k] = (i, int(room_at[near_r[r, c], near_c[r, c]]))
    found: dict[tuple[int, int], list] = {}
    for ln in read_lines(engine, dark, ink, lines, sorted(where), hc):
        k = int(np.max(lines[ln.box[0]:ln.box[2], ln.box[1]:ln.box[3]]))
        found.setdefault(where[k], []).append(ln)
    best: dict[tuple, tuple[float, int]] = {}
    numbers: dict[tuple[int, int], str] = {}
    for (i, room), got in found.items():
        name, conf, area = room_name(got, hc)
        key = (i, name) if name and NUMBER_RE.match(name) else (i, name, room)  # words repeat: 'Bedroom', 'WC'
        if name and conf > best.get(key, (-1.0, 0))[0]:
            best[key] = (conf, room)
        if area is not None:
            plans[i].printed[room] = area
        if (number := room_number(got, hc)) is not None and number != name:
            numbers[(i, room)] = number
    for (i, name, *_), (_, room) in best.items():
        plans[i].names[room] = name
    for i, plan in enumerate(plans):  # a word naming several rooms: with each one's number, as IFC's 'Foyer A101'
        seen = Counter(plan.names.values())
        for room, name in plan.names.items():
            if seen[name] > 1 and (i, room) in numbers:
                plan.names[room] = f"{name} {numbers[(i, room)]}"
