"""Robustness to camera failure: which cameras are essential, and placements that stay
good when any one camera fails.

Failure cost of camera i in a selection S: cost(S minus i) (one matrix-vector product
over the selected rows gives all of them: removing i raises the cost by
Σ_{j in row i} w_j (max(Γ_j − c_j + 1, 0)² − max(Γ_j − c_j, 0)²)).
Worst case: W(S) = max_i cost(S minus i).

``robust_placement`` (run option robust=1) minimises W:

- ``robust_search``: best-improvement swap local search from the nominal placement on
  (W, second and third worst failure costs, nominal cost) in lexicographic order, continued
  as a short tabu search; it returns the best selection seen, so W never rises.
- ``scenario_mip``: the exact scenario MIP (one coverage scenario per failure, no big-M),
  solved by lazy scenario generation on HiGHS; a model with a subset of the scenarios is a
  relaxation, so its dual bound is a lower bound on the optimal W*. Whole problem when V
  is small; on store-sized V, ``robust_lns`` solves it on neighbourhoods of the costliest
  failures (most cameras fixed).
- Lower bounds on W*: ``robust_bound`` (Lagrangian bound with one camera fewer: W(S) >=
  OPT(N_s − 1)) and ``mean_failure_bound`` (W(S) >= cost(S) + mean loss, a convex placement
  problem, by LP). Proofs in docs/beyond-the-grid.md.

Modules: failures (losses, worst case, essential cameras), search (swap / tabu heuristic on
camplace.solvers.local_search), scenario (scenario MIP), lns (its neighbourhood search),
bounds (lower bounds on W*), placement (robust_placement, RobustResult).
"""

from camplace.solvers.robust.bounds import mean_failure_bound, robust_bound
from camplace.solvers.robust.failures import essential_cameras, removal_losses, worst_case
from camplace.solvers.robust.lns import robust_lns
from camplace.solvers.robust.placement import RobustResult, robust_placement
from camplace.solvers.robust.scenario import ScenarioResult, _ScenarioModel, scenario_mip  # noqa: F401 (tests)
from camplace.solvers.robust.search import _SwapScorer, robust_search  # noqa: F401 (tests)

__all__ = ["RobustResult", "ScenarioResult", "essential_cameras", "mean_failure_bound", "removal_losses",
           "robust_bound", "robust_lns", "robust_placement", "robust_search", "scenario_mip", "worst_case"]
