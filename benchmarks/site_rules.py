"""What each real-site rule costs on retail-site (issue 17): the scene as shipped against
the same scene with one rule taken out, all else equal (same targets, same budget of new
cameras, solver and refinement mode).

    without privacy    the restroom zone kept with coverage 0 (no targets, as with the
                       rule) but not private: cameras that see it stay candidates
    without forbid     mount_rules.forbid removed (cameras may hang above the freezers)
    without existing   no installed cameras, the same 12 new ones; and 12 + 6 new ones
                       (as many cameras as the site has in all)
    without max_per_type  any number of fisheyes

Each variant runs ``camplace.run`` (grid placement; ``--refine``: refined off the grid, the
CLI default) and reports cost (Σ w (Γ − c)⁺², existing cameras included), coverage gap,
cameras and fisheyes placed, candidates and seconds. Writes one JSON object to stdout.

    python benchmarks/site_rules.py [--solver greedy] [--refine]
"""

from __future__ import annotations

import argparse
import copy
import json
import time

import numpy as np
import yaml

from camplace.spec.builtin import builtin_yaml
from camplace.spec.loading import parse_scene
from camplace.workflows.run import run


def variants(base: dict) -> dict[str, dict]:
    """name -> scene dict: the shipped scene and each rule taken out."""
    out = {"retail-site (all rules)": base}
    d = copy.deepcopy(base)
    for z in d["zones"]:
        if z.get("privacy"):
            z.pop("privacy")
            z["coverage"] = 0
    out["without privacy"] = d
    d = copy.deepcopy(base)
    d["mount_rules"].pop("forbid")
    out["without forbid"] = d
    d = copy.deepcopy(base)
    n_existing = len(d.pop("existing"))
    out["without existing (same new budget)"] = d
    d = copy.deepcopy(d)
    d["placement"]["budget"] += n_existing
    out["without existing (budget + existing)"] = d
    d = copy.deepcopy(base)
    d["mount_rules"].pop("max_per_type")
    out["without max_per_type"] = d
    return out


def measure(data: dict, solver: str, refine: bool) -> dict:
    """Figures of one run of scene dict ``data``."""
    t0 = time.perf_counter()
    r = run(parse_scene(data), solver=solver, refine=refine, refine_time_s=60.0)
    c = r.visibility.candidates
    sel = np.asarray(r.placement.selected, np.int64)
    names = [c.cameras[k].name for k in c.camera_ids[sel]]
    existing = (r.metrics.existing or {}).get("cameras", 0)
    return {"cost": r.metrics.cost, "grid_cost": r.metrics.grid_cost, "coverage_gap": r.metrics.coverage_gap,
            "cameras": int(len(sel)), "new_cameras": int(len(sel) - existing), "fisheyes": names.count("fisheye"),
            "candidates": int(r.visibility.V.shape[0]), "targets": int(r.visibility.V.shape[1]),
            "privacy_violations": (r.metrics.privacy or {}).get("violations"),
            "seconds": round(time.perf_counter() - t0, 2)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--solver", default="greedy")
    ap.add_argument("--refine", action="store_true", help="refine off the grid (the CLI default)")
    a = ap.parse_args()
    base = yaml.safe_load(builtin_yaml("retail-site"))
    rows = {name: measure(d, a.solver, a.refine) for name, d in variants(base).items()}
    ref = rows["retail-site (all rules)"]["cost"]
    for v in rows.values():
        v["cost_of_rule"] = ref - v["cost"]  # > 0: the rule raises the cost by this much
    print(json.dumps({"scene": "retail-site", "solver": a.solver, "refine": a.refine, "runs": rows}, indent=1))


if __name__ == "__main__":
    main()
