"""Pixel visibility mode: hand-computed coverage on simple geometry, agreement with voxel mode."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp

from camplace.cameras.models import CameraModel
from camplace.cameras.candidates import Candidates, location_ids_of, rotation_from_ypr
from camplace.workflows.compare import compare_visibility, entry_agreement
from camplace.core.errors import InputError
from camplace.scene.build import build_scene
from camplace.targets.build import build_targets
from camplace.visibility.voxel import Visibility, compute_visibility
from camplace.visibility.pixel import compute_pixel_visibility

from conftest import box_room, same_csr


def _poses(cam, positions, ypr) -> Candidates:
    p = np.asarray(positions, float)
    a = np.asarray(ypr, float)
    return Candidates(p, rotation_from_ypr(a[:, 0], a[:, 1], a[:, 2]), a, np.zeros(len(p), np.int32),
                      location_ids_of(p), (cam,))


@pytest.fixture(scope="module")
def down_room():
    """4 x 4 x 3 m room, volume targets at z = 1.0 on the 0.25 m lattice (centres 0.125 + 0.25 i);
    a 64 x 64 px, 60 x 60 deg pinhole at (2, 2, 2.8) looking straight down."""
    sc = build_scene(box_room())
    t = build_targets(sc)
    cam = CameraModel.pinhole_from_fov("down", (64, 64), (60, 60), max_range=10)
    return sc, t, _poses(cam, [[2.0, 2.0, 2.8]], [[0.0, 90.0, 0.0]])


def _lattice_index(t):
    return np.round((t.positions[:, :2] - 0.125) / 0.25).astype(int)


def test_pixel_mode_covers_exactly_the_hand_computed_voxels(down_room):
    """Any part of a voxel (cube z in [0.875, 1.125]) inside the view pyramid counts. The
    outermost rays (pixel centres) leave at slope 31.5 / f = 0.5683 (f = 32 / tan 30 deg),
    so at the cube bottom (depth 1.925) the view spans 2 +- 1.094 m: lattice columns
    i = 3..12 (cells [0.75, 1.0] .. [3.0, 3.25]) on both axes = 100 voxels."""
    sc, t, cands = down_room
    vis = compute_pixel_visibility(sc.occupancy, t, cands, stride=1, probe=1.0)
    assert isinstance(vis, Visibility) and vis.mode == "pixel" and vis.V.shape == (1, len(t))
    ij = _lattice_index(t)
    want = np.all((ij >= 3) & (ij <= 12), axis=1)
    got = vis.V.toarray()[0].astype(bool)
    assert got.sum() == 100
    assert np.array_equal(got, want)


def test_centre_probe_matches_the_centre_test(down_room):
    """probe 0: the centre must be in a ray's footprint: |c - 2| <= 1.9 tan 30 = 1.097 m,
    columns i = 4..11 = 64 voxels, the same as voxel mode."""
    sc, t, cands = down_room
    vis = compute_pixel_visibility(sc.occupancy, t, cands, stride=1, probe=0.0)
    vox = compute_visibility(sc.occupancy, t, cands)
    ij = _lattice_index(t)
    want = np.all((ij >= 4) & (ij <= 11), axis=1)
    assert np.array_equal(vis.V.toarray()[0].astype(bool), want)
    assert np.array_equal(vox.V.toarray()[0].astype(bool), want)


def test_occluder_hides_voxels_behind_it():
    """A 1 m table top (z 1.4..1.5) under the camera hides the column below it."""
    table = {"name": "table", "box": {"min": [1.5, 1.5, 1.4], "max": [2.5, 2.5, 1.5]}}
    sc = build_scene(box_room(obstacles=[table]))
    t = build_targets(sc)
    cam = CameraModel.pinhole_from_fov("down", (64, 64), (60, 60), max_range=10)
    cands = _poses(cam, [[2.0, 2.0, 2.8]], [[0.0, 90.0, 0.0]])
    got = compute_pixel_visibility(sc.occupancy, t, cands, stride=1, probe=1.0).V.toarray()[0].astype(bool)
    ij = _lattice_index(t)
    # voxel columns whose whole cube lies in the table's shadow: the shadow of the table edge
    # (1.5 / 2.5 at depth 1.3) at the cube top (depth 1.675) is 2 +- 0.5 * 1.675 / 1.3 = 2 +- 0.644
    hidden = np.all((ij >= 6) & (ij <= 9), axis=1)  # cells [1.5, 2.5]: entirely inside 2 +- 0.644
    assert not got[hidden].any()
    assert got[np.all((ij >= 3) & (ij <= 4), axis=1)].all()  # far from the shadow: seen


@pytest.fixture(scope="module")
def wall_face():
    """Camera at (1, 2, 1) looking +x at the -x face of a slab (x = 3, y 1..3, z 0..2): 8 x 8
    patches of 0.25 m, incidence limit 27 deg = a disc of radius 2 tan 27 deg = 1.019 m
    around (y, z) = (2, 1) on the face."""
    slab = {"name": "slab", "box": {"min": [3.0, 1.0, 0.0], "max": [3.5, 3.0, 2.0]}}
    spec = box_room(obstacles=[slab], targets=[{"name": "face", "kind": "surface", "of": ["slab"],
                                                "faces": ["-x"], "coverage": 1, "max_incidence_deg": 27}])
    sc = build_scene(spec)
    t = build_targets(sc)
    cam = CameraModel.pinhole_from_fov("c", (400, 400), (90, 90), max_range=10)
    return sc, t, _poses(cam, [[1.0, 2.0, 1.0]], [[0.0, 0.0, 0.0]])


def test_surface_patches_hit_within_incidence_limit(wall_face):
    sc, t, cands = wall_face
    assert len(t) == 64
    R = 2.0 * math.tan(math.radians(27))
    dy, dz = np.abs(t.positions[:, 1] - 2.0), np.abs(t.positions[:, 2] - 1.0)
    centre_in = np.hypot(dy, dz) <= R
    rect_in = np.hypot(np.maximum(dy - 0.125, 0), np.maximum(dz - 0.125, 0)) <= R
    assert centre_in.sum() == 52 and rect_in.sum() == 60  # hand count (margins >= 4 cm)
    any_part = compute_pixel_visibility(sc.occupancy, t, cands, stride=1, probe=1.0).V.toarray()[0]
    centre = compute_pixel_visibility(sc.occupancy, t, cands, stride=1, probe=0.0).V.toarray()[0]
    voxel = compute_visibility(sc.occupancy, t, cands).V.toarray()[0]
    assert np.array_equal(any_part.astype(bool), rect_in)
    assert np.array_equal(centre.astype(bool), centre_in)
    assert np.array_equal(voxel.astype(bool), centre_in)


def test_back_of_surface_is_not_seen(wall_face):
    sc, t, _ = wall_face
    cam = CameraModel.pinhole_from_fov("c", (200, 200), (90, 90), max_range=10)
    behind = _poses(cam, [[3.8, 2.0, 1.0]], [[180.0, 0.0, 0.0]])  # inside the room, behind the slab, facing it
    assert compute_pixel_visibility(sc.occupancy, t, behind, stride=1).V.nnz == 0


def test_modes_agree_on_a_grid_of_candidates():
    spec = box_room(obstacles=[{"name": "shelf", "box": {"min": [1.5, 1.0, 0.0], "max": [2.5, 1.6, 1.6]}}],
                    targets=[{"name": "w", "kind": "volume", "heights": [0.5, 1.0, 1.5], "coverage": 2},
                             {"name": "s", "kind": "surface", "of": ["shelf"], "coverage": 1,
                              "max_incidence_deg": 60}],
                    cameras=[{"name": "cam", "resolution": [320, 240], "fov_deg": [71, 54], "max_range": 5.0}],
                    mounts=[{"kind": "ceiling_grid", "camera": "cam", "spacing": 1.0,
                             "yaw_deg": [0, 90, 180, 270], "pitch_deg": [45]}])
    a = compare_visibility(spec, stride=1, probe=0.0, budget=2)
    assert a.candidates == 36 and a.nnz_voxel > 1000
    assert a.voxel_in_pixel > 0.995 and a.jaccard > 0.98
    assert set(a.gap) == {"voxel", "pixel"} and all(0 <= g <= 1 for row in a.gap.values() for g in row.values())
    paper = compare_visibility(spec, stride=1, probe=1.0, budget=2)  # both modes under the paper's rule
    assert paper.nnz_pixel > a.nnz_pixel and paper.nnz_voxel > a.nnz_voxel  # any part counts: more entries
    assert paper.jaccard > 0.98


def test_stride_reduces_rays(down_room):
    sc, t, cands = down_room
    v1 = compute_pixel_visibility(sc.occupancy, t, cands, stride=1)
    v4 = compute_pixel_visibility(sc.occupancy, t, cands, stride=4)
    assert v1.info["rays"] == 64 * 64 and v4.info["rays"] == 16 * 16
    assert entry_agreement(v1.V, v4.V)["jaccard"] > 0.95


def test_bad_options(down_room):
    sc, t, cands = down_room
    with pytest.raises(InputError, match="stride"):
        compute_pixel_visibility(sc.occupancy, t, cands, stride=0)
    with pytest.raises(InputError, match="probe"):
        compute_pixel_visibility(sc.occupancy, t, cands, probe=1.5)


def test_entry_agreement_counts():
    A = sp.csr_matrix(np.array([[1, 1, 0], [0, 1, 0]], np.uint8))
    B = sp.csr_matrix(np.array([[1, 0, 0], [0, 1, 1]], np.uint8))
    e = entry_agreement(A, B)
    assert (e["shared"], e["nnz_a"], e["nnz_b"]) == (2, 3, 3) and e["jaccard"] == pytest.approx(0.5)


def test_empty_space_skipping_gives_the_same_v():
    """Jumping rays through empty space changes nothing, also for rays along cell
    boundaries (a camera on a cell boundary looking along an axis once looped forever)."""
    from camplace.workflows.run import scene_inputs
    from camplace.cameras.candidates import build_candidates

    sc, t, cams, _ = scene_inputs("demo")
    c = build_candidates(sc, cams)
    c = c.subset(np.arange(0, len(c), 23))
    a = compute_pixel_visibility(sc.occupancy, t, c, stride=8, skip_empty=True).V
    b = compute_pixel_visibility(sc.occupancy, t, c, stride=8, skip_empty=False).V
    assert a.nnz > 0 and (a != b).nnz == 0


def test_workers_and_cache_give_the_same_v(demo_inputs, tmp_path):
    """Pixel mode runs on the same executors and block cache as voxel mode: a 2-process
    pool and a cached / reloaded V equal the in-process V bit for bit (demo, every 4th
    candidate, stride 16, chunks of 16 candidates)."""
    from camplace.core.executors import InProcessExecutor, ProcessPoolChunkExecutor

    sc, t, c = demo_inputs
    c = c.subset(np.arange(0, len(c), 4))
    kw = dict(stride=16, chunk_size=16)
    ref = compute_pixel_visibility(sc.occupancy, t, c, **kw)
    assert ref.V.nnz > 1000 and ref.info["chunks"] >= 4 and ref.info["executor"] == "in-process"
    with ProcessPoolChunkExecutor(2) as ex:
        pooled = compute_pixel_visibility(sc.occupancy, t, c, executor=ex, cache_dir=tmp_path, **kw)
    assert pooled.info["executor"] == "process-pool" and pooled.info["cached_chunks"] == 0
    again = compute_pixel_visibility(sc.occupancy, t, c, executor=InProcessExecutor(), cache_dir=tmp_path, **kw)
    assert again.info["cached_chunks"] == again.info["chunks"] and again.info["rays_cast"] == 0
    assert again.info["rays"] == ref.info["rays"] == ref.info["rays_cast"]
    for v in (pooled, again):
        same_csr(v.V, ref.V)
    # other pixel parameters, or voxel mode, never reuse these blocks
    other = compute_pixel_visibility(sc.occupancy, t, c, probe=0.5, cache_dir=tmp_path, **kw)
    assert other.info["cached_chunks"] == 0 and other.info["cache"] != again.info["cache"]
    from camplace.visibility.voxel import compute_visibility

    vox = compute_visibility(sc.occupancy, t, c, chunk_size=16, cache_dir=tmp_path)
    assert vox.info["cached_chunks"] == 0 and vox.info["cache"] not in (again.info["cache"], other.info["cache"])


def test_pipeline_pixel_mode_uses_workers_and_cache(tmp_path):
    """prepare(visibility_mode='pixel', workers=2, cache_dir=...) runs the process pool and
    a second run loads every block; V equals the in-process, uncached one."""
    from camplace.workflows.run import prepare

    kw = dict(visibility_mode="pixel", stride=32)
    _, ref = prepare("demo", **kw)
    log: list[str] = []
    _, pooled = prepare("demo", workers=2, cache_dir=tmp_path, log=log, **kw)
    _, cached = prepare("demo", cache_dir=tmp_path, **kw)
    assert pooled.info["executor"] == "process-pool" and any("process-pool" in line for line in log)
    assert cached.info["cached_chunks"] == cached.info["chunks"] > 0
    same_csr(pooled.V, ref.V)
    same_csr(cached.V, ref.V)
