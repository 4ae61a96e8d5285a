"""Buildings (issue 33): storeys stacked in one occupancy grid. Cases whose answer is known
by hand: a two-storey box with a 2 m x 2 m void in the upper floor — the lower floor is seen
from the upper one only through the void, never through the slab; one budget shared by a
large and a small storey beats an equal split; the scene file's storeys: form and its errors."""

from __future__ import annotations

import numpy as np
import pytest
from shapely.geometry import Point, Polygon

from camplace.core.errors import InputError
from camplace.scene.build import build_scene, storey_index
from camplace.spec.loading import parse_scene
from camplace.workflows.run import run

VOID = [[4.0, 4.0], [6.0, 4.0], [6.0, 6.0], [4.0, 6.0]]
SQUARE = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]


def building(storeys: dict, budget: int = 4, **extra) -> dict:
    return {"name": "b", "voxel_size": 0.5, "occupancy_resolution": 0.1,
            "cameras": [{"name": "cam", "fov_deg": [90, 70], "resolution": [640, 480], "max_range": 20}],
            "targets": [{"name": "floor", "kind": "volume", "coverage": 1, "heights": [1.0]}],
            "mounts": [{"kind": "ceiling_grid", "camera": "cam", "spacing": 2.0, "pitch_deg": [45, 90],
                        "yaw_deg": {"start": 0, "stop": 270, "step": 90}}],
            "placement": {"budget": budget}, "storeys": storeys, **extra}


def two_storeys(void: bool = True) -> dict:
    upper = {"elevation": 3.5, "room": {"footprint": SQUARE, "height": 3.0}}
    if void:
        upper["floor_openings"] = [VOID]
    return building({"Ground": {"elevation": 0.0, "room": {"footprint": SQUARE, "height": 3.0}}, "First": upper})


@pytest.fixture(scope="module")
def void_run():
    return run(parse_scene(two_storeys(), "void"), solver="greedy")


def test_slab_is_solid_except_the_void():
    sc = build_scene(parse_scene(two_storeys(), "void"))
    slab = np.array([[5.0, 5.0, 3.25], [1.0, 1.0, 3.25], [7.0, 5.0, 3.25], [5.0, 5.0, 1.0], [5.0, 5.0, 4.5]])
    assert sc.occupancy.is_occupied(slab).tolist() == [False, True, True, False, False]
    assert [st.name for st in sc.storeys] == ["Ground", "First"]
    assert storey_index(sc.storeys, np.array([0.0, 2.9, 3.49, 3.5, 6.4])).tolist() == [0, 0, 0, 1, 1]


def test_lower_floor_seen_from_above_only_through_the_void(void_run):
    vis = void_run.visibility
    cams, tg = vis.candidates.positions, vis.targets.positions
    upper_cams = np.flatnonzero(cams[:, 2] > 3.5)
    lower_targets = tg[:, 2] < 3.0
    V = vis.V.tocsr()
    hole = Polygon(VOID)
    through = 0
    for i in upper_cams:
        seen = V.indices[V.indptr[i]:V.indptr[i + 1]]
        for j in seen[lower_targets[seen]]:
            c, t = cams[i], tg[j]
            for z in (3.05, 3.25, 3.45):  # the slab between the storeys: the sight line crosses it in the void
                s = (z - c[2]) / (t[2] - c[2])
                assert hole.buffer(0.11).contains(Point(c[:2] + s * (t[:2] - c[:2])))
            through += 1
    assert through > 0  # the void does let the upper floor see down
    # the lower floor's targets right under the void are seen from some upper camera
    under = np.flatnonzero(lower_targets & (np.abs(tg[:, 0] - 5) < 0.8) & (np.abs(tg[:, 1] - 5) < 0.8))
    assert len(under) and np.asarray(V[upper_cams][:, under].sum(axis=0)).ravel().max() > 0


def test_no_view_between_floors_without_a_void():
    sc = run(parse_scene(two_storeys(void=False), "solid"), solver="greedy", refine=False)
    vis = sc.visibility
    up_cam = vis.candidates.positions[:, 2] > 3.5
    up_tg = vis.targets.positions[:, 2] > 3.5
    V = vis.V.tocsc()
    assert V[np.flatnonzero(up_cam)][:, np.flatnonzero(~up_tg)].nnz == 0
    assert V[np.flatnonzero(~up_cam)][:, np.flatnonzero(up_tg)].nnz == 0


def test_targets_over_the_void_are_dropped(void_run):
    tg = void_run.visibility.targets.positions
    upper = tg[tg[:, 2] > 3.5]
    assert not any(Polygon(VOID).contains(Point(p[:2])) for p in upper)
    assert set(void_run.visibility.targets.region_names) == {"Ground/floor", "First/floor"}


