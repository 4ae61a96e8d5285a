"""Image-quality conditions per target region: pixel density (px/m) and DORI levels.

EN/IEC 62676-4 names four pixel-density levels on the target ("DORI"): detect 25,
observe 62.5, recognise 125, identify 250 px/m. A region's ``min_px_per_m`` takes a
number or one of these names. The density itself is computed in the kernels by
``camplace.cameras.models.px_per_m_nb`` from the lens model (the projection's Jacobian).
This module imports nothing from camplace but the errors, so the scene schema can use it.
"""

from __future__ import annotations

import numpy as np

DORI_PX_PER_M: dict[str, float] = {
    "detect": 25.0,
    "observe": 62.5,
    "recognise": 125.0,
    "recognize": 125.0,
    "identify": 250.0,
}


def px_per_m_value(value: float | str | None) -> float:
    """A ``min_px_per_m`` setting (number, DORI level name or None) -> px/m (0 = no limit).

    Raises ValueError naming the accepted level names for an unknown name."""
    if value is None:
        return 0.0
    if isinstance(value, str):
        key = value.strip().lower()
        if key not in DORI_PX_PER_M:
            raise ValueError(f"expected a number of px/m or a DORI level ({', '.join(DORI_PX_PER_M)}), got {value!r}")
        return DORI_PX_PER_M[key]
    v = float(value)
    if not np.isfinite(v) or v < 0:
        raise ValueError(f"expected a non-negative number of px/m, got {value!r}")
    return v


def target_min_px(targets) -> np.ndarray:
    """(N_p,) float64 minimum pixel density of each target (0 = no limit), from the
    per-region ``targets.min_px_per_m`` (absent on older Targets objects = no limit)."""
    per_region = getattr(targets, "min_px_per_m", None)
    if per_region is None or len(per_region) == 0:
        return np.zeros(len(targets.positions), dtype=np.float64)
    return np.asarray(per_region, dtype=np.float64)[targets.region_ids]


def range_density(spec) -> float:
    """The least pixel density (px/m) any required target of a scene (``spec``: a
    SceneSpec) needs: over the target regions and non-privacy zones with coverage >= 1,
    their ``min_px_per_m``, or the DORI ``detect`` level (25) for one that sets none.
    A lens given as sold, without ``max_range``, sees up to where its density falls to this."""
    need = [px_per_m_value(r.min_px_per_m) or DORI_PX_PER_M["detect"]
            for r in [*spec.targets, *(z for z in spec.zones if not z.privacy)] if r.coverage > 0]
    return min(need, default=DORI_PX_PER_M["detect"])
