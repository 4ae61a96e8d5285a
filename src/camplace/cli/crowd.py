"""The crowd options of ``camplace run`` and ``camplace evaluate`` (issue 28): they override
the scene's ``crowd:`` keys (a scene without one gets the defaults; docs/scene-file.md#crowd)."""

from __future__ import annotations

from typing import Optional

import typer

DENSITY_OPT = typer.Option(None, "--crowd-density", help="People per m² of walkable floor (the scene's crowd "
                           "density; a scene without crowd: gets one). Adds crowd metrics.")
SAMPLES_OPT = typer.Option(None, "--crowd-samples", help="Crowd samples a --crowd-aware run optimises over "
                           "(default 64).")
SCORE_SAMPLES_OPT = typer.Option(None, "--crowd-score-samples", help="Held-out crowd samples the crowd metrics "
                                 "average over (default 32).")
SEED_OPT = typer.Option(None, "--crowd-seed", help="Seed of the crowd samples (default 0).")
AWARE_OPT = typer.Option(False, "--crowd-aware", help="Optimise for the crowd: the average cost over the crowd "
                         "samples (a person may block a sight line); scored on held-out crowds.")

FLAGS = {"crowd_density": "--crowd-density", "crowd_samples": "--crowd-samples",
         "crowd_score_samples": "--crowd-score-samples", "crowd_seed": "--crowd-seed",
         "crowd_optimise": "--crowd-aware", "crowd": "--crowd-density"}


def crowd_overrides(density: Optional[float] = None, samples: Optional[int] = None,
                    score_samples: Optional[int] = None, seed: Optional[int] = None,
                    aware: bool = False) -> dict:
    """run() / evaluate() ``crowd=`` overrides of the options given ({} when none)."""
    out = {"density": density, "samples": samples, "score_samples": score_samples, "seed": seed,
           "optimise": True if aware else None}
    return {k: v for k, v in out.items() if v is not None}
