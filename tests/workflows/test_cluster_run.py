"""A cluster run is the same run (issue 21): ``camplace run SCENE --scheduler ADDR`` computes V
on a Dask cluster and writes the same placement and metrics as the local run."""

from __future__ import annotations

import json

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")

from conftest import run_cli, same_csr  # noqa: E402

SCENE = "warehouse:200"  # the smallest warehouse: 4 visibility chunks, 6 zone tiles


def _outputs(d):
    placement = json.loads((d / "placement.json").read_text())
    metrics = json.loads((d / "metrics.json").read_text())
    metrics.pop("timings_s", None)
    return placement, metrics


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cl:
        yield cl


def test_cli_run_on_a_cluster_writes_the_local_placement(tmp_path, monkeypatch, capsys, cluster):
    monkeypatch.delenv("CAMPLACE_SCHEDULER", raising=False)
    common = ["run", SCENE, "--solver", "greedy-fast", "--no-plan", "--repeatable"]
    code, out = run_cli([*common, "--no-cache", "--out", tmp_path / "local"], monkeypatch, capsys)
    assert code == 0, out
    code, out = run_cli([*common, "--cache", tmp_path / "cache", "--scheduler", cluster.scheduler_address,
                         "--out", tmp_path / "cluster"], monkeypatch, capsys)
    assert code == 0, out
    local_p, local_m = _outputs(tmp_path / "local")
    cl_p, cl_m = _outputs(tmp_path / "cluster")
    assert len(local_p["cameras"]) > 0
    assert cl_p["cameras"] == local_p["cameras"]
    assert cl_m == local_m
    with np.load(tmp_path / "local" / "visibility.npz") as a, np.load(tmp_path / "cluster" / "visibility.npz") as b:
        for k in ("indptr", "indices", "data"):
            assert np.array_equal(a[k], b[k])


def test_api_run_on_a_cluster_used_the_cluster(cluster):
    from camplace.workflows.run import run

    local = run(SCENE, solver="greedy-fast")
    remote = run(SCENE, solver="greedy-fast", scheduler=cluster.scheduler_address)
    assert remote.visibility.info["executor"] == "dask" and local.visibility.info["executor"] == "in-process"
    same_csr(remote.visibility.V, local.visibility.V)
    assert np.array_equal(remote.placement.selected, local.placement.selected)
    assert remote.placement.objective == local.placement.objective


def test_zones_tiles_run_on_the_same_cluster(cluster):
    from camplace.workflows.run import run

    opts = {"solver": "zones", "max_sweeps": 1, "tile_time_s": 60.0, "bound_time_s": 0.2,  # the bound: reported only
            "tile_m": 6.0}
    local = run(SCENE, **opts)
    remote = run(SCENE, scheduler=cluster.scheduler_address, **opts)
    assert remote.placement.info["executor"] == "dask" and local.placement.info["executor"] == "in-process"
    assert np.array_equal(remote.placement.selected, local.placement.selected)
    assert remote.placement.objective == local.placement.objective
