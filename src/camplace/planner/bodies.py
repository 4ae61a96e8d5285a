"""Request bodies of the planner's API checked field by field: every refusal is an
camplace.planner.errors.ApiError naming the field and what was expected."""

from __future__ import annotations

import json
import math

from camplace.planner.errors import ApiError

ANGLES = ("yaw_deg", "pitch_deg", "roll_deg")
CAMERA_KEYS = ("position", *ANGLES, "camera", "locked", "snap", "storey")


def parse_json(raw: bytes, empty_ok: bool = True) -> dict:
    """The body as a JSON object (an empty body is {} when ``empty_ok``)."""
    if not raw.strip():
        if empty_ok:
            return {}
        raise ApiError("body: expected a JSON object, got an empty body", "body")
    try:
        data = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ApiError(f"body: not valid JSON ({err})", "body") from None
    if not isinstance(data, dict):
        raise ApiError(f"body: expected a JSON object, got {type(data).__name__}", "body")
    return data


def number(value, field: str) -> float:
    """A finite number (not a bool)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ApiError(f"{field}: expected a number, got {json.dumps(value)[:40]}", field)
    v = float(value)
    if not math.isfinite(v):
        raise ApiError(f"{field}: expected a finite number, got {value!r}", field)
    return v


def boolean(value, field: str) -> bool:
    if not isinstance(value, bool):
        raise ApiError(f"{field}: expected true or false, got {json.dumps(value)[:40]}", field)
    return value


def position(value, field: str = "position", allow_xy: bool = False) -> list[float]:
    """[x, y, z] (or [x, y] when ``allow_xy``) in metres."""
    sizes = (2, 3) if allow_xy else (3,)
    want = "[x, y, z] or [x, y]" if allow_xy else "[x, y, z]"
    if not isinstance(value, list) or len(value) not in sizes:
        raise ApiError(f"{field}: expected {want} (metres), got {json.dumps(value)[:60]}", field)
    return [number(v, field) for v in value]


def _known(body: dict, keys: tuple[str, ...]) -> None:
    for k in body:
        if k not in keys:
            raise ApiError(f"{k}: unknown field; expected some of {', '.join(keys)}", str(k))


def camera_change(body: dict) -> dict:
    """PUT /api/cameras/{id}: any of position, yaw_deg, pitch_deg, roll_deg, camera, locked, snap, storey."""
    _known(body, CAMERA_KEYS)
    if not body:
        raise ApiError(f"body: expected at least one of {', '.join(CAMERA_KEYS)}", "body")
    out: dict = {}
    if "position" in body:
        out["position"] = position(body["position"], allow_xy=True)
    for f in ANGLES:
        if f in body:
            out[f] = number(body[f], f)
    if "pitch_deg" in out and not -90.0 <= out["pitch_deg"] <= 90.0:
        raise ApiError(f"pitch_deg: expected -90..90 degrees (downward tilt), got {out['pitch_deg']:g}", "pitch_deg")
    if "camera" in body:
        if not isinstance(body["camera"], str):
            raise ApiError(f"camera: expected a camera type name, got {json.dumps(body['camera'])[:40]}", "camera")
        out["camera"] = body["camera"]
    for f in ("locked", "snap"):
        if f in body:
            out[f] = boolean(body[f], f)
    if "storey" in body:  # a building: move the camera to that storey's nearest mount (issue 33)
        if not isinstance(body["storey"], str):
            raise ApiError(f"storey: expected a storey name, got {json.dumps(body['storey'])[:40]}", "storey")
        out["storey"] = body["storey"]
    return out


def new_camera(body: dict) -> dict:
    """POST /api/cameras: position required, the rest as for a change."""
    if "position" not in body:
        raise ApiError("position: required ([x, y, z] or [x, y] metres)", "position")
    return camera_change(body)


def optimize_request(body: dict, default_budget: int) -> dict:
    """POST /api/optimize: solver (a registered name), time_limit_s (> 0), budget (integer ≥ 0)."""
    from camplace.solvers import SOLVERS

    _known(body, ("solver", "time_limit_s", "budget"))
    solver = body.get("solver", "greedy")
    if not isinstance(solver, str) or solver not in SOLVERS:
        raise ApiError(f"solver: unknown solver {json.dumps(solver)[:40]}; expected one of "
                       f"{', '.join(sorted(SOLVERS))}", "solver")
    if SOLVERS[solver].tags.ignores_camera_budget:
        from camplace.planner.sceneinfo import budget_solvers

        raise ApiError(f"solver: '{solver}' chooses how many cameras, the planner fills a budget; expected one of "
                       f"{', '.join(budget_solvers())}", "solver")
    limit = number(body.get("time_limit_s", 10.0), "time_limit_s")
    if not 0.0 < limit <= 3600.0:
        raise ApiError(f"time_limit_s: expected 0 < seconds <= 3600, got {limit:g}", "time_limit_s")
    budget = body.get("budget", default_budget)
    if isinstance(budget, bool) or not isinstance(budget, int) or budget < 0:
        raise ApiError(f"budget: expected a non-negative integer (cameras, locked included), got "
                       f"{json.dumps(budget)[:40]}", "budget")
    return {"solver": solver, "time_limit_s": limit, "budget": budget}


def save_dir(body: dict) -> str | None:
    """POST /api/save: ``dir``, a relative folder (checked against the start folder by camplace.planner.save)."""
    _known(body, ("dir",))
    d = body.get("dir")
    if d is not None and (not isinstance(d, str) or not d.strip()):
        raise ApiError(f"dir: expected a relative folder name, got {json.dumps(d)[:40]}", "dir")
    return d
