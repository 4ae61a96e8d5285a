"""report.html's crowd part (camplace.outputs.report_crowd): the people in the 3D view, the
map of P(seen by >= 2) at one height, the section with the crowd figures (issue 28)."""

from __future__ import annotations

import numpy as np

from camplace.metrics.crowd import crowd_metrics
from camplace.outputs.figures import SceneView
from camplace.outputs.report_crowd import crowd_report, cylinder_mesh
from camplace.outputs.report_html import render_report


def test_cylinders_stand_on_the_floor_where_the_people_are():
    v, t = cylinder_mesh(np.array([[1.0, 2.0], [3.0, 1.0]]), 0.25, 1.75, sides=8)
    assert v.shape == (2 * 18, 3) and t.shape == (2 * 32, 3) and t.max() == len(v) - 1
    first = v[:18]
    assert np.allclose(np.hypot(first[:16, 0] - 1.0, first[:16, 1] - 2.0), 0.25)
    assert set(np.round(v[:, 2], 6)) == {0.0, 1.75}


def test_report_shows_the_crowd():
    xs, ys = np.meshgrid(np.arange(4) + 0.5, np.arange(3) + 0.5)
    pos = np.c_[xs.ravel(), ys.ravel(), np.full(12, 1.5)]
    pos = np.r_[pos, [[0.5, 0.5, 0.5]]]
    gamma, w, rid = np.full(13, 2), np.ones(13), np.zeros(13, np.int32)
    cov = np.array([np.r_[np.full(12, 2), 0], np.r_[np.full(12, 1), 0]])  # two samples
    cm = crowd_metrics(gamma, w, cov, rid, ["walk"], np.array([[1.0, 1.0], [3.0, 2.0]]), 0.25, 1.75,
                       {"density": 0.5, "zones": {}, "radius": 0.25, "height": 1.75, "seed": 0, "samples": 2,
                        "persons": {"mean": 2.0, "std": 0.0, "min": 2.0, "max": 2.0}}, report_height=1.5)
    assert cm.summary["triangulatable_pct"]["mean"] == 100 * 6 / 13 and np.isclose(cm.p_triangulatable[0], 0.5)
    view = SceneView("room", np.array([[0, 0], [4, 0], [4, 3], [0, 3]], float), 3.0, 1.0)
    metrics = {"cost": 4.0, "coverage_gap": 0.077, "non_triangulatable_pct": 7.7, "regions": {
        "walk": {"coverage_gap": 0.077, "non_triangulatable_pct": 7.7}}, "crowd": cm.to_dict()}

    class T:
        positions, is_surface = pos, np.zeros(13, bool)

    cr = crowd_report(view, T, cm, metrics, [])
    z = cr.figures["crowdmap"]["data"][0]["z"]
    assert z[0][0] == 0.5 and "In a crowd" in cr.section and "0.5 persons/m" in cr.section
    page = render_report(view, {"scene": "room", "cameras": []}, metrics, pos, np.zeros(13, bool),
                         cov[0], gamma, rid, ["walk"], extra_html=cr.section, extra_figures=cr.figures,
                         extra_traces=cr.traces, dated=False)
    assert "id='crowdmap'" in page and '"crowdmap":' in page and "people (one crowd sample, 2)" in page


def test_the_map_shows_the_chance_a_person_standing_there_is_triangulatable():
    from dataclasses import replace

    from camplace.metrics.crowd import people_metrics

    xs, ys = np.meshgrid(np.arange(4) + 0.5, np.arange(3) + 0.5)
    pos = np.c_[xs.ravel(), ys.ravel(), np.full(12, 1.5)]
    cm = crowd_metrics(np.full(12, 2), np.ones(12), np.full((1, 12), 2), np.zeros(12, np.int32), ["walk"],
                       np.zeros((0, 2)), 0.25, 1.75, {"density": 0.5, "zones": {}, "radius": 0.25, "height": 1.75,
                                                      "seed": 0, "samples": 1, "persons": {"mean": 3.0}},
                       report_height=1.5)
    people = people_metrics(np.array([2, 1, 3]), np.zeros(3, np.int64), 1, np.zeros(3), ["walk"], 2, [1.25, 1.6])
    cm = replace(cm, summary=dict(cm.summary, people=people), p_person=np.linspace(0.0, 1.0, 12))
    view = SceneView("room", np.array([[0, 0], [4, 0], [4, 3], [0, 3]], float), 3.0, 1.0)

    class T:
        positions, is_surface = pos, np.zeros(12, bool)

    cr = crowd_report(view, T, cm, {"regions": {}}, [])
    fig = cr.figures["crowdmap"]
    assert "a person standing here" in fig["layout"]["title"]["text"]
    assert fig["data"][0]["z"][0][0] == 0.0 and fig["data"][0]["z"][-1][-1] == 1.0
    assert "all people" in cr.section and "66.7 %" in cr.section  # 2 of the 3 people seen by >= 2
