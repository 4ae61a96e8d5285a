"""Who sees the people (issue 36): V of the points on the sampled people, in their crowds.

A camera sees a point on a person of sample s when the run's engine sees it past the
scene (shelves, walls: the same raycast as any target, people are not in the occupancy
grid) and no other person of sample s cuts the sight line; the person's own cylinder
never blocks it (camplace.visibility.crowd.segment_blocked leaves out the person whose
disc holds the target, and each point is on its person's axis).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from camplace.cameras.candidates import Candidates
from camplace.scene.build import OccupancyGrid
from camplace.targets.people import People
from camplace.visibility.crowd import PeopleGrid, sample_rows
from camplace.visibility.engine import VisibilityEngine, compute_visibility, raycast_rows

FEW_ROWS = 256  # at most this many poses are raycast here (raycast_rows), more through compute_visibility


def thin_people(V: sp.csr_matrix, cam_positions: np.ndarray, people: People, grid: PeopleGrid) -> sp.csr_matrix:
    """V (n, M) of the people's points past the scene -> the entries no other person of the
    point's own sample blocks (n, M) CSR uint8; ``grid`` holds the same samples as ``people``."""
    V = sp.csr_matrix(V)
    n, m = V.shape
    if m == 0 or n == 0:
        return sp.csr_matrix((n, m), dtype=np.uint8)
    cams = np.asarray(cam_positions, np.float64).reshape(-1, 3)
    pos = people.targets.positions
    ptrs, idxs = [], []
    for s in range(people.n_samples):
        sl = people.sample_slice(s)
        sub = V[:, sl].tocsr()
        sub.sort_indices()
        ip, ix = sample_rows(sub, cams, pos[sl], grid, s)
        ptrs.append(ip)
        idxs.append(ix.astype(np.int64) + sl.start)
    counts = np.sum([np.diff(p) for p in ptrs], axis=0)
    order = np.concatenate([np.repeat(np.arange(n), np.diff(p)) for p in ptrs])
    cols = np.concatenate(idxs)
    rank = np.lexsort((cols, order))  # row by row, columns ascending (samples are column blocks)
    indptr = np.r_[0, np.cumsum(counts)].astype(np.int64)
    return sp.csr_matrix((np.ones(len(cols), np.uint8), cols[rank].astype(np.int32), indptr), shape=(n, m))


def people_rows(engine: VisibilityEngine, occupancy: OccupancyGrid, people: People, candidates: Candidates,
                grid: PeopleGrid, executor=None) -> sp.csr_matrix:
    """(len(candidates), M) CSR uint8: which poses see which points on the people in their
    crowds (module doc); ``executor`` as for V (used for more than FEW_ROWS poses)."""
    if len(candidates) <= FEW_ROWS:
        V = raycast_rows(engine, occupancy, people.targets, candidates)
    else:
        V = compute_visibility(engine, occupancy, people.targets, candidates, executor=executor).V
    return thin_people(V, candidates.positions, people, grid)


__all__ = ["FEW_ROWS", "people_rows", "thin_people"]
