"""The DXF importer on plans drawn as offices draw them (issue 25; tests/scene/dxf_drawings.py):
wall layers found by their names in several conventions and languages, or by their
geometry; walls inside nested blocks; rooms named by room-stamp attributes and texts; the
title block, dimensions, axes and hatches never walls or footprint; a file with nothing
wall-like ends in one line listing its layers."""

from __future__ import annotations

import pytest
from shapely.geometry import Point, Polygon

pytest.importorskip("ezdxf")

from camplace.core.errors import InputError  # noqa: E402
from camplace.scene.importers import read_plan  # noqa: E402
from camplace.scene.importers.dxf_layers import layer_role  # noqa: E402
from camplace.scene.importers.dxf_rooms import label_kind  # noqa: E402
from tests.scene import dxf_drawings as dd  # noqa: E402


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("dxf")
    return {"fm": dd.draw_fm_plan(tmp / "eg.dxf"), "fr": dd.draw_latin_plan(tmp / "fr.dxf", "fr"),
            "es": dd.draw_latin_plan(tmp / "es.dxf", "es"), "r12": dd.draw_latin_plan(tmp / "r12.dxf", "es", "R12"),
            "unnamed": dd.draw_unnamed_plan(tmp / "hall.dxf"), "none": dd.draw_no_walls(tmp / "none.dxf"),
            "single": dd.draw_single_line_plan(tmp / "single.dxf"), "wc": dd.draw_wc_plan(tmp / "wc.dxf"),
            "renovation": dd.draw_single_line_plan(tmp / "renovation.dxf", named_partition=True),
            "door layer": dd.draw_walls_on_door_layer(tmp / "door-layer.dxf")}


@pytest.fixture(scope="module")
def fm(files):
    return read_plan(files["fm"])


def _prisms(got, prefix):
    return [o for o in got.scene["obstacles"] if o["name"].startswith(prefix + "-")]


def _area(got) -> float:
    return Polygon(got.scene["room"]["footprint"]).area


@pytest.mark.parametrize("name, role", [
    ("E41_AUSSENWAENDE", "wall"), ("E62_INNENWAENDE_LEICHT", "wall"), ("Wände", "wall"), ("MURS_PORTEURS", "wall"),
    ("Cloisons", "wall"), ("A-WALL-PATT", "wall"), ("A-221--G", "wall"), ("PARETI", "wall"), ("Walls - Exterior", "wall"),
    ("A-WALL-IDEN", "annotation"), ("Z21_RAUMSTEMPEL", "annotation"), ("COTAS", "annotation"),
    ("Z23_NGF-POLYGONE", "room"), ("LOCAUX", "room"), ("A-AREA", "room"), ("PORTES", "door"), ("Türen", "door"),
    ("Crystal", "window"), ("VENTANAS", "window"), ("S-COLS", "column"), ("Stützen", "column"),
    ("M10_MOEBEL", "furniture"), ("Flooring", "other"), ("L4", None), ("0", None)])
def test_layer_roles_by_name(name, role):
    assert layer_role(name) == role


@pytest.mark.parametrize("text, tag, kind", [("Büro", "RAUMNAME", 3), ("Sitzungszimmer", "", 2), ("WC", "", 2),
                                             ("E.012", "RAUMNUMMER", 1), ("A101", "", 1), ("24.35 m²", "", 0),
                                             ("24.35 m²", "NGF", 0), ("+0.00", "", 0), ("", "", -1)])
def test_label_kinds(text, tag, kind):
    assert label_kind(text, tag) == kind


def test_fm_plan_walls_by_name_rooms_by_stamps(fm):
    walls = fm.used["wall layers"]
    assert all(la in walls for la in ("E41_AUSSENWAENDE", "E61_INNENWAENDE_TRAGEND", "E62_INNENWAENDE_LEICHT"))
    assert "by name" in walls and fm.used["units"].startswith("cm")
    assert _area(fm) == pytest.approx(dd.FM_OUTLINE_M2, rel=0.03)
    names = [z["name"] for z in fm.scene["zones"]]
    assert sorted(names) == sorted(n if n != "Büro" else f"{n} {k}" for n, k, *_ in dd.FM_ROOMS)
    pieces = [Polygon(o["prism"]["polygon"], o["prism"].get("holes", [])) for o in _prisms(fm, "wall")]
    assert any(p.contains(Point(17.0, 15.0)) for p in pieces)  # a toilet wall from the nested blocks


