"""People as targets (issue 36): a hand-built case whose answer is known by hand.

A 10 m x 4 m empty room. Person T stands at (6, 2), person B at (3, 2), between camera A
(at eye height, (0, 2, 1.6), looking along +x) and T. Camera C at (9.5, 2, 1.6) looks back
at T; camera D hangs high at (0, 2, 2.9), tilted down, and looks over B's head:

- A sees B (its own cylinder never blocks it) but not T (B is in the way);
- C sees T but not B (T is in the way);
- D sees both (the sight line to T passes x = 3 m at z ≈ 2.1 m, above B's 1.75 m).

So with cameras {A, C} each person is seen by one camera (neither triangulatable), with
D added both are seen by two; a budget of 2 on the people-only problem must take D.
"""

from __future__ import annotations

import numpy as np
import pytest

from camplace.cameras.candidates import Candidates, rotation_from_ypr
from camplace.cameras.models import camera_from_spec
from camplace.problem.model import PlacementProblem
from camplace.problem.people import people_problem
from camplace.scene.build import build_scene
from camplace.spec.loading import parse_scene
from camplace.targets.build import build_targets
from camplace.targets.crowd import Crowds
from camplace.targets.people import people_targets, person_coverage
from camplace.visibility.crowd import people_grid
from camplace.visibility.people import people_rows
from camplace.visibility.voxel import VoxelEngine

ROOM = {"name": "corridor", "voxel_size": 0.5, "occupancy_resolution": 0.1,
        "room": {"footprint": [[0, 0], [10, 0], [10, 4], [0, 4]], "height": 3.0},
        "targets": [{"name": "floor", "kind": "volume", "heights": [1.0], "coverage": 2}],
        "cameras": [{"name": "cam", "resolution": [640, 480], "fov_deg": [90, 70], "max_range": 20.0}],
        "mounts": [{"kind": "ceiling_grid", "camera": "cam", "spacing": 2.0, "pitch_deg": [45]}],
        "placement": {"budget": 2}}
POSES = {"A": ((0.1, 2.0, 1.6), (0.0, 0.0)), "C": ((9.9, 2.0, 1.6), (180.0, 0.0)),
         "D": ((0.1, 2.0, 2.9), (0.0, 14.0))}


@pytest.fixture(scope="module")
def seen():
    spec = parse_scene(ROOM)
    sc = build_scene(spec)
    base = build_targets(sc)
    pos = np.array([p for p, _ in POSES.values()], float)
    ang = np.array([[y, p, 0.0] for _, (y, p) in POSES.values()], float)
    cams = Candidates(pos, rotation_from_ypr(ang[:, 0], ang[:, 1], ang[:, 2]), ang, np.zeros(3, np.int32),
                      np.arange(3, dtype=np.int64), (camera_from_spec(spec.cameras[0]),))
    crowds = Crowds(np.array([[6.0, 2.0], [3.0, 2.0]]), np.array([0, 2], np.int64), 0.25, 1.75)
    people = people_targets(crowds, base, [1.25, 1.6], 2)
    grid = people_grid(crowds, np.zeros(2), np.array([10.0, 4.0]))
    return people, people_rows(VoxelEngine(), sc.occupancy, people, cams, grid)


def test_each_camera_sees_whom_it_should(seen):
    people, V = seen
    got = V.toarray()  # rows A, C, D; columns T torso, T head, B torso, B head
    assert got.tolist() == [[0, 0, 1, 1], [1, 1, 0, 0], [1, 1, 1, 1]]


def test_people_coverage_and_the_choice_of_two_cameras(seen):
    people, V = seen
    cov = lambda rows: person_coverage(np.asarray(V[rows].sum(axis=0)).ravel(), people.n_heights)
    assert cov([0, 1]).tolist() == [1, 1] and cov([0, 1, 2]).tolist() == [2, 2]
    t = people.targets
    empty = PlacementProblem(V[:, :0].tocsr(), np.zeros(0, np.int64), np.zeros(0), 2, np.arange(3))
    p = people_problem(empty, V, t.gamma, t.weights, 1.0)
    costs = {tuple(s): p.cost(np.array(s)) for s in ([0, 1], [0, 2], [1, 2])}
    assert costs[(0, 1)] > costs[(0, 2)] == costs[(1, 2)]  # A + C miss a view of each person; D is in the best
