"""Out-of-core V (issue 21): with a cache, V is assembled block by block into memory-mapped
CSR files and read from them (same V bit for bit), a damaged or missing assembled file is
rebuilt from the blocks, and an interrupted run resumes from its finished blocks."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.core.errors import Interrupted
from camplace.visibility.voxel import compute_visibility

from conftest import same_csr

CHUNK = 48


@pytest.fixture(scope="module")
def ref_v(demo_inputs):
    sc, t, c = demo_inputs
    return compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK).V


def _mapped(arr) -> bool:
    """arr is a view of a memory-mapped file."""
    import mmap

    base = arr
    while base is not None:
        if isinstance(base, (np.memmap, mmap.mmap)):
            return True
        base = getattr(base, "base", None)
    return False


def _files(vis):
    from pathlib import Path

    d = Path(vis.info["cache"])
    return {n: d / f"V-{n}.npy" for n in ("indptr", "indices", "data")}


def test_cached_v_is_memory_mapped_and_identical(tmp_path, demo_inputs, ref_v):
    sc, t, c = demo_inputs
    vis = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    same_csr(vis.V, ref_v)
    files = _files(vis)
    assert all(p.is_file() for p in files.values())
    # the matrix reads the files: its index and data arrays are views of read-only maps
    for arr in (vis.V.indices, vis.V.data):
        assert _mapped(arr) and not arr.flags.writeable
    again = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    assert again.info["cached_chunks"] == again.info["chunks"]
    same_csr(again.V, ref_v)


@pytest.mark.parametrize("damage", ["truncate", "delete", "wrong_shape"])
def test_damaged_assembled_v_is_rebuilt_from_the_blocks(tmp_path, demo_inputs, ref_v, damage):
    sc, t, c = demo_inputs
    vis = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    files = _files(vis)
    del vis
    if damage == "truncate":
        raw = files["indices"].read_bytes()
        files["indices"].unlink()  # a new file: never truncate one that a live map may read (SIGBUS)
        files["indices"].write_bytes(raw[: len(raw) // 2])
    elif damage == "delete":
        files["data"].unlink()
    else:
        files["indptr"].unlink()
        np.save(files["indptr"], np.zeros(5, np.int64))
    again = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path)
    assert again.info["cached_chunks"] == again.info["chunks"]  # no raycasting: the blocks were fine
    same_csr(again.V, ref_v)


def test_run_resumes_from_the_cached_blocks(tmp_path):
    """camplace run stopped after k visibility blocks (should_stop), run again: the second
    run computes only the missing blocks and gives the uninterrupted run's placement."""
    from camplace.workflows.run import run

    scene = "warehouse:300"
    ref = run(scene, solver="greedy-fast")
    cache = tmp_path / "cache"
    seen: list[tuple[int, int]] = []
    k = 2

    def progress(stage, done, total):
        if stage == "visibility":
            seen.append((done, total))

    with pytest.raises(Interrupted):
        run(scene, solver="greedy-fast", cache_dir=cache, progress=progress,
            should_stop=lambda: bool(seen) and seen[-1][0] >= k)
    total = seen[-1][1]
    assert total > k and seen[-1][0] == k
    seen.clear()
    resumed = run(scene, solver="greedy-fast", cache_dir=cache, progress=progress)
    assert resumed.visibility.info["cached_chunks"] == k
    assert seen[0] == (k, total) and seen[-1] == (total, total)
    assert len(seen) == 1 + total - k  # one callback per block computed now
    same_csr(resumed.visibility.V, ref.visibility.V)
    assert np.array_equal(resumed.placement.selected, ref.placement.selected)
    assert resumed.metrics.to_dict() | {"timings_s": {}} == ref.metrics.to_dict() | {"timings_s": {}}


def test_zones_run_resumes_from_its_checkpoint_under_the_cache(tmp_path):
    """With the zone solver, the run's cache also holds the per-sweep checkpoint: a second
    run loads every V block and starts from the last finished sweep."""
    from camplace.workflows.run import run

    opts = {"solver": "zones", "cache_dir": tmp_path, "tile_time_s": 20.0, "bound_time_s": 0.2,
            "tile_m": 6.0}  # small tiles, each MIP well inside its limit; the smallest warehouse: several tiles
    first = run("warehouse:200", max_sweeps=1, **opts)
    assert list((tmp_path / "zones").glob("*.json"))
    assert first.placement.info.get("resumed_from_sweep") is None
    second = run("warehouse:200", max_sweeps=2, **opts)
    assert second.visibility.info["cached_chunks"] == second.visibility.info["chunks"]
    assert second.placement.info["resumed_from_sweep"] == 1
    assert second.placement.objective <= first.placement.objective


def test_release_pages_keeps_the_values(tmp_path, demo_inputs, ref_v):
    from camplace.core.memory import release_pages

    sc, t, c = demo_inputs
    V = compute_visibility(sc.occupancy, t, c, chunk_size=CHUNK, cache_dir=tmp_path).V
    assert int(V.indices.sum()) == int(ref_v.indices.sum())  # every page touched
    assert release_pages(V.indices, V.data) == 2
    same_csr(V, ref_v)  # read back from the page cache
    assert release_pages(np.arange(5), ref_v.indices) == 0  # plain arrays: nothing to release
