"""The solver output type shared by every solver."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Placement:
    """selected: (k,) int64 sorted candidate ids (rows of V); objective: cost of the
    selection; bound: proven lower bound on the optimal cost (None if none); status:
    'optimal' | 'feasible' | 'time_limit' | 'interrupted' | 'heuristic'."""

    selected: np.ndarray
    objective: float
    bound: float | None
    status: str
    solver: str
    seconds: float
    info: dict = field(default_factory=dict)

    @property
    def gap(self) -> float | None:
        """Proven relative gap (objective − bound) / objective, 0 when both are 0."""
        if self.bound is None:
            return None
        if self.objective <= 0:
            return 0.0
        return max(0.0, (self.objective - self.bound) / self.objective)
