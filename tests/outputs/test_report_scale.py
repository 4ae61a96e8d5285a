"""The report at site scale (issue 21): past VIEW_MAX_CELLS occupancy cells no camera view is
rendered (preparing the grids alone would overrun the budget) and the page says how many
of how many it shows; the 3D view's target cloud is a capped sample, said on the page."""

from __future__ import annotations

import numpy as np

from camplace.outputs import report_html


def test_no_views_past_the_cell_cap_and_the_page_says_so(demo_run, monkeypatch):
    sel = demo_run.placement.selected
    views, skipped = report_html.camera_views(demo_run.scene, demo_run.visibility, sel, budget_s=1.0)
    assert len(views) >= 1
    monkeypatch.setattr(report_html, "VIEW_MAX_CELLS", 10)
    views, skipped = report_html.camera_views(demo_run.scene, demo_run.visibility, sel, budget_s=1.0)
    assert views == [] and skipped == len(sel) > 0
    text = report_html._views_section(views, skipped)
    assert f"showing 0 of {len(sel)} camera views" in text and "too large" in text
    # repeatable reports (no budget) still render every view
    views, skipped = report_html.camera_views(demo_run.scene, demo_run.visibility, sel[:1], budget_s=float("inf"))
    assert len(views) == 1 and skipped == 0


def test_target_cloud_is_capped_and_said(demo_run):
    from camplace.outputs.figures import SceneView

    t = demo_run.visibility.targets
    cov = demo_run.problem.coverage(demo_run.placement.selected)
    view = SceneView.from_targets("demo", t.positions, [])
    page = report_html.render_report(view, {"cameras": []}, {"regions": {}}, t.positions, t.is_surface, cov, t.gamma,
                                     t.region_ids, t.region_names, max_points=100, dated=False)
    assert f"showing 100 of {len(t.positions)} targets" in page or \
        (f"of {len(t.positions)} targets" in page and "showing" in page)
    assert np.all(cov >= 0)


def test_many_cameras_draw_a_sample_of_frusta_and_say_so(demo_run, monkeypatch):
    from camplace.outputs import report_figures
    from camplace.outputs.figures import SceneView
    from camplace.outputs.write import placement_dict

    t = demo_run.visibility.targets
    cov = demo_run.problem.coverage(demo_run.placement.selected)
    placement = placement_dict(demo_run.scene.name, demo_run.placement, demo_run.problem.budget,
                               demo_run.visibility.candidates)
    cams = placement["cameras"]
    assert len(cams) >= 3
    monkeypatch.setattr(report_figures, "MAX_FRUSTA", 2)
    view = SceneView.from_targets("demo", t.positions, cams)
    fig, _ = report_figures.view3d_figure(view, t.positions, cov, t.gamma, t.region_ids, t.region_names, cams)
    frusta = next(d for d in fig["data"] if str(d.get("name", "")).startswith("camera frusta"))
    assert frusta["name"] == f"camera frusta (showing 2 of {len(cams)})"
    assert sum(v is None for v in frusta["x"]) == 2 * 8  # 8 edges per drawn frustum
    page = report_html.render_report(view, placement, {"regions": {}}, t.positions, t.is_surface, cov, t.gamma,
                                     t.region_ids, t.region_names, dated=False)
    assert f"showing 2 of {len(cams)} camera frusta" in page
