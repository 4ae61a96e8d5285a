"""The any-part rule (probe 1, the paper's) in the voxel engine: it agrees with the pixel
engine at stride 1 on >= 99 % of V's entries under both rules, and hand-checked cases:
a voxel hidden at its centre but visible at a corner, a voxel at the image edge."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from camplace.cameras.candidates import Candidates, build_candidates
from camplace.cameras.models import camera_from_spec
from camplace.core.errors import InputError
from camplace.scene.build import build_scene
from camplace.targets.build import Targets, build_targets
from camplace.visibility import footprint
from camplace.visibility.engine import compute_visibility
from camplace.visibility.pixel import PixelEngine
from camplace.visibility.voxel import VoxelEngine

from conftest import box_room

SMALL_CAM = {"name": "cam", "resolution": [320, 240], "fov_deg": [90, 70], "max_range": 4.0}
LOOK_X = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])  # world from camera: looking along +x


def jaccard(a, b) -> float:
    """Shared non-zeros / union of two same-shape sparse 0/1 matrices."""
    shared = a.multiply(b).nnz
    union = a.nnz + b.nnz - shared
    return shared / union if union else 1.0


@pytest.fixture(scope="module")
def probe_scene():
    """A 4 x 4 x 3 m room with two boxes, volume targets at two heights, the boxes'
    surface patches, and a small low-resolution camera (cheap at stride 1)."""
    spec = box_room(obstacles=[{"name": "a", "box": {"min": [1.2, 1.2, 0.0], "max": [2.0, 2.4, 1.6]}},
                               {"name": "b", "box": {"min": [2.6, 2.2, 0.0], "max": [3.1, 3.3, 1.1]}}],
                    targets=[{"name": "walkable", "kind": "volume", "heights": [0.5, 1.25], "coverage": 1},
                             {"name": "boxes", "kind": "surface", "of": ["a", "b"], "coverage": 1}],
                    cameras=[SMALL_CAM],
                    mounts=[{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0, "yaw_deg": [0, 90, 200],
                             "pitch_deg": [40]}])
    sc = build_scene(spec)
    t = build_targets(sc)
    c = build_candidates(sc, {x.name: camera_from_spec(x) for x in spec.cameras})
    return sc, t, c


@pytest.mark.parametrize("probe", [0.0, 1.0])
def test_voxel_agrees_with_pixel_at_stride_1(probe_scene, probe):
    sc, t, c = probe_scene
    vox = compute_visibility(VoxelEngine(probe), sc.occupancy, t, c).V
    pix = compute_visibility(PixelEngine(stride=1, probe=probe), sc.occupancy, t, c).V
    assert pix.nnz > 1000
    assert jaccard(vox, pix) >= 0.99, (probe, vox.nnz, pix.nnz)
    for surface, least in ((False, 0.99), (True, 0.96)):  # ~430 surface entries: 13 differ under probe 0
        cols = np.nonzero(t.is_surface == surface)[0]
        assert jaccard(vox[:, cols], pix[:, cols]) >= least, (probe, surface)


def test_the_any_part_rule_contains_the_centre_rule(probe_scene):
    sc, t, c = probe_scene
    centre = compute_visibility(VoxelEngine(), sc.occupancy, t, c).V
    half = compute_visibility(VoxelEngine(0.5), sc.occupancy, t, c).V
    part = compute_visibility(VoxelEngine(1.0), sc.occupancy, t, c).V
    assert centre.nnz < half.nnz < part.nnz
    assert centre.multiply(half).nnz == centre.nnz and half.multiply(part).nnz == half.nnz


def one_target(position, normal=(0.0, 0.0, 0.0)) -> Targets:
    """A single target (volume when normal is zero)."""
    kind = "surface" if any(normal) else "volume"
    return Targets(np.array([position], float), np.array([normal], float), np.ones(1, np.int64), np.ones(1),
                   np.zeros(1, np.int32), ("t",), (kind,), np.array([90.0]), np.array([0.0]), 0.25)


def one_camera(position, spec=SMALL_CAM) -> Candidates:
    """One candidate at ``position`` looking along +x (horizontal)."""
    return Candidates(np.array([position], float), LOOK_X[None].copy(), np.zeros((1, 3)), np.zeros(1, np.int32),
                      np.zeros(1, np.int64), (camera_from_spec(box_room(cameras=[spec]).cameras[0]),))


def seen(engine, occupancy, targets, candidates) -> bool:
    return bool(compute_visibility(engine, occupancy, targets, candidates).V.nnz)


def test_centre_hidden_behind_a_box_edge_corner_visible():
    """A wall-like box ends at y = 2.0; the camera and the target centre sit at y = 1.98,
    so the centre line runs through the box, but the voxel's +y corners (y = 2.105) are
    in plain view past the box's edge."""
    sc = build_scene(box_room(obstacles=[{"name": "w", "box": {"min": [1.5, 1.0, 0.0], "max": [2.0, 2.0, 3.0]}}],
                              cameras=[SMALL_CAM]))
    t, c = one_target([3.0, 1.98, 1.0]), one_camera([0.5, 1.98, 1.0])
    for probe, expect in ((0.0, False), (1.0, True)):
        assert seen(VoxelEngine(probe), sc.occupancy, t, c) is expect, probe
        assert seen(PixelEngine(stride=1, probe=probe), sc.occupancy, t, c) is expect, probe
    far = one_target([3.0, 1.7, 1.0])  # 0.3 m behind the edge: every part hidden
    assert not seen(VoxelEngine(1.0), sc.occupancy, far, c)


