"""The planner on a building (issue 33): which storey a camera, a mount or a target is on,
each storey's floor plan for the page's floor selector, and moving a camera to another floor.

A building scene (camplace.scene.build.Scene with ``storeys``) is one session: positions
are in building z. A camera's viewshed is drawn at the working height above its own
storey's floor, the coverage raster holds each storey's layer nearest that height, and a
camera moved to another storey goes to that storey's allowed mount nearest its plan
position (so its z follows the storey's mount height).
"""

from __future__ import annotations

import numpy as np
import shapely

from camplace.planner.errors import ApiError
from camplace.scene.build import storey_index


def storeys_of(scene) -> tuple:
    """The scene's storeys (camplace.scene.build.Storey, lowest first); () for one room."""
    return tuple(getattr(scene, "storeys", ()))


def storey_at(scene, z) -> np.ndarray:
    """(N,) int: the storey index of building z values (N,) m; zeros for one room."""
    z = np.asarray(z, float).reshape(-1)
    st = storeys_of(scene)
    return storey_index(st, z) if st else np.zeros(len(z), np.int64)


def storey_names(scene, z) -> list[str | None]:
    """The storey name of each building z (N,) m; None for each in one room."""
    st = storeys_of(scene)
    return [st[int(k)].name if st else None for k in storey_at(scene, z)]


def storey_number(scene, name: str, field: str = "storey") -> int:
    """The index of storey ``name``; ApiError(field) naming the storeys when there is none."""
    names = [st.name for st in storeys_of(scene)]
    if name not in names:
        raise ApiError(f"{field}: no storey {name!r}; expected one of {', '.join(names) or '(one room: none)'}",
                       field)
    return names.index(name)


def nearest_layer(z: np.ndarray, idx: np.ndarray, height: float) -> np.ndarray:
    """The indices ``idx`` whose z (``z[idx]``, m) is the level nearest ``height`` m."""
    if not len(idx):
        return idx
    zi = z[idx]
    levels = np.unique(np.round(zi, 6))
    best = levels[np.argmin(np.abs(levels - height))]
    return idx[np.abs(zi - best) < 1e-6]


def storey_floor_layer(targets, scene, height: float) -> np.ndarray:
    """The coverage raster's targets: per storey, its volume targets in the layer nearest
    ``height`` m above its floor (one room: above z = 0)."""
    z = targets.positions[:, 2]
    vol = np.flatnonzero(~targets.is_surface)
    st = storeys_of(scene)
    if not st:
        return nearest_layer(z, vol, height)
    where = storey_at(scene, z[vol])
    return np.concatenate([nearest_layer(z, vol[where == k], s.elevation + height) for k, s in enumerate(st)])


def viewshed_height(scene, z: float, height: float) -> float:
    """The building z (m) of the working ``height`` above the floor of the storey at ``z``."""
    st = storeys_of(scene)
    return height + (st[int(storey_at(scene, z)[0])].elevation if st else 0.0)


def check_in_storey(scene, position: np.ndarray) -> None:
    """ApiError('position') unless the point lies in its storey's footprint, between its floor
    and ceiling (a building; a single room is checked by the session)."""
    x, y, z = (float(v) for v in position)
    st = storeys_of(scene)[int(storey_at(scene, z)[0])]
    if not shapely.intersects_xy(st.scene.polygon, x, y):
        raise ApiError(f"position: ({x:.3f}, {y:.3f}) is outside storey {st.name}'s footprint", "position")
    if not st.elevation < z < st.top:
        raise ApiError(f"position: z {z:.3f} m is outside storey {st.name} ({st.elevation:g}..{st.top:g} m)",
                       "position")


def floor_z(scene, name: str) -> float:
    """The building z (m) of storey ``name``'s floor."""
    return float(storeys_of(scene)[storey_number(scene, name)].elevation)


def same_height(scene, z: float, name: str) -> float:
    """Building z (m) at the same height above storey ``name``'s floor as ``z`` is above its own."""
    st = storeys_of(scene)
    return float(z) - st[int(storey_at(scene, z)[0])].elevation + st[storey_number(scene, name)].elevation


def storey_mounts(scene, mounts: np.ndarray, name: str) -> np.ndarray:
    """(M,) bool: which allowed mounts (M, 3) m lie on storey ``name``."""
    return storey_at(scene, mounts[:, 2]) == storey_number(scene, name)


def storeys_payload(scene, session_height: float, floor: np.ndarray, targets, mounts: np.ndarray) -> dict:
    """/api/scene's building keys: ``storeys`` ([{name, elevation_m, top_m, footprint,
    working_z_m}], [] for one room), ``targets_storey`` (the storey of each raster target) and
    ``mounts_storey`` (of each mount); None entries for one room."""
    st = storeys_of(scene)
    rows = [{"name": s.name, "elevation_m": float(s.elevation), "top_m": float(s.top),
             "footprint": np.round(np.asarray(s.scene.footprint, float), 4).tolist(),
             "working_z_m": float(s.elevation + session_height)} for s in st]
    return {"storeys": rows, "targets_storey": storey_names(scene, targets.positions[floor, 2]) if st else [],
            "mounts_storey": storey_names(scene, mounts[:, 2]) if st else []}
