"""The site keys of the scene file (camplace.spec.sites): zones, mount_rules, existing.
Bad values are one-line errors naming the key path."""

from __future__ import annotations

import copy

import pytest

from camplace.core.errors import InputError
from camplace.spec.loading import check_referenced_files, parse_scene
from conftest import BASE
from test_config import err  # one line, starts with 's.yaml: '

SQUARE = [[0, 0], [1, 0], [1, 1], [0, 1]]


def scene(**keys) -> dict:
    d = copy.deepcopy(BASE)
    d.update(keys)
    return d


def test_every_site_key_parses_with_its_defaults():
    spec = parse_scene(scene(
        zones=[{"name": "checkout", "polygon": SQUARE, "coverage": 2, "weight": 2.0, "min_px_per_m": "identify"},
               {"name": "wc", "polygon": [[2, 2], [3, 2], [3, 3], [2, 3]], "privacy": True},
               {"name": "crate-faces", "of": ["crate"], "faces": ["+x"], "max_incidence_deg": 60}],
        mount_rules={"forbid": [SQUARE], "allow": None, "max_per_type": {"cam": 1}},
        existing=[{"id": 1, "camera": "cam", "position": [0.5, 0.5, 2.9], "yaw_deg": 0, "pitch_deg": 45}]))
    z = spec.zones
    assert z[0].heights is None and z[0].privacy is False and z[1].privacy and z[2].is_surface
    assert spec.mount_rules.forbid[0][1] == (1.0, 0.0) and spec.mount_rules.max_per_type == {"cam": 1}
    assert spec.existing[0].id == "1" and spec.existing[0].roll_deg == 0.0
    assert parse_scene(copy.deepcopy(BASE)).zones == [] and not parse_scene(copy.deepcopy(BASE)).mount_rules.active


@pytest.mark.parametrize("keys, path", [
    ({"zones": [{"name": "a", "polygon": SQUARE, "colour": 1}]}, "zones[0].colour"),
    ({"zones": [{"name": "a", "polygon": [[0, 0], [1, 1], [1, 0], [0, 1]]}]}, "zones[0].polygon"),
    ({"zones": [{"name": "a", "polygon": SQUARE, "of": ["crate"]}]}, "zones[0]"),
    ({"zones": [{"name": "a", "polygon": SQUARE, "privacy": True, "coverage": 2}]}, "zones[0].coverage"),
    ({"zones": [{"name": "a", "polygon": SQUARE, "privacy": "yes"}]}, "zones[0].privacy"),
    ({"zones": [{"name": "a", "polygon": SQUARE, "heights": [9.0]}]}, "zones[0].heights[0]"),
    ({"zones": [{"name": "walk", "polygon": SQUARE}]}, "zones[0].name"),
    ({"zones": [{"name": "a", "of": ["crat"]}]}, "zones[0].of[0]"),
    ({"zones": [{"name": "a", "polygon": SQUARE, "min_px_per_m": "sharp"}]}, "zones[0].min_px_per_m"),
    ({"mount_rules": {"forbid": [[[0, 0], [1, 0]]]}}, "mount_rules.forbid[0]"),
    ({"mount_rules": {"allow": [[[0, 0], [1, 1], [1, 0], [0, 1]]]}}, "mount_rules.allow[0]"),
    ({"mount_rules": {"max_per_type": {"camm": 1}}}, "mount_rules.max_per_type.camm"),
    ({"mount_rules": {"max_per_type": {"cam": -1}}}, "mount_rules.max_per_type.cam"),
    ({"mount_rules": {"pionts": "m.csv"}}, "mount_rules.pionts"),
    ({"existing": [{"id": "E1", "camera": "lens", "position": [1, 1, 2], "yaw_deg": 0, "pitch_deg": 30}]},
     "existing[0].camera"),
    ({"existing": [{"id": "E1", "camera": "cam", "position": [1, 1], "yaw_deg": 0, "pitch_deg": 30}]},
     "existing[0].position"),
])
def test_bad_site_values_name_their_key_path(keys, path):
    msg = err(scene(**keys))
    assert f"s.yaml: {path}" in msg, msg


def test_duplicate_existing_ids_and_unknown_suggestions():
    e = {"camera": "cam", "position": [1, 1, 2], "yaw_deg": 0, "pitch_deg": 30}
    assert "existing[1].id: duplicate id 'E1'" in err(scene(existing=[dict(e, id="E1"), dict(e, id="E1")]))
    assert "did you mean 'crate'" in err(scene(zones=[{"name": "a", "of": ["crat"]}]))


def test_zone_coverage_counts_for_the_nothing_to_place_check():
    d = scene(zones=[{"name": "a", "polygon": SQUARE, "coverage": 1}])
    d["targets"][0]["coverage"] = 0
    parse_scene(d)  # the zone needs a camera
    d["zones"][0]["coverage"] = 0
    assert "every region has coverage 0" in err(d)


def test_point_and_existing_files_are_checked_like_other_files(tmp_path):
    spec = parse_scene(scene(mount_rules={"points": "drops.csv"}, existing="installed.csv"))
    with pytest.raises(InputError, match=r"mount_rules\.points: file 'drops.csv' not found"):
        check_referenced_files(spec, tmp_path, "s.yaml")
    (tmp_path / "drops.csv").write_text("x,y,z\n1,1,2.9\n")
    with pytest.raises(InputError, match=r"existing: file 'installed.csv' not found"):
        check_referenced_files(spec, tmp_path, "s.yaml")
