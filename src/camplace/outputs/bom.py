"""What to buy (issue 27): the bill of materials and the recording load of a placement.

``bom.csv`` has one row per camera model and focal setting of the **new** cameras
(columns ``model,focal_mm,count,unit_price,total``; the focal length rounded to 0.1 mm,
empty for a type not given by focal_mm); existing cameras are listed apart
(``bom_existing.csv``, same columns). Its totals equal the schedule's prices: both come
from the same camera objects and per-camera prices (camplace.outputs.plan_data).

The recording load: Σ bitrate (Mbit/s) of the cameras whose type gives ``bitrate_mbps``,
and the storage that stream fills in ``recording.retention_days`` days of continuous
recording: Mbit/s × 86,400 s × days / 8 → MB, / 10⁶ → TB (decimal units, as disks are sold).
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

from camplace.core.files import atomic_write_text

BOM_COLUMNS = ("model", "focal_mm", "count", "unit_price", "total")
SECONDS_PER_DAY = 86_400.0


@dataclass(frozen=True)
class BomRow:
    """One line of the bill of materials: ``count`` cameras of ``model`` set to ``focal_mm``
    (None: a type not given by focal_mm) at ``unit_price`` each."""

    model: str
    focal_mm: float | None
    count: int
    unit_price: float

    @property
    def total(self) -> float:
        return self.count * self.unit_price

    def cells(self) -> tuple[str, ...]:
        """The row as bom.csv writes it."""
        return (self.model, "" if self.focal_mm is None else f"{self.focal_mm:.1f}", str(self.count),
                f"{self.unit_price:g}", f"{self.total:g}")


def bom_rows(cameras: list[dict], prices: list[float], existing: bool = False) -> list[BomRow]:
    """Rows for the new cameras (``existing=True``: the existing ones) of placement.json camera
    objects with their prices (same order), grouped by (model, focal to 0.1 mm, price), sorted."""
    groups: dict[tuple, int] = {}
    for c, price in zip(cameras, prices):
        if bool(c.get("existing")) != existing:
            continue
        f = c.get("focal_mm")
        key = (str(c["camera"]), None if f is None else round(float(f), 1), float(price))
        groups[key] = groups.get(key, 0) + 1
    rows = [BomRow(m, f, n, p) for (m, f, p), n in groups.items()]
    return sorted(rows, key=lambda r: (r.model, -1.0 if r.focal_mm is None else r.focal_mm, r.unit_price))


def bom_csv(rows: list[BomRow]) -> str:
    """bom.csv text: header BOM_COLUMNS, one line per row."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(BOM_COLUMNS)
    w.writerows(r.cells() for r in rows)
    return buf.getvalue()


def storage_tb(bandwidth_mbps: float, days: float) -> float:
    """TB (10¹² bytes) that a continuous stream of ``bandwidth_mbps`` Mbit/s fills in ``days`` days."""
    return float(bandwidth_mbps) * SECONDS_PER_DAY * float(days) / 8.0 / 1e6


def recording_load(cameras: list[dict], bitrates: list[float | None], retention_days: float | None) -> dict | None:
    """placement.json ``recording``: bandwidth (Mbit/s) of the new cameras and of all of them,
    the storage (TB) for ``retention_days`` (None: no storage figure), and how many cameras
    have no bitrate (not counted). None when no camera has a bitrate and no retention is asked."""
    if retention_days is None and all(b is None for b in bitrates):
        return None
    new = sum(float(b) for c, b in zip(cameras, bitrates) if b is not None and not c.get("existing"))
    total = sum(float(b) for b in bitrates if b is not None)
    out = {"bandwidth_new_mbps": round(new, 6), "bandwidth_mbps": round(total, 6),
           "cameras_without_bitrate": sum(b is None for b in bitrates)}
    if retention_days is not None:
        out.update(retention_days=float(retention_days), storage_new_tb=round(storage_tb(new, retention_days), 6),
                   storage_tb=round(storage_tb(total, retention_days), 6))
    return out


def selected_models(candidates, selected) -> list:
    """The camera model (camplace.cameras.models.CameraModel) of each selected candidate, in
    the order of placement.json (ascending candidate id)."""
    return [candidates.cameras[int(candidates.camera_ids[i])] for i in sorted(int(i) for i in selected)]


def write_bom(out_dir, cameras: list[dict], prices: list[float]) -> dict:
    """bom.csv (new cameras) and, with existing cameras, bom_existing.csv into ``out_dir``;
    returns name -> path."""
    out = Path(out_dir)
    paths = {"bom.csv": atomic_write_text(out / "bom.csv", bom_csv(bom_rows(cameras, prices)))}
    if any(c.get("existing") for c in cameras):
        paths["bom_existing.csv"] = atomic_write_text(out / "bom_existing.csv",
                                                      bom_csv(bom_rows(cameras, prices, existing=True)))
    return paths


def bom_writer(out_dir, result) -> list[Path]:
    """The registered output writer ``bom`` (entry point of ``camplace.outputs``;
    camplace.outputs.writers): bom.csv and bom_existing.csv of a result with candidates
    (nothing for ``camplace solve``, which has no camera types)."""
    vis = result.visibility
    if vis is None:
        return []
    prices = [m.cost for m in selected_models(vis.candidates, result.solution.selected)]
    return list(write_bom(out_dir, result.placement["cameras"], prices).values())
