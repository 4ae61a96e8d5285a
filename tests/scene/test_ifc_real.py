"""The IFC importer on real files nobody here wrote (issue 25; facts in
../shared/data/plans/SOURCES.md): the buildingSMART Duplex (Revit 2011, IFC2X3, four
storeys), a Revit 2021 file in mm with two separate blocks and RPC trees around them,
and the FreeCAD Barcelona Pavilion (IFC4, no storeys, no IfcSpace). Every storey imports
and the scene schema takes it; the default storey is the one a user plans; a small
grid-only run on each puts its cameras inside the footprint and outside every obstacle."""

from __future__ import annotations

from pathlib import Path

import pytest
from shapely.geometry import Point, Polygon

pytest.importorskip("ifcopenshell")

import camplace  # noqa: E402
from camplace.scene.importers import read_plan, read_storey_plans  # noqa: E402
from camplace.spec.loading import parse_scene  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
# ../shared beside the repository (CI, the main checkout), or beside the folder of a worktree
PLANS = next((p for p in (REPO.parent / "shared/data/plans", REPO.parent.parent / "shared/data/plans")
              if p.is_dir()), REPO.parent / "shared/data/plans")
DUPLEX, WHALE, PAVILION = (PLANS / n for n in ("Duplex_A_20110907.ifc", "bim-whale_LargeBuilding.ifc",
                                               "Pabellon_de_Barcelona.ifc"))
pytestmark = pytest.mark.skipif(not all(p.is_file() for p in (DUPLEX, WHALE, PAVILION)),
                                reason=f"the real plans are not in {PLANS} (../shared/data/plans)")
LEVEL_1 = {"Foyer", "Living Room", "Kitchen", "Bathroom 1", "Stair", "Room"}
LEVEL_2 = {"Hallway", "Bedroom 1", "Bedroom 2", "Bathroom 2", "Utility"}
# footprints (m²) at the outer faces of the outer walls (SOURCES.md): the Duplex 8.8 x 17.8 m; bim-whale's west
# block x -14.783..-6.583, y -10.648..9.552 (its walls) and east block x 0.583..20.783, y -5.758..2.442 (spaces 5-8,
# x 0.783..20.583, y -5.558..2.242, in 0.2 m walls)
DUPLEX_M2 = 8.8 * 17.8
WHALE_M2 = 8.2 * 20.2 + 20.2 * 8.2
WHALE_ROOMS = {"Room 1": 49.92, "Room 2": 39.78, "Room 3": 33.18, "Room 4": 26.86, "Room 5": 49.92, "Room 6": 39.78,
               "Room 7": 33.18, "Room 8": 26.86}  # GrossFloorArea (SOURCES.md)


@pytest.fixture(scope="module")
def duplex_all():
    return read_storey_plans(DUPLEX)


@pytest.fixture(scope="module")
def got(duplex_all):
    """What the importer understood of every storey of the three files (key: file, storey)."""
    out = {("duplex", None): read_plan(DUPLEX), ("whale", None): read_plan(WHALE),
           ("pavilion", None): read_plan(PAVILION)}
    out.update({("duplex", n): g for n, g, _ in duplex_all})
    out.update({("duplex", n): read_plan(DUPLEX, storey=n) for n in ("T/FDN", "Roof")})
    out[("whale", "Level 2")] = read_plan(WHALE, storey="Level 2")
    return out


def _base(name: str) -> str:
    return name.rsplit(" ", 1)[0] if name[-1].isdigit() and name.split()[-1][0] in "AB" else name


def _area(data) -> float:
    return Polygon(data["room"]["footprint"]).area


def test_every_storey_imports_and_the_schema_takes_it(got):
    for key, g in got.items():
        spec = parse_scene(g.scene, str(key))
        assert spec.room.height > 1.0 and _area(g.scene) > 100, key
        for o in g.scene["obstacles"]:
            assert -1e-6 <= o["prism"]["z"][0] < o["prism"]["z"][1] <= spec.room.height + 1e-6, (key, o["name"])
        assert g.used["units"] and g.used["storey"] and g.used["footprint"] and g.notes, key


def test_duplex_default_is_level_1_with_its_rooms_named(got):
    g = got[("duplex", None)]
    assert g.used["storey"].startswith("Level 1") and "Roof" in g.notes[0] and "most rooms" in g.notes[0]
    assert [(s["name"], s["elevation_m"], len(s["rooms"]), s["chosen"]) for s in g.storeys] == [
        ("T/FDN", -1.25, 0, False), ("Level 1", 0.0, 10, True), ("Level 2", pytest.approx(3.1), 10, False),
        ("Roof", pytest.approx(6.0), 1, False)]
    names = [z["name"] for z in g.scene["zones"]]
    assert len(names) == 10 and {_base(n) for n in names} == LEVEL_1 and "Foyer A101" in names
    assert _area(g.scene) == pytest.approx(DUPLEX_M2, rel=0.1)  # the outer faces of its 0.42 m outer walls
    assert len(g.openings) >= 10  # 6 doors and 4 windows on Level 1