def test_fm_plan_title_block_dimensions_axes_left_out(fm):
    pieces = [Polygon(o["prism"]["polygon"]) for o in fm.scene["obstacles"]]
    w, h = (v / 100 for v in dd.FM_OUTER)
    assert all(-0.01 <= b[0] and b[2] <= w + 0.01 and -0.01 <= b[1] and b[3] <= h + 0.01
               for b in (p.bounds for p in pieces))
    assert fm.skipped["wall, glass and column pieces apart from the main building"] >= 1  # the key plan
    assert len(_prisms(fm, "window")) == 7 and len(_prisms(fm, "pult_160")) == 4
    assert len(fm.openings) >= 10 + 7


@pytest.mark.parametrize("lang", ["fr", "es", "r12"])
def test_latin_layers(files, lang):
    got = read_plan(files[lang])
    wall = {"fr": "MURS", "es": "MUROS", "r12": "MUROS"}[lang]
    assert got.used["wall layers"].startswith(wall) and _area(got) == pytest.approx(dd.LATIN_OUTLINE_M2, rel=0.03)
    assert {z["name"] for z in got.scene["zones"]} == set(dd.LATIN_ROOMS["fr" if lang == "fr" else "es"])
    if lang == "r12":  # R12 cannot say its units: guessed, and said so
        assert "guessed" in got.used["units"] and any("units" in n for n in got.notes)


def test_walls_found_by_geometry(files):
    got = read_plan(files["unnamed"])
    assert got.used["wall layers"].startswith("L4 ") and "by geometry" in got.used["wall layers"]
    assert {o["source"]["layer"] for o in _prisms(got, "wall")} == {"L4"}  # not the shelves, stair or hatch
    assert _area(got) == pytest.approx(dd.UNNAMED_OUTLINE_M2, rel=0.03)
    assert any("parallel line pairs" in n for n in got.notes)


def test_single_line_walls_found_rooms_named(files):
    """Walls drawn as one line each (no pairs, layer 0) are found by the rooms they
    enclose; the 0.9 m hall, narrower than the doorways bridged for finding rooms, is a
    room too; door swings (arcs) and the leaves drawn as lines from their centres are no
    walls (the front door's, open outward, leaves the footprint at the outer wall)."""
    got = read_plan(files["single"])
    assert "single lines enclosing rooms" in got.used["wall layers"]
    w, h = (v / 100 for v in dd.SINGLE_OUTER)
    assert _area(got) == pytest.approx((w + 0.2) * (h + 0.2), rel=0.02)  # the outer face of 0.2 m walls
    assert Polygon(got.scene["room"]["footprint"]).bounds[1] == pytest.approx(-0.1, abs=0.05)
    assert got.skipped["door leaves drawn as a line from a swing's centre (no wall)"] == 4
    zones = {z["name"]: Polygon(z["polygon"]).area for z in got.scene["zones"]}
    assert set(zones) == set(dd.SINGLE_ROOMS)
    for name, (x0, y0, x1, y1) in dd.SINGLE_ROOMS.items():
        assert zones[name] == pytest.approx((x1 - x0 - 20) * (y1 - y0 - 20) / 1e4, rel=0.1), name


def test_named_walls_that_close_no_room_take_the_single_line_walls_around(files):
    """Only the new partition is on a layer named like walls (a renovation plan); the
    building's walls, single lines on layer 0 around it, are taken too: the footprint is
    the flat, not the partition's sliver."""
    got = read_plan(files["renovation"])
    assert "Wand neu" in got.used["wall layers"] and "around the named walls" in got.used["wall layers"]
    w, h = (v / 100 for v in dd.SINGLE_OUTER)
    assert _area(got) == pytest.approx((w + 0.2) * (h + 0.2), rel=0.02)
    assert any("close no room" in n for n in got.notes)


def test_walls_drawn_on_the_door_layer_are_found_by_their_geometry(files):
    """A web planner's export puts the walls on the door layer: lines longer than any
    door are measured like unnamed linework (the 1 m stub on A-WALL is all that is named),
    so the room is the footprint, not the stub; the door still cuts its gap."""
    got = read_plan(files["door layer"])
    assert "A-DOOR-INTERNAL" in got.used["wall layers"] and "by geometry" in got.used["wall layers"]
    assert _area(got) == pytest.approx(dd.DOOR_LAYER_ROOM[0] * dd.DOOR_LAYER_ROOM[1], rel=0.05)
    assert len(got.scene["zones"]) == 1 and got.openings


