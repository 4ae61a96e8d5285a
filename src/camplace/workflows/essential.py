"""``camplace essential``: which cameras of a run's output folder matter most, ranked by
the cost added if each one fails alone (camplace.solvers.robust.essential_cameras)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from camplace.core.errors import InputError
from camplace.problem.instance import load_problem_npz
from camplace.solvers.robust import essential_cameras, worst_case


def essential_from_folder(out_dir) -> tuple[list[dict], dict]:
    """``essential_cameras`` for a run's output folder (visibility.npz + placement.json):
    (ranking with each camera's candidate_id, position and type, summary dict)."""
    out = Path(out_dir)
    for name in ("visibility.npz", "placement.json"):
        if not (out / name).is_file():
            raise InputError(f"{out}: {name} not found (expected the output folder of camplace run / evaluate)")
    try:
        pdict = json.loads((out / "placement.json").read_text())
        cams = pdict["cameras"]
        ids = [c["candidate_id"] for c in cams]
    except (ValueError, KeyError, TypeError) as err:
        raise InputError(f"{out / 'placement.json'}: not a camplace placement ({err})") from None
    if any(i is None for i in ids):
        raise InputError(f"{out / 'placement.json'}: some cameras are not rows of V (candidate_id null); "
                         "score the placement with `camplace evaluate` first")
    problem, _ = load_problem_npz(out / "visibility.npz", len(ids))
    sel = np.asarray(ids, np.int64)
    if len(sel) and (sel.min() < 0 or sel.max() >= problem.n_candidates):
        raise InputError(f"{out / 'placement.json'}: candidate_id outside the rows of visibility.npz")
    ranking = essential_cameras(problem, sel)
    by_id = {int(c["candidate_id"]): c for c in cams}
    for r in ranking:
        c = by_id[r["candidate_id"]]
        r.update(position=c.get("position"), yaw_deg=c.get("yaw_deg"), pitch_deg=c.get("pitch_deg"),
                 camera=c.get("camera"))
    w, who = worst_case(problem, sel)
    cost = problem.cost(sel)
    return ranking, {"cost": cost, "worst_case_cost": w, "worst_failure_candidate": who,
                     "coverage_gap": cost / problem.normalizer if problem.normalizer > 0 else 0.0}


__all__ = ["essential_from_folder"]
