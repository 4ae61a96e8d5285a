"""Issue 33's acceptance on the real Duplex (../shared/data/plans, buildingSMART sample):
``camplace run Duplex_A_20110907.ifc --storey all --budget 12`` is one run folder with 12
cameras in total over Level 1 and Level 2; each names its storey and stands inside a room
of that storey, between its floor and ceiling in building z; cameras.ifc holds 12 camera
elements, each contained in the storey placement.json names, within 0.05 m of its position."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
import yaml
from shapely.geometry import Point, Polygon

ifcopenshell = pytest.importorskip("ifcopenshell")
import ifcopenshell.util.element as ifc_element  # noqa: E402
import ifcopenshell.util.placement as ifc_placement  # noqa: E402

from tests.conftest import SHARED  # noqa: E402

DUPLEX = SHARED / "data" / "plans" / "Duplex_A_20110907.ifc"


@pytest.fixture(scope="module")
def duplex_run(tmp_path_factory):
    if not DUPLEX.is_file():
        pytest.skip("../shared/data/plans/Duplex_A_20110907.ifc absent")
    out = tmp_path_factory.mktemp("duplex") / "run"
    from camplace.cli import main

    mp = pytest.MonkeyPatch()
    mp.setattr(sys, "argv", ["camplace", "--quiet", "run", str(DUPLEX), "--storey", "all", "--budget", "12", "--out",
                             str(out), "--no-plan", "--no-cache", "--repeatable"])
    try:
        main()
    except SystemExit as e:
        assert not e.code, e.code
    finally:
        mp.undo()
    return out


def test_one_folder_twelve_cameras_each_in_a_room_of_its_storey(duplex_run):
    out = duplex_run
    placement = json.loads((out / "placement.json").read_text())
    cams = placement["cameras"]
    assert len(cams) == 12
    assert {c["storey"] for c in cams} == {"Level 1", "Level 2"}
    storeys = {s["name"]: s for s in placement["storeys"]}
    assert storeys["Level 2"]["elevation_m"] == pytest.approx(3.1)
    data = yaml.safe_load((out / "building.yaml").read_text())  # the building the run planned
    for c in cams:
        st = storeys[c["storey"]]
        x, y, z = c["position"]
        assert st["elevation_m"] < z < st["top_m"]
        rooms = [Polygon(zn["polygon"]) for zn in data["storeys"][c["storey"]]["zones"] if zn.get("polygon")]
        assert any(r.buffer(1e-6).contains(Point(x, y)) for r in rooms), c


def test_cameras_ifc_holds_every_camera_in_its_storey(duplex_run):
    out = duplex_run
    cams = json.loads((out / "placement.json").read_text())["cameras"]
    model = ifcopenshell.open(str(out / "cameras.ifc"))
    source = ifcopenshell.open(str(DUPLEX))
    assert {s.GlobalId for s in model.by_type("IfcBuildingStorey")} == {s.GlobalId for s in
                                                                        source.by_type("IfcBuildingStorey")}
    elements = [e for e in model.by_type("IfcFlowTerminal") if e.ObjectType == "CAMERA"]  # IFC2X3
    assert len(elements) == 12
    by_pos = sorted(cams, key=lambda c: tuple(c["position"]))
    placed = sorted(((ifc_placement.get_local_placement(e.ObjectPlacement)[:3, 3], ifc_element.get_container(e).Name)
                     for e in elements), key=lambda p: tuple(p[0]))
    for c, (pos, storey) in zip(by_pos, placed):
        assert np.linalg.norm(np.asarray(c["position"]) - pos) < 0.05
        assert storey == c["storey"]