def test_voxel_at_the_image_edge():
    """The image spans +-45 deg horizontally; the target centre is at 45.5 deg (outside),
    its nearest corner at 42 deg (inside)."""
    sc = build_scene(box_room(cameras=[SMALL_CAM]))
    c = one_camera([0.5, 3.0, 1.0])
    t = one_target([2.5, 3.0 - 2.0 * np.tan(np.radians(45.5)), 1.0])
    for probe, expect in ((0.0, False), (1.0, True)):
        assert seen(VoxelEngine(probe), sc.occupancy, t, c) is expect, probe
        assert seen(PixelEngine(stride=1, probe=probe), sc.occupancy, t, c) is expect, probe
    outside = one_target([2.5, 3.0 - 2.0 * np.tan(np.radians(52.0)), 1.0])  # nearest corner at 48 deg
    assert not seen(VoxelEngine(1.0), sc.occupancy, outside, c)


def test_a_voxel_part_within_range():
    """Range 4 m: a centre 4.1 m away is out of range, its front face (3.975 m) is not."""
    sc = build_scene(box_room(footprint=[[0, 0], [6, 0], [6, 4], [0, 4]], cameras=[SMALL_CAM]))
    c = one_camera([0.5, 2.0, 1.0])
    t = one_target([4.6, 2.0, 1.0])
    assert not seen(VoxelEngine(), sc.occupancy, t, c)
    assert seen(VoxelEngine(1.0), sc.occupancy, t, c)
    assert not seen(VoxelEngine(0.2), sc.occupancy, t, c)  # the central 5 cm cube ends at 4.075 m


def test_probe_parameters():
    with pytest.raises(InputError, match="^probe: expected a fraction") as err:
        VoxelEngine(-0.1)
    assert err.value.option == "probe"
    sc = build_scene(box_room(cameras=[SMALL_CAM]))
    bare = replace(one_target([2.0, 2.0, 1.0]), voxel_size=None)  # targets that do not say their voxel edge
    for engine, option in ((VoxelEngine(0.5), "probe"), (PixelEngine(), "visibility_mode")):
        with pytest.raises(InputError, match="needs the targets' voxel edge") as err:
            seen(engine, sc.occupancy, bare, one_camera([0.5, 2.0, 1.0]))
        assert err.value.option == option
    assert VoxelEngine(0.5).cache_tag() != VoxelEngine(1.0).cache_tag() != VoxelEngine().cache_tag()


def test_footprint_lattices():
    lat = footprint.cube_lattice(3)
    assert lat.shape == (26, 3) and np.all(np.abs(lat).max(1) == 1.0)
    assert len(footprint.cube_lattice(5)) == 5 ** 3 - 3 ** 3
