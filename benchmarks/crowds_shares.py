"""Issue 36: the share of the people seen by >= 1 / >= 2 / >= 3 cameras, on the crowds a
crowd-aware placement was optimised over and on the held-out ones, for the two placements
of one row of a benchmarks/crowds.py result (the crowd-aware one over the steep views).

    python benchmarks/crowds_shares.py SCENE RESULT.json DENSITY SOLVER
"""

from __future__ import annotations

import json
import sys
import numpy as np
from camplace.spec.crowd import CrowdSpec
from camplace.targets.crowd import OPTIMISE, SCORE, sample_crowds
from camplace.targets.people import people_targets, person_coverage
from camplace.visibility.crowd import people_grid
from camplace.visibility.people import people_rows
from camplace.visibility.registry import engine_of
from camplace.workflows.run import prepare

scene, f, d, solver = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
with open(f) as fh:
    r = json.load(fh)
g = r["densities"][d]["solvers"][solver]
sc, vis = prepare(scene)
sc2, vis2 = prepare(scene, extra_pitches=(75.0, 90.0))
crowd = CrowdSpec(density=float(d), samples=64, score_samples=32)
fp = np.asarray(sc.footprint, float)
for stream, name in ((OPTIMISE, "in-sample"), (SCORE, "held-out")):
    cr = sample_crowds(sc, crowd, stream)
    people = people_targets(cr, vis.targets, crowd.people_heights, crowd.people_gamma)
    grid = people_grid(cr, fp.min(0), fp.max(0))
    who = np.repeat(np.arange(cr.n_samples), cr.counts)
    for label, v, sel in (("empty", vis, g["empty-store"]["selected"]), ("aware", vis2, g["crowd-aware"]["selected"])):
        seen = people_rows(engine_of(v), sc.occupancy, people, v.candidates.subset(np.asarray(sel)), grid)
        cov = person_coverage(np.asarray(seen.sum(axis=0)).ravel(), people.n_heights)
        print(name, label, {k: round(100 * float(np.mean(cov >= k)), 2) for k in (1, 2, 3)})
