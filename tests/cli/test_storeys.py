"""Buildings from the command line (issue 33): a two-storey IFC building (ifcopenshell.api)
planned as one building by camplace run --storey all (one folder, one budget, cameras
on both storeys in building z), and written as one scene with storeys: by camplace
scene import; the errors of the building options."""

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


def test_run_storey_all_plans_the_building_in_one_run(building, tmp_path, monkeypatch, capsys):
    out = tmp_path / "out"
    code, text = run_cli(["run", building, "--storey", "all", "--out", out, "--budget", "4", "--grid-only",
                          "--repeatable", "--no-plan", "--no-cache"], monkeypatch, capsys)
    assert code == 0, text
    assert _check_run()(out) == []
    placement = json.loads((out / "placement.json").read_text())
    metrics = json.loads((out / "metrics.json").read_text())
    assert [s["name"] for s in placement["storeys"]] == list(FLOORS)  # no 'Roof' (no rooms)
    elev = {s["name"]: s["elevation_m"] for s in placement["storeys"]}
    assert elev["First Floor"] == pytest.approx(B.height + B.slab) and elev["Ground Floor"] == 0.0
    cams = placement["cameras"]
    assert len(cams) == 4 and placement["budget"] == 4  # one budget for the building
    for c in cams:  # building z: between the floor and the ceiling of the storey the camera names
        top = {s["name"]: s["top_m"] for s in placement["storeys"]}[c["storey"]]
        assert elev[c["storey"]] < c["position"][2] < top
    assert {s["storey"] for s in metrics["storeys"]} == set(FLOORS)
    assert sum(s["cameras"] for s in metrics["storeys"]) == 4
    assert {"Ground Floor/Office", "First Floor/Lab"} <= set(metrics["regions"])


def test_storey_budget_and_subset(building, tmp_path, monkeypatch, capsys):
    out = tmp_path / "out"
    code, text = run_cli(["run", building, "--storey", "First Floor,Ground Floor", "--out", out, "--budget", "4",
                          "--storey-budget", "Ground Floor=1", "--grid-only", "--no-plan", "--no-cache"],
                         monkeypatch, capsys)
    assert code == 0, text
    cams = json.loads((out / "placement.json").read_text())["cameras"]
    assert sum(c["storey"] == "Ground Floor" for c in cams) <= 1 and len(cams) <= 4
    code, text = run_cli(["run", building, "--storey", "Ground Floor,Attic", "--out", out], monkeypatch, capsys)
    assert code == 2 and "--storey: no storey 'Attic'" in text and "Traceback" not in text
    code, text = run_cli(["run", building, "--storey", "all", "--storey-budget", "Cellar=2", "--out", out],
                         monkeypatch, capsys)
    assert code == 2 and "--storey-budget: no storey 'Cellar'" in text
    code, text = run_cli(["run", building, "--storey-budget", "oops", "--out", out], monkeypatch, capsys)
    assert code == 2 and "--storey-budget: expected NAME=K" in text


def test_scene_import_storey_all_writes_one_building_scene(building, tmp_path, monkeypatch, capsys):
    out = tmp_path / "site.yaml"
    code, text = run_cli(["scene", "import", building, "--storey", "all", "--out", out], monkeypatch, capsys)
    assert code == 0, text
    data = yaml.safe_load(out.read_text())
    assert list(data["storeys"]) == list(FLOORS)
    assert data["storeys"]["First Floor"]["elevation"] == pytest.approx(B.height + B.slab)
    for slug in ("ground-floor", "first-floor"):
        assert "Office" in (tmp_path / f"site.{slug}.preview.svg").read_text()
    code, text = run_cli(["run", out, "--budget", "2", "--grid-only", "--no-plan", "--no-cache", "--out",
                          tmp_path / "o"], monkeypatch, capsys)
    assert code == 0, text
    assert len(json.loads((tmp_path / "o" / "placement.json").read_text())["cameras"]) == 2


def test_several_plan_files_need_elevations(building, tmp_path, monkeypatch, capsys):
    code, text = run_cli(["run", building, building, "--out", tmp_path / "o"], monkeypatch, capsys)
    assert code == 2 and "--elevations" in text and "Traceback" not in text
    code, text = run_cli(["run", building, building, "--elevations", "0", "--out", tmp_path / "o"], monkeypatch,
                         capsys)
    assert code == 2 and "--elevations: 1 value(s) for 2 plan file(s)" in text


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
    assert sorted(p.name for p in tmp_path.iterdir() if p.suffix == ".yaml") == ["site.yaml"]
    assert list(yaml.safe_load((tmp_path / "site.yaml").read_text())["storeys"]) == ["plan-1"]
    code, text = run_cli(["scene", "import", dxf, "--storey", "plan-2", "--out", tmp_path / "two.yaml"], monkeypatch,
                         capsys)
    assert code == 2 and "--storey" in text and "it has plan-1" in text and len(text.strip().splitlines()) == 1
    assert not (tmp_path / "two.yaml").exists()


def test_one_storey_run_of_an_ifc_writes_cameras_ifc_at_building_z(building, tmp_path, monkeypatch, capsys):
    """Every IFC run writes cameras.ifc (issue 33): a one-storey run's poses are above that
    storey's floor, its cameras.ifc puts them in that storey at building z (elevation + z)."""
    import ifcopenshell
    import ifcopenshell.util.element as ifc_element
    import ifcopenshell.util.placement as ifc_placement

    out = tmp_path / "out"
    code, text = run_cli(["--quiet", "run", building, "--storey", "First Floor", "--budget", "2", "--grid-only",
                          "--no-plan", "--no-cache", "--out", out], monkeypatch, capsys)
    assert code == 0, text
    cams = json.loads((out / "placement.json").read_text())["cameras"]
    model = ifcopenshell.open(str(out / "cameras.ifc"))
    elements = [e for e in model.by_type("IfcAudioVisualAppliance")]
    assert len(elements) == len(cams) == 2
    up = B.height + B.slab
    got = sorted(tuple(np.round(ifc_placement.get_local_placement(e.ObjectPlacement)[:3, 3] / 1000.0, 4))
                 for e in elements)  # the generated model is in mm
    want = sorted(tuple(np.round([c["position"][0], c["position"][1], c["position"][2] + up], 4)) for c in cams)
    assert got == pytest.approx(want, abs=1e-3)
    assert {ifc_element.get_container(e).Name for e in elements} == {"First Floor"}