def test_shared_budget_beats_an_equal_split():
    big = [[0.0, 0.0], [24.0, 0.0], [24.0, 12.0], [0.0, 12.0]]
    small = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]
    storeys = {"Hall": {"elevation": 0.0, "room": {"footprint": big, "height": 3.0}},
               "Office": {"elevation": 3.5, "room": {"footprint": small, "height": 3.0}}}
    shared = run(parse_scene(building(storeys, budget=8), "shared"), solver="greedy", refine=False)
    split = {k: dict(v, budget=4) for k, v in storeys.items()}
    equal = run(parse_scene(building(split, budget=8), "split"), solver="greedy", refine=False)
    per = {s["storey"]: s["cameras"] for s in shared.metrics.storeys}
    assert per["Hall"] > 4 and sum(per.values()) == 8  # the solver gave the big floor more
    eq = {s["storey"]: s["cameras"] for s in equal.metrics.storeys}
    assert eq["Hall"] == 4 and eq["Office"] <= 4  # each floor held to its half
    assert shared.placement.objective < equal.placement.objective


def test_scene_file_storeys_errors():
    with pytest.raises(InputError, match=r"storeys\.First\.room\.footprint"):
        parse_scene(building({"First": {"room": {"footprint": [[0, 0], [1, 1], [0, 1], [1, 0]], "height": 3}}}))
    with pytest.raises(InputError, match=r"storeys\.Upper\.elevation"):
        parse_scene(building({"Lower": {"elevation": 2.0, "room": {"footprint": SQUARE, "height": 3}},
                              "Upper": {"elevation": 2.0, "room": {"footprint": SQUARE, "height": 3}}}))
    with pytest.raises(InputError, match="obstacles"):
        parse_scene(building({"A": {"room": {"footprint": SQUARE, "height": 3}}},
                             obstacles=[{"name": "x", "box": {"min": [0, 0, 0], "max": [1, 1, 1]}}]))
    with pytest.raises(InputError, match=r"storeys\.A\.budget"):
        parse_scene(building({"A": {"room": {"footprint": SQUARE, "height": 3}, "budget": -1}}))


def test_a_storey_of_a_building_is_the_single_room_scene():
    spec = parse_scene(two_storeys(), "void")
    one = spec.storey_spec("Ground")
    assert one.storeys is None and one.room.height == 3.0 and one.name == "b/Ground"
    assert spec.room.height == pytest.approx(6.5)  # the envelope: lowest floor to highest ceiling


def test_visibility_by_storey_groups_is_the_whole_buildings_v():
    from camplace.cameras.candidates import build_candidates
    from camplace.cameras.models import cameras_from_spec
    from camplace.targets.build import build_targets
    from camplace.visibility.engine import compute_visibility
    from camplace.visibility.voxel import VoxelEngine
    from camplace.workflows.building import building_visibility, storey_groups

    data = two_storeys()
    data["storeys"]["Top"] = {"elevation": 7.0, "room": {"footprint": SQUARE, "height": 3.0}}  # a solid slab below
    spec = parse_scene(data, "three")
    sc = build_scene(spec)
    assert storey_groups(sc) == [[0, 1], [2]]
    targets, cands = build_targets(sc), build_candidates(sc, cameras_from_spec(spec))
    whole = compute_visibility(VoxelEngine(), sc.occupancy, targets, cands).V
    split = building_visibility(VoxelEngine(), sc, targets, cands).V
    assert split.shape == whole.shape and (split != whole).nnz == 0 and whole.nnz > 0


def test_building_scene_from_imported_storeys_keeps_levels_apart():
    from camplace.workflows.building import building_scene

    def plan(rooms: int, height: float = 3.0) -> dict:
        return {"room": {"footprint": SQUARE, "height": height}, "obstacles": [
            {"name": "wall", "prism": {"polygon": [[0, 0], [1, 0], [1, 0.2], [0, 0.2]], "z": [0.0, height]}}],
            "zones": [{"name": f"r{k}", "polygon": SQUARE} for k in range(rooms)],
            **{k: v for k, v in building({}).items() if k not in ("name", "storeys")}}

    notes: list[str] = []
    data = building_scene("b", [("Upper", plan(2, 3.4), 3.2, [VOID]), ("Ground", plan(3, 3.4), 0.0, []),
                                ("Ground copy", plan(1), 0.5, [])], budget=6, notes=notes)
    assert list(data["storeys"]) == ["Ground", "Upper"] and data["placement"]["budget"] == 6
    assert "Ground copy" in notes[0] and "planned as 'Ground' alone" in notes[0]
    ground = data["storeys"]["Ground"]
    assert ground["room"]["height"] == pytest.approx(3.0)  # lowered to 0.2 m below the next floor (3.2 m)
    assert ground["obstacles"][0]["prism"]["z"] == [0.0, 3.0]
    assert data["storeys"]["Upper"]["floor_openings"] == [VOID]
    spec = parse_scene(data, "imported")
    assert spec.storey_names == ["Ground", "Upper"]
