"""Every registered solver keeps the site's rules (issue 17): on one small scene with an
existing camera, a privacy zone behind a doorway, a forbidden mount area and a per-type
limit, each solver's placement keeps the budget (new cameras only), one camera per
location, the type limit, never selects a pose that sees the restroom or hangs in the
forbidden area, keeps the existing camera, and reports the cost recomputed from V."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import shapely

from camplace.solvers import SOLVERS
from camplace.spec.loading import parse_scene
from camplace.workflows.run import run

from workflows.test_sites import SITE  # the hand-checked site of test_sites

FORBID = [[6.5, 0], [8, 0], [8, 4], [6.5, 4]]
E1 = {"id": "E1", "camera": "cam", "position": [5.0, 1.0, 2.9], "yaw_deg": 0, "pitch_deg": 45}  # faces away
BUDGET = 3


def site_scene():
    d = copy.deepcopy(SITE)
    d["cameras"] = [SITE["cameras"][0], {"name": "wide", "resolution": [64, 48], "fov_deg": [120, 90],
                                         "max_range": 10.0}]
    d["mounts"] = [dict(SITE["mounts"][0]), dict(SITE["mounts"][0], camera="wide")]
    d["mount_rules"] = {"forbid": [FORBID], "max_per_type": {"wide": 1}}
    d["existing"] = [E1]
    d["targets"] = [{"name": "walk", "kind": "volume", "heights": [1.0], "coverage": 2}]
    return parse_scene(d)


OPTIONS = {"min-cameras": {}, "robust": {}, "certify": {}, "paper-mip": {}, "mip": {"threads": 1}}


@pytest.fixture(scope="module")
def guard():
    """Every candidate pose of the scene that sees the restroom, by the pipeline's own guard."""
    from camplace.workflows.run import prepare

    _, vis = prepare(site_scene())
    return vis


@pytest.mark.parametrize("name", sorted(SOLVERS))
def test_every_solver_keeps_the_site_rules(name, guard):
    r = run(site_scene(), budget=BUDGET, solver=name, time_limit_s=10.0, **OPTIONS.get(name, {}))
    p, vis = r.placement, r.visibility
    sel = np.asarray(p.selected, np.int64)
    existing = set(p.info.get("existing_ids", {}))
    assert len(existing) == 1 and existing <= set(sel.tolist()), "the existing camera stays in the placement"
    new = np.array([i for i in sel if i not in existing], np.int64)
    if not SOLVERS[name].tags.ignores_camera_budget:
        assert len(new) <= BUDGET
    locs = vis.candidates.location_ids[sel]
    assert len(set(locs.tolist())) == len(sel), "one camera per location"
    cams = [vis.candidates.cameras[c].name for c in vis.candidates.camera_ids[new]]
    assert cams.count("wide") <= 1, "max_per_type: wide <= 1"
    xy = vis.candidates.positions[new, :2]
    assert not np.any(shapely.contains_xy(shapely.Polygon(FORBID), xy[:, 0], xy[:, 1])), "no camera in forbid"
    # no selected new pose is one the privacy guard removed: it is among the guarded candidates
    kept = {tuple(np.round(np.r_[q, R.ravel()], 6)) for q, R in zip(guard.candidates.positions,
                                                                     guard.candidates.rotations)}
    for i in new:
        key = tuple(np.round(np.r_[vis.candidates.positions[i], vis.candidates.rotations[i].ravel()], 6))
        assert key in kept, f"{name}: selected pose {i} is not a privacy-safe candidate"
    assert r.metrics.privacy["violations"] == 0 and r.metrics.privacy["camera_ids"] == []
    cov = np.bincount(vis.V[sel].indices, minlength=vis.V.shape[1])
    t = vis.targets
    assert p.objective == pytest.approx(float((t.weights * np.maximum(t.gamma - cov, 0) ** 2).sum()))
    assert r.metrics.cost == pytest.approx(p.objective)
