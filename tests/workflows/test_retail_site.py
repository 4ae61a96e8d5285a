"""The built-in retail-site (issue 17) runs end to end with every real-site rule in force."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from camplace.workflows.run import run


@pytest.fixture(scope="module", params=[False, True], ids=["grid", "refined"])
def retail(request):
    return run("retail-site", refine=request.param, refine_time_s=20)


def test_every_rule_holds(retail):
    r = retail
    spec = r.scene.spec
    assert {z.name for z in spec.zones} == {"aisles", "checkout", "back-aisle", "restroom"}
    assert set(r.metrics.regions) >= {"checkout", "aisles", "back-aisle"}
    assert r.metrics.privacy["violations"] == 0
    assert r.metrics.existing["cameras"] == 6 and r.metrics.existing["new_cameras"] == 12
    sel = np.asarray(r.placement.selected, np.int64)
    c = r.visibility.candidates
    existing = set(r.placement.info["existing_ids"])
    new = np.array([i for i in sel if int(i) not in existing], np.int64)
    names = [c.cameras[k].name for k in c.camera_ids[new]]
    assert names.count("fisheye") <= spec.mount_rules.max_per_type["fisheye"]
    forbid = Polygon(spec.mount_rules.forbid[0])
    assert not shapely.intersects_xy(forbid, c.positions[new, 0], c.positions[new, 1]).any()
    assert r.metrics.cost == pytest.approx(r.problem.cost(sel))


def test_refined_run_reports_both_costs(retail):
    if retail.metrics.grid_cost is None:
        assert "refine" not in retail.placement.info
    else:
        assert retail.metrics.cost <= retail.metrics.grid_cost + 1e-9
        assert retail.metrics.to_dict()["grid_cost"] == retail.metrics.grid_cost
