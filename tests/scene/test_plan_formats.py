"""The same two-room plan as IFC, DXF and a plan image (issue 18's acceptance): imported
with defaults (the image needs its scale), footprints within 2 % of each other, coverage
gaps within 0.02 after the same greedy run, zones per room, no camera in a wall or
outside the footprint."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import Point, Polygon

pytest.importorskip("ifcopenshell")
pytest.importorskip("ezdxf")

import camplace  # noqa: E402
from camplace.scene.importers import import_plan  # noqa: E402
from camplace.scene.importers.ifc_build import GridBuilding  # noqa: E402
from camplace.spec.loading import parse_scene  # noqa: E402
from tests.scene.plan_drawings import PLAN_PX, write_plan_formats  # noqa: E402

PLAN = GridBuilding(names=("Office", "Lab"), door=(0.9, 2.1))  # 5 x 4 m rooms, a 0.9 m door between them
OPTIONS = {"ifc": {}, "dxf": {}, "image": {"scale": PLAN_PX}}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    files = write_plan_formats(tmp_path_factory.mktemp("plans"), PLAN)
    out = {}
    for kind, path in files.items():
        data = import_plan(path, **OPTIONS[kind])
        out[kind] = (data, camplace.run(parse_scene(data, str(path)), budget=4, solver="greedy"))
    return out


def test_footprints_agree_within_2_percent(runs):
    areas = {k: Polygon(d["room"]["footprint"]).area for k, (d, _) in runs.items()}
    assert areas["ifc"] == pytest.approx(PLAN.outline_area(), rel=0.01)
    assert max(areas.values()) <= 1.02 * min(areas.values()), areas


def test_coverage_gaps_agree_within_0_02(runs):
    gaps = {k: r.metrics.coverage_gap for k, (_, r) in runs.items()}
    assert max(gaps.values()) - min(gaps.values()) <= 0.02, gaps


def test_zones_per_room(runs):
    for kind, (data, res) in runs.items():
        zones = {z["name"]: Polygon(z["polygon"]) for z in data["zones"]}
        assert len(zones) == 2 and all(p.area == pytest.approx(18.24, rel=0.02) for p in zones.values()), kind
        if kind != "image":  # a plan image carries no room names (no OCR): room-1, room-2
            assert set(zones) == {"Office", "Lab"} and set(res.metrics.regions) >= {"Office", "Lab"}, kind
        else:
            assert set(zones) == {"room-1", "room-2"}


def test_cameras_inside_the_footprint_and_not_in_a_wall(runs):
    for kind, (_, res) in runs.items():
        pos = res.visibility.candidates.positions[res.placement.selected]
        assert len(pos) == 4, kind
        assert not res.scene.occupancy.is_occupied(pos).any(), kind
        assert all(res.scene.polygon.contains(Point(*p[:2])) for p in pos), kind
        assert np.all(pos[:, 2] > 0) and np.all(pos[:, 2] < 3.0), kind
