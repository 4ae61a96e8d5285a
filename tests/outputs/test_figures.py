"""PNG figures: coverage slices per target height and the coverage histogram."""

from __future__ import annotations

import numpy as np

from camplace.outputs.figures import (SceneView, coverage_class, coverage_slices, histogram_figure_png, slice_figure_png,
                              write_figures)

PNG = b"\x89PNG\r\n\x1a\n"


def _view():
    fp = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float)
    return SceneView("room", fp, 3.0, 0.5, {"box": (np.array([1.0, 0.0, 0.0]), np.array([1.5, 0.5, 1.2]))})


def _grid_targets():
    """Voxel centres of a 2 m x 1 m floor at 0.5 m, two heights, box cell missing at z=0.5."""
    xs, ys = np.array([0.25, 0.75, 1.25, 1.75]), np.array([0.25, 0.75])
    pts = [(x, y, z) for z in (0.5, 1.5) for y in ys for x in xs if not (z == 0.5 and x == 1.25 and y == 0.25)]
    return np.array(pts, float)


def test_coverage_class_caps_at_three():
    assert coverage_class(np.array([0, 1, 2, 3, 4, 9])).tolist() == [0, 1, 2, 3, 3, 3]


def test_coverage_slices_place_each_target_in_its_cell():
    view = _view()
    pos = _grid_targets()
    cov = np.arange(len(pos))
    surf = np.zeros(len(pos), bool)
    surf[-1] = True  # a surface target is not part of any slice
    sl = coverage_slices(view, pos, surf, cov)
    assert [s.height for s in sl] == [0.5, 1.5]
    s0, s1 = sl
    assert s0.coverage.shape == (2, 4) and np.allclose(s0.x, [0.25, 0.75, 1.25, 1.75]) and np.allclose(s0.y, [0.25, 0.75])
    assert np.isnan(s0.coverage[0, 2])  # the cell inside the box has no target
    for p, c in zip(pos[:-1], cov[:-1]):
        s = s0 if p[2] == 0.5 else s1
        assert s.coverage[int(p[1] / 0.5), int(p[0] / 0.5)] == c
    assert np.isnan(s1.coverage[1, 3])  # the surface target's cell
    # the box (z 0..1.2) crosses 0.5 m, not 1.5 m
    assert [b[0] for b in s0.boxes] == ["box"] and s1.boxes == []


def test_slice_and_histogram_pngs(tmp_path):
    view = _view()
    pos = _grid_targets()
    cov = np.array([0, 1, 2, 3, 5, 0, 1, 2, 3, 4, 0, 1, 2, 3, 4])[: len(pos)]
    sl = coverage_slices(view, pos, np.zeros(len(pos), bool), cov)
    cam = {"candidate_id": 7, "position": [0.1, 0.1, 2.9],
           "rotation": np.array([[0, 0, 1], [-1, 0, 0], [0, -1, 0.0]]).tolist()}
    png = slice_figure_png(sl[0], view, [cam])
    assert png[:8] == PNG and len(png) > 5000
    h = histogram_figure_png({"a": {"0": 3, "1": 2}, "b": {"2": 5}}, {"a": 3, "b": 1})
    assert h[:8] == PNG
    # write_figures: one PNG per height + the histogram; stale heights of an earlier run removed
    (tmp_path / "coverage_slice_z9.99m.png").write_bytes(b"old")
    paths = write_figures(tmp_path, view, pos, np.zeros(len(pos), bool), cov, [cam], {"all": {"0": 1}})
    assert sorted(paths) == ["coverage_histogram.png", "coverage_slice_z0.50m.png", "coverage_slice_z1.50m.png"]
    assert not (tmp_path / "coverage_slice_z9.99m.png").exists()
    assert all(p.read_bytes()[:8] == PNG for p in paths.values())


def test_scene_view_from_targets_only():
    pos = _grid_targets()
    v = SceneView.from_targets("x", pos, [{"position": [3.0, 2.0, 2.5]}])
    assert v.voxel_size == 0.5 and v.boxes == {}
    assert np.allclose(v.footprint.max(0), [3.0, 2.0]) and v.height == 2.5
