"""Free space from scans: carving, clearance, connectivity, scene glue, surface targets
on scans, wall mounts."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from camplace.core.errors import InputError
from camplace.spec.loading import parse_scene
from camplace.scene.build import build_scene
from camplace.scene.freespace import carve_observed, compute_free_space
from camplace.scene.loaders.pointcloud import write_ply
from camplace.targets.build import build_targets
from tests.conftest import box_room


def test_carving_does_not_see_inside_a_closed_box():
    res = 0.1
    occ = np.zeros((40, 40, 20), bool)
    occ[[1, -2], :, :] = occ[:, [1, -2], :] = occ[:, :, [1, -2]] = True  # room shell (inside a 1-cell margin)
    occ[20:26, 20:26, 1:8] = True
    occ[21:25, 21:25, 2:7] = False  # a hollow closed box
    observed, n = carve_observed(occ, np.zeros(3), res, np.array([[1.05, 1.05, 1.05]]))
    assert n > 0
    assert not observed[21:25, 21:25, 2:7].any()  # its inside is never seen
    assert observed[5, 5, 5] and observed[10, 30, 10]
    assert not observed[30, 30, 2]  # hidden behind the box from the viewpoint


def test_free_space_clearance_and_connectivity():
    res = 0.1
    occ = np.zeros((30, 30, 20), bool)
    occ[[0, -1], :, :] = occ[:, [0, -1], :] = occ[:, :, [0, -1]] = True
    occ[10:16, 10:16, 0:10] = True
    occ[11:15, 11:15, 1:9] = False  # a sealed cavity inside the block
    fs = compute_free_space(occ, np.zeros(3), res, clearance=0.1, floor_z=0.1)
    assert not fs.free[12, 12, 4]  # the cavity is not connected to the floor area
    assert fs.free[5, 5, 5]
    assert not fs.free[9, 12, 5]  # within 0.1 m of the block
    assert fs.free[8, 12, 5]
    assert fs.info["components_kept"] == 1


@pytest.fixture(scope="module")
def scan_scene_dir(tmp_path_factory):
    """The demo room scanned (synthetic, 2 viewpoints) + a scene file using it."""
    from camplace.spec.builtin import resolve_scene
    from camplace.workflows.scan import scan_scene

    d = tmp_path_factory.mktemp("scan")
    spec, _, _ = resolve_scene("demo")
    cloud = scan_scene(build_scene(spec), step_deg=0.6, noise=0.005)
    write_ply(d / "room.ply", cloud.points, viewpoints=cloud.viewpoints)
    return d


def _scan_spec(d, **extra):
    data = {
        "name": "scanned", "room": {"footprint": [[0, 0], [6, 0], [6, 5], [0, 5]], "height": 3.0},
        "obstacles": [{"name": "scan", "point_cloud": "room.ply", "downsample": 0.02},
                      {"name": "shelf", "box": {"min": [2.0, 1.5, 0.0], "max": [4.0, 2.1, 1.6]}, "occludes": False}],
        "targets": [{"name": "walkable", "kind": "volume", "heights": [1.0], "coverage": 1},
                    {"name": "faces", "kind": "surface", "of": ["shelf"], "faces": ["+y"], "coverage": 1}],
        "cameras": [{"name": "cam", "resolution": [640, 480], "fov_deg": [90, 70]}],
        "mounts": [{"kind": "ceiling_grid", "camera": "cam", "yaw_deg": [0], "pitch_deg": [45]}],
    }
    data.update(extra)
    (d / "scene.yaml").write_text(yaml.safe_dump(data))
    from camplace.spec.builtin import resolve_scene

    return resolve_scene(str(d / "scene.yaml"))


def test_scan_obstacle_scene(scan_scene_dir):
    spec, base, src = _scan_spec(scan_scene_dir)
    sc = build_scene(spec, base, src)
    fs = sc.free_space
    assert fs is not None and fs.observed is not None
    rep = sc.info["obstacle_files"]["scan"]
    assert rep["viewpoints"] >= 1 and rep["cleanup"][0]["step"] == "downsample"
    # the shelf (a hollow scanned shell) and the pillar hide space that is not free
    assert not fs.contains(np.array([[3.0, 1.8, 1.0], [5.0, 3.8, 1.0]])).any()
    assert fs.contains(np.array([[1.0, 1.0, 1.0], [4.5, 4.5, 1.0]])).all()
    # the unseen inside of the shelf blocks sight lines like an obstacle
    assert sc.occupancy.is_occupied(np.array([[3.0, 1.8, 0.8]]))[0]
    t = build_targets(sc)
    walk = t.positions[t.region_ids == 0]
    assert not np.any(np.all((walk[:, :2] > [2.0, 1.5]) & (walk[:, :2] < [4.0, 2.1]), axis=1))
    faces = t.positions[t.region_ids == 1]
    assert len(faces) > 0 and np.all(faces[:, 1] >= 2.1 - 1e-9)  # stepped out of the scanned shell
    assert np.all(t.normals[t.region_ids == 1] == [0, 1, 0])


def test_surface_targets_from_a_box_on_the_scan(scan_scene_dir):
    spec, base, src = _scan_spec(scan_scene_dir, targets=[
        {"name": "front", "kind": "surface", "box": {"min": [2.0, 2.0, 0.2], "max": [4.0, 2.2, 1.4]}, "coverage": 1}])
    sc = build_scene(spec, base, src)
    t = build_targets(sc)
    assert len(t) >= 8
    assert np.mean(t.normals[:, 1] > 0.9) > 0.9  # the +y face: normals point out, toward free space


def test_octomap_obstacle_free_leaves_bound_targets(tmp_path):
    from camplace.scene.loaders.octomap import write_octomap

    res = 0.1
    occ = np.zeros((62, 52, 32), bool)
    free = np.zeros_like(occ)
    free[1:31, 1:51, 1:31] = True  # only the x < 3 m half was observed free
    occ[:, :, 0] = True  # the floor
    write_octomap(tmp_path / "m.bt", occ, free, np.array([-0.1, -0.1, -0.1]), res)
    spec = box_room(footprint=[[0, 0], [6, 0], [6, 5], [0, 5]])
    data = spec.model_dump(mode="json", exclude_defaults=True)
    data["obstacles"] = [{"name": "map", "octomap": str(tmp_path / "m.bt")}]
    sc = build_scene(parse_scene(data))
    assert sc.info["free_space"]["octomap_free_leaves"] > 0
    t = build_targets(sc)
    assert t.positions[:, 0].max() < 3.0 and t.positions[:, 0].min() < 0.5


def test_wall_mounts_face_inward():
    from camplace.cameras.models import camera_from_spec
    from camplace.cameras.candidates import build_candidates

    spec = box_room(mounts=[{"kind": "wall", "camera": "cam", "height": 2.5, "spacing": 1.0, "yaw_deg": [0],
                             "pitch_deg": [30]}])
    sc = build_scene(spec)
    c = build_candidates(sc, {k.name: camera_from_spec(k) for k in spec.cameras})
    assert len(c) == 16  # 4 walls x 4 m / 1 m
    assert np.allclose(c.positions[:, 2], 2.5)
    centre = np.array([2.0, 2.0])
    fwd = c.rotations[:, :2, 2]  # camera z axis (forward) in world x, y
    to_centre = centre - c.positions[:, :2]
    assert np.all(np.einsum("ij,ij->i", fwd, to_centre) > 0)
    on_wall = np.minimum.reduce([c.positions[:, 0], 4 - c.positions[:, 0], c.positions[:, 1], 4 - c.positions[:, 1]])
    assert np.allclose(on_wall, 0.05)  # wall_clearance from the wall


def test_given_wall_segment_and_relative_yaw():
    from camplace.cameras.candidates import wall_positions

    spec = box_room(mounts=[{"kind": "wall", "camera": "cam", "height": 2.0, "spacing": 2.0,
                             "walls": [[[4, 0], [4, 4]]]}])
    p, yaw = wall_positions(build_scene(spec), spec.mounts[0])
    assert np.allclose(p[:, 0], 3.95) and np.allclose(yaw, 180.0)  # the x = 4 wall faces -x
    assert spec.mounts[0].yaw_values() == [-60.0, -30.0, 0.0, 30.0, 60.0]


def test_wall_mount_needs_height():
    with pytest.raises(InputError, match="height"):
        box_room(mounts=[{"kind": "wall", "camera": "cam"}])


def test_a_viewpoint_outside_the_room_is_ignored_and_reported(tmp_path):
    from camplace.spec.builtin import resolve_scene
    from camplace.scene.from_scan import describe_free_space
    from camplace.scene.loaders.pointcloud import write_pcd
    from camplace.workflows.scan import roundtrip_spec, scan_scene

    spec, _, _ = resolve_scene("demo")
    cloud = scan_scene(build_scene(spec), step_deg=0.8)
    write_pcd(tmp_path / "s.pcd", cloud.points, viewpoints=[[-5.0, -5.0, 1.0]])  # a default/bogus VIEWPOINT
    sc = build_scene(roundtrip_spec(spec, "point_cloud", tmp_path / "s.pcd"))
    info = sc.info["free_space"]
    assert info["viewpoints_ignored"] == 1 and sc.free_space.observed is None
    assert "ignored" in describe_free_space(info) and "unknown" in describe_free_space(info)
    assert len(build_targets(sc)) > 500  # free = not occupied: targets remain
