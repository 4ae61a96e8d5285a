"""Distributed visibility: a Dask cluster and a local process pool give exactly the V of
the in-process path; executors are chosen from --workers / --scheduler / env."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.core.executors import (DaskExecutor, InProcessExecutor, ProcessPoolChunkExecutor, SCHEDULER_ENV,
                                  make_executor)
from camplace.core.errors import InputError
from camplace.visibility.voxel import compute_visibility

from conftest import same_csr


@pytest.fixture(scope="module")
def local_v(demo_inputs):
    sc, t, c = demo_inputs
    return compute_visibility(sc.occupancy, t, c, chunk_size=37).V


def test_dask_local_cluster_equals_local(demo_inputs, local_v):
    distributed = pytest.importorskip("dask.distributed")
    sc, t, c = demo_inputs
    seen = []
    with distributed.LocalCluster(n_workers=3, threads_per_worker=1, processes=False, dashboard_address=None) as cl, \
            distributed.Client(cl, set_as_default=False) as client:
        ex = DaskExecutor(client=client)
        assert ex.workers == 3
        with distributed.get_task_stream(client) as ts:
            vis = compute_visibility(sc.occupancy, t, c, chunk_size=37, executor=ex,
                                     progress=lambda s, d, n: seen.append((d, n)))
        # the chunks were spread over the cluster, not run on one worker
        chunk_tasks = [x for x in ts.data if "camplace-chunk" in str(x["key"])]
        assert len(chunk_tasks) == vis.info["chunks"]
        assert len({x["worker"] for x in chunk_tasks}) >= 2
    assert vis.info["executor"] == "dask" and vis.info["chunks"] == int(np.ceil(len(c) / 37)) > 3
    assert seen[-1] == (vis.info["chunks"], vis.info["chunks"])
    same_csr(vis.V, local_v)


def test_make_executor_choice(monkeypatch):
    monkeypatch.delenv(SCHEDULER_ENV, raising=False)
    assert isinstance(make_executor(1), InProcessExecutor)
    ex = make_executor(3)
    assert isinstance(ex, ProcessPoolChunkExecutor) and ex.workers == 3
    with pytest.raises(InputError, match="^workers: expected a positive integer") as err:
        make_executor(0)
    assert err.value.option == "workers"
    with pytest.raises(InputError, match="^scheduler: ") as err:
        make_executor(1, "localhost-no-scheme")
    assert err.value.option == "scheduler"
    monkeypatch.setenv(SCHEDULER_ENV, "not-an-address")
    with pytest.raises(InputError, match="not-an-address"):
        make_executor(4)  # the environment's scheduler wins over workers


def test_cli_workers_process_pool_equals_local(tmp_path, monkeypatch):
    """`camplace run demo --workers 2 --no-cache` runs the process pool and writes the V of
    the in-process path."""
    from typer.testing import CliRunner

    from camplace.cli.app import app
    from camplace.workflows.run import prepare

    monkeypatch.delenv(SCHEDULER_ENV, raising=False)
    r = CliRunner().invoke(app, ["run", "demo", "--grid-only", "--out", str(tmp_path / "o"), "--workers", "2",
                                 "--no-cache", "--no-plan"])
    assert r.exit_code == 0, r.output
    assert "process-pool" in r.output
    with np.load(tmp_path / "o" / "visibility.npz") as z:
        indptr, indices = z["indptr"], z["indices"]
    _, vis = prepare("demo")  # in-process
    assert np.array_equal(indptr, vis.V.indptr) and np.array_equal(indices, vis.V.indices)
