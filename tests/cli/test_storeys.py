"""--storey all (issue 18): a two-storey IFC building (ifcopenshell.api) planned storey by
storey by camplace run, and written as one scene per storey by camplace scene import."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest
import yaml

pytest.importorskip("ifcopenshell")

from camplace.scene.importers.ifc_build import GridBuilding, write_grid_building  # noqa: E402
from camplace.workflows.storeys import storey_slugs  # noqa: E402
from tests.conftest import SHARED, run_cli  # noqa: E402

B = GridBuilding(names=("Office", "Lab"))
FLOORS = ("Ground Floor", "First Floor")


@pytest.fixture(scope="module")
def building(tmp_path_factory):
    return write_grid_building(tmp_path_factory.mktemp("storeys") / "building.ifc", B, unit="mm", floors=FLOORS)


def _check_run():
    path = SHARED / "contract" / "check_run.py"
    if not path.is_file():
        pytest.skip("../shared/contract/check_run.py absent")
    spec = importlib.util.spec_from_file_location("check_run", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.check


def test_slugs_are_folder_safe_and_unique():
    assert storey_slugs(["Ground Floor", "ground floor", "Étage 1/2", "***"]) == [
        "ground-floor", "ground-floor-2", "tage-1-2", "storey-4"]


def test_run_storey_all_plans_each_storey_into_its_own_folder(building, tmp_path, monkeypatch, capsys):
    out = tmp_path / "out"
    code, text = run_cli(["run", building, "--storey", "all", "--out", out, "--budget", "3", "--grid-only",
                          "--repeatable", "--no-plan", "--no-cache"], monkeypatch, capsys)
    assert code == 0, text
    summary = json.loads((out / "storeys.json").read_text())
    rows = summary["storeys"]
    assert summary["source"] == "building.ifc" and [r["storey"] for r in rows] == list(FLOORS)  # no 'Roof' (no rooms)
    assert [r["folder"] for r in rows] == ["ground-floor", "first-floor"]
    assert [r["elevation_m"] for r in rows] == pytest.approx([0.0, B.height + B.slab])
    check = _check_run()
    for r in rows:
        folder = out / r["folder"]
        assert check(folder) == [], r
        placement = json.loads((folder / "placement.json").read_text())
        metrics = json.loads((folder / "metrics.json").read_text())
        assert r["cameras"] == len(placement["cameras"]) == 3 and r["budget"] == 3
        assert r["coverage_gap"] == pytest.approx(metrics["coverage_gap"]) and r["coverage_gap"] < 1
        z = np.array([c["position"][2] for c in placement["cameras"]])
        assert ((z > 0) & (z < r["height_m"])).all()  # scene frame: the storey's floor is z = 0
        building_z = r["elevation_m"] + z  # within that storey's slice of the building, not the other's
        assert ((building_z > r["elevation_m"]) & (building_z < r["elevation_m"] + r["height_m"])).all()
        assert set(metrics["regions"]) >= {"Office", "Lab"}
        svg = (folder / "preview.svg").read_text()  # issue 25: each storey's picture names its rooms
        assert (folder / "preview.png").stat().st_size > 0 and "Office" in svg and "Lab" in svg


def test_scene_import_storey_all_writes_one_scene_per_storey(building, tmp_path, monkeypatch, capsys):
    out = tmp_path / "site.yaml"
    code, text = run_cli(["scene", "import", building, "--storey", "all", "--out", out], monkeypatch, capsys)
    assert code == 0, text
    text = text.replace("\n", "")  # the console wraps long lines
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        f"site-{slug}{ext}" for slug in ("first-floor", "ground-floor") for ext in (".yaml", ".preview.png",
                                                                                    ".preview.svg"))
    for slug, floor in (("ground-floor", "Ground Floor"), ("first-floor", "First Floor")):
        assert f"site-{slug}.yaml" in text and floor in text
        assert "Office" in (tmp_path / f"site-{slug}.preview.svg").read_text()
        data = yaml.safe_load((tmp_path / f"site-{slug}.yaml").read_text())
        assert [z["name"] for z in data["zones"]] == ["Office", "Lab"] and data["name"].endswith(floor)
        zs = np.array([o["prism"]["z"] for o in data["obstacles"]])
        assert zs.min() >= -1e-6 and zs.max() <= data["room"]["height"] + 1e-6


@pytest.mark.parametrize("cmd", [["run", "{ifc}", "--out", "{tmp}/out"], ["scene", "import", "{ifc}", "--out",
                                                                            "{tmp}/site.yaml"]])
def test_unknown_storey_is_one_line_exit_2_nothing_written(building, tmp_path, monkeypatch, capsys, cmd):
    args = [a.format(ifc=building, tmp=tmp_path) for a in cmd] + ["--storey", "Attic"]
    code, text = run_cli(args, monkeypatch, capsys)
    assert code == 2 and "Attic" in text and "'Ground Floor', 'First Floor', 'Roof'" in text
    assert len(text.strip().splitlines()) == 1 and list(tmp_path.iterdir()) == []


def test_storey_all_on_a_dxf_plan_gives_its_plans(tmp_path, monkeypatch, capsys):
    """A DXF sheet's plans are its storeys (issue 33): one plan, one scene file; a plan it
    does not draw is refused in one line naming the ones it has."""
    from tests.scene.plan_drawings import draw_grid_dxf

    dxf = draw_grid_dxf(tmp_path / "plan.dxf", B)
    code, text = run_cli(["--quiet", "scene", "import", dxf, "--storey", "all", "--out", tmp_path / "site.yaml"],
                         monkeypatch, capsys)
    assert code == 0, text
    assert sorted(p.name for p in tmp_path.iterdir() if p.suffix == ".yaml") == ["site-plan-1.yaml"]
    code, text = run_cli(["scene", "import", dxf, "--storey", "plan-2", "--out", tmp_path / "two.yaml"], monkeypatch,
                         capsys)
    assert code == 2 and "--storey" in text and "it has plan-1" in text and len(text.strip().splitlines()) == 1
    assert not (tmp_path / "two.yaml").exists()
