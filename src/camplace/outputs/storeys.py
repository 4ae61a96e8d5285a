"""A building's storeys in the output files (issue 33): which storey each camera hangs on.

placement.json's cameras each carry ``storey`` (the storey's name) with their position in
building coordinates (z is the building's, not above the storey floor); the storey is
the one whose floor is the highest at or below the camera (camplace.scene.build.storey_index).
"""

from __future__ import annotations

import numpy as np

from camplace.scene.build import storey_index


def mark_storeys(pdict: dict, scene) -> None:
    """Add ``storey`` to every camera of the placement.json dict ``pdict`` (scene frame) and
    ``storeys`` ([{name, elevation_m, top_m}], lowest first) to ``pdict``, for a building
    ``scene`` (camplace.scene.build.Scene with storeys); nothing for one room."""
    storeys = getattr(scene, "storeys", ())
    if not storeys:
        return
    cams = pdict.get("cameras", [])
    z = np.array([c["position"][2] for c in cams], np.float64)
    for c, k in zip(cams, storey_index(storeys, z) if len(cams) else []):
        c["storey"] = storeys[int(k)].name
    pdict["storeys"] = [{"name": st.name, "elevation_m": round(float(st.elevation), 4), "top_m": round(float(st.top), 4)}
                        for st in storeys]


def storey_cameras(pdict: dict, name: str) -> list[dict]:
    """The placement.json cameras on storey ``name``."""
    return [c for c in pdict.get("cameras", []) if c.get("storey") == name]
