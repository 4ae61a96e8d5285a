"""Plan formats as plugins (issue 35): a '.rooms' importer from another distribution joins
the suffix map and the format lists, its plain scene mapping gets the defaults of every
plan import and is checked like a scene file, options it does not take are refused in
one vocabulary, and a broken importer is one warning naming it."""

from __future__ import annotations

import pytest

from camplace.core.errors import InputError
from camplace.scene.formats import IMPORTERS, formats_text, plan_kind, plan_suffixes
from camplace.scene.importers import read_plan, read_storey_plans
from plugin_kit import installed, write_rooms

BUILT_IN = {".ifc": "ifc", ".ifczip": "ifc", ".dxf": "dxf", ".png": "image", ".jpg": "image", ".jpeg": "image",
            ".tif": "image", ".tiff": "image", ".webp": "image", ".bmp": "image", ".gif": "image", ".pdf": "image"}


@pytest.fixture()
def plugin(tmp_path):
    yield from installed(tmp_path / "site")


def test_the_built_in_formats_come_from_the_registry():
    assert list(IMPORTERS)[:3] == ["ifc", "dxf", "image"]
    assert {s: n for s, n in plan_suffixes().items() if n in ("ifc", "dxf", "image")} == BUILT_IN
    assert plan_kind("A.DXF") == "dxf" and plan_kind("scan.ply") is None
    assert formats_text().startswith("IFC (BIM) models (.ifc, .ifczip), DXF drawings (.dxf), plan images")


def test_a_plugin_format_joins_the_suffix_map_and_the_lists(plugin):
    assert plan_suffixes()[".rooms"] == "rooms" and plan_kind("x.ROOMS") == "rooms"
    assert formats_text().endswith(", rooms (.rooms)")
    assert IMPORTERS.distribution("rooms") == "rooms-plugin"


def test_a_broken_importer_is_one_warning_naming_it(plugin):
    hits = [t for t in plugin if t.startswith("camplace.importers")]
    assert len(hits) == 1 and "plugin 'no-suffix' (from rooms-plugin)" in hits[0] and "suffixes" in hits[0], hits
    assert "rooms" in IMPORTERS and "no-suffix" not in IMPORTERS


def test_a_plain_mapping_gets_the_defaults_of_every_plan_import(plugin, tmp_path):
    got = read_plan(write_rooms(tmp_path / "two.rooms"), heights=[1.0, 2.5], coverage=3, budget=5)
    s = got.scene
    assert got.kind == "rooms" and s["name"] == "two"
    assert [(z["name"], z["coverage"]) for z in s["zones"]] == [("Office", 3), ("Lab", 3)]  # the rooms: zones
    assert s["targets"] == [{"name": "walkable", "kind": "volume", "heights": [1.0, 2.5], "coverage": 3}]
    assert s["placement"] == {"budget": 5, "solver": "greedy"} and s["cameras"][0]["name"] == "wide"
    assert s["mounts"][0]["kind"] == "ceiling_grid" and s["voxel_size"] == 0.25
    assert read_plan(tmp_path / "two.rooms", name="site").scene["name"] == "site"
    assert s["room"]["height"] == 3.0 and s["obstacles"] == []


def test_a_bad_mapping_is_one_line_naming_the_file_and_key(plugin, tmp_path):
    path = write_rooms(tmp_path / "bad.rooms", outline=[[0, 0], [1, 0]])
    with pytest.raises(InputError) as err:
        read_plan(path)
    assert str(path) in str(err.value) and "room.footprint" in str(err.value) and "\n" not in str(err.value)


def test_an_importer_that_breaks_is_one_line_naming_it(plugin, tmp_path):
    path = tmp_path / "broken.rooms"
    path.write_text("{}")  # no 'outline': the plugin's read raises KeyError
    with pytest.raises(InputError, match=r"broken.rooms: the rooms importer \(from rooms-plugin\) failed: "
                                         r"KeyError: 'outline'$"):
        read_plan(path)


def test_an_option_the_format_does_not_take_is_refused_in_one_vocabulary(plugin, tmp_path):
    from camplace.cli.common import word_error

    path = write_rooms(tmp_path / "two.rooms")
    with pytest.raises(InputError) as err:
        read_plan(path, scale="1:100")
    assert str(err.value) == "scale: not an option of rooms plans (it takes wall_height, name, heights, coverage, " \
                             "budget)" and err.value.option == "scale"
    assert word_error(err.value) == "--scale: not an option of rooms plans (it takes --wall-height, --heights, " \
                                    "--coverage, --budget)"
    assert read_plan(path, wall_height=2.0).kind == "rooms"  # one it takes goes to read


def test_storey_all_needs_an_importer_that_reads_storeys(plugin, tmp_path):
    with pytest.raises(InputError, match=r"^storey: 'all' belongs to formats with several storeys \(IFC \(BIM\) models; DXF "
                                         r"drawings; plan images and PDF pages\); "
                                         r"two.rooms is a rooms plan with one storey$"):
        read_storey_plans(write_rooms(tmp_path / "two.rooms"))


def test_the_docs_formats_table_is_the_registry():
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "plans.md").read_text()
    rows = re.findall(r"^\| `(\w+)` \| ([^|]+) \| ([^|]+) \|", text, flags=re.M)
    table = {name: (label.strip(), re.findall(r"`(\.\w+)`", sx)) for name, label, sx in rows}
    assert table == {name: (IMPORTERS[name].label, list(IMPORTERS[name].suffixes)) for name in ("ifc", "dxf", "image")}
