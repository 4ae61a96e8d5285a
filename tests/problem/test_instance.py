"""Saved instances (camplace.problem.instance): load a visibility.npz without geometry, save one."""

from __future__ import annotations

import numpy as np
import pytest

from camplace.core.errors import InputError
from camplace.problem.instance import load_problem_npz, save_problem_npz
from tests.solvers.test_bounds import random_problem


def test_round_trip_minimal_arrays(tmp_path):
    p = random_problem(3, n_g=20, n_p=30, budget=3, n_loc=8, weighted=True)
    path = save_problem_npz(tmp_path / "inst.npz", p)
    q, arrays = load_problem_npz(path, 3)
    assert (q.V != p.V).nnz == 0
    assert np.array_equal(q.gamma, p.gamma) and np.allclose(q.weights, p.weights)
    assert np.array_equal(q.location_ids, p.location_ids) and q.budget == 3


def test_weights_optional_default_one(tmp_path):
    p = random_problem(4, n_g=10, n_p=12)
    V = p.V
    np.savez(tmp_path / "v.npz", data=V.data, indices=V.indices, indptr=V.indptr, shape=np.array(V.shape),
             gamma=p.gamma, location_ids=p.location_ids)
    q, _ = load_problem_npz(tmp_path / "v.npz", 2)
    assert np.all(q.weights == 1.0)


@pytest.mark.parametrize("drop,msg", [("gamma", "'gamma' missing"), ("location_ids", "'location_ids' missing")])
def test_missing_required_array(tmp_path, drop, msg):
    p = random_problem(4, n_g=10, n_p=12)
    V = p.V
    arrays = dict(data=V.data, indices=V.indices, indptr=V.indptr, shape=np.array(V.shape), gamma=p.gamma,
                  location_ids=p.location_ids)
    arrays.pop(drop)
    np.savez(tmp_path / "v.npz", **arrays)
    with pytest.raises(InputError, match=msg):
        load_problem_npz(tmp_path / "v.npz", 2)


def test_bad_inputs(tmp_path):
    with pytest.raises(InputError, match="not found"):
        load_problem_npz(tmp_path / "nope.npz", 1)
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(InputError, match="not a readable"):
        load_problem_npz(tmp_path / "junk.npz", 1)
    p = random_problem(4, n_g=10, n_p=12)
    V = p.V
    np.savez(tmp_path / "v.npz", data=V.data, indices=V.indices, indptr=V.indptr, shape=np.array(V.shape),
             gamma=p.gamma[:-1], location_ids=p.location_ids)
    with pytest.raises(InputError, match="'gamma' must be 12"):
        load_problem_npz(tmp_path / "v.npz", 1)




def test_negative_budget_names_the_parameter(tmp_path):
    path = save_problem_npz(tmp_path / "inst.npz", random_problem(1, n_g=5, n_p=6, budget=1, n_loc=3))
    with pytest.raises(InputError, match=r"^budget: expected a non-negative integer, got -1$") as e:
        load_problem_npz(path, -1)
    assert e.value.option == "budget"
