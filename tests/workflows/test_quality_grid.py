"""quality="high" raycasts a denser grid (issue 37): camplace.workflows.quality.denser_candidates."""

from __future__ import annotations

import pytest

from camplace.cameras.candidates import build_candidates
from camplace.workflows.quality import denser_candidates
from camplace.workflows.run import scene_inputs


@pytest.fixture(scope="module")
def demo_inputs():
    sc, _, cameras, _ = scene_inputs("demo")
    return sc, cameras, build_candidates(sc, cameras)


def test_half_the_spacing_four_times_the_ceiling_poses(demo_inputs):
    sc, cameras, cands = demo_inputs
    dense_sc, dense, note = denser_candidates(sc, cameras, cands, density=2)
    assert [m.spacing for m in dense_sc.spec.mounts] == [m.spacing / 2 for m in sc.spec.mounts]
    assert 3 * len(cands) < len(dense) <= 6 * len(cands)  # (2x)^2 positions and a row along the walls
    assert f"{len(dense)} poses" in note
    # the scene's grid positions are among the denser grid's
    have = {tuple(p) for p in (dense.positions * 1000).round().astype(int).tolist()}
    assert all(tuple(p) in have for p in (cands.positions * 1000).round().astype(int).tolist())
    assert dense_sc.occupancy is sc.occupancy and dense_sc.spec.placement == sc.spec.placement


def test_over_the_cap_or_density_one_keeps_the_scene_grid(demo_inputs):
    sc, cameras, cands = demo_inputs
    same_sc, same, note = denser_candidates(sc, cameras, cands, density=2, max_candidates=len(cands))
    assert same_sc is sc and same is cands and "the scene's grid is kept" in note
    assert denser_candidates(sc, cameras, cands, density=1) == (sc, cands, "")


def test_a_site_grid_is_not_even_built_denser(demo_inputs, monkeypatch):
    import camplace.workflows.quality as q

    sc, cameras, cands = demo_inputs
    monkeypatch.setattr(q, "build_candidates", lambda *a, **k: pytest.fail("built"))
    same_sc, same, note = denser_candidates(sc, cameras, cands, density=2, max_candidates=len(cands) // 3)
    assert same_sc is sc and same is cands and f"~{4 * len(cands)} poses" in note
