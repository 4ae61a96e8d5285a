"""--doors / --glass (issue 18): the IFC and DXF importers' door and glass options from the
command line, and their refusals in one line."""

from __future__ import annotations

import pytest
import yaml

pytest.importorskip("ifcopenshell")

from camplace.scene.importers.ifc_build import GridBuilding, write_grid_building  # noqa: E402
from tests.conftest import run_cli  # noqa: E402
from tests.scene.plan_drawings import draw_grid_dxf  # noqa: E402

B = GridBuilding(names=("Office", "Lab"))


@pytest.fixture(scope="module")
def plans(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("flags")
    return write_grid_building(tmp / "b.ifc", B), draw_grid_dxf(tmp / "p.dxf", B)


def _classes(path):
    return {o["source"].get("class") or o["name"].split("-")[0] for o in yaml.safe_load(path.read_text())["obstacles"]}


@pytest.mark.parametrize("flags, classes", [([], {"IfcWall", "IfcWindow"}),
                                            (["--doors", "closed", "--glass", "transparent"], {"IfcWall", "IfcDoor"})])
def test_ifc_doors_and_glass(plans, tmp_path, monkeypatch, capsys, flags, classes):
    out = tmp_path / "site.yaml"
    code, text = run_cli(["scene", "import", plans[0], *flags, "--out", out], monkeypatch, capsys)
    assert code == 0, text
    assert _classes(out) == classes


def _wall_area(path) -> float:
    from shapely.geometry import Polygon

    return sum(Polygon(o["prism"]["polygon"], o["prism"].get("holes", [])).area
               for o in yaml.safe_load(path.read_text())["obstacles"] if "prism" in o)


def test_dxf_closed_doors_keep_the_wall_whole(plans, tmp_path, monkeypatch, capsys):
    areas = {}
    for doors in ("open", "closed"):
        out = tmp_path / f"site-{doors}.yaml"
        code, text = run_cli(["scene", "import", plans[1], "--doors", doors, "--out", out], monkeypatch, capsys)
        assert code == 0, text
        areas[doors] = _wall_area(out)
    door_w, wall_t = B.door[0], B.wall
    assert areas["closed"] - areas["open"] == pytest.approx(door_w * wall_t, rel=0.05)  # the one door's gap


@pytest.mark.parametrize("args, words", [
    (["scene", "import", "{dxf}", "--glass", "transparent"], "--glass: not an option of dxf plans"),
    (["scene", "import", "{ifc}", "--doors", "ajar"], "--doors: expected 'open' or 'closed', got 'ajar'"),
    (["run", "demo", "--doors", "closed"], "--doors: belongs to plans")])
def test_refused_in_one_line_nothing_written(plans, tmp_path, monkeypatch, capsys, args, words):
    args = [a.format(ifc=plans[0], dxf=plans[1]) for a in args] + ["--out", tmp_path / "site.yaml"]
    code, text = run_cli(args, monkeypatch, capsys)
    assert code == 2 and words in text and len(text.strip().splitlines()) == 1, text
    assert list(tmp_path.iterdir()) == []
