"""Mount rules (issue 17): where cameras may hang.

``mount_rules.forbid`` polygons (floor plan, m) hold no camera (their boundary included);
with ``allow`` cameras hang only inside those polygons (boundary included); ``points``
(a CSV of x,y,z, metres, header optional) replaces the grid positions of every mount.
The same rules bound refined and adaptive poses (camplace.improve.refine.pose_box).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import Polygon
from shapely.ops import unary_union

from camplace.core.errors import InputError
from camplace.scene.build import Scene


def _union(polygons) -> object:
    return unary_union([Polygon(p) for p in polygons])


def allowed_xy(scene: Scene, xy: np.ndarray) -> np.ndarray:
    """(M,) bool: mount positions (M, 2) m that the rules allow (all True without rules)."""
    rules = scene.spec.mount_rules
    xy = np.asarray(xy, float).reshape(-1, 2)
    ok = np.ones(len(xy), bool)
    if rules.allow is not None:
        ok &= shapely.intersects_xy(_union(rules.allow), xy[:, 0], xy[:, 1])
    if rules.forbid:
        ok &= ~shapely.intersects_xy(_union(rules.forbid), xy[:, 0], xy[:, 1])
    return ok


def restrict_region(scene: Scene, region) -> object:
    """``region`` (shapely geometry) cut to the allowed mount area: inside ``allow`` (if
    given), outside every ``forbid`` polygon (its boundary too, for contains_xy tests)."""
    rules = scene.spec.mount_rules
    if rules.allow is not None:
        region = region.intersection(_union(rules.allow))
    if rules.forbid:
        region = region.difference(_union(rules.forbid))
    return region


def points_path(scene: Scene) -> Path | None:
    """The ``mount_rules.points`` file, resolved against the scene file's folder (None if not given)."""
    name = scene.spec.mount_rules.points
    if name is None:
        return None
    p = Path(name).expanduser()
    return p if p.is_absolute() or scene.base_dir is None else Path(scene.base_dir) / p


def explicit_points(scene: Scene) -> np.ndarray | None:
    """(K, 3) m: the mount points of ``mount_rules.points`` (rows x,y,z; a first row that is
    not numbers is a header; blank and '#' lines skipped), or None when not given."""
    path = points_path(scene)
    if path is None:
        return None
    key = f"{scene.spec.name}: mount_rules.points"
    try:
        rows = list(csv.reader(path.read_text(encoding="utf-8-sig").splitlines()))
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"{key}: cannot read '{path}' ({err})") from None
    rows = [r for r in rows if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    out = []
    for n, row in enumerate(rows):
        try:
            xyz = [float(c) for c in row[:3]]
        except ValueError:
            if n == 0:
                continue  # header
            raise InputError(f"{key}: line {n + 1} of '{path.name}': expected x,y,z numbers, got {row}") from None
        if len(xyz) != 3 or not all(math.isfinite(v) for v in xyz):
            raise InputError(f"{key}: line {n + 1} of '{path.name}': expected x,y,z finite numbers, got {row}")
        out.append(xyz)
    if not out:
        raise InputError(f"{key}: '{path.name}' holds no x,y,z row; expected one mount point per line")
    return np.asarray(out, float)
