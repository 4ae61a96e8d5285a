"""Lenses as they are sold (issue 27): sensor pixel pitch + focal length -> intrinsics,
the usable range from the pixel density the targets need, and the focal settings a
varifocal lens offers the optimiser.

- Focal length in pixels: f_px = f_mm / pixel pitch (mm), the textbook pinhole (and the
  equidistant fisheye's r = f θ): a 4 mm lens on 2.0 µm pixels has f_px = 2000.
- Pixel density on the optical axis at distance d: f_px / d px/m (pinhole, and every
  model near its centre). So the distance at which a lens still gives ``px_per_m`` is
  d = f_px / px_per_m: the DORI distances (EN 62676-4: detect 25, observe 62.5,
  recognise 125, identify 250 px/m) and, when a camera type gives no ``max_range``, its
  usable range (at the least density the scene's targets need).
- A varifocal lens [f_min, f_max] contributes ``steps`` settings, spaced geometrically
  (equal ratios: each step narrows the view and lengthens the range by the same
  factor), both ends included.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def focal_px(focal_mm: float, pixel_um: float) -> float:
    """Focal length in pixels from the focal length (mm) and the pixel pitch (µm)."""
    return float(focal_mm) * 1000.0 / float(pixel_um)


def distance_for_density(f_px: float, px_per_m: float) -> float:
    """Distance (m) along the optical axis at which a lens of focal f_px (pixels) gives
    ``px_per_m`` on a target perpendicular to the view (pinhole: density = f_px / d)."""
    return float(f_px) / float(px_per_m)


def focal_steps_mm(focal_min_mm: float, focal_max_mm: float, steps: int) -> np.ndarray:
    """(steps,) focal lengths (mm) from min to max, geometric spacing, both ends included
    (one step: the widest, f_min)."""
    if steps <= 1 or focal_max_mm <= focal_min_mm:
        return np.array([float(focal_min_mm)])
    return np.geomspace(float(focal_min_mm), float(focal_max_mm), int(steps))


@dataclass(frozen=True)
class Lens:
    """A lens + sensor as sold. pixel_um: pixel pitch (µm); focal_min_mm / focal_max_mm:
    the focal range (equal for a fixed lens); steps: focal settings a varifocal lens gives
    the candidate grid; range_px_per_m: the density at which its range ends (None: the
    camera type's ``max_range`` holds at every focal length)."""

    pixel_um: float
    focal_min_mm: float
    focal_max_mm: float
    steps: int = 1
    range_px_per_m: float | None = None

    @property
    def varifocal(self) -> bool:
        return self.focal_max_mm > self.focal_min_mm

    def f_px(self, focal_mm: float) -> float:
        return focal_px(focal_mm, self.pixel_um)

    def range_at(self, focal_mm: float, fallback: float) -> float:
        """Usable range (m) at ``focal_mm``: where the axis density falls to range_px_per_m,
        else ``fallback`` (the type's max_range)."""
        if self.range_px_per_m is None:
            return float(fallback)
        return distance_for_density(self.f_px(focal_mm), self.range_px_per_m)

    def clamp(self, focal_mm: float) -> float:
        """``focal_mm`` within the lens's range."""
        return float(min(max(float(focal_mm), self.focal_min_mm), self.focal_max_mm))

    def settings_mm(self) -> np.ndarray:
        """The focal lengths (mm) of the candidate grid (camplace.cameras.lenses.focal_steps_mm)."""
        return focal_steps_mm(self.focal_min_mm, self.focal_max_mm, self.steps if self.varifocal else 1)
