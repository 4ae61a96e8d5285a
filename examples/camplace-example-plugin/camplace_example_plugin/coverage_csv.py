"""``camera-coverage``: camera_coverage.csv, one row per placed camera (an output file
added by a plugin, issue 35).

Columns ``id,camera,targets_seen,seen_only_by_it``: the targets in the camera's row of V
and those no other placed camera sees (the ones lost if it fails). Written by every
command that writes outputs (run, demo, evaluate, solve, the planner's save).
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from camplace.core.files import atomic_write_text


def write_camera_coverage(out_dir: Path, result) -> list[Path]:
    """The writer the entry point loads: ``write(out_dir, result)`` -> the paths it wrote."""
    V = result.V  # visibility.npz's CSR; rows = placement.json's candidate_id
    cameras = [c for c in result.placement["cameras"] if c.get("candidate_id") is not None]
    if V is None or not cameras:
        return []
    rows = np.array([c["candidate_id"] for c in cameras], np.int64)
    seen_by = np.bincount(V[rows].indices, minlength=V.shape[1])
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["id", "camera", "targets_seen", "seen_only_by_it"])
    for c, i in zip(cameras, rows):
        seen = V.indices[V.indptr[i]:V.indptr[i + 1]]
        ident = c.get("id", c.get("source_id", c["candidate_id"]))  # an evaluated camera: the id its file gave
        w.writerow([ident, c.get("camera") or "", len(seen), int((seen_by[seen] == 1).sum())])
    return [atomic_write_text(Path(out_dir) / "camera_coverage.csv", buf.getvalue())]
