"""Meshes: write/read per format, voxelized surfaces and solids, clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.scene.loaders.mesh import boxes_to_mesh, load_mesh, voxelize_mesh, write_mesh

BOX = (np.array([1.0, 1.0, 0.0]), np.array([2.0, 3.0, 1.5]))


@pytest.mark.parametrize("suffix", ["obj", "ply", "stl", "glb", "off"])
def test_round_trip_formats_closed(tmp_path, suffix):
    write_mesh(tmp_path / f"b.{suffix}", boxes_to_mesh([BOX]))
    m = load_mesh(tmp_path / f"b.{suffix}")
    assert m.info["faces"] == 12
    assert m.info["watertight"]
    assert np.allclose(m.vertices.min(0), BOX[0]) and np.allclose(m.vertices.max(0), BOX[1])


def test_solid_fills_and_surface_does_not():
    mesh = boxes_to_mesh([BOX])
    res = 0.05
    solid = np.zeros((80, 80, 40), bool)
    voxelize_mesh(mesh, solid, np.zeros(3), res, solid=True)
    shell = np.zeros_like(solid)
    voxelize_mesh(mesh, shell, np.zeros(3), res, solid=False)
    inner = (30, 40, 15)  # cell centre (1.525, 2.025, 0.775): inside the box
    assert solid[inner] and not shell[inner]
    # the box is 20 x 40 x 30 cells; faces on cell boundaries mark both sides: one layer more
    assert 20 * 40 * 30 <= solid.sum() <= 22 * 42 * 31
    assert not solid[10, 10, 10] and not shell[10, 10, 10]  # outside stays free
    assert shell.sum() < solid.sum()


def test_thin_slanted_triangle_leaves_no_gaps():
    v = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 3.0], [0.0, 3.0, 3.0]]) + 0.01
    from camplace.scene.loaders.mesh import Mesh

    occ = np.zeros((64, 64, 64), bool)
    voxelize_mesh(Mesh(v, np.array([[0, 1, 2]])), occ, np.zeros(3), 0.05)
    # every cell a dense sampling of the plane crosses is marked
    rng = np.random.default_rng(0)
    a, b = rng.uniform(0, 1, (2, 100_000))
    keep = a + b <= 1
    p = v[0] + np.outer(a[keep], v[1] - v[0]) + np.outer(b[keep], v[2] - v[0])
    c = np.floor(p / 0.05).astype(int)
    assert occ[c[:, 0], c[:, 1], c[:, 2]].all()


@pytest.mark.parametrize("name,content", [("e.obj", b""), ("g.stl", b"solid x\nfacet garbage\n"),
                                          ("n.obj", b"# no faces\nv 0 0 0\n")])
def test_bad_mesh_files_one_line(tmp_path, name, content):
    (tmp_path / name).write_bytes(content)
    with pytest.raises(InputError) as e:
        load_mesh(tmp_path / name)
    assert name in str(e.value) and "\n" not in str(e.value)


def test_unknown_write_suffix(tmp_path):
    with pytest.raises(InputError):
        write_mesh(tmp_path / "a.xyz", boxes_to_mesh([BOX]))
