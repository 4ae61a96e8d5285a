"""The synthetic scanner: hits on the true surfaces, occlusion, viewpoints, CLI."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from camplace.spec.builtin import resolve_scene
from camplace.scene.loaders.pointcloud import load_point_cloud
from camplace.scene.build import build_scene
from camplace.workflows.scan import default_viewpoints, scan_directions, scan_scene
from tests.conftest import box_room


def _dist_to_surfaces(p, w, d, h, box):
    """Distance of points to the nearest room boundary or box face (for points outside the box)."""
    room = np.minimum.reduce([p[:, 0], w - p[:, 0], p[:, 1], d - p[:, 1], p[:, 2], h - p[:, 2]])
    lo, hi = np.asarray(box[0]), np.asarray(box[1])
    q = np.clip(p, lo, hi)
    to_box = np.linalg.norm(p - q, axis=1)
    return np.minimum(np.abs(room), to_box)


def test_points_lie_on_surfaces_and_shadow_is_empty():
    box = ([1.5, 1.0, 0.0], [2.5, 3.0, 2.0])
    sc = build_scene(box_room(obstacles=[{"name": "b", "box": {"min": box[0], "max": box[1]}}]))
    vp = np.array([[0.5, 2.0, 2.5]])  # above the box top (2 m): it sees over it
    pc = scan_scene(sc, viewpoints=vp, step_deg=1.0, noise=0.0)
    assert len(pc) == len(scan_directions(1.0))  # closed room: every ray hits
    assert np.all(_dist_to_surfaces(pc.points, 4, 4, 3, box) < 1e-6)
    # behind the box (seen from x = 0.5), low on the x = 4 wall: occluded, no points
    shadow = (pc.points[:, 0] > 3.99) & (np.abs(pc.points[:, 1] - 2.0) < 0.3) & (pc.points[:, 2] < 1.0)
    assert not shadow.any()
    lit = (pc.points[:, 0] > 3.99) & (np.abs(pc.points[:, 1] - 2.0) < 0.3) & (pc.points[:, 2] > 2.0)
    assert lit.any()


def test_range_noise_statistics():
    sc = build_scene(box_room())
    pc = scan_scene(sc, viewpoints=np.array([[2.0, 2.0, 1.5]]), step_deg=2.0, noise=0.02, seed=3)
    err = _dist_to_surfaces(pc.points, 4, 4, 3, ([9, 9, 9], [9.1, 9.1, 9.1]))
    assert 0.005 < np.median(err) < 0.03


def test_default_viewpoints_on_free_floor():
    spec, _, _ = resolve_scene("standard-store")
    sc = build_scene(spec)
    vps = default_viewpoints(sc)
    assert 2 <= len(vps) <= 40
    assert not sc.occupancy.is_occupied(vps).any()
    assert len(default_viewpoints(sc, count=3)) == 3


def test_scan_requires_box_scene(tmp_path):
    from camplace.core.errors import InputError
    from camplace.scene.loaders.pointcloud import write_ply
    from camplace.spec.loading import parse_scene

    write_ply(tmp_path / "p.ply", np.random.default_rng(0).uniform(0, 3, (100, 3)))
    data = box_room().model_dump(mode="json", exclude_defaults=True)
    data["obstacles"] = [{"name": "s", "point_cloud": str(tmp_path / "p.ply")}]
    with pytest.raises(InputError, match="box obstacles"):
        scan_scene(build_scene(parse_scene(data)))


@pytest.mark.parametrize("suffix", ["ply", "pcd", "las", "obj", "bt"])
def test_cli_scan_and_exports(tmp_path, suffix):
    from camplace.cli.app import app

    out = tmp_path / f"demo.{suffix}"
    r = CliRunner().invoke(app, ["scan", "demo", "--out", str(out), "--step", "2", "--noise", "0.01"])
    assert r.exit_code == 0, r.output
    assert out.stat().st_size > 0
    if suffix in ("ply", "pcd", "las"):
        pc = load_point_cloud(out)
        assert len(pc) > 1000
        assert pc.points[:, 2].min() > -0.1 and pc.points[:, 2].max() < 3.1
