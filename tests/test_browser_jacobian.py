"""The Jacobian's panels in real headless Chromium: forces and gravity, the ellipsoids, velocities, motion,
and the course's 3-DOF desktop arm."""

from __future__ import annotations

import re

import numpy as np
import pytest

from ur10dev.browser import (
    HANG_TIMEOUT_MS, canvas_changed, choose, click, dom_id, set_checkbox, settled_canvas, unfold,
)
from ur10dev.waiting import wait_for

pytestmark = pytest.mark.browser


def test_what_the_jacobian_does_on_the_ur10_and_the_desktop_arm(open_page, light_app, tmp_path):
    """Torque bars and the force arrow (its direction by a handle too), the ellipsoids, joint rates for
    a typed velocity, a path charted both ways, a drop's energies; then the desktop arm plays the course's path and finds
    the pose that needs the most torque."""
    from ur10teach.features.arm_picker import DESKTOP
    from ur10teach.features.course_arms.desktop_lessons import CoursePathLesson, StaticsExercise
    from ur10teach.features.statics import DRAGGED

    app = light_app
    page, session = open_page()
    session.ik_target.show_ghosts.value = False  # what changes below is easier to see

    # forces and gravity: the bars, with each joint's rating, and the arrow on the canvas
    unfold(page, "Forces and gravity", session.statics.enabled)
    before = settled_canvas(page)
    set_checkbox(page, session.statics.enabled, True)
    wait_for(lambda: session.statics.bars.visible, what="the torque bars")
    wait_for(lambda: page.get_by_text("rated 330", exact=False).count() >= 2, what="the bars in the page")
    assert page.locator(".torque-bar").count() == 6
    with_force = canvas_changed(page, before, 0.0003, "the force arrow and its label to show")
    # the direction by a handle: it shows at the arrow's end, this browser's own
    choose(page, session.statics.direction, DRAGGED)
    wait_for(lambda: session.statics.handle.visible, what="the direction handle")
    canvas_changed(page, with_force, 0.0003, "the direction handle to show")
    page.screenshot(path=str(tmp_path / "force_handle.png"))
    # the ellipsoids at the flange
    unfold(page, "Manipulability ellipsoids", session.ellipsoids.enabled)
    shown = settled_canvas(page)
    set_checkbox(page, session.ellipsoids.enabled, True)
    wait_for(lambda: session.ellipsoids.velocity.visible, what="the ellipsoids")
    wait_for(lambda: page.get_by_text("Velocity ellipsoid", exact=False).count() > 0, what="their lengths")
    canvas_changed(page, shown, 0.003, "the ellipsoids to show")
    # velocities: a typed flange velocity gets its joint rates in the page
    unfold(page, "Velocities", session.velocity.solve)
    click(page, session.velocity.solve, lambda: page.get_by_text("within its speed limit", exact=False).count() > 0,
          "the joint rates")
    assert np.isfinite(session.velocity.joint_rates()).all()

    # a path across s5 = 0: both charts show in the page, and the straight line's carries both marks
    motion = session.motion
    start = np.radians([10, -60, 80, -110, 20, 20])
    session.apply(lambda state: state.set_joints(start))
    unfold(page, "Motion", motion.remember)
    click(page, motion.remember, lambda: motion.start is not None, "the start remembered")
    session.apply(lambda state: state.set_joints(np.radians([10, -60, 80, -110, -20, 20])))
    click(page, page.get_by_role("button", name="straight tool line"),
          lambda: motion.player.playing or any(chart.visible for chart in motion.path_charts.values()), "the path started")
    wait_for(lambda: all(chart.visible for chart in motion.path_charts.values()), what="both charts")
    line = motion.path_charts["straight tool line"].data
    assert line[9].any() and line[10].any(), "the straight line's marks are missing"
    wait_for(lambda: page.get_by_text("near a singularity", exact=True).count() >= 2, what="the charts' legends")
    wait_for(lambda: page.get_by_text("Joints interpolated: joint speeds", exact=True).count() == 1, what="the second chart")
    wait_for(lambda: not motion.player.playing, what="the path played")
    assert page.get_by_text("1/1/70", exact=False).count() == 0, "the time axis is read as dates"
    page.get_by_text("Joints interpolated: joint speeds", exact=True).scroll_into_view_if_needed()
    page.screenshot(path=str(tmp_path / "path_charts.png"))
    # let go: the drop's energies take the paths' place in the page
    click(page, motion.release, lambda: motion.player.playing or motion.energy.visible, "the drop started")
    wait_for(lambda: motion.energy.visible, what="the drop's energy chart")
    wait_for(lambda: page.get_by_text("Gravity drop: energy", exact=True).count() == 1, what="the energy chart in the page")
    wait_for(lambda: page.get_by_text("Joints interpolated: joint speeds", exact=True).count() == 0, what="the path charts gone")
    wait_for(lambda: not motion.player.playing, what="the drop played")
    assert "T + V stays at" in motion.summary.content

    # the 3-DOF desktop arm from the picker: its parallelogram, its velocity plots, the path's arrows while it plays
    client_id = next(k for k, v in app.sessions.items() if v is session)
    before = settled_canvas(page)
    wait_for(lambda: app.can_switch(client_id), what="the arm to be ready for a change")
    choose(page, session.arm_picker.dropdown, DESKTOP)
    wait_for(lambda: app.sessions.get(client_id) is not None and app.sessions[client_id].built
             and app.sessions[client_id].arm.name == "three_dof", what="the desktop arm's session")
    desktop = app.sessions[client_id]
    path, exercise = (next(lesson for lesson in desktop.lessons if isinstance(lesson, kind))
                      for kind in (CoursePathLesson, StaticsExercise))
    page.wait_for_selector(dom_id(desktop.joints.sliders[0]), timeout=HANG_TIMEOUT_MS)
    wait_for(lambda: "the upper arm and the forearm are in one line" in desktop.singularities.gauges.content, what="det J_v's factors")
    unfold(page, "Velocities along the course's path", path.play)
    wait_for(lambda: page.get_by_text("Tool turning rate ω", exact=True).count() == 1, what="the velocity plots")
    assert page.get_by_text("1/1/70", exact=False).count() == 0, "the time axis is read as dates"
    still = canvas_changed(page, before, 0.02, "the desktop arm drawn in place of the UR10")
    rest = desktop.state.last.q
    click(page, path.play, lambda: desktop.velocity.linear.visible, "the path playing")
    wait_for(lambda: np.abs(desktop.state.last.q - rest).max() > 0.05, what="the arm to move along the path")
    with desktop.state.lock:  # the path waits at its next frame, however slow the machine, while the picture is taken
        canvas_changed(page, still, 0.003, "the arm and its arrows to show the path")
        page.screenshot(path=str(tmp_path / "desktop_arm_playing.png"))
    click(page, path.stop, lambda: not desktop.velocity.linear.visible, "the path stopped")
    # the pose that needs the most torque, marked by a red ball with its label
    unfold(page, "The course's statics exercise", exercise.search)
    click(page, exercise.search, lambda: "Largest ‖τ‖" in exercise.result.content, "the worst pose")
    wait_for(lambda: page.get_by_text(re.compile(r"^Largest ‖τ‖ = ")).count() > 0, what="the result in the page")
    marker = exercise._map[1]
    label = exercise._scene._handle_from_node_name[f"{marker.name}/label"]
    shown = settled_canvas(page)
    page.screenshot(path=str(tmp_path / "desktop_arm_worst.png"))
    label.visible = False  # viser draws 3D labels on the canvas: the label shows if hiding it changes the picture
    canvas_changed(page, shown, 0.0005, "the worst pose's label to go")
