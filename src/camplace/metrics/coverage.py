"""Stage 7 - metrics: how good a placement is, from V and the selection alone.

coverage_gap = cost / Σ_j w_j Γ_j² (paper eq. 8); non-triangulatable = share of
targets seen by fewer than 2 selected cameras; both overall and per target region.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from camplace.problem.model import PlacementProblem, shortfall_cost


@dataclass(frozen=True)
class Metrics:
    cost: float
    coverage_gap: float
    non_triangulatable_pct: float
    coverage_histogram: dict[str, int]
    regions: dict[str, dict]
    timings_s: dict[str, float] = field(default_factory=dict)
    well_triangulated_pct: float | None = None  # % of targets with a camera pair meeting at a usable angle
    privacy: dict | None = None  # privacy zones: cameras that see one (camplace.visibility.privacy.privacy_report)
    existing: dict | None = None  # existing / kept cameras (camplace.workflows.sites)
    grid_cost: float | None = None  # a refined / adaptive run's cost of its grid placement (issue 17)
    crowd: Any = None  # camplace.metrics.crowd.CrowdMetrics: the placement in held-out crowds (issue 28)
    storeys: list[dict] | None = None  # a building: per-storey figures (camplace.workflows.building, issue 33)

    def to_dict(self) -> dict:
        out = {"cost": self.cost, **({} if self.grid_cost is None else {"grid_cost": self.grid_cost}),
               "coverage_gap": self.coverage_gap,
               "non_triangulatable_pct": self.non_triangulatable_pct,
               "coverage_histogram": self.coverage_histogram, "regions": self.regions,
               "timings_s": self.timings_s}
        if self.well_triangulated_pct is not None:
            out["well_triangulated_pct"] = self.well_triangulated_pct
        for key in ("privacy", "existing"):  # issue 17: only when the scene has privacy zones / existing cameras
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        if self.storeys is not None:  # issue 33: only for buildings
            out["storeys"] = self.storeys
        if self.crowd is not None:  # issue 28: only when the scene has a crowd
            out["crowd"] = self.crowd.to_dict()
        return out


def target_figures(gamma: np.ndarray, weights: np.ndarray, cov: np.ndarray) -> dict:
    cost = shortfall_cost(gamma, weights, cov)
    g = gamma.astype(np.float64)
    norm = float(np.einsum("i,i->", np.asarray(weights, np.float64), g * g))  # no BLAS thread team (gains)
    hist = np.bincount(cov, minlength=1) if len(cov) else np.zeros(1, np.int64)
    return {
        "cost": cost,
        "coverage_gap": cost / norm if norm > 0 else 0.0,
        "non_triangulatable_pct": 100.0 * float(np.mean(cov < 2)) if len(cov) else 0.0,
        "coverage_histogram": {str(k): int(n) for k, n in enumerate(hist)},
    }


def compute_metrics(problem: PlacementProblem, selected: np.ndarray, region_ids: np.ndarray | None = None,
                    region_names: tuple[str, ...] | list[str] = (),
                    well_triangulated: np.ndarray | None = None) -> Metrics:
    """Score a selection (candidate ids) on the problem; per region when ids are given.
    well_triangulated: optional (N_p,) bool from camplace.metrics.triangulation (adds the
    ``well_triangulated_pct`` figures, overall and per region)."""
    return metrics_of_coverage(problem.gamma, problem.weights, problem.coverage(selected), region_ids, region_names,
                               well_triangulated)


def metrics_of_coverage(gamma: np.ndarray, weights: np.ndarray, cov: np.ndarray, region_ids: np.ndarray | None = None,
                        region_names: tuple[str, ...] | list[str] = (),
                        well_triangulated: np.ndarray | None = None) -> Metrics:
    """compute_metrics from the coverage counts ``cov`` (N_p,) int64 (views of each target)
    instead of a selection: what an editor that keeps the counts up to date (the planner)
    rescores with, O(N_p) and no visibility rows."""
    top = target_figures(gamma, weights, cov)
    regions: dict[str, dict] = {}
    if region_ids is not None:
        for r, name in enumerate(region_names):
            m = region_ids == r
            fig = target_figures(gamma[m], weights[m], cov[m])
            fig["targets"] = int(m.sum())
            if well_triangulated is not None:
                fig["well_triangulated_pct"] = 100.0 * float(np.mean(well_triangulated[m])) if m.any() else 0.0
            regions[str(name)] = fig
    wt = None
    if well_triangulated is not None:
        wt = 100.0 * float(np.mean(well_triangulated)) if len(well_triangulated) else 0.0
    return Metrics(top["cost"], top["coverage_gap"], top["non_triangulatable_pct"], top["coverage_histogram"], regions,
                   well_triangulated_pct=wt)
