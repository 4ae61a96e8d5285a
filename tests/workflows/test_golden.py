"""Golden tests: pinned before the package layout moved (issue 15) and unchanged since.

They fix, through the public API only, the visibility matrix (a hash of its CSR index
arrays) and the chosen candidate ids of greedy, mip, tabu (seeded) and off-grid
refinement on the demo and on standard-store. A change of any of them is a change of
behaviour: regenerate with ``python tests/test_golden.py`` only on purpose, and say why.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import numpy as np
import pytest

GOLDEN = Path(__file__).with_name("golden") / "golden.json"

CASES = {  # name -> (scene, run options)
    "demo-greedy": ("demo", {"budget": 6, "solver": "greedy"}),
    "demo-mip": ("demo", {"budget": 4, "solver": "mip", "threads": 1, "time_limit_s": 120}),
    "demo-tabu": ("demo", {"budget": 6, "solver": "tabu", "seed": 3, "max_iterations": 400, "threads": 1}),
    "demo-refine": ("demo", {"budget": 6, "solver": "greedy", "refine": True, "refine_time_s": 600}),
    "standard-store-greedy": ("standard-store", {"budget": 40, "solver": "greedy"}),
    "standard-store-tabu": ("standard-store", {"budget": 40, "solver": "tabu", "seed": 1, "max_iterations": 300,
                                               "threads": 1}),
    "standard-store-refine": ("standard-store", {"budget": 20, "solver": "greedy", "refine": True,
                                                 "refine_time_s": 600}),
}


def v_hash(V) -> str:
    """sha256 of V's shape, indptr and indices (as int64)."""
    h = hashlib.sha256()
    h.update(np.asarray(V.shape, np.int64).tobytes())
    h.update(np.asarray(V.indptr, np.int64).tobytes())
    h.update(np.asarray(V.indices, np.int64).tobytes())
    return h.hexdigest()


def observe(name: str) -> dict:
    import camplace

    scene, opts = CASES[name]
    r = camplace.run(scene, **opts)
    return {"v_hash": v_hash(r.visibility.V), "nnz": int(r.visibility.V.nnz),
            "selected": [int(i) for i in r.placement.selected], "objective": float(r.placement.objective)}


@pytest.fixture(scope="module")
def golden() -> dict:
    return json.loads(GOLDEN.read_text())


@pytest.mark.parametrize("name", sorted(CASES))
def test_golden(name, golden):
    got = observe(name)
    want = golden[name]
    assert got["nnz"] == want["nnz"] and got["v_hash"] == want["v_hash"], "V changed"
    assert got["selected"] == want["selected"], f"{name}: selection changed"
    assert got["objective"] == pytest.approx(want["objective"], rel=1e-12, abs=1e-9)


if __name__ == "__main__":  # regenerate (on purpose only)
    names = sys.argv[1:] or sorted(CASES)
    old = json.loads(GOLDEN.read_text()) if GOLDEN.exists() else {}
    old.update({n: observe(n) for n in names})
    GOLDEN.write_text(json.dumps(old, indent=1, sort_keys=True) + "\n")
    print(f"wrote {GOLDEN}")
