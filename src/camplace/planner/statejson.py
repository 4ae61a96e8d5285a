"""The state's JSON without re-encoding every camera (issue 37).

Every mutating call answers the full state; with hundreds of cameras (their rotations,
intrinsics and viewshed polygons) encoding it is most of a change's time. A camera never
changes in place (a change makes a new one), so its JSON is encoded once:
:class:`CameraObject` is the camera's state object (a dict, as Python callers read it)
carrying the encoded JSON of all but its two positional keys (``candidate_id``: its row,
``location_id``: numbers every camera's position), which :func:`state_bytes` writes around
it. The bytes are the same JSON as starlette's JSONResponse of the dict (compact, UTF-8).
"""

from __future__ import annotations

import json

POSITIONAL = ("candidate_id", "location_id")  # the keys that depend on the other cameras


def dumps(obj) -> str:
    """Compact JSON as starlette's JSONResponse writes it (no NaN, UTF-8 text)."""
    return json.dumps(obj, ensure_ascii=False, allow_nan=False, indent=None, separators=(",", ":"))


class CameraObject(dict):
    """A camera's state object: ``candidate_id``, ``location_id``, then ``static`` (the
    dict of the other keys, encoded once into ``static_json``)."""

    __slots__ = ("static_json",)

    def __init__(self, candidate_id: int, location_id: int, static: dict, static_json: str) -> None:
        super().__init__(candidate_id=int(candidate_id), location_id=int(location_id))
        self.update(static)
        self.static_json = static_json


def camera_json(obj: dict) -> str:
    """One camera object's JSON: the positional keys written, the rest from its encoding."""
    if not isinstance(obj, CameraObject):
        return dumps(obj)
    head = ",".join(f'"{k}":{int(obj[k])}' for k in POSITIONAL)
    rest = obj.static_json[1:]
    return "{" + head + ("," + rest if rest != "}" else "}")


def state_bytes(state: dict) -> bytes:
    """The state dict (Session.state) as JSON bytes, each camera from its cached encoding."""
    rest = dumps({k: v for k, v in state.items() if k != "cameras"})
    cams = "[" + ",".join(camera_json(c) for c in state.get("cameras", [])) + "]"
    return ('{"cameras":' + cams + ("," + rest[1:] if rest != "{}" else "}")).encode("utf-8")
