"""Camera catalogues (issue 27): ``cameras: {catalogue: FILE, models: [names]}`` reads the
camera types from a company's price list instead of the scene file.

A catalogue is a CSV file (one row per model, a header, ``#`` lines are comments) or a
YAML file (a list of mappings, or ``{cameras: [...]}``) with these columns; empty cells
are absent. The column names are the scene's ``cameras`` keys except ``kind`` (= ``model``):

- ``name`` (required, unique), ``kind`` (``pinhole`` | ``opencv`` | ``fisheye``, default pinhole)
- ``resolution`` (``2688x1520``; YAML also ``[2688, 1520]``), ``pixel_um`` or ``sensor_width_mm``
- ``focal_mm`` (``4``, or ``2.8-12`` for a varifocal lens; YAML also ``[2.8, 12]``), ``focal_steps``
- ``distortion`` (coefficients separated by spaces), ``max_fov_deg``, ``max_range``
- ``price`` (or ``cost``), ``bitrate_mbps`` (the stream at its recording profile), ``ir_range_m``
- ``fov_deg`` (``90x55``) instead of a sensor and focal length, and ``notes`` (ignored)

Every row is checked like a ``cameras`` entry; a problem is one line naming the file,
the row (CSV: the line number, as a spreadsheet counts; YAML: the list index) and the column.
"""

from __future__ import annotations

import csv
import re
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from camplace.core.errors import InputError
from camplace.spec.lenses import Camera
from camplace.spec.wording import did_you_mean, format_error_entry
from camplace.spec.yamltext import load_yaml_text

COLUMNS = ("name", "kind", "resolution", "pixel_um", "sensor_width_mm", "focal_mm", "focal_steps", "distortion",
           "max_fov_deg", "max_range", "price", "cost", "bitrate_mbps", "ir_range_m", "fov_deg", "notes")
KEY_OF = {"kind": "model"}  # column -> cameras key where they differ
NUMBERS = ("pixel_um", "sensor_width_mm", "max_fov_deg", "max_range", "price", "cost", "bitrate_mbps", "ir_range_m")
CATALOGUE_KEYS = ("catalogue", "models")


def expand_catalogue(data: Any, base_dir: Path | None, source: str) -> Any:
    """A scene mapping with ``cameras: {catalogue, models}`` -> the same mapping with the
    catalogue's rows (or the named ``models`` of it, in that order) as its ``cameras`` list;
    anything else unchanged. ``base_dir``: where a relative catalogue path starts."""
    if not isinstance(data, dict) or not isinstance(data.get("cameras"), dict):
        return data
    spec = data["cameras"]
    extra = [k for k in spec if k not in CATALOGUE_KEYS]
    if extra or "catalogue" not in spec:
        key = extra[0] if extra else "catalogue"
        what = f"unknown key '{key}'{did_you_mean(str(key), list(CATALOGUE_KEYS))}" if extra else "required key is missing"
        raise InputError(f"{source}: cameras.{key}: {what} (cameras is a list of camera types, or "
                         "{catalogue: FILE, models: [names]})")
    name = spec["catalogue"]
    if not isinstance(name, str) or not name:
        raise InputError(f"{source}: cameras.catalogue: expected a file name (CSV or YAML), got {name!r}")
    path = Path(name).expanduser()
    if not path.is_absolute() and base_dir is not None:
        path = Path(base_dir) / path
    if not path.is_file():
        raise InputError(f"{source}: cameras.catalogue: file '{name}' not found (looked in {path.parent})")
    rows = read_catalogue(path)
    return {**data, "cameras": _chosen(rows, spec.get("models"), source)}


def _chosen(rows: list[dict], models: Any, source: str) -> list[dict]:
    if models is None:
        return rows
    by_name = {r["name"]: r for r in rows}
    if not isinstance(models, list) or not models or not all(isinstance(m, str) for m in models):
        raise InputError(f"{source}: cameras.models: expected a non-empty list of model names of the catalogue")
    for k, m in enumerate(models):
        if m not in by_name:
            names = list(by_name)
            raise InputError(f"{source}: cameras.models[{k}]: '{m}' is not in the catalogue{did_you_mean(m, names)}; "
                             f"expected one of {', '.join(names[:8])}{', ...' if len(names) > 8 else ''}")
    return [by_name[m] for m in dict.fromkeys(models)]


