"""What to buy (issue 27): bom.csv against the schedule, the recording load, the focal length
through placement.json / placement.csv (read back by evaluate) and the OpenCV / COLMAP exports."""

from __future__ import annotations

import csv
import json

import pytest

from camplace.spec.loading import parse_scene
from conftest import box_room

VARI = {"name": "vari", "resolution": [1920, 1080], "pixel_um": 2.9, "focal_mm": [2.8, 12], "price": 2.5,
        "bitrate_mbps": 4.0, "ir_range_m": 30}
DOME = {"name": "dome", "resolution": [1920, 1080], "sensor_width_mm": 5.568, "focal_mm": 4, "price": 1.0,
        "bitrate_mbps": 3.0}


def _spec():
    d = box_room(cameras=[VARI, DOME], targets=[{"name": "floor", "kind": "volume", "heights": [1.0], "coverage": 2,
                                                 "min_px_per_m": "observe"}],
                 mounts=[{"kind": "ceiling_grid", "camera": ["vari", "dome"], "spacing": 1.0, "yaw_deg": [0, 90],
                          "pitch_deg": [45]}]).model_dump(exclude_none=True)
    d["existing"] = [{"id": "E1", "camera": "vari", "position": [0.5, 0.5, 2.9], "yaw_deg": 45, "pitch_deg": 30,
                      "focal_mm": 6}]
    d["recording"] = {"retention_days": 30}
    return parse_scene(d)


@pytest.fixture(scope="module")
def lens_run(tmp_path_factory):
    from camplace.outputs.write import write_outputs
    from camplace.workflows.run import run

    r = run(_spec(), budget=3, refine=True, refine_time_s=3)
    out = tmp_path_factory.mktemp("bom")
    write_outputs(out, r.scene.name, r.visibility, r.placement, r.problem.budget, r.metrics, r.timings_s,
                  scene=r.scene, report=False)
    return r, out


def _csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_bom_totals_equal_the_schedule(lens_run):
    from camplace.outputs.plan_bom import bom_figure
    from camplace.outputs.plan_data import SCHEDULE_HEAD, plan_data

    r, out = lens_run
    pdict = json.loads((out / "placement.json").read_text())
    data = plan_data(r.scene, r.visibility, pdict, {}, r.placement.selected, budget_s=0.0)
    rows = [dict(zip(SCHEDULE_HEAD, row)) for row in data.schedule_rows()]
    bom = _csv(out / "bom.csv")
    assert list(bom[0]) == ["model", "focal_mm", "count", "unit_price", "total"]
    new = [row for row in rows if row["status"] == "new"]
    assert sum(int(b["count"]) for b in bom) == len(new) == 3
    assert sum(float(b["total"]) for b in bom) == pytest.approx(sum(float(row["price"]) for row in new))
    assert all(float(b["total"]) == pytest.approx(int(b["count"]) * float(b["unit_price"])) for b in bom)
    assert _csv(out / "bom_existing.csv") == [{"model": "vari", "focal_mm": "6.0", "count": "1", "unit_price": "2.5",
                                              "total": "2.5"}]
    texts = [t.get_text() for t in bom_figure(data).texts]
    total = sum(float(b["total"]) for b in bom)
    assert any(f"total price of the new cameras: {total:g} (3 cameras)" in t for t in texts)
    assert any("storage for 30 days" in t for t in texts)


def test_recording_load(lens_run):
    r, out = lens_run
    p = json.loads((out / "placement.json").read_text())
    bitrate = {"vari": 4.0, "dome": 3.0}
    new = sum(bitrate[c["camera"]] for c in p["cameras"] if not c["existing"])
    rec = p["recording"]
    assert rec["bandwidth_new_mbps"] == pytest.approx(new) and rec["bandwidth_mbps"] == pytest.approx(new + 4.0)
    assert rec["storage_tb"] == pytest.approx((new + 4.0) * 86400 * 30 / 8 / 1e6)  # Mbit/s x s / 8 = MB; 1e6 MB = TB


def test_focal_round_trips_through_placement_files_and_exports(lens_run, tmp_path):
    from camplace.outputs.exports import read_colmap_text, read_opencv_yaml, write_exports
    from camplace.workflows.evaluate import evaluate

    r, out = lens_run
    p = json.loads((out / "placement.json").read_text())
    for c in p["cameras"]:  # every camera is a lens as sold: focal_mm and the intrinsics that follow
        assert c["intrinsics"]["fx"] == pytest.approx(c["focal_mm"] / 0.0029)  # both: 2.9 µm pixels
    assert [float(row["focal_mm"]) for row in _csv(out / "placement.csv")] == [c["focal_mm"] for c in p["cameras"]]
    for name in ("placement.json", "placement.csv"):  # evaluate reads the focal back: the same cost
        assert evaluate(_spec(), out / name).metrics.cost == pytest.approx(r.metrics.cost)
    write_exports(tmp_path, p["cameras"])
    colmap = read_colmap_text(tmp_path / "colmap")
    for k, c in enumerate(p["cameras"]):
        cv = read_opencv_yaml(tmp_path / "opencv" / f"camera_{c['candidate_id']}.yaml")
        assert cv["focal_mm"] == colmap[k]["focal_mm"] == c["focal_mm"]
        assert cv["fx"] == colmap[k]["fx"] == c["intrinsics"]["fx"]
