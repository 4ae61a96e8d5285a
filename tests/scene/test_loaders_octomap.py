"""OctoMap .bt / .ot: hand-built trees, write/read round trips, the real geb079.bt figures."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.scene.loaders.octomap import load_octomap, write_octomap

SHARED = Path(__file__).resolve().parents[3] / "shared" / "data"
HEAD = b"# Octomap OcTree binary file\nid OcTree\nsize 9\nres 0.1\ndata\n"


def head(nodes: int) -> bytes:
    """A .bt header whose size (the node count, inner nodes and leaves) is ``nodes``."""
    return HEAD.replace(b"size 9", b"size %d" % nodes)


def test_hand_built_bt_one_occupied_child():
    # root node: child 7 (x, y, z keys >= 32768) is an occupied leaf (bits 14, 15 = 0b10)
    code = np.array([0b10 << 14], "<u2").tobytes()
    path = Path(__file__).parent / "_tmp_hand.bt"
    try:
        path.write_bytes(head(2) + code)  # the root and one leaf
        om = load_octomap(path)
    finally:
        path.unlink()
    assert om.info["occupied_leaves"] == 1 and om.info["free_leaves"] == 0
    assert np.allclose(om.occupied_lo, [[0, 0, 0]])
    assert np.allclose(om.occupied_size, [0.1 * 2 ** 15])


def test_hand_built_bt_nested(tmp_path):
    # root: child 0 inner (0b11); that node: child 1 free (0b01), child 2 occupied (0b10)
    body = np.array([0b11, (0b01 << 2) | (0b10 << 4)], "<u2").tobytes()
    (tmp_path / "n.bt").write_bytes(head(4) + body)  # root, inner node, two leaves
    om = load_octomap(tmp_path / "n.bt")
    size = 0.1 * 2 ** 14
    # child 0 of the root: keys < 32768 on all axes; its child 1 sets x bit 14, child 2 sets y bit 14
    assert np.allclose(om.free_lo, [[-0.1 * 32768 + size, -0.1 * 32768, -0.1 * 32768]])
    assert np.allclose(om.occupied_lo, [[-0.1 * 32768, -0.1 * 32768 + size, -0.1 * 32768]])
    assert np.allclose(om.occupied_size, [size])


@pytest.mark.parametrize("suffix", ["bt", "ot"])
def test_grid_round_trip(tmp_path, suffix):
    rng = np.random.default_rng(0)
    occ = rng.random((16, 12, 8)) < 0.2
    occ[:8, :8, :8] = True  # an aligned 8-block: pruned into bigger leaves
    free = ~occ
    free[15, :, :] = False  # some unknown space
    origin = np.array([-0.4, 0.2, 0.0])
    write_octomap(tmp_path / f"g.{suffix}", occ, free, origin, 0.05)
    om = load_octomap(tmp_path / f"g.{suffix}")
    assert om.resolution == 0.05
    assert np.isclose(om.volume(True), occ.sum() * 0.05 ** 3)
    assert np.isclose(om.volume(False), (free & ~occ).sum() * 0.05 ** 3)
    assert om.occupied_size.max() > 0.05  # pruning happened
    # every occupied cell centre lies in an occupied leaf
    cells = origin + (np.argwhere(occ) + 0.5) * 0.05
    lo, s = om.occupied_lo, om.occupied_size
    inside = np.all((cells[:, None, :] >= lo[None]) & (cells[:, None, :] < lo[None] + s[None, :, None]), axis=2)
    assert inside.any(axis=1).all()


@pytest.mark.parametrize("content,expect", [
    (b"", "empty"),
    (b"hello\n", "not an OctoMap"),
    (HEAD, "no nodes"),
    (HEAD + np.array([0xFFFF], "<u2").tobytes(), "truncated"),
    (b"# Octomap OcTree file\nid ColorOcTree\nsize 1\nres 0.1\ndata\n\x00\x00\x00\x00\x00", "not supported"),
])
def test_corrupt_files_one_line(tmp_path, content, expect):
    (tmp_path / "bad.bt").write_bytes(content)
    if content.startswith(b"# Octomap OcTree file"):
        (tmp_path / "bad.bt").rename(tmp_path / "bad.ot")
    f = tmp_path / ("bad.ot" if content.startswith(b"# Octomap OcTree file") else "bad.bt")
    with pytest.raises(InputError) as e:
        load_octomap(f)
    assert expect in str(e.value) and "\n" not in str(e.value)


@pytest.mark.skipif(not (SHARED / "geb079.bt").is_file(), reason="../shared/data/geb079.bt not present")
def test_geb079_figures_from_the_data_readme():
    om = load_octomap(SHARED / "geb079.bt")
    assert om.resolution == 0.08
    assert om.info["occupied_leaves"] == 143_729
    assert om.info["free_leaves"] == 284_415
    sizes, counts = np.unique(np.round(om.occupied_size, 3), return_counts=True)
    assert dict(zip(sizes.tolist(), counts.tolist())) == {0.08: 137_745, 0.16: 5_983, 0.32: 1}
    assert abs(om.volume(True) - 95) < 1 and abs(om.volume(False) - 487) < 1
    c = om.centres(True)
    assert np.allclose(c.min(0), [-7.96, -7.48, -0.28], atol=0.01)
    assert np.allclose(c.max(0), [30.92, 7.40, 2.76], atol=0.01)


from hypothesis import given, settings, strategies as st  # noqa: E402


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), shift=st.tuples(st.integers(-40, 40), st.integers(-40, 40), st.integers(-5, 5)),
       share=st.floats(0.0, 1.0), suffix=st.sampled_from(["bt", "ot"]))
def test_any_grid_survives_the_round_trip(tmp_path_factory, seed, shift, share, suffix):
    rng = np.random.default_rng(seed)
    shape = tuple(int(v) for v in rng.integers(1, 12, 3))
    occ = rng.random(shape) < share
    free = ~occ & (rng.random(shape) < 0.8)
    if not (occ.any() or free.any()):
        free[0, 0, 0] = True
    res = 0.1
    origin = np.array(shift) * res
    f = tmp_path_factory.mktemp("om") / f"g.{suffix}"
    write_octomap(f, occ, free, origin, res)
    om = load_octomap(f)
    # rasterize the leaves back onto the grid: the same cells, occupied and free
    from camplace.scene.loaders.obstacles import mark_boxes

    back_o, back_f = np.zeros(shape, bool), np.zeros(shape, bool)
    mark_boxes(back_o, origin, res, om.occupied_lo, om.occupied_size)
    mark_boxes(back_f, origin, res, om.free_lo, om.free_size)
    assert np.array_equal(back_o, occ) and np.array_equal(back_f, free)


@pytest.mark.parametrize("body", [b"id OcTree\nres 0.1\n", b"".join(b"k%d 1\n" % k for k in range(20))])
def test_octomap_header_without_data_line(tmp_path, body):
    f = tmp_path / "bad.bt"
    f.write_bytes(b"# Octomap OcTree binary file\n" + body)
    with pytest.raises(InputError, match="no 'data' line"):
        load_octomap(f)