def test_closed_outline_on_a_furniture_layer_is_furniture(files):
    """A table drawn as a closed polyline on a furniture layer (no block) is a furniture
    prism of its outline; a speck on that layer is not."""
    got = read_plan(files["door layer"])
    tables = [o for o in got.scene["obstacles"] if o["source"].get("layer") == "Furniture 4"]
    assert len(tables) == 1 and "block" not in tables[0]["source"]
    assert Polygon(tables[0]["prism"]["polygon"]).area == pytest.approx(Polygon(dd.DOOR_LAYER_TABLE).area, rel=0.01)
    assert "1 outline on furniture layers" in got.used["furniture"]


def test_door_swinging_into_a_small_room_leaves_the_room(files):
    """The gap fill of a door that swings into a 1.2 m wide WC closes the doorway, not the
    WC behind it (the jambs there join the walls across the WC)."""
    got = read_plan(files["wc"])
    zones = {z["name"]: Polygon(z["polygon"]).area for z in got.scene["zones"]}
    assert set(zones) == set(dd.WC_ROOMS)
    for name, area in dd.WC_ROOMS.items():
        assert zones[name] == pytest.approx(area, rel=0.05), name


def test_wall_layers_given_replace_the_conventions(files):
    got = read_plan(files["fm"], wall_layers=("E41*",))
    assert "E61" not in got.used["wall layers"] and "given" in got.used["wall layers"]


def test_nothing_wall_like_lists_the_layers(files, tmp_path, monkeypatch, capsys):
    from tests.conftest import run_cli

    with pytest.raises(InputError) as err:
        read_plan(files["none"])
    assert err.value.option == "wall_layers"
    assert "SYMBOLS (5 CIRCLE)" in str(err.value) and "SKETCH (2 LINE)" in str(err.value)
    code, text = run_cli(["scene", "import", files["none"], "--out", tmp_path / "s.yaml"], monkeypatch, capsys)
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and "--wall-layers" in lines[0] and "SKETCH (2 LINE)" in lines[0], text
    assert not (tmp_path / "s.yaml").exists()


def test_wall_like_layer_besides_the_named_ones_gets_a_note(files, tmp_path):
    import ezdxf

    doc = ezdxf.readfile(files["fm"])
    for e in doc.modelspace():
        if e.dxf.layer == "E62_INNENWAENDE_LEICHT":
            e.dxf.layer = "X62_LEICHTBAU"
    doc.saveas(tmp_path / "renamed.dxf")
    got = read_plan(tmp_path / "renamed.dxf")
    assert "X62" not in got.used["wall layers"]  # not taken on a guess ...
    assert any(n.startswith("X62_LEICHTBAU also holds parallel line pairs") for n in got.notes)  # ... but said


def test_declared_units_that_make_no_sense_get_a_note(files, tmp_path):
    """Inches declared for a drawing in cm: without area texts to prove the unit, a note
    on the doors' size; with the room stamps' areas (issue 34), read in cm with a note."""
    import ezdxf

    doc = ezdxf.readfile(files["fm"])
    doc.header["$INSUNITS"] = 1  # inches, for a drawing in cm
    doc.saveas(tmp_path / "inches.dxf")
    got = read_plan(tmp_path / "inches.dxf")
    assert got.used["units"].startswith("cm (from its area texts") and _area(got) == pytest.approx(
        dd.FM_OUTLINE_M2, rel=0.03)
    assert any(n.startswith("read in cm, not in the file's unit (in ($INSUNITS 1))") for n in got.notes), got.notes
    for e in list(doc.modelspace().query("INSERT[layer=='Z21_RAUMSTEMPEL']")):
        doc.modelspace().delete_entity(e)
    doc.saveas(tmp_path / "inches-no-stamps.dxf")
    got = read_plan(tmp_path / "inches-no-stamps.dxf")
    assert any("the doors measure 2.29 m" in n and "cm: 0.90 m" in n for n in got.notes), got.notes


def test_damaged_file_read_in_recover_mode_with_a_note(files, tmp_path):
    text = files["fm"].read_text(encoding="utf-8").rstrip().splitlines()
    assert text[-1].strip() == "EOF"
    (tmp_path / "cut.dxf").write_text("\n".join(text[:-2]) + "\n", encoding="utf-8")  # the EOF tag lost
    got = read_plan(tmp_path / "cut.dxf")
    assert any("structure errors" in n and "recover" in n for n in got.notes)
    assert _area(got) == pytest.approx(dd.FM_OUTLINE_M2, rel=0.03)
