"""The visibility-engine interface: every registered engine passes camplace.visibility.testing
(same V under every executor, block size and cache state), the registry refuses what an
engine does not take, and the old entry points equal the engine loop."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.scene.build import build_scene
from camplace.targets.build import build_targets
from camplace.cameras.models import camera_from_spec
from camplace.cameras.candidates import build_candidates
from camplace.visibility import ENGINES, compute_visibility, get_engine
from camplace.visibility.pixel import PixelEngine, compute_pixel_visibility
from camplace.visibility.testing import Check, check_engine, csr_problems
from camplace.visibility.voxel import VoxelEngine
from camplace.visibility import voxel

from conftest import box_room, same_csr

FAST = {"voxel": {"chunk_size": 8}, "pixel": {"stride": 32, "chunk_size": 8, "probe": 0.5}}
PROBED = {"voxel": {"chunk_size": 8, "probe": 1.0}}  # the engines again under the any-part rule


@pytest.fixture(scope="module")
def small_scene():
    """A 4 x 4 x 3 m room with a box, volume targets at 1 m and the box's surface patches."""
    spec = box_room(obstacles=[{"name": "box", "box": {"min": [1.5, 1.5, 0.0], "max": [2.5, 2.5, 1.5]}}],
                    targets=[{"name": "walkable", "kind": "volume", "heights": [1.0], "coverage": 1},
                             {"name": "box", "kind": "surface", "of": ["box"], "coverage": 1}],
                    cameras=[{"name": "cam", "resolution": [320, 240], "fov_deg": [90, 70], "max_range": 6.0}])
    sc = build_scene(spec)
    t = build_targets(sc)
    c = build_candidates(sc, {x.name: camera_from_spec(x) for x in spec.cameras})
    return sc, t, c


@pytest.mark.parametrize("mode, params", [(m, FAST[m]) for m in sorted(ENGINES)] + sorted(PROBED.items()))
def test_every_engine_conforms(mode, params, small_scene, tmp_path):
    sc, t, c = small_scene
    engine = get_engine(mode, **params)
    checks = check_engine(engine, sc.occupancy, t, c, tmp_path)
    by_name = {k.name: k for k in checks}
    assert all(k.status in ("ok", "skipped") for k in checks)
    for name in ("executor in-process", "executor process-pool", "chunking", "cache cold", "cache warm", "V"):
        assert by_name[name].status == "ok", name
    dask = by_name["executor dask"]
    assert dask.status == "ok" or (dask.status == "skipped" and dask.detail)
    assert compute_visibility(engine, sc.occupancy, t, c).V.nnz > 0


@dataclasses.dataclass(frozen=True)
class FirstRowOnly(VoxelEngine):
    """A wrong engine: only the first row of each block keeps its entries."""

    def rows(self, shared, start, stop):
        indptr, indices = super().rows(shared, start, stop)
        indptr = np.minimum(indptr, indptr[min(1, len(indptr) - 1)])
        return indptr, indices[:indptr[-1]]


def test_check_engine_catches_a_wrong_engine(small_scene):
    """An engine whose V depends on the block size fails the chunking check; one that
    does not pickle fails the pickle check."""
    sc, t, c = small_scene
    with pytest.raises(AssertionError, match="chunking"):
        check_engine(FirstRowOnly(chunk_size=8), sc.occupancy, t, c, executors=("in-process",))

    @dataclasses.dataclass(frozen=True)
    class Local(VoxelEngine):
        pass

    with pytest.raises(AssertionError, match="pickle: the engine does not pickle"):
        check_engine(Local(), sc.occupancy, t, c, executors=("in-process",))


def test_csr_problems():
    import scipy.sparse as sp

    ok = sp.csr_matrix((np.ones(3, np.uint8), np.array([0, 2, 1], np.int32), np.array([0, 2, 3])), shape=(2, 3))
    assert csr_problems(ok, (2, 3)) == []
    bad = sp.csr_matrix((np.ones(2, np.uint8), np.array([2, 0], np.int32), np.array([0, 2, 2])), shape=(2, 3))
    assert csr_problems(bad, (2, 3)) == ["column indices not strictly ascending within a row"]
    assert "shape" in csr_problems(ok, (3, 3))[0]
    assert Check("x", "ok").detail == ""


def test_registry_parameters_and_refusals():
    assert get_engine("voxel") == VoxelEngine() and get_engine("voxel", probe=None, stride=None) == VoxelEngine()
    px = get_engine("pixel", stride=None, probe=None)
    assert px == PixelEngine() and px.stride == 4 and px.probe == 1.0
    with pytest.raises(InputError, match="^stride: the voxel engine takes no stride .*pixel") as err:
        get_engine("voxel", stride=2)
    assert err.value.option == "stride"
    with pytest.raises(InputError, match="^probe: expected a fraction in \\[0, 1\\], got 1.5") as err:
        get_engine("voxel", probe=1.5)
    assert err.value.option == "probe"
    assert get_engine("voxel", probe=1.0) == VoxelEngine(1.0)  # the voxel edge comes with the targets
    with pytest.raises(InputError, match="^voxel_size: the voxel engine takes no voxel_size \\(no engine takes it\\)"):
        get_engine("voxel", voxel_size=0.25)  # no hidden parameter every engine must take
    with pytest.raises(InputError, match="^visibility_mode: expected one of 'voxel', 'pixel'.*, got 'raster'") as err:
        get_engine("raster")
    assert err.value.option == "visibility_mode"
    with pytest.raises(InputError, match="^stride: expected a positive integer") as err:
        get_engine("pixel", stride=0)
    assert err.value.option == "stride"
    with pytest.raises(InputError, match="^probe: expected a fraction") as err:
        get_engine("pixel", probe=2.0)
    assert err.value.option == "probe"
    with pytest.raises(InputError, match="^chunk_size: ") as err:
        VoxelEngine(chunk_size=0)
    assert err.value.option == "chunk_size"


def test_cache_tags_name_the_parameters():
    assert VoxelEngine().cache_tag() == "voxel:probe=0.0"
    assert VoxelEngine(1.0).cache_tag() == "voxel:probe=1.0:lattice=5x3"
    assert PixelEngine(8, 0.5).cache_tag() == "pixel:stride=8:probe=0.5:skip=True"
    assert PixelEngine(8).cache_tag() != PixelEngine(4).cache_tag()


def test_old_entry_points_equal_the_engine_loop(small_scene):
    sc, t, c = small_scene
    same_csr(voxel.compute_visibility(sc.occupancy, t, c).V, compute_visibility(VoxelEngine(), sc.occupancy, t, c).V)
    old = compute_pixel_visibility(sc.occupancy, t, c, stride=32)
    new = compute_visibility(PixelEngine(32), sc.occupancy, t, c)
    same_csr(old.V, new.V)
    assert old.mode == new.mode == "pixel" and old.info["rays"] == new.info["rays"] == new.info["rays_cast"] > 0
