"""The procedural ``warehouse[:AREA]`` built-in scene: geometry as documented, usable
by name, and small instances run through the pipeline."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from shapely.geometry import Polygon

from camplace.spec.builtin import BUILTIN_SCENES, WAREHOUSE, builtin_yaml, resolve_scene, warehouse_spec
from camplace.spec.loading import parse_scene
from camplace.spec.schema import angle_values
from camplace.core.errors import InputError


@pytest.mark.parametrize("area", [1000, 5000, 10000])
def test_floor_area_and_layout(area):
    s = warehouse_spec(area)
    assert s.name == f"warehouse-{area}"
    assert Polygon(s.room.footprint).area == pytest.approx(area, rel=1e-3)
    assert 6.0 <= s.room.height <= 8.0
    racks = [o.box for o in s.obstacles]
    assert racks
    ys = sorted({(b.min[1], b.max[1]) for b in racks})
    for (lo, hi) in ys:
        assert hi - lo == pytest.approx(1.2)  # rack depth
    gaps = [b[0] - a[1] for a, b in zip(ys, ys[1:])]
    assert all(g == pytest.approx(3.0) for g in gaps)  # aisles
    assert all(2.5 <= b.max[2] <= 4.0 and b.min[2] == 0 for b in racks)
    width = s.room.footprint[2][1]
    assert ys[0][0] >= 3.0 - 1e-9 and ys[-1][1] <= width - 3.0 + 1e-9
    if area >= 5000:  # long rows are broken by cross aisles
        segs = sorted({(b.min[0], b.max[0]) for b in racks})
        assert len(segs) >= 2
        assert all(b[0] - a[1] == pytest.approx(3.0) for a, b in zip(segs, segs[1:]))


def test_targets_cameras_mounts():
    s = warehouse_spec(2000)
    walk, faces = s.targets
    assert walk.kind == "volume" and walk.coverage == 3 and len(walk.heights) >= 2
    assert faces.kind == "surface" and faces.coverage == 1 and set(faces.of) == {o.name for o in s.obstacles}
    cam = s.cameras[0]
    assert tuple(cam.resolution) == (1780, 720) and tuple(cam.fov_deg) == (71, 36)  # the stores' camera
    assert cam.max_range == WAREHOUSE["max_range"] > s.room.height  # reaches the floor from the ceiling
    m = s.mounts[0]
    assert m.kind == "ceiling_grid" and m.spacing == 1.0
    assert len(angle_values(m.yaw_deg)) == 12 and len(angle_values(m.pitch_deg)) == 3


def test_names_resolve():
    assert "warehouse" in BUILTIN_SCENES
    spec, base, src = resolve_scene("warehouse")
    assert spec.name == "warehouse-10000" and base is None
    assert resolve_scene("warehouse:2500")[0].name == "warehouse-2500"
    assert resolve_scene("warehouse:2.5e3")[0] == resolve_scene("warehouse:2500")[0]
    for bad in ("warehouse:abc", "warehouse:10", "warehouse:-5", "warehouse:nan", "warehouse:inf"):
        with pytest.raises(InputError, match="warehouse"):
            resolve_scene(bad)


def test_yaml_round_trip():
    text = builtin_yaml("warehouse:1500")
    assert parse_scene(yaml.safe_load(text)) == warehouse_spec(1500)


def test_small_warehouse_pipeline():
    from camplace.workflows.run import run

    r = run("warehouse:200", budget=12, solver="greedy-fast")
    n_xy = 36  # 12 yaws x 3 pitches per ceiling point
    assert len(r.visibility.candidates) <= r.visibility.candidates.info["generated"]
    assert r.visibility.candidates.info["generated"] % n_xy == 0
    assert len(r.placement.selected) == 12
    # rack faces are seen from the aisles; the walkable volume is in the aisles only
    t = r.visibility.targets
    assert set(t.region_names) == {"walkable", "rack-faces"}
    assert r.metrics.coverage_gap < 1.0
    assert np.all(t.positions[:, 2] < r.scene.height)
