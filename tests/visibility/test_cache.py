"""Out-of-core V: blocks cached under a content hash are reused on a second run,
resumed after an interruption, and never reused when an input changes."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from camplace.visibility.cache import BlockStore, content_key, default_cache_dir
from camplace.core.errors import Interrupted
from camplace.scene.build import OccupancyGrid
from camplace.visibility.voxel import compute_visibility

from conftest import same_csr

CHUNK = 64


@pytest.fixture(scope="module")
def ref_v(demo_inputs):
    sc, t, c = demo_inputs
    return compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK).V


def _blocks(vis):
    return sorted((p.name for p in (vis_dir(vis)).glob("block-*.npz")))


def vis_dir(vis):
    from pathlib import Path

    return Path(vis.info["cache"])


def test_hit_after_miss(tmp_path, demo_inputs, ref_v):
    sc, t, c = demo_inputs
    first = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    n = first.info["chunks"]
    assert first.info["cached_chunks"] == 0 and len(_blocks(first)) == n > 1
    second = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    assert second.info["cached_chunks"] == n and second.info["cache"] == first.info["cache"]
    same_csr(first.V, ref_v)
    same_csr(second.V, ref_v)


def test_resume_recomputes_only_missing_blocks(tmp_path, demo_inputs, ref_v):
    sc, t, c = demo_inputs
    calls = []

    def stop_after_two(stage, done, total):
        calls.append(done)
        if done == 2:
            raise Interrupted("test: stop")

    with pytest.raises(Interrupted):
        compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path, progress=stop_after_two)
    resumed = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    assert resumed.info["cached_chunks"] == 2
    same_csr(resumed.V, ref_v)


def test_corrupt_block_is_recomputed(tmp_path, demo_inputs, ref_v):
    sc, t, c = demo_inputs
    vis = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    (vis_dir(vis) / "block-000001.npz").write_bytes(b"not an npz")
    again = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    assert again.info["cached_chunks"] == vis.info["chunks"] - 1
    same_csr(again.V, ref_v)


def _changed_inputs(sc, t, c):
    """(label, occupancy, targets, candidates) with one input changed each."""
    occ = sc.occupancy.occupied.copy()
    occ[tuple(np.array(occ.shape) // 2)] ^= True
    cams = tuple(dataclasses.replace(cm, max_range=cm.max_range - 0.5) for cm in c.cameras)
    pos = t.positions.copy()
    pos[0, 2] += 0.01
    rot = c.rotations.copy()
    rot[5] = rot[6]
    return [
        ("occupancy", OccupancyGrid(occ, sc.occupancy.origin, sc.occupancy.resolution), t, c),
        ("target moved", sc.occupancy, dataclasses.replace(t, positions=pos), c),
        ("camera range", sc.occupancy, t, dataclasses.replace(c, cameras=cams)),
        ("candidate pose", sc.occupancy, t, dataclasses.replace(c, rotations=rot)),
    ]


def test_changed_input_never_reuses(tmp_path, demo_inputs):
    sc, t, c = demo_inputs
    base = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    dirs = {base.info["cache"]}
    for label, occ, tt, cc in _changed_inputs(sc, t, c):
        v = compute_visibility(occ, tt, cc, chunk_size=CHUNK, cache_dir=tmp_path)
        assert v.info["cached_chunks"] == 0, label
        assert v.info["cache"] not in dirs, label
        dirs.add(v.info["cache"])
        if label == "occupancy":  # the fresh entry holds the V of the changed input
            same_csr(v.V, compute_visibility(occ, tt, cc, chunk_size=CHUNK).V)
    # a different chunking is a different layout: a new entry, same V
    other = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK + 1, cache_dir=tmp_path)
    assert other.info["cached_chunks"] == 0 and other.info["cache"] not in dirs
    same_csr(other.V, base.V)


def test_code_version_is_part_of_the_key(tmp_path, demo_inputs, monkeypatch):
    import camplace

    sc, t, c = demo_inputs
    a = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    monkeypatch.setattr(camplace, "__version__", camplace.__version__ + ".test")
    b = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    assert b.info["cached_chunks"] == 0 and b.info["cache"] != a.info["cache"]


def test_content_key_distinguishes_dtype_shape_and_values():
    x = np.arange(6, dtype=np.int32)
    assert content_key(x) == content_key(x.copy())
    assert content_key(x) != content_key(x.astype(np.int64))
    assert content_key(x) != content_key(x.reshape(2, 3))
    assert content_key(x) != content_key(x[::-1])
    assert content_key("a", 1) != content_key("a", 1.0)
    assert content_key({"a": 1, "b": 2}) == content_key({"b": 2, "a": 1})
    with pytest.raises(TypeError):
        content_key(object())


def test_block_store_layout_change_clears_blocks(tmp_path):
    s = BlockStore(tmp_path, "k", [(0, 2), (2, 3)], 10)
    s.save(0, np.array([0, 1, 3]), np.array([4, 1, 2], np.int32))
    assert s.done() == [0] and s.nnz(0) == 3
    ip, ix = s.load(0)
    assert list(ip) == [0, 1, 3] and list(ix) == [4, 1, 2]
    with pytest.raises(ValueError):
        s.save(1, np.array([0, 5]), np.array([1], np.int32))
    s2 = BlockStore(tmp_path, "k", [(0, 3)], 10)  # same key, other bounds: old blocks dropped
    assert s2.done() == []


def test_default_cache_dir(monkeypatch, tmp_path):
    monkeypatch.setenv("CAMPLACE_CACHE", str(tmp_path / "c"))
    assert default_cache_dir() == tmp_path / "c"
    monkeypatch.delenv("CAMPLACE_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert default_cache_dir() == tmp_path / "x" / "camplace"
