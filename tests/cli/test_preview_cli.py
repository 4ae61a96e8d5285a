"""See before you run (issue 25): ``scene import`` and ``run`` of a plan write the preview
picture (PNG and SVG) and print the import summary (rooms table) or put it in the JSON."""

from __future__ import annotations

import json

import pytest
import yaml

pytest.importorskip("ezdxf")

from camplace.scene.importers.ifc_build import GridBuilding  # noqa: E402
from tests.conftest import run_cli  # noqa: E402
from tests.scene.plan_drawings import draw_grid_dxf  # noqa: E402

B = GridBuilding(names=("Office", "Lab"))
AREA = f"{(B.room[0] - B.wall) * (B.room[1] - B.wall):.1f}"  # each room's clear area, m²


@pytest.fixture(scope="module")
def plan(tmp_path_factory):
    return draw_grid_dxf(tmp_path_factory.mktemp("preview") / "plan.dxf", B)


def test_scene_import_writes_the_preview_and_prints_the_rooms(plan, tmp_path, monkeypatch, capsys):
    out = tmp_path / "site.yaml"
    code, text = run_cli(["scene", "import", plan, "--out", out], monkeypatch, capsys)
    assert code == 0, text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["site.preview.png", "site.preview.svg", "site.yaml"]
    assert (tmp_path / "site.preview.png").read_bytes()[:4] == b"\x89PNG"
    svg = (tmp_path / "site.preview.svg").read_text()
    assert "Office" in svg and "Lab" in svg and f"{AREA} m\u00b2" in svg
    rows = [line for line in text.splitlines() if "Office" in line or "Lab" in line]  # the rooms table
    assert len(rows) == 2 and all(AREA in r for r in rows), text
    assert "2 rooms" in text and "site.preview.png" in text.replace("\n", "")
    assert [z["name"] for z in yaml.safe_load(out.read_text())["zones"]] == ["Office", "Lab"]


def test_json_mode_carries_the_summary(plan, tmp_path, monkeypatch, capsys):
    out = tmp_path / "site.yaml"
    code, text = run_cli(["--json", "scene", "import", plan, "--out", out], monkeypatch, capsys)
    assert code == 0, text
    doc = json.JSONDecoder().raw_decode(text[text.index("{"):])[0]
    assert doc["scene"] == str(out) and doc["preview"] == [str(tmp_path / "site.preview.png"),
                                                           str(tmp_path / "site.preview.svg")]
    assert [(r["name"], f"{r['area_m2']:.1f}") for r in doc["plan"]["rooms"]] == [("Office", AREA), ("Lab", AREA)]
    assert doc["plan"]["kind"] == "dxf" and doc["plan"]["mount_positions"] > 0 and doc["plan"]["clearance_m"] == 0.1


def test_run_writes_the_preview_into_the_run_folder(plan, tmp_path, monkeypatch, capsys):
    out = tmp_path / "out"
    code, text = run_cli(["--json", "run", plan, "--out", out, "--budget", "1", "--grid-only", "--no-plan",
                          "--no-cache"], monkeypatch, capsys)
    assert code == 0, text
    doc = json.JSONDecoder().raw_decode(text[text.index("{"):])[0]  # the log follows on stderr
    assert doc["files"]["preview.png"] == str(out / "preview.png") and (out / "preview.svg").is_file()
    assert [r["name"] for r in doc["plan"]["rooms"]] == ["Office", "Lab"]
    assert "Office" in (out / "preview.svg").read_text()


def test_plan_image_flags(tmp_path, monkeypatch, capsys):
    """--threshold, --max-opening, --min-room-area and --no-ocr reach the image importer; bad
    values and image flags on a DXF end in one line naming the flag, nothing written."""
    from tests.scene.plan_drawings import PLAN_PX, draw_grid_png

    png = draw_grid_png(tmp_path / "plan.png", B)
    code, text = run_cli(["--json", "scene", "import", png, "--scale", PLAN_PX, "--threshold", "100", "--max-opening",
                          "1.2", "--min-room-area", "2", "--no-ocr", "--out", tmp_path / "site.yaml"], monkeypatch,
                         capsys)
    assert code == 0, text
    plan = json.JSONDecoder().raw_decode(text[text.index("{"):])[0]["plan"]
    assert plan["used"]["threshold"].startswith("100 of 255") and "(given)" in plan["used"]["threshold"]
    assert plan["used"]["ocr"] == "off" and len(plan["rooms"]) == 2
    for args, flag in ((["--threshold", "300"], "--threshold"), (["--max-opening", "0"], "--max-opening"),
                       (["--min-room-area", "-1"], "--min-room-area")):
        code, text = run_cli(["scene", "import", png, "--scale", PLAN_PX, *args, "--out", tmp_path / "bad.yaml"],
                             monkeypatch, capsys)
        lines = [ln for ln in text.strip().splitlines() if ln.strip()]
        assert code == 2 and len(lines) == 1 and lines[0].startswith(f"error: {flag}:"), text
    dxf = draw_grid_dxf(tmp_path / "plan.dxf", B)
    code, text = run_cli(["scene", "import", dxf, "--no-ocr", "--out", tmp_path / "bad.yaml"], monkeypatch, capsys)
    assert code == 2 and "--no-ocr" in text and "dxf" in text, text
    assert not (tmp_path / "bad.yaml").exists()
