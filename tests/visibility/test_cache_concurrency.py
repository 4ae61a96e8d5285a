"""A shared cache folder under concurrency and damage (issue 16): two runs of the same
scene at once on one cache give the same V, and a block cut short mid-write, a stray
temporary file of an interrupted write or a block of the wrong shape is recomputed,
never trusted."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from camplace.visibility.voxel import compute_visibility

from conftest import same_csr

CHUNK = 64

SCRIPT = textwrap.dedent("""
    import hashlib, sys
    import numpy as np
    from camplace.spec.builtin import resolve_scene
    from camplace.scene.build import build_scene
    from camplace.targets.build import build_targets
    from camplace.cameras.models import camera_from_spec
    from camplace.cameras.candidates import build_candidates
    from camplace.visibility.voxel import compute_visibility

    spec, _, _ = resolve_scene("demo")
    sc = build_scene(spec)
    t = build_targets(sc)
    c = build_candidates(sc, {x.name: camera_from_spec(x) for x in spec.cameras})
    V = compute_visibility(sc.occupancy, t, c, chunk_size=%d, cache_dir=sys.argv[1]).V
    h = hashlib.sha256(np.asarray(V.indptr, np.int64).tobytes() + np.asarray(V.indices, np.int64).tobytes())
    print(h.hexdigest())
""" % CHUNK)


def _hash(V) -> str:
    import hashlib

    return hashlib.sha256(np.asarray(V.indptr, np.int64).tobytes()
                          + np.asarray(V.indices, np.int64).tobytes()).hexdigest()


@pytest.fixture(scope="module")
def ref_v(demo_inputs):
    sc, t, c = demo_inputs
    return compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK).V


def test_two_runs_at_once_on_one_cache_give_the_same_v(tmp_path, demo_inputs, ref_v):
    cache = tmp_path / "cache"
    procs = [subprocess.Popen([sys.executable, "-c", SCRIPT, str(cache)], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    outs = [p.communicate(timeout=600) for p in procs]
    for p, (out, err) in zip(procs, outs):
        assert p.returncode == 0, err
    assert [o.strip() for o, _ in outs] == [_hash(ref_v)] * 2
    sc, t, c = demo_inputs
    again = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=cache)
    assert again.info["cached_chunks"] == again.info["chunks"]  # both wrote the same, complete entry
    same_csr(again.V, ref_v)


def _entry(tmp_path, demo_inputs):
    sc, t, c = demo_inputs
    vis = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    from pathlib import Path

    return vis, Path(vis.info["cache"])


@pytest.mark.parametrize("keep", [0.0, 0.1, 0.5, 0.9, 0.999])
def test_block_truncated_mid_write_is_recomputed(tmp_path, demo_inputs, ref_v, keep):
    vis, folder = _entry(tmp_path, demo_inputs)
    block = folder / "block-000002.npz"
    data = block.read_bytes()
    block.write_bytes(data[:int(len(data) * keep)])
    sc, t, c = demo_inputs
    again = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    assert again.info["cached_chunks"] == vis.info["chunks"] - 1
    same_csr(again.V, ref_v)
    assert block.read_bytes() == data  # rewritten whole


def test_stray_temporary_file_of_an_interrupted_write_is_ignored(tmp_path, demo_inputs, ref_v):
    vis, folder = _entry(tmp_path, demo_inputs)
    block = folder / "block-000001.npz"
    data = block.read_bytes()
    block.unlink()
    (folder / ".block-000001.npz.tmp").write_bytes(data[: len(data) // 2])  # the rename never happened
    sc, t, c = demo_inputs
    again = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    assert again.info["cached_chunks"] == vis.info["chunks"] - 1
    same_csr(again.V, ref_v)


def test_block_of_the_wrong_rows_or_columns_is_recomputed(tmp_path, demo_inputs, ref_v):
    vis, folder = _entry(tmp_path, demo_inputs)
    sc, t, c = demo_inputs
    n_cols = len(t)
    np.savez(folder / "block-000000.npz", indptr=np.array([0, 1], np.int64), indices=np.array([0], np.int32))
    np.savez(folder / "block-000003.npz", indptr=np.r_[0, np.full(CHUNK, 1)].astype(np.int64),
             indices=np.array([n_cols + 5], np.int32))
    again = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    assert again.info["cached_chunks"] == vis.info["chunks"] - 2
    same_csr(again.V, ref_v)
