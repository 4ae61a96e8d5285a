"""The planner page on a building (issue 33) in headless Chromium: the floor selector shows one
storey's cameras, and the editor's floor list moves a camera to another floor."""

from __future__ import annotations

import pytest

from conftest import two_storeys
from test_browser import browser, serve, severe, wait_for  # noqa: F401 (browser: the fixture)


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    from camplace.planner.opening import open_start

    yield from serve(open_start, two_storeys(), root=tmp_path_factory.mktemp("planner-building-page"))


def shown_cameras(drv) -> list[str]:
    return drv.execute_script("return [...document.querySelectorAll('#g-cameras .cam')]"
                              ".filter(g => g.style.display !== 'none').map(g => g.dataset.id).sort()")


def test_floor_selector_and_moving_a_camera_to_another_floor(browser, server):  # noqa: F811
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    drv = browser
    drv.get(server)
    wait_for(drv, "document.body.dataset.ready", "the page to load the scene and state")
    cams = drv.execute_script("return planner.S.state.cameras.map(c => [c.id, c.storey])")
    on = {f: sorted(i for i, s in cams if s == f) for f in ("Ground", "Level 1")}
    floor = Select(drv.find_element(By.ID, "floor"))
    assert [o.text for o in floor.options] == ["Ground", "Level 1"]
    assert shown_cameras(drv) == on["Ground"]
    floor.select_by_visible_text("Level 1")
    assert shown_cameras(drv) == on["Level 1"]

    floor.select_by_visible_text("Ground")
    cid = on["Ground"][0]
    drv.execute_script("planner.select(arguments[0])", cid)
    wait_for(drv, f"planner.S.sel === {cid!r}", "the camera to be selected")
    version = drv.execute_script("return planner.S.state.version")
    Select(drv.find_element(By.ID, "ed-storey")).select_by_visible_text("Level 1")
    wait_for(drv, f"planner.S.state.version > {version}", "the move to Level 1")
    moved = drv.execute_script("return planner.S.state.cameras.find(c => c.id === arguments[0])", cid)
    assert moved["storey"] == "Level 1" and moved["position"][2] > 3.5
    assert floor.first_selected_option.text == "Level 1" and cid in shown_cameras(drv)
    assert not severe(drv), f"browser console errors: {severe(drv)}"


def test_the_3d_view_is_a_cut_away_at_the_selected_floor(browser, server):  # noqa: F811
    """The 3D view of a building shows the selected storey and those below it: Ground alone
    shows only Ground's cameras; Level 1 shows both floors and every camera."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    drv = browser
    drv.get(server)
    wait_for(drv, "document.body.dataset.ready", "the page to load the scene and state")
    cams = drv.execute_script("return planner.S.state.cameras.map(c => [c.id, c.storey])")
    floor = Select(drv.find_element(By.ID, "floor"))
    floor.select_by_visible_text("Ground")
    drv.find_element(By.ID, "tab-3d").click()
    wait_for(drv, "planner.S.drawn3d !== undefined", "the 3D view to draw")
    drawn = drv.execute_script("return planner.S.drawn3d")
    assert drawn["storeys"] == ["Ground"]
    assert sorted(drawn["cameras"]) == sorted(i for i, s in cams if s == "Ground")
    floor.select_by_visible_text("Level 1")
    drawn = drv.execute_script("return planner.S.drawn3d")
    assert drawn["storeys"] == ["Ground", "Level 1"] and sorted(drawn["cameras"]) == sorted(i for i, _ in cams)
    assert any(s == "Level 1" for _, s in cams) and any(s == "Ground" for _, s in cams)
    assert not severe(drv), f"browser console errors: {severe(drv)}"
