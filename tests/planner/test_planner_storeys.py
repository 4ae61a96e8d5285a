"""The planner on a building (issue 33): storeys in /api/scene, viewsheds at the working height
above each camera's own floor, and a camera moved to another floor."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from camplace.planner.errors import ApiError
from camplace.planner.opening import open_start
from camplace.planner.session import Session
from conftest import two_storeys

E1 = 3.5


@pytest.fixture(scope="module")
def building(tmp_path_factory):
    return open_start(two_storeys(E1), root=tmp_path_factory.mktemp("planner-building"))


@pytest.fixture
def session(building):
    return Session(building)


def test_scene_names_the_storeys_their_targets_and_mounts(session):
    from camplace.planner.sceneinfo import scene_payload

    sc = scene_payload(session)
    assert [s["name"] for s in sc["storeys"]] == ["Ground", "Level 1"]
    assert sc["storeys"][1]["elevation_m"] == E1 and sc["storeys"][1]["working_z_m"] == pytest.approx(E1 + 1.5)
    assert sc["storeys"][1]["footprint"] == [[0, 0], [6, 0], [6, 6], [0, 6]]
    assert len(sc["targets_storey"]) == len(sc["targets_xy"]) and set(sc["targets_storey"]) == {"Ground", "Level 1"}
    up = [m[2] for m, s in zip(sc["mounts"], sc["mounts_storey"]) if s == "Level 1"]
    assert up and all(E1 < z < E1 + 3.0 for z in up)


def test_cameras_carry_their_storey_and_see_their_own_floor(session):
    cams = session.state()["cameras"]
    assert sorted(c["storey"] for c in cams) == ["Ground", "Ground", "Level 1", "Level 1"]
    for c in cams:
        if c["storey"] == "Level 1":  # drawn at 1.5 m above its floor: not only through the 1 m² opening
            shed = shapely.Polygon(c["viewshed"])
            assert shed.area > 5.0 and shapely.box(0, 0, 6, 6).buffer(1e-6).contains(shed)


def test_a_camera_moves_to_another_floor_at_that_floors_mount_height(session):
    ground = next(c for c in session.state()["cameras"] if c["storey"] == "Ground")
    st = session.update(ground["id"], {"storey": "Level 1"})
    moved = next(c for c in st["cameras"] if c["id"] == ground["id"])
    assert moved["storey"] == "Level 1"
    assert moved["position"][2] == pytest.approx(ground["position"][2] + E1)  # same mount height above its floor
    mounts = session.mounts[(session.mounts[:, 2] > E1)]
    assert np.abs(mounts - moved["position"]).max(1).min() < 1e-6  # one of Level 1's mounts
    session.undo()
    assert next(c for c in session.state()["cameras"] if c["id"] == ground["id"])["storey"] == "Ground"


def test_unknown_storey_and_a_point_outside_its_floor_are_refused(session):
    cid = session.state()["cameras"][0]["id"]
    with pytest.raises(ApiError) as err:
        session.update(cid, {"storey": "Roof"})
    assert err.value.field == "storey" and "Ground, Level 1" in str(err.value)
    with pytest.raises(ApiError) as err:  # inside the ground floor's plan, outside Level 1's (6 m wide)
        session.update(cid, {"position": [7.0, 3.0, E1 + 2.5], "snap": False})
    assert err.value.field == "position" and "Level 1" in str(err.value)


def test_storey_is_a_string_in_a_camera_change():
    from camplace.planner.bodies import camera_change

    assert camera_change({"storey": "Level 1"}) == {"storey": "Level 1"}
    with pytest.raises(ApiError):
        camera_change({"storey": 1})


def test_a_snap_to_a_storey_with_taken_mounts_stays_on_that_storey(session):
    """Taken mounts are skipped without losing the storey (issue 37: the free mask was overwritten)."""
    up = session.mounts[session.mounts[:, 2] > E1]
    ground = session.mounts[session.mounts[:, 2] < E1]
    got = session.snap(ground[0], up[:1], "Level 1")  # a ground point, one Level 1 mount taken
    assert got[2] > E1 and np.abs(got - up[0]).max() > 1e-3