def read_catalogue(path: str | Path) -> list[dict]:
    """The rows of a catalogue file as ``cameras`` entries (dicts), each validated."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"{p}: cannot read the camera catalogue ({err})") from None
    if p.suffix.lower() in (".yaml", ".yml"):
        raw = _yaml_rows(text, p)
    else:
        raw = _csv_rows(text, p)
    out, seen = [], {}
    for where, row in raw:
        cam = camera_of_row(row, f"{p}: {where}")
        if cam["name"] in seen:
            raise InputError(f"{p}: {where}, column name: duplicate name '{cam['name']}' (already {seen[cam['name']]})")
        seen[cam["name"]] = where
        out.append(cam)
    if not out:
        raise InputError(f"{p}: the camera catalogue has no model (expected a header and one row per model)")
    return out


def _csv_rows(text: str, p: Path) -> list[tuple[str, dict]]:
    lines = [(n, line) for n, line in enumerate(text.splitlines(), start=1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        return []
    parsed = list(csv.reader([line for _, line in lines]))
    header = [h.strip() for h in parsed[0]]
    for h in header:
        if h not in COLUMNS:
            raise InputError(f"{p}: line {lines[0][0]}: column '{h}' is not a catalogue column"
                             f"{did_you_mean(h, list(COLUMNS))}; expected {', '.join(COLUMNS)}")
    out = []
    for (n, _), cells in zip(lines[1:], parsed[1:]):
        if len(cells) > len(header):
            raise InputError(f"{p}: row {n}: {len(cells)} cells, expected at most {len(header)} ({','.join(header)})")
        out.append((f"row {n}", {h: c.strip() for h, c in zip(header, cells) if c.strip()}))
    return out


def _yaml_rows(text: str, p: Path) -> list[tuple[str, dict]]:
    data = load_yaml_text(text, str(p))
    if isinstance(data, dict) and set(data) == {"cameras"}:
        data = data["cameras"]
    if not isinstance(data, list):
        raise InputError(f"{p}: expected a list of camera models (or {{cameras: [...]}})")
    out = []
    for k, row in enumerate(data):
        if not isinstance(row, dict):
            raise InputError(f"{p}: [{k}]: expected a mapping of catalogue columns, got {type(row).__name__}")
        for h in row:
            if h not in COLUMNS:
                raise InputError(f"{p}: [{k}], column {h}: not a catalogue column{did_you_mean(str(h), list(COLUMNS))}"
                                 f"; expected {', '.join(COLUMNS)}")
        out.append((f"[{k}]", {h: v for h, v in row.items() if v is not None and v != ""}))
    return out


def camera_of_row(row: dict, where: str) -> dict:
    """One catalogue row (text cells or YAML values) -> a validated ``cameras`` entry (dict)."""
    if "name" not in row:
        raise InputError(f"{where}, column name: required (the model's name)")
    cam: dict[str, Any] = {}
    for col, value in row.items():
        if col == "notes":
            continue
        cell = f"{where}, column {col}"
        cam[KEY_OF.get(col, col)] = _value(col, value, cell)
    try:
        Camera.model_validate(cam)
    except ValidationError as err:
        e = err.errors()[0]
        path, msg = format_error_entry(e, Camera)
        key = path.split(".")[0].split("[")[0]
        col = {v: k for k, v in KEY_OF.items()}.get(key, key)
        raise InputError(f"{where}, column {col or 'name'}: {msg}") from None
    return cam


def _value(col: str, value: Any, cell: str) -> Any:
    """A cell as the cameras key takes it (text cells parsed; YAML values passed on)."""
    if not isinstance(value, str) or col in ("name", "kind"):
        return value
    if col in NUMBERS:
        return _number(value, cell)
    if col == "focal_steps":
        try:
            return int(value)
        except ValueError:
            raise InputError(f"{cell}: expected a whole number of focal settings, got {value!r}") from None
    if col in ("resolution", "fov_deg"):
        parts = re.split(r"\s*[xX\u00d7,]\s*", value)
        if len(parts) != 2:
            raise InputError(f"{cell}: expected WIDTHxHEIGHT (e.g. 2688x1520), got {value!r}")
        nums = [_number(v, cell) for v in parts]
        return [int(v) for v in nums] if col == "resolution" and all(v == int(v) for v in nums) else nums
    if col == "focal_mm":
        parts = re.split(r"\s*[-\u2013]\s*", value) if not value.startswith("-") else [value]
        nums = [_number(v, cell) for v in parts]
        if len(nums) > 2:
            raise InputError(f"{cell}: expected a focal length (4) or a range MIN-MAX (2.8-12), got {value!r}")
        return nums[0] if len(nums) == 1 else nums
    if col == "distortion":
        return [_number(v, cell) for v in value.split()]
    return value


def _number(text: str, cell: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise InputError(f"{cell}: expected a number, got {text!r}") from None
