"""The state's JSON with each camera encoded once (camplace.planner.statejson, issue 37)."""

from __future__ import annotations

import json

from starlette.responses import JSONResponse

from camplace.planner.session import Session
from camplace.planner.statejson import CameraObject, dumps, state_bytes


def test_state_bytes_are_the_json_of_the_state_after_edits(opened):
    s = Session(opened)
    first = s.cams[0]
    states = [s.state(), s.update(first.id, {"yaw_deg": 33.0}), s.update(first.id, {"locked": True}),
              s.add({"position": s.mounts[0][:2].tolist()}), s.undo()]
    for st in states:
        assert json.loads(state_bytes(st)) == json.loads(JSONResponse(st).body)
    assert all(isinstance(c, CameraObject) for c in states[-1]["cameras"])
    assert states[1]["cameras"][0]["yaw_deg"] == 33.0 and states[2]["cameras"][0]["locked"] is True
    assert len(s._json) == len(s.cams)  # only the current cameras' encodings are kept


def test_a_camera_object_reads_as_a_dict_and_encodes_its_positions():
    obj = CameraObject(3, 1, {"id": "C9", "viewshed": [[0.5, 1.0]]}, dumps({"id": "C9", "viewshed": [[0.5, 1.0]]}))
    assert obj == {"candidate_id": 3, "location_id": 1, "id": "C9", "viewshed": [[0.5, 1.0]]}
    empty = CameraObject(0, 0, {}, "{}")
    state = {"cameras": [obj, empty, {"plain": "é"}], "version": 2}
    assert json.loads(state_bytes(state)) == {"cameras": [dict(obj), {"candidate_id": 0, "location_id": 0},
                                                          {"plain": "é"}], "version": 2}
    assert json.loads(state_bytes({"cameras": []})) == {"cameras": []}
