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


def cameras_ifc_wanted(scene) -> bool:
    """True for a building or an IFC input: those runs write cameras.ifc."""
    return bool(getattr(scene, "storeys", ())) or bool((getattr(scene, "info", None) or {}).get("source"))


def write_run_cameras_ifc(out_dir, pdict: dict, scene, models: list) -> dict:
    """cameras.ifc of a run (camplace.outputs.cameras_ifc): a copy of the IFC input (the
    scene's ``info['source']``: {"file", "storey": {name, elevation_m}} of a one-storey run,
    whose z then gains the storey's elevation) or a new IFC4 model of the building's storeys,
    with every camera of ``pdict`` (placement.json, scene frame) at its building pose;
    ``models``: each camera's CameraModel (its DORI distances and range). {} when the run
    is neither a building nor an IFC."""
    from pathlib import Path

    from camplace.outputs.cameras_ifc import ifc_camera_extras, write_cameras_ifc

    if not cameras_ifc_wanted(scene):
        return {}
    source = (getattr(scene, "info", None) or {}).get("source") or {}
    one = source.get("storey")  # a one-storey run of an IFC: z above that storey's floor
    cams = []
    for c, m in zip(pdict.get("cameras", []), models):
        c = dict(c, **ifc_camera_extras(m))
        if one and "storey" not in c:
            p = list(c["position"])
            c.update(storey=one["name"], position=[p[0], p[1], p[2] + float(one["elevation_m"])])
        cams.append(c)
    storeys = [{"name": s["name"], "elevation_m": s["elevation_m"]} for s in pdict.get("storeys", [])]
    if one and not storeys:
        storeys = [{"name": one["name"], "elevation_m": float(one["elevation_m"])}]
    if not storeys and not source.get("file"):
        return {}
    path = Path(out_dir) / "cameras.ifc"
    write_cameras_ifc(path, cams, storeys, Path(source["file"]) if source.get("file") else None,
                      project=str(pdict.get("scene", "camplace")))
    return {"cameras.ifc": path}


def cameras_ifc_writer(out_dir, result) -> list:
    """The ``cameras-ifc`` output writer (entry point of camplace.outputs, issue 35): cameras.ifc
    for a building or an IFC input (write_run_cameras_ifc), nothing otherwise or without a
    scene (``camplace solve``). ``result``: camplace.outputs.writers.OutputResult; a plan's
    input frame is its scene frame (plan imports are not moved), so the poses are used as
    placement.json has them."""
    from camplace.outputs.bom import selected_models

    scene, vis = result.scene, result.visibility
    if scene is None or vis is None or result.solution is None or not cameras_ifc_wanted(scene):
        return []
    pdict = dict(result.placement)
    mark_storeys(pdict, scene)
    models = selected_models(vis.candidates, result.solution.selected)
    return list(write_run_cameras_ifc(out_dir, pdict, scene, models).values())
