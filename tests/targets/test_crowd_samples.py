"""Crowd samples (camplace.targets.crowd): where people may stand, how many, deterministic."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.distance import pdist

from camplace.scene.build import build_scene
from camplace.spec.crowd import CrowdSpec
from camplace.targets.crowd import OPTIMISE, SCORE, sample_crowds, walkable_floor
from camplace.targets.zones import in_polygon
from conftest import box_room

QUEUE = [[0, 0], [2, 0], [2, 1.5], [0, 1.5]]
WC = [[3, 3], [4, 3], [4, 4], [3, 4]]


@pytest.fixture(scope="module")
def room():
    spec = box_room(obstacles=[{"name": "crate", "box": {"min": [1.5, 2.0, 0.0], "max": [2.5, 3.0, 1.0]}}])
    data = spec.model_dump(exclude_none=True)
    data["zones"] = [{"name": "queue", "polygon": QUEUE}, {"name": "wc", "polygon": WC, "privacy": True}]
    from camplace.spec.loading import parse_scene

    return build_scene(parse_scene(data))


def test_people_stand_on_free_floor_apart_and_as_many_as_asked(room):
    crowd = CrowdSpec(density=1.0, zones={"queue": 2.0}, samples=16)
    floor = walkable_floor(room, crowd)
    cr = sample_crowds(room, crowd, floor=floor)
    areas = floor.areas()
    want = np.rint(floor.densities * areas).astype(int)
    assert cr.n_samples == 16 and list(cr.info["wanted"]) == [int(want.sum())] * 16
    assert abs(areas.sum() - (16 - 1 - 1)) < 0.3  # 4x4 room minus crate and privacy zone (1 m² each)
    for s in range(cr.n_samples):
        xy = cr.sample(s)
        assert len(xy) == want.sum()  # reachable density: everyone placed
        assert pdist(xy).min() >= 2 * crowd.radius  # no overlap
        ring = xy[:, None, :] + crowd.radius * np.stack([np.cos(a := np.linspace(0, 2 * np.pi, 16)),
                                                         np.sin(a)], 1)[None]
        pts = np.c_[ring.reshape(-1, 2), np.full(ring.size // 2, 0.5)]
        assert not room.occupancy.is_occupied(pts).any()  # the whole disc on free floor
        assert not in_polygon(WC, ring.reshape(-1, 2)).any()  # never in a privacy zone
        assert in_polygon(QUEUE, xy).sum() >= want[1] - 1  # the zone's own density (boundary cells aside)


def test_same_seed_same_crowds_other_stream_other_crowds(room):
    crowd = CrowdSpec(density=0.5, samples=3, score_samples=3, seed=7)
    a, b = sample_crowds(room, crowd), sample_crowds(room, crowd)
    assert np.array_equal(a.xy, b.xy) and np.array_equal(a.ptr, b.ptr)
    held_out = sample_crowds(room, crowd, SCORE)
    assert not np.array_equal(a.xy[:5], held_out.xy[:5]) and a.info["stream"] == OPTIMISE
    assert not np.array_equal(a.sample(0), a.sample(1))  # independent samples
    assert sample_crowds(room, CrowdSpec(density=0.0)).empty
