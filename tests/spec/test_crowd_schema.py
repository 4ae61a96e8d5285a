"""The scene key ``crowd:`` (camplace.spec.crowd): defaults, overrides, and bad values as
one-line errors naming the key path (issue 28)."""

from __future__ import annotations

import copy

import pytest

from camplace.core.errors import InputError
from camplace.spec.crowd import crowd_with
from camplace.spec.loading import parse_scene
from conftest import BASE
from test_config import err  # one line, starts with 's.yaml: '

ZONES = [{"name": "queue", "polygon": [[0, 0], [1, 0], [1, 1], [0, 1]]},
         {"name": "wc", "polygon": [[2, 2], [3, 2], [3, 3], [2, 3]], "privacy": True}]


def scene(crowd, zones=()) -> dict:
    return dict(copy.deepcopy(BASE), crowd=crowd, zones=list(zones))


def test_defaults_and_overrides():
    c = parse_scene(scene({})).crowd
    assert (c.density, c.radius, c.height, c.samples, c.score_samples, c.seed, c.optimise) == \
        (0.3, 0.25, 1.75, 256, 32, 0, False)
    assert (c.people_heights, c.people_gamma, c.people_weight, c.steep_pitches) == ([1.25, 1.6], 2, 0.5, [75.0, 90.0])
    assert (c.people_cost, c.people_count_weight, c.max_cost_rise) == ("count", 0.25, None)
    assert parse_scene(scene({"max_cost_rise": 0})).crowd.max_cost_rise == 0.0
    assert parse_scene(copy.deepcopy(BASE)).crowd is None
    assert crowd_with(None, {}) is None and crowd_with(None, {"density": None}) is None
    o = crowd_with(c, {"density": 1.0, "optimise": True})
    assert o.density == 1.0 and o.optimise and o.samples == 256
    assert crowd_with(None, {"seed": 3}).density == 0.3  # a scene without crowd: the defaults


@pytest.mark.parametrize("crowd, zones, path", [
    ({"density": -0.1}, (), "crowd.density"),
    ({"radius": 2.0}, (), "crowd.radius"),  # 4 m across: larger than the 3 m room
    ({"height": 3.5}, (), "crowd.height"),
    ({"density": 3.0}, (), "crowd.density"),  # cannot be placed without overlap
    ({"samples": 0}, (), "crowd.samples"),
    ({"sample": 4}, (), "crowd.sample"),
    ({"zones": {"queue": -1}}, ZONES, "crowd.zones.queue"),
    ({"zones": {"queu": 1.0}}, ZONES, "crowd.zones.queu"),
    ({"zones": {"wc": 1.0}}, ZONES, "crowd.zones.wc"),
    ({"optimise": "yes"}, (), "crowd.optimise"),
])
def test_bad_crowd_keys_name_their_key_path(crowd, zones, path):
    msg = err(scene(crowd, zones))
    assert f"s.yaml: {path}:" in msg, msg


def test_bad_overrides_name_their_option():
    with pytest.raises(InputError) as e:
        crowd_with(None, {"density": -1})
    assert e.value.option == "crowd_density" and str(e.value).startswith("crowd_density:")
    with pytest.raises(InputError) as e:
        crowd_with(None, {"samples": 0})
    assert e.value.option == "crowd_samples"


def test_people_keys_are_checked():
    """issue 36: points on the person, a share for the mix, pitches within [0, 90]."""
    for crowd, key in (({"people_heights": [1.2, 1.9]}, "crowd.people_heights"),
                       ({"people_heights": []}, "crowd.people_heights"),
                       ({"people_heights": [1.2, 1.2]}, "crowd.people_heights"),
                       ({"people_weight": 1.5}, "crowd.people_weight"),
                       ({"people_gamma": 0}, "crowd.people_gamma"),
                       ({"people_cost": "linear"}, "crowd.people_cost"),
                       ({"people_count_weight": -1}, "crowd.people_count_weight"),
                       ({"max_cost_rise": -0.1}, "crowd.max_cost_rise"),
                       ({"max_cost_rise": True}, "crowd.max_cost_rise"),
                       ({"steep_pitches": [95]}, "crowd.steep_pitches")):
        with pytest.raises(InputError, match=key.replace(".", r"\.")):
            parse_scene(scene(crowd))
    with pytest.raises(InputError, match="people_weight"):
        crowd_with(parse_scene(scene({})).crowd, {"people_weight": -0.1})
    c = parse_scene(scene({"density": 0.5, "optimise": True})).crowd
    assert c.offers_steep() == (75.0, 90.0)
    assert crowd_with(c, {"people_weight": 0.0}).offers_steep() == () and crowd_with(c, {"density": 0.0}).offers_steep() == ()
