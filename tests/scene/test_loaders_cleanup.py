"""Scan clean-up: outliers, transform, RANSAC floor levelling, crop; each step reported."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from camplace.scene.loaders.cleanup import (apply_matrix, clean_cloud, crop_mask, level_floor_matrix, remove_outliers,
                                      rigid_matrix)
from camplace.scene.loaders.pointcloud import PointCloud


def _room_cloud(rng, n=20_000):
    """Floor z=0 (6 x 5 m), ceiling z=3, one wall x=0: a small scan-like cloud."""
    floor = np.c_[rng.uniform(0, 6, n), rng.uniform(0, 5, n), rng.normal(0, 0.005, n)]
    ceil = np.c_[rng.uniform(0, 6, n // 2), rng.uniform(0, 5, n // 2), 3 + rng.normal(0, 0.005, n // 2)]
    wall = np.c_[rng.normal(0, 0.005, n // 2), rng.uniform(0, 5, n // 2), rng.uniform(0, 3, n // 2)]
    return np.concatenate([floor, ceil, wall])


def test_outliers_removed_cluster_kept():
    rng = np.random.default_rng(0)
    cluster = rng.normal(0, 0.05, size=(2000, 3))
    far = rng.uniform(5, 10, size=(10, 3))
    keep = remove_outliers(np.concatenate([cluster, far]), neighbors=8, std_ratio=2.0)
    assert not keep[-10:].any()
    assert keep[:2000].mean() > 0.95


def test_rigid_matrix_matches_scipy():
    m = rigid_matrix(2.0, (10, 20, 30), (1, 2, 3))
    p = np.array([[1.0, 0.5, -0.25]])
    expect = Rotation.from_euler("xyz", [10, 20, 30], degrees=True).apply(2.0 * p) + [1, 2, 3]
    assert np.allclose(apply_matrix(p, m), expect)


def test_level_floor_undoes_a_tilt_and_offset():
    rng = np.random.default_rng(2)
    room = _room_cloud(rng)
    tilt = rigid_matrix(1.0, (4.0, -3.0, 25.0), (0.3, -0.2, -1.3))
    scanned = apply_matrix(room, tilt)  # like a scan whose frame is tilted and whose floor is at -1.3
    m, info = level_floor_matrix(scanned)
    back = apply_matrix(scanned, m)
    floor = back[: 20_000]
    assert abs(np.median(floor[:, 2])) < 0.01  # floor at z = 0
    assert np.std(floor[:, 2]) < 0.02  # and level
    assert abs(np.median(back[20_000:30_000, 2]) - 3.0) < 0.02  # the ceiling 3 m above it
    assert 4.0 < info["tilt_deg"] < 6.0


def test_level_floor_y_up_phone_scan():
    rng = np.random.default_rng(3)
    room = _room_cloud(rng)
    y_up = room[:, [0, 2, 1]] * [1, 1, -1]  # x, z->y up, y->-z
    m, _ = level_floor_matrix(y_up, up="+y")
    back = apply_matrix(y_up, m)
    assert abs(np.median(back[:20_000, 2])) < 0.01
    assert abs(np.median(back[20_000:30_000, 2]) - 3.0) < 0.02


def test_clean_cloud_reports_every_step():
    rng = np.random.default_rng(4)
    p = _room_cloud(rng, 5000)
    pc = PointCloud(p, np.array([[1.0, 1.0, 1.5]]))
    out, rep = clean_cloud(pc, translate=(0, 0, 1.0), crop=((0, 0, 0.5), (6, 5, 3.5)), downsample=0.1,
                           outliers=(8, 2.0))
    steps = [r["step"] for r in rep]
    assert steps == ["transform", "crop", "downsample", "remove_outliers"]
    assert np.allclose(out.viewpoints, [[1.0, 1.0, 2.5]])  # viewpoints move with the cloud
    assert out.points[:, 2].min() >= 0.5
    assert rep[1]["points"] < rep[1]["points_in"]
    assert rep[-1]["points"] == len(out.points)


def test_crop_mask_inclusive():
    p = np.array([[0, 0, 0], [1, 1, 1], [2, 2, 2.0]])
    assert crop_mask(p, (0, 0, 0), (1, 1, 1)).tolist() == [True, True, False]
