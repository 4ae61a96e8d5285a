"""Metrics in a crowd (issue 28): how well a placement sees people when the store is full.

From the coverage of each target in each held-out crowd sample (S, N_p), per sample
and then averaged over the samples with their spread (mean, std, min, max), overall
and per target region:

- ``coverage_gap``: the crowd coverage gap, cost_s / Σ_j w_j Γ_j² (paper eq. 8 with
  coverage in sample s; its mean is the sample-average crowd cost normalised the same way);
- ``seen_by_gamma_pct``: % of targets seen by at least Γ_j cameras;
- ``triangulatable_pct``: % of targets still seen by at least 2 cameras.

and of the people themselves (issue 36, ``people``): % of the persons in each held-out crowd
seen by ≥ 2 and by ≥ Γ^p cameras (a person's coverage is the least coverage among its
points, camplace.targets.people), mean and spread over the crowds, overall and per zone.

Per target: the share of samples in which it is seen by ≥ 2 cameras and by ≥ Γ_j (drawn
by report.html), and one sampled crowd to show.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from camplace.metrics.coverage import target_figures

FIGURES = ("coverage_gap", "seen_by_gamma_pct", "triangulatable_pct")


def spread(values: np.ndarray) -> dict:
    """{'mean', 'std', 'min', 'max'} of per-sample values (S,); equal values give exactly that value."""
    v = np.asarray(values, np.float64)
    if len(v) == 0:
        return {"mean": 0.0, "std": 0.0, "min": 0.0, "max": 0.0}
    mean = float(v[0]) if np.all(v == v[0]) else float(np.mean(v))
    return {"mean": mean, "std": float(np.std(v)), "min": float(v.min()), "max": float(v.max())}


def sample_figures(gamma: np.ndarray, weights: np.ndarray, coverage: np.ndarray) -> dict[str, float]:
    """The FIGURES of one sample: gamma, weights, coverage (N,) of some targets."""
    cov = np.asarray(coverage, np.int64)
    fig = target_figures(gamma, weights, cov)
    seen = 100.0 * float(np.mean(cov >= gamma)) if len(cov) else 0.0
    return {"coverage_gap": fig["coverage_gap"], "seen_by_gamma_pct": seen,
            "triangulatable_pct": 100.0 - fig["non_triangulatable_pct"] if len(cov) else 0.0}


def _summary(gamma: np.ndarray, weights: np.ndarray, cov: np.ndarray) -> dict:
    per = [sample_figures(gamma, weights, c) for c in cov]
    return {k: spread(np.array([p[k] for p in per])) for k in FIGURES}


def _people_pct(cov: np.ndarray, sample: np.ndarray, n_samples: int, need: int) -> np.ndarray:
    """(S',) % of the persons of each sample that has anyone with coverage ≥ need (samples without persons left out)."""
    n = np.bincount(sample, minlength=n_samples)
    ok = np.bincount(sample, weights=(cov >= need).astype(np.float64), minlength=n_samples)
    has = n > 0
    return 100.0 * ok[has] / n[has]


def people_metrics(person_cov: np.ndarray, sample: np.ndarray, n_samples: int, region: np.ndarray, region_names,
                   gamma: int, heights) -> dict:
    """metrics.json ``crowd.people``: person_cov (P,) coverage of each person of the held-out
    crowds (sample (P,) its crowd, region (P,) its zone index into region_names), Γ^p
    ``gamma``, the points' ``heights`` (m)."""
    cov = np.asarray(person_cov, np.int64)
    smp = np.asarray(sample, np.int64)
    reg = np.asarray(region, np.int64)

    def figs(m: np.ndarray) -> dict:
        return {"persons": spread(np.bincount(smp[m], minlength=n_samples)),
                "seen_by_2_pct": spread(_people_pct(cov[m], smp[m], n_samples, 2)),
                "seen_by_gamma_pct": spread(_people_pct(cov[m], smp[m], n_samples, int(gamma)))}

    out = {"heights": [float(z) for z in heights], "gamma": int(gamma), **figs(np.ones(len(cov), bool))}
    out["regions"] = {str(name): figs(reg == r) for r, name in enumerate(region_names) if np.any(reg == r)}
    return out


@dataclass(frozen=True)
class CrowdMetrics:
    """summary: metrics.json ``crowd``; p_triangulatable / p_seen: (N_p,) share of samples
    in which each target is seen by ≥ 2 / ≥ Γ_j cameras; p_person: (N_p,) at the volume
    targets of report_height, the share of the crowds in which a person standing at the
    target's (x, y) is seen by ≥ 2 cameras (NaN elsewhere; issue 36); shown: (n, 2) m the people of one
    sample (for the report's 3D view); radius, height: m; report_height: m, the target
    height the report draws."""

    summary: dict
    p_triangulatable: np.ndarray
    p_seen: np.ndarray
    shown: np.ndarray
    radius: float
    height: float
    report_height: float | None = None
    extra: dict = field(default_factory=dict)
    p_person: np.ndarray | None = None  # (N_p,) chance a person standing there is seen by ≥ 2 (NaN: not drawn)

    def to_dict(self) -> dict:
        return {**self.summary, **self.extra}


def crowd_metrics(gamma: np.ndarray, weights: np.ndarray, coverage: np.ndarray, region_ids: np.ndarray,
                  region_names, shown: np.ndarray, radius: float, height: float, info: dict | None = None,
                  report_height: float | None = None) -> CrowdMetrics:
    """The crowd metrics of a placement from its coverage (S, N_p) in S held-out crowd
    samples (gamma, weights, region_ids: (N_p,)); ``info``: what the crowds were (density,
    seed, persons per sample, ...), written first."""
    cov = np.asarray(coverage, np.int64).reshape(-1, len(gamma))
    gamma = np.asarray(gamma, np.int64)
    w = np.asarray(weights, np.float64)
    summary = dict(info or {})
    summary.update(_summary(gamma, w, cov))
    regions = {}
    for r, name in enumerate(region_names):
        m = np.asarray(region_ids) == r
        regions[str(name)] = {"targets": int(m.sum()), **_summary(gamma[m], w[m], cov[:, m])}
    summary["regions"] = regions
    p2 = np.mean(cov >= 2, axis=0) if len(cov) else np.zeros(len(gamma))
    pg = np.mean(cov >= gamma[None, :], axis=0) if len(cov) else np.zeros(len(gamma))
    return CrowdMetrics(summary, p2, pg, np.asarray(shown, np.float64).reshape(-1, 2), float(radius), float(height),
                        report_height)


__all__ = ["CrowdMetrics", "FIGURES", "crowd_metrics", "people_metrics", "sample_figures", "spread"]
