"""Plans people have (issue 18): prism obstacles, the importer registry, DXF floor
plans and plan images, each generated here with the libraries themselves."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.scene.build import build_scene
from camplace.scene.importers import import_plan, plan_kind, prism_obstacles
from tests.conftest import box_room

L_WALL = [[1, 1], [3, 1], [3, 3], [2.5, 3], [2.5, 1.5], [1, 1.5]]  # a non-convex (L-shaped) wall in plan


def test_prism_cells_follow_the_polygon_and_z():
    spec = box_room(obstacles=[{"name": "w", "prism": {"polygon": L_WALL, "z": [0, 2]},
                                "source": {"file": "plan.dxf", "layer": "A-WALL", "handle": "1F"}}])
    scene = build_scene(spec)
    pts = np.array([[2.0, 1.2, 1.0],   # in the L's foot
                    [2.7, 2.5, 1.0],   # in the L's leg
                    [2.0, 2.5, 1.0],   # in the L's notch: free
                    [2.0, 1.2, 2.5]])  # above the wall: free
    assert scene.occupancy.is_occupied(pts).tolist() == [True, True, False, False]
    assert set(scene.prisms) == {"w"} and scene.prisms["w"][1:] == (0.0, 2.0)
    res = scene.occupancy.resolution
    cells = scene.occupancy.occupied[:, :, int(1.0 / res)].sum() - build_scene(box_room()).occupancy.occupied[
        :, :, int(1.0 / res)].sum()
    area = 2 * 0.5 + 0.5 * 1.5  # foot + leg, m²
    assert cells * res**2 == pytest.approx(area, rel=0.08)


def test_prism_with_a_hole_leaves_the_hole_free():
    ring = {"polygon": [[1, 1], [3, 1], [3, 3], [1, 3]], "holes": [[[1.5, 1.5], [2.5, 1.5], [2.5, 2.5], [1.5, 2.5]]],
            "z": [0, 3]}
    occ = build_scene(box_room(obstacles=[{"name": "r", "prism": ring}])).occupancy
    assert occ.is_occupied(np.array([[1.2, 2.0, 1.0], [2.0, 2.0, 1.0]])).tolist() == [True, False]


@pytest.mark.parametrize("prism, key", [({"polygon": [[0, 0], [1, 0]], "z": [0, 1]}, "polygon"),
                                        ({"polygon": L_WALL, "z": [2, 1]}, "z"),
                                        ({"polygon": [[0, 0], [1, 1], [1, 0], [0, 1]], "z": [0, 1]}, "polygon")])
def test_bad_prisms_are_refused_naming_the_key(prism, key):
    with pytest.raises(Exception, match=key):
        box_room(obstacles=[{"name": "w", "prism": prism}])


def test_prism_and_box_together_are_refused():
    with pytest.raises(Exception, match="exactly one"):
        box_room(obstacles=[{"name": "w", "prism": {"polygon": L_WALL, "z": [0, 1]},
                             "box": {"min": [0, 0, 0], "max": [1, 1, 1]}}])


def test_registry_kinds_and_refusals(tmp_path):
    assert [plan_kind(f"a{s}") for s in (".DXF", ".png", ".jpeg", ".tif", ".ifc", ".ply")] == \
        ["dxf", "image", "image", "image", "ifc", None]
    with pytest.raises(InputError, match="file not found"):
        import_plan(tmp_path / "none.dxf")
    with pytest.raises(InputError, match="not a plan"):
        import_plan(tmp_path / "a.ply")


def test_prism_obstacles_keep_holes_and_provenance():
    from shapely.geometry import Polygon

    ring = Polygon([(0, 0), (4, 0), (4, 4), (0, 4)], [[(0.2, 0.2), (3.8, 0.2), (3.8, 3.8), (0.2, 3.8)]])
    (ob,) = prism_obstacles(ring, 0, 2.5, "wall", {"file": "p.dxf", "layer": "A-WALL"})
    assert ob["name"] == "wall-1" and ob["source"]["layer"] == "A-WALL"
    assert len(ob["prism"]["holes"]) == 1 and ob["prism"]["z"] == [0, 2.5]
