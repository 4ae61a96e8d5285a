"""camplace.visibility (layer 5): the sparse matrix V (N_g x N_p) of which candidate sees which target.

- ``engine``: the engine interface (``VisibilityEngine``), ``Visibility`` and the one
  loop ``compute_visibility(engine, occupancy, targets, candidates, ...)``;
- ``registry``: ``ENGINES`` and ``get_engine(mode, **params)``;
- ``voxel`` (default: centre test by line of sight) and ``pixel`` (the paper's per-pixel
  raycasting): the engines;
- ``raywalk``: the 3D DDA and first-hit routines they (and the renders) share;
- ``cache``: V's blocks by content hash (the executors that run the blocks are in
  camplace.core.executors);
- ``testing``: ``check_engine``, the conformance checks every engine passes.
"""

from camplace.visibility.engine import Visibility, VisibilityEngine, compute_visibility, drop_blind_candidates
from camplace.visibility.registry import ENGINES, get_engine

__all__ = ["ENGINES", "Visibility", "VisibilityEngine", "compute_visibility", "drop_blind_candidates", "get_engine"]
