"""A scene from a scan (camplace.scene.from_scan): floor/ceiling, footprint, PCA normals,
a scene mapping from just a cloud, and its errors naming the parameter to change."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.scene.build import build_scene
from camplace.scene.from_scan import auto_footprint, detect_floor_ceiling, pca_normals, scene_from_cloud
from camplace.scene.loaders.pointcloud import write_ply
from camplace.spec.loading import parse_scene


def _box_room_cloud(rng, w=6.0, d=5.0, h=3.0, n=40_000):
    """Points on the floor, ceiling and four walls of a w x d x h room."""
    k = n // 6
    pts = [np.c_[rng.uniform(0, w, k), rng.uniform(0, d, k), np.zeros(k)],
           np.c_[rng.uniform(0, w, k), rng.uniform(0, d, k), np.full(k, h)],
           np.c_[np.zeros(k), rng.uniform(0, d, k), rng.uniform(0, h, k)],
           np.c_[np.full(k, w), rng.uniform(0, d, k), rng.uniform(0, h, k)],
           np.c_[rng.uniform(0, w, k), np.zeros(k), rng.uniform(0, h, k)],
           np.c_[rng.uniform(0, w, k), np.full(k, d), rng.uniform(0, h, k)]]
    return np.concatenate(pts) + rng.normal(0, 0.005, (6 * k, 3))


def test_floor_and_ceiling_detected():
    rng = np.random.default_rng(0)
    lv = detect_floor_ceiling(_box_room_cloud(rng) + [0, 0, -1.2])
    assert abs(lv["floor_z"] + 1.2) < 0.03 and abs(lv["ceiling_z"] - 1.8) < 0.03


def test_no_ceiling_when_open_top():
    rng = np.random.default_rng(1)
    p = _box_room_cloud(rng)
    lv = detect_floor_ceiling(p[p[:, 2] < 2.9])
    assert abs(lv["floor_z"]) < 0.03 and lv["ceiling_z"] is None


def test_auto_footprint_of_a_room():
    rng = np.random.default_rng(2)
    fp = auto_footprint(_box_room_cloud(rng), 0.0, 3.0)
    from shapely.geometry import Polygon

    assert abs(Polygon(fp).area - 30.0) < 1.0


def test_pca_normals_of_a_plane():
    rng = np.random.default_rng(3)
    p = np.c_[rng.uniform(0, 1, 2000), rng.uniform(0, 1, 2000), 0.3 + rng.normal(0, 0.001, 2000)]
    n = pca_normals(p, p[:10])
    assert np.allclose(np.abs(n[:, 2]), 1.0, atol=1e-3)


def test_scene_from_cloud_tilted_scan(tmp_path):
    from camplace.scene.loaders.cleanup import apply_matrix, rigid_matrix

    rng = np.random.default_rng(5)
    p = apply_matrix(_box_room_cloud(rng), rigid_matrix(1.0, (3.0, -2.0, 0.0), (0.0, 0.0, -1.4)))
    write_ply(tmp_path / "s.ply", p)
    data, rep = scene_from_cloud(str(tmp_path / "s.ply"), heights=(0.5, 1.0, 1.5, 2.9))
    assert abs(data["room"]["height"] - 3.0) < 0.05
    assert abs(rep["floor_area_m2"] - 30.0) < 1.5
    assert data["targets"][0]["heights"] == [0.5, 1.0, 1.5]  # 2.9 m is too close to the ceiling
    assert "transform" in data["obstacles"][0] and "level_floor" not in data["obstacles"][0]["transform"]
    sc = build_scene(parse_scene(data))
    z = sc.points[:, 2]
    assert abs(np.median(z[z < 0.5])) < 0.02  # floor at z = 0 after the stored transform


def test_auto_footprint_keeps_an_l_shape():
    from shapely.geometry import Polygon

    from camplace.spec.builtin import resolve_scene
    from camplace.workflows.scan import scan_scene

    spec, _, _ = resolve_scene("store-a")  # L-shaped, wall shelves up to 2.2 m
    sc = build_scene(spec)
    cloud = scan_scene(sc, step_deg=0.6, noise=0.005)
    fp = Polygon(auto_footprint(cloud.points, 0.0, 3.0))
    iou = fp.intersection(sc.polygon).area / fp.union(sc.polygon).area
    assert iou > 0.95
    assert not fp.contains(Polygon([(14.0, 8.0), (15.5, 8.0), (15.5, 11.5), (14.0, 11.5)]).centroid)  # the notch


def test_errors_name_the_parameter_not_a_flag(tmp_path):
    rng = np.random.default_rng(3)
    flat = np.c_[rng.uniform(0, 5, 5000), rng.uniform(0, 4, 5000), rng.normal(0, 0.003, 5000)]
    write_ply(tmp_path / "flat.ply", flat)
    with pytest.raises(InputError, match=r"is it z-up\? \(try up='\+y' for phone scans, or level_floor=False\)") as e:
        scene_from_cloud(str(tmp_path / "flat.ply"))
    assert e.value.option == "up" and "--" not in str(e.value)
    with pytest.raises(InputError, match=r"^cloud: ") as e:
        scene_from_cloud(str(tmp_path / "missing.ply"))
    assert e.value.option == "cloud"
    with pytest.raises(InputError, match="give footprint= or a scene file") as e:
        auto_footprint(np.c_[np.zeros(50), np.zeros(50), np.linspace(0, 3, 50)], 0.0, 3.0)
    assert e.value.option == "footprint"
