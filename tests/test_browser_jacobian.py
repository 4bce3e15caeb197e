"""The Jacobian's panels in real headless Chromium: forces and gravity, the ellipsoids, velocities."""

from __future__ import annotations

import re

import numpy as np
import pytest

from .browser_support import canvas_pixels, changed, dom_id, set_checkbox, wait_for

pytestmark = pytest.mark.browser


def unfold(page, title: str, widget) -> None:
    """Open a folded folder by its title, as a student does, until ``widget`` shows."""
    if not page.locator(dom_id(widget)).is_visible():
        page.get_by_text(title, exact=True).first.click()
        page.locator(dom_id(widget)).wait_for(state="visible", timeout=10_000)


def test_forces_ellipsoids_and_velocities_show_in_the_browser(open_page, tmp_path):
    page, session = open_page()
    # forces and gravity: the bars, with each joint's rating, and the arrow on the canvas
    unfold(page, "Forces and gravity", session.statics.enabled)
    before = canvas_pixels(page)
    set_checkbox(page, session.statics.enabled, True)
    wait_for(lambda: session.statics.bars.visible, what="the torque bars")
    wait_for(lambda: page.get_by_text("rated 330", exact=False).count() >= 2, what="the bars in the page")
    assert page.locator(".torque-bar").count() == 6
    page.wait_for_timeout(2000)
    with_force = canvas_pixels(page)
    assert changed(before, with_force) > 0.0003, "the force arrow and its label did not show"
    # the direction by a handle: it shows at the arrow's end, this browser's own
    from app.statics import DRAGGED

    from .browser_support import choose

    choose(page, session.statics.direction, DRAGGED)
    wait_for(lambda: session.statics.handle.visible, what="the direction handle")
    page.wait_for_timeout(2000)
    assert changed(with_force, canvas_pixels(page)) > 0.0003, "the direction handle did not show"
    page.screenshot(path=str(tmp_path / "force_handle.png"))
    # the ellipsoids at the flange
    unfold(page, "Manipulability ellipsoids", session.ellipsoids.enabled)
    set_checkbox(page, session.ellipsoids.enabled, True)
    wait_for(lambda: session.ellipsoids.velocity.visible, what="the ellipsoids")
    wait_for(lambda: page.get_by_text("Velocity ellipsoid", exact=False).count() > 0, what="their lengths")
    page.wait_for_timeout(2000)
    with_ellipsoids = canvas_pixels(page)
    assert changed(with_force, with_ellipsoids) > 0.003, "the ellipsoids did not show"
    # velocities: a typed flange velocity gets its joint rates in the page
    unfold(page, "Velocities", session.velocity.solve)
    page.locator(dom_id(session.velocity.solve)).click()
    wait_for(lambda: page.get_by_text("within its speed limit", exact=False).count() > 0, what="the joint rates")
    assert np.isfinite(session.velocity.joint_rates()).all()


def test_the_desktop_arm_plays_the_courses_path_and_finds_its_worst_pose(open_page, app, tmp_path):
    """The 3-DOF arm from the picker: drawn with its parallelogram, its velocity plots, the path's
    arrows while it plays, and the torque map with its worst pose."""
    from app.arm_picker import DESKTOP
    from app.course_arms.desktop_arm import DesktopArmSession

    from .browser_support import choose

    page, session = open_page()
    client_id = next(k for k, v in app.sessions.items() if v is session)
    before = canvas_pixels(page)
    choose(page, session.arm_picker.dropdown, DESKTOP)
    wait_for(lambda: isinstance(app.sessions.get(client_id), DesktopArmSession), what="the desktop arm's session")
    desktop = app.sessions[client_id]
    page.wait_for_selector(dom_id(desktop.joints.sliders[0]), timeout=30_000)
    wait_for(lambda: page.get_by_text("upper arm and forearm in one line", exact=False).count() > 0, what="det J_v's factors")
    wait_for(lambda: page.get_by_text("Tool turning rate ω", exact=True).count() == 1, what="the velocity plots")
    assert page.get_by_text("1/1/70", exact=False).count() == 0, "the time axis is read as dates"
    page.wait_for_timeout(2500)
    still = canvas_pixels(page)
    assert changed(before, still) > 0.02, "the desktop arm was not drawn in place of the UR10"
    page.locator(dom_id(desktop.path.play)).click()
    wait_for(lambda: desktop.scene.velocity[0].visible, what="the path playing")
    page.wait_for_timeout(1500)
    playing = canvas_pixels(page)
    assert changed(still, playing) > 0.003, "the arm did not move along the path"
    page.screenshot(path=str(tmp_path / "desktop_arm_playing.png"))
    page.locator(dom_id(desktop.path.stop)).click()
    wait_for(lambda: not desktop.scene.velocity[0].visible, what="the path stopped")
    unfold(page, "Forces", desktop.forces.search)
    for _ in range(3):  # the folder may still be opening under the first click
        page.locator(dom_id(desktop.forces.search)).click()
        try:
            wait_for(lambda: "Largest ‖τ‖" in desktop.forces.result.content, timeout=10.0, what="the worst pose")
            break
        except AssertionError:
            continue
    assert "Largest ‖τ‖" in desktop.forces.result.content, "the search never ran"
    wait_for(lambda: page.get_by_text(re.compile(r"^Largest ‖τ‖ = ")).count() > 0, what="the result in the page")
    marker = desktop.forces._map[1]  # the red ball at the worst pose, with its label under it
    label = desktop.forces._scene._handle_from_node_name[f"{marker.name}/label"]
    # viser draws 3D labels on the canvas, not as page text: the label shows if hiding it changes the picture
    page.wait_for_timeout(2000)
    shown = canvas_pixels(page)
    page.screenshot(path=str(tmp_path / "desktop_arm_worst.png"))
    label.visible = False
    page.wait_for_timeout(2000)
    assert changed(canvas_pixels(page), shown) > 0.0005, "the worst pose's label was not drawn"


def test_a_path_is_charted_both_ways_with_its_marks(open_page, tmp_path):
    """Across s5 = 0: both charts show in the page, and the straight line's carries both marks."""
    page, session = open_page()
    motion = session.motion
    start = np.radians([10, -60, 80, -110, 20, 20])
    session.apply(lambda state: state.set_joints(start))
    unfold(page, "Motion", motion.remember)
    page.locator(dom_id(motion.remember)).click()
    wait_for(lambda: motion.start is not None, what="the start remembered")
    session.apply(lambda state: state.set_joints(np.radians([10, -60, 80, -110, -20, 20])))
    page.get_by_role("button", name="straight tool line").click()
    wait_for(lambda: all(chart.visible for chart in motion.charts.values()), what="both charts")
    line = motion.charts["straight tool line"].data
    assert line[9].any() and line[10].any(), "the straight line's marks are missing"
    wait_for(lambda: page.get_by_text("near a singularity", exact=True).count() >= 2, what="the charts' legends")
    wait_for(lambda: page.get_by_text("Joints interpolated: joint speeds", exact=True).count() == 1, what="the second chart")
    wait_for(lambda: not motion.player.playing, timeout=30, what="the path played")
    assert page.get_by_text("1/1/70", exact=False).count() == 0, "the time axis is read as dates"
    page.get_by_text("Joints interpolated: joint speeds", exact=True).scroll_into_view_if_needed()
    page.screenshot(path=str(tmp_path / "path_charts.png"))
