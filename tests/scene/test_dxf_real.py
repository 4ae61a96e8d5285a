"""The DXF importer on a real plan nobody here drew (issue 25): the Barcelona Pavilion,
FreeCAD's DXF export (../shared/data/plans, facts in its SOURCES.md section 2): walls
found with the defaults, the footprint of the open plan within 5 % of the pavilion's IFC
(both the walls' outline, 862.7 m²), glass and columns as obstacles, and a small run whose
cameras are inside the footprint and not in a wall."""

from __future__ import annotations

from pathlib import Path

import pytest
from shapely.geometry import Point, Polygon

pytest.importorskip("ezdxf")

import camplace  # noqa: E402
from camplace.scene.importers import read_plan  # noqa: E402
from camplace.spec.loading import parse_scene  # noqa: E402

PLANS = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "plans"
PAVILION = PLANS / "barcelona-pavillion_plan.dxf"
IFC_OUTLINE_M2 = 862.7  # the pavilion's IFC walls' outline (walls_outline), m²


@pytest.fixture(scope="module")
def pavilion():
    if not PAVILION.is_file():
        pytest.skip(f"{PAVILION} is absent (the shared plans folder beside the repository)")
    return read_plan(PAVILION, heights=[1.0])


def test_walls_found_by_default_and_footprint_agrees_with_the_ifc(pavilion):
    assert pavilion.used["wall layers"].startswith("Walls (60 LINE)")
    assert pavilion.used["units"].startswith("m ")
    assert Polygon(pavilion.scene["room"]["footprint"]).area == pytest.approx(IFC_OUTLINE_M2, rel=0.05)


def test_glass_occludes_and_columns_reach_the_ceiling(pavilion):
    obs = pavilion.scene["obstacles"]
    glass = [o for o in obs if o["name"].startswith("window-")]
    columns = [o for o in obs if o["name"].startswith("column-")]
    assert glass and all(o["source"]["layer"] == "Crystal" for o in glass)
    assert len(columns) == 8 and all(o["prism"]["z"][1] == pavilion.scene["room"]["height"] for o in columns)


def test_small_run_puts_cameras_inside_and_not_in_walls(pavilion):
    data = dict(pavilion.scene, voxel_size=1.0)
    data["mounts"] = [dict(data["mounts"][0], spacing=3.0, yaw_deg={"start": 0, "stop": 270, "step": 90},
                           pitch_deg=[45])]
    res = camplace.run(parse_scene(data, str(PAVILION)), budget=4, solver="greedy")
    pos = res.visibility.candidates.positions[res.placement.selected]
    assert len(pos) == 4 and not res.scene.occupancy.is_occupied(pos).any()
    assert all(res.scene.polygon.contains(Point(*p[:2])) for p in pos)
