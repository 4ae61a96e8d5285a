"""Range culling in the visibility kernel: the culled kernel gives exactly the V of the
brute-force one (every candidate against every target), and the target grid is a
valid bucketing."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.visibility.voxel import compute_visibility, drop_blind_candidates, target_grid

from conftest import builtin_inputs, same_csr


@pytest.mark.parametrize("cell", [0.3, 0.625, 1.7, 5.0])
def test_culled_equals_brute_force_demo(demo_inputs, cell):
    sc, t, c = demo_inputs
    brute = compute_visibility(sc.occupancy, t, c, grid_cell=np.inf).V
    culled = compute_visibility(sc.occupancy, t, c, grid_cell=cell, chunk_size=100).V
    assert brute.nnz > 10_000
    same_csr(brute, culled)


def test_culled_equals_brute_force_small_warehouse():
    """A scene much larger than the camera range, where culling actually skips targets."""
    sc, t, c = builtin_inputs("warehouse:300")
    c = c.subset(np.arange(0, len(c), 7))  # every 7th pose: all positions, mixed angles
    brute = compute_visibility(sc.occupancy, t, c, grid_cell=np.inf).V
    culled = compute_visibility(sc.occupancy, t, c).V
    assert brute.nnz > 100_000
    # culling matters here: most targets are out of range of most cameras
    assert brute.nnz < 0.5 * brute.shape[0] * brute.shape[1]
    same_csr(brute, culled)
    # rows are sorted, as the contract's CSR expects
    assert culled.has_sorted_indices


def test_target_grid_is_a_bucketing(demo_inputs):
    _, t, _ = demo_inputs
    g = target_grid(t, 0.7)
    x0, y0, cell, nx, ny = g.params
    nx, ny = int(nx), int(ny)
    assert len(g.cell_start) == nx * ny + 1 and g.cell_start[-1] == len(t)
    assert np.array_equal(np.sort(g.cell_tids), np.arange(len(t)))
    for k in range(nx * ny):
        ids = g.cell_tids[g.cell_start[k]:g.cell_start[k + 1]]
        assert np.all(np.diff(ids) > 0)
        cx, cy = divmod(k, ny)
        p = t.positions[ids]
        assert np.all(p[:, 0] >= x0 + cx * cell - 1e-9) and np.all(p[:, 0] <= x0 + (cx + 1) * cell + 1e-9)
        assert np.all(p[:, 1] >= y0 + cy * cell - 1e-9) and np.all(p[:, 1] <= y0 + (cy + 1) * cell + 1e-9)
    one = target_grid(t, np.inf)
    assert one.params[3] == 1 and one.params[4] == 1 and np.array_equal(one.cell_tids, np.arange(len(t)))


def test_drop_blind_shares_arrays_and_matches_slicing(demo_inputs):
    sc, t, c = demo_inputs
    vis = compute_visibility(sc.occupancy, t, c)
    keep = np.diff(vis.V.indptr) > 0
    assert (~keep).sum() > 0  # the demo has blind candidates (into the shelf / walls)
    out = drop_blind_candidates(vis)
    ref = vis.V[keep]
    same_csr(out.V, ref)
    assert np.shares_memory(out.V.indices, vis.V.indices)
    assert len(out.candidates) == out.V.shape[0]
