"""Every storey of a building in one run (IFC ``storey: all``): one folder per storey
and a short summary.

Each storey is its own scene (floor at z = 0, its own mounts and budget, from
camplace.scene.importers.import_storey_plans); the caller runs it into
``DIR/<slug>/`` like any run. ``storeys_summary`` then reads those folders back
(placement.json, metrics.json) into ``DIR/storeys.json``.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from camplace.core.files import atomic_write_json


def storey_slugs(names: list[str]) -> list[str]:
    """A folder-safe slug per storey name ('Ground Floor' -> 'ground-floor'), unique
    (-2, -3... on repeats; 'storey-K' when a name has no letters or digits)."""
    out: list[str] = []
    for k, name in enumerate(names):
        base = re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-") or f"storey-{k + 1}"
        slug, n = base, 1
        while slug in out:
            n += 1
            slug = f"{base}-{n}"
        out.append(slug)
    return out


def storey_row(storey: str, folder: Path, elevation: float, height: float) -> dict:
    """One storeys.json row from a finished run folder: storey, folder (its name),
    floor elevation and ceiling height (m; a pose's building z = elevation + its z),
    cameras, budget, cost and coverage gap."""
    placement = json.loads((folder / "placement.json").read_text())
    metrics = json.loads((folder / "metrics.json").read_text())
    return {"storey": storey, "folder": folder.name, "elevation_m": round(float(elevation), 4),
            "height_m": round(float(height), 4), "cameras": len(placement["cameras"]),
            "budget": int(placement["budget"]), "status": placement["status"], "cost": float(metrics["cost"]),
            "coverage_gap": float(metrics["coverage_gap"])}


def storeys_summary(out_dir: Path, source: str, rows: list[dict]) -> Path:
    """Write ``out_dir``/storeys.json: {"source": file name, "storeys": rows} (atomic)."""
    return atomic_write_json(Path(out_dir) / "storeys.json", {"source": source, "storeys": rows})
