"""The scene key ``crowd:`` (issue 28): people as vertical cylinders that may block sight lines.

A crowd sample puts ``density`` persons per m² of walkable floor (a zone may set its own
in ``zones``) at random, without overlap, in the walkable free space; ``samples``
independent crowds from ``seed`` are what a crowd-aware run (``optimise``) averages over,
``score_samples`` further ones (another random stream: never the same crowds) are what
the crowd metrics average over. The people themselves are targets (issue 36): points on
each sampled person at ``people_heights`` (default torso and head), each to be seen by
``people_gamma`` cameras (default 2: triangulatable); a crowd-aware run minimises the
sample-average people cost mixed with the empty-store cost by ``people_weight``; with
``people_cost: count`` (default) a swap descent then also counts the people seen by
``people_gamma`` cameras, weighted by ``people_count_weight`` (camplace.improve.people),
with ``max_cost_rise`` (the cost cap; none by default) never lifting the empty-store cost by
more than that share over the greedy grid solve's.
See docs/scene-file.md#crowd.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, StrictBool, ValidationError

from camplace.core.errors import InputError
from camplace.spec.basics import Finite, PositiveFloat, _no_bool, _Strict, scene_error
from camplace.spec.wording import did_you_mean, format_error_entry, name_list

Density = Annotated[float, BeforeValidator(_no_bool), Field(ge=0, allow_inf_nan=False)]
Count = Annotated[int, Field(ge=1, le=4096, strict=True)]
Share = Annotated[float, BeforeValidator(_no_bool), Field(ge=0, le=1, allow_inf_nan=False)]
MAX_COVER = 0.45  # at most this share of the floor under people (random packing jams near 0.55)


class CrowdSpec(_Strict):
    """Persons: cylinders of ``radius`` and ``height`` (m) standing on the floor (z = 0)."""

    density: Density = 0.3  # persons per m² of walkable floor
    radius: PositiveFloat = 0.25
    height: PositiveFloat = 1.75
    zones: dict[str, Density] = {}  # zone name -> its own density
    samples: Count = 256  # crowds the crowd-aware optimisation averages over (the people count overfits 64, issue 36)
    score_samples: Count = 32  # held-out crowds the metrics average over
    seed: Annotated[int, Field(ge=0, strict=True)] = 0
    optimise: StrictBool = False  # optimise the sample-average crowd cost (a crowd-aware run)
    report_height: Finite | None = None  # m: where the report draws P(seen by >= 2); default nearest 1.5 m
    people_heights: list[PositiveFloat] = [1.25, 1.6]  # m: the points on each person to be seen (torso, head)
    people_gamma: Annotated[int, Field(ge=1, le=64, strict=True)] = 2  # cameras each person point needs
    people_weight: Share = 0.5  # crowd-aware objective: this share people cost, the rest empty-store cost
    people_cost: Literal["count", "squared"] = "count"  # count: then a swap descent counting people seen by ≥ Γ
    people_count_weight: Annotated[float, BeforeValidator(_no_bool), Field(ge=0, allow_inf_nan=False)] = 0.25
    # people_cost count's cost cap: no move lifts the empty-store cost above (1 + this) × the greedy grid
    # solve's (camplace.workflows.crowd); null (the default: the cap at 0 cost store-a people, issue 36): no cap
    max_cost_rise: Annotated[float, BeforeValidator(_no_bool), Field(ge=0, allow_inf_nan=False)] | None = None
    steep_pitches: list[Annotated[float, BeforeValidator(_no_bool), Field(ge=0, le=90, allow_inf_nan=False)]] = \
        [75.0, 90.0]  # degrees down: offered at every mount of a crowd-aware run with people in it

    def offers_steep(self) -> tuple[float, ...]:
        """The extra candidate pitches of a run with this crowd: ``steep_pitches`` when it
        optimises for a crowd with anybody in it (some density > 0) who counts
        (``people_weight`` > 0), else none."""
        if self.optimise and self.people_weight > 0 and any(rho > 0 for _, rho in self.densities()):
            return tuple(float(v) for v in self.steep_pitches)
        return ()

    def max_density(self) -> float:
        """Persons per m² above which random non-overlapping placement cannot reach the density."""
        return MAX_COVER / (math.pi * self.radius ** 2)

    def densities(self) -> list[tuple[str, float]]:
        """(key path, density) of the default and of every zone."""
        return [("density", self.density)] + [(f"zones.{k}", v) for k, v in self.zones.items()]


def crowd_references(spec) -> None:
    """``spec.crowd`` (a SceneSpec's) fits the room and names volume zones that exist;
    scene_error naming the key path otherwise."""
    c = spec.crowd
    if c is None:
        return
    fp = spec.room.footprint
    w = max(p[0] for p in fp) - min(p[0] for p in fp)
    d = max(p[1] for p in fp) - min(p[1] for p in fp)
    if 2 * c.radius > min(w, d):
        raise scene_error("crowd.radius", f"{c.radius} m: a person ({2 * c.radius:g} m across) does not fit in the "
                                          f"room ({w:g} m x {d:g} m); expected a radius below {min(w, d) / 2:g} m")
    if c.height > spec.room.height:
        raise scene_error("crowd.height", f"{c.height} m is taller than the room ({spec.room.height} m)")
    check_people_heights(c, scene_error)
    for key, rho in c.densities():
        if rho > c.max_density():
            raise scene_error(f"crowd.{key}", f"{rho} persons/m² cannot be placed without overlap at radius "
                                              f"{c.radius} m; expected at most {c.max_density():.3g}")
    zones = {z.name: z for z in spec.zones}
    volume = [n for n, z in zones.items() if not z.is_surface and not z.privacy]
    for name in c.zones:
        if name not in zones:
            raise scene_error(f"crowd.zones.{name}", f"unknown zone '{name}'{did_you_mean(name, list(zones))}; "
                                                     f"expected one of {name_list(volume)}")
        if zones[name].is_surface or zones[name].privacy:
            raise scene_error(f"crowd.zones.{name}", "a crowd density needs a volume zone (with 'polygon'), not a "
                                                     "privacy or surface zone (nobody stands in a privacy zone)")


def check_people_heights(c: CrowdSpec, error) -> None:
    """``c.people_heights`` are 1 to 8 distinct points within the person (0 < z <= height);
    ``error(key, message)`` (an exception to raise) otherwise."""
    z = list(c.people_heights)
    if not 1 <= len(z) <= 8 or len(set(z)) != len(z):
        raise error("crowd.people_heights", f"{z}: expected 1 to 8 distinct heights (m)")
    for h in z:
        if h > c.height:
            raise error("crowd.people_heights", f"{h} m is above the people's height ({c.height} m); expected "
                                                f"points on the person, at most {c.height} m")


CROWD_OPTIONS = ("density", "samples", "score_samples", "seed", "optimise", "people_weight", "people_gamma",
                 "people_cost", "people_count_weight", "max_cost_rise")  # run() / evaluate() overrides


def crowd_with(spec_crowd: CrowdSpec | None, overrides: dict[str, Any] | None) -> CrowdSpec | None:
    """The scene's crowd with ``overrides`` ({key: value} of CROWD_OPTIONS; None values
    ignored) applied; a scene without ``crowd:`` gets the defaults when any override is
    given. An override the schema refuses is an InputError(option='crowd_<key>')."""
    given = {k: v for k, v in (overrides or {}).items() if v is not None}
    for k in given:
        if k not in CROWD_OPTIONS:
            raise InputError(f"crowd: unknown option '{k}'{did_you_mean(k, list(CROWD_OPTIONS))}; expected one of "
                             f"{name_list(list(CROWD_OPTIONS))}", option="crowd")
    if not given:
        return spec_crowd
    base = spec_crowd.model_dump() if spec_crowd is not None else {}
    try:
        out = CrowdSpec(**{**base, **given})
    except ValidationError as err:
        e = err.errors()[0]
        key = str(e["loc"][0]) if e["loc"] else next(iter(given))
        _, msg = format_error_entry(e, CrowdSpec)
        raise InputError(f"crowd_{key}: {msg}", option=f"crowd_{key}") from None
    check_people_heights(out, lambda key, msg: InputError(f"{key}: {msg}", option="crowd"))
    if out.density > out.max_density():
        raise InputError(f"crowd_density: {out.density} persons/m² cannot be placed without overlap at radius "
                         f"{out.radius} m; expected at most {out.max_density():.3g}", option="crowd_density")
    return out