def test_duplex_storey_all_gives_both_floors(got, duplex_all):
    assert [(n, e) for n, _, e in duplex_all] == [("Level 1", 0.0), ("Level 2", pytest.approx(3.1))]
    for name, rooms in (("Level 1", LEVEL_1), ("Level 2", LEVEL_2)):
        zones = [z["name"] for z in got[("duplex", name)].scene["zones"]]
        assert len(zones) == 10 and {_base(n) for n in zones} == rooms, name
        assert _area(got[("duplex", name)].scene) == pytest.approx(DUPLEX_M2, rel=0.1), name
    for key, g in got.items():  # every wall of the building is inside the footprint (an obstacle in it)
        assert not [k for k in g.skipped if k.startswith("outside the footprint: IfcWall")], (key, g.skipped)
    assert got[("duplex", "Roof")].scene["zones"][0]["name"] == "Roof"


def test_duplex_level_2_is_open_over_the_two_stairs_of_level_1(got):
    """Issue 33: the Duplex's Level 2 floor is open where the stairs of Level 1 rise to it
    (each about 1.0 x 3.5 m, over Level 1's two stair spaces, which are two storeys high);
    Level 1 is closed over T/FDN; the summaries say so and name no other walls or ceiling."""
    l1, l2 = got[("duplex", "Level 1")], got[("duplex", "Level 2")]
    assert l1.floor_openings == [] and l1.used["floor openings"] == "0 open to the storey below"
    assert l2.used["floor openings"] == "2 open to the storey below (stair voids 2, atria 2)"
    stairs = [Polygon(z["polygon"]) for z in l1.scene["zones"] if z["name"] in ("Stair", "Room")]
    for ring in l2.floor_openings:
        hole = Polygon(ring)
        assert hole.area == pytest.approx(3.55, abs=0.1)
        assert max(hole.intersection(q).area for q in stairs) > 0.95 * hole.area
    for key in (("duplex", "Level 1"), ("duplex", "Level 2"), ("whale", None), ("pavilion", None)):
        assert "shaped like walls" not in got[key].used["walls"], key  # the stairs' stringers are no walls
    assert got[("duplex", "Level 1")].used["ceiling"] == "2.60 m (IfcCovering underside over the rooms)"


def test_bim_whale_two_blocks_eight_rooms_no_trees(got):
    g = got[("whale", None)]
    zones = {z["name"]: Polygon(z["polygon"]).area for z in g.scene["zones"]}
    assert zones == pytest.approx(WHALE_ROOMS, rel=0.02)
    assert _area(g.scene) == pytest.approx(WHALE_M2, rel=0.1)  # both blocks to their outer faces, and the seam
    outside = [o for o in g.scene["obstacles"] if o["source"]["class"] == "outside"]
    assert len(outside) == 1 and Polygon(outside[0]["prism"]["polygon"]).area < 1.0
    xs = [x for o in g.scene["obstacles"] for x, _ in o["prism"]["polygon"]]
    assert -14.9 < min(xs) and max(xs) < 20.9  # the trees (x -22.6..30.6) are left out
    assert g.skipped["outside the footprint: IfcBuildingElementProxy"] == 13  # 11 trees, 2 model texts
    assert len(g.openings) >= 40 and "mm" in g.used["units"]


def test_bim_whale_level_2_walls_only(got):
    g = got[("whale", "Level 2")]
    assert _area(g.scene) == pytest.approx(8.2 * 20.2, rel=0.02)  # its floor slab, under the west block's walls
    assert len(g.scene["zones"]) == 1 and g.storeys[1]["chosen"] and g.storeys[1]["elevation_m"] == 4.0
    assert {o["source"]["class"] for o in g.scene["obstacles"]} >= {"IfcWallStandardCase", "IfcWindow"}


def test_pavilion_one_storey_footprint_agrees_with_the_dxf(got):
    g = got[("pavilion", None)]
    assert _area(g.scene) == pytest.approx(862.7, rel=0.05)  # walls_outline of the DXF's Walls layer
    assert len(g.scene["zones"]) == 1 and [s["name"] for s in g.storeys] == ["Pabellon"]
    assert "no IfcBuildingStorey" in g.notes[0] and g.storeys[0]["elevation_m"] == 0.0
    assert not any("Footing" in o["name"] for o in g.scene["obstacles"])  # below the floor


def _small(data: dict) -> dict:
    """The scene with a coarse grid (0.5 m voxels, one height, 2 m mounts, four yaws): a quick run."""
    d = dict(data, voxel_size=0.5)
    d["targets"] = [dict(data["targets"][0], heights=[1.0])]
    d["mounts"] = [dict(data["mounts"][0], spacing=2.0, yaw_deg={"start": 0, "stop": 270, "step": 90},
                        pitch_deg=[45])]
    return d


@pytest.mark.parametrize("which", ["duplex", "whale", "pavilion"])
def test_grid_run_puts_cameras_inside_and_not_in_an_obstacle(got, which):
    data = _small(got[(which, None)].scene)
    res = camplace.run(parse_scene(data, which), budget=4, solver="greedy")
    pos = res.visibility.candidates.positions[res.placement.selected]
    assert len(pos) == 4
    assert not res.scene.occupancy.is_occupied(pos).any()
    fp = Polygon(data["room"]["footprint"])
    assert all(fp.contains(Point(*p[:2])) for p in pos)
    assert ((pos[:, 2] > 0) & (pos[:, 2] < data["room"]["height"])).all()
