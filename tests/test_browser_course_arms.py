"""The course's other arms in real headless Chromium: the picker, the arm with its DH frames, a slider."""

from __future__ import annotations

import numpy as np
import pytest

from app.course_arms.session import CourseArmSession

from .browser_support import canvas_pixels, changed, choose, dom_id, set_checkbox, step_slider, wait_for

pytestmark = pytest.mark.browser


def test_picking_the_kr210_draws_it_with_its_dh_frames_and_its_panel(open_page, app):
    page, session = open_page()
    client_id = next(k for k, v in app.sessions.items() if v is session)
    before = canvas_pixels(page)
    choose(page, session.arm_picker.dropdown, "KUKA KR210 (spherical wrist)")
    wait_for(lambda: isinstance(app.sessions.get(client_id), CourseArmSession), what="the KR210's session")
    course = app.sessions[client_id]
    page.wait_for_selector(dom_id(course.joints.sliders[0]), timeout=30_000)
    # the panel shows the branches, det J's factors with their meaning, and the DH table
    wait_for(lambda: page.get_by_text("branches reach the target", exact=False).count() > 0, what="the branch table")
    assert page.get_by_text("shoulder front, elbow up, wrist not flipped").count() >= 1
    assert page.get_by_text("the wrist centre on axis 1", exact=False).count() >= 1
    assert page.get_by_text("As defined (modified DH)", exact=False).count() >= 1
    page.wait_for_timeout(2500)
    with_frames = canvas_pixels(page)
    assert changed(before, with_frames) > 0.02, "the KR210 was not drawn in place of the UR10"
    # the DH frames' x axes (red) and z axes (blue) are on screen, and go when switched off
    set_checkbox(page, course.dh_table.show_frames, False)
    wait_for(lambda: not course.scene.x_axes.visible and not course.scene.z_axes.visible, what="the frames hidden")
    page.wait_for_timeout(2500)
    without = canvas_pixels(page)
    # nothing else moved: what changed is the frames (the renderer's colour management shifts
    # every colour a little, so the test compares two pictures rather than looking for one colour)
    assert changed(with_frames, without) > 0.003, "the frames' axes did not show, or did not go"
    # the first slider turns joint 1, in degrees, and the skeleton follows
    step_slider(page, course.joints.sliders[0], "ArrowRight", 1.0)
    wait_for(lambda: abs(np.degrees(course.state.last.q[0]) - 1.0) < 1e-6, what="A1 at 1°")
    # det J's factors drawn on the arm: axis 1, the links, axes 4 and 6, each named in 3D
    page.wait_for_timeout(2500)
    plain = canvas_pixels(page)
    set_checkbox(page, course.singularities.show, True)
    wait_for(lambda: course.scene.overlay.lines["wrist"].visible, what="the factors drawn")
    page.wait_for_timeout(2500)
    with_factors = canvas_pixels(page)
    assert changed(plain, with_factors) > 0.003, "the singular geometry did not show"
    # viser draws 3D labels on the canvas, not as page text: the label shows if hiding it changes the picture
    course.scene.overlay.labels["shoulder"].visible = False
    page.wait_for_timeout(2500)
    assert changed(with_factors, canvas_pixels(page)) > 0.0003, "the shoulder factor's 3D label was not drawn"


def test_typing_a_dh_table_builds_that_arm(open_page, app):
    page, session = open_page()
    client_id = next(k for k, v in app.sessions.items() if v is session)
    choose(page, session.arm_picker.dropdown, "Your own DH table")
    wait_for(lambda: isinstance(app.sessions.get(client_id), CourseArmSession), what="the editor's arm")
    first = app.sessions[client_id]
    label = f"label[for='{first.editor.rows._impl.uuid}']"  # a text field's label carries its uuid
    page.wait_for_selector(label, timeout=30_000)
    before = canvas_pixels(page)
    rows = page.locator(label).locator("xpath=ancestor::div[2]").locator("textarea").first
    rows.fill("400 0 300 0 R\n350 180 0 0 R\n0 0 100 0 P")  # a SCARA of the student's own
    page.wait_for_timeout(300)
    page.locator(dom_id(first.editor.build)).click()
    wait_for(lambda: app.sessions.get(client_id) is not first and getattr(app.sessions.get(client_id), "arm", None) is not None
             and app.sessions[client_id].arm.joint_types == "RRP", what="the typed arm")
    typed = app.sessions[client_id]
    page.wait_for_selector(dom_id(typed.joints.sliders[2]), timeout=30_000)
    assert page.get_by_text("joint 3 (mm)", exact=True).count() == 1  # the prismatic joint, in millimetres
    page.wait_for_timeout(2500)
    assert changed(before, canvas_pixels(page)) > 0.005, "the typed arm was not drawn"
    page.locator(dom_id(typed.search.button)).click()
    wait_for(lambda: typed.state.last.solution is not None, what="the numerical search")
    wait_for(lambda: page.get_by_text("found numerically 1", exact=True).count() > 0, what="the branches in the table")


def test_the_dh_walkthrough_draws_each_step(open_page, app):
    page, session = open_page()
    client_id = next(k for k, v in app.sessions.items() if v is session)
    choose(page, session.arm_picker.dropdown, "Elbow arm + spherical wrist")
    wait_for(lambda: isinstance(app.sessions.get(client_id), CourseArmSession), what="the elbow arm")
    course = app.sessions[client_id]
    page.wait_for_selector(dom_id(course.joints.sliders[0]), timeout=30_000)
    page.get_by_text("DH walkthrough", exact=True).first.click()  # folded by default
    next_button = page.get_by_role("button", name="Next ▶")
    next_button.wait_for(state="visible", timeout=10_000)
    page.wait_for_timeout(2000)
    frames = canvas_pixels(page)
    next_button.click()  # step 1: the z axes alone
    wait_for(lambda: course.walkthrough.step == 0 and not course.scene.x_axes.visible, what="step 1")
    wait_for(lambda: page.get_by_text("Step 1 — the z axes", exact=False).count() > 0, what="step 1's text")
    page.wait_for_timeout(2000)
    z_only = canvas_pixels(page)
    assert changed(frames, z_only) > 0.002, "the x axes did not go"
    next_button.click()  # step 2: the x axes back
    wait_for(lambda: course.walkthrough.step == 1 and course.scene.x_axes.visible, what="step 2")
    page.wait_for_timeout(2000)
    with_x = canvas_pixels(page)
    assert changed(z_only, with_x) > 0.002, "the x axes did not come back"
    page.wait_for_timeout(200)
    next_button.click()  # step 3: row 1's θ1 and α1 (its d1 too: a1 = 0 is listed, not drawn)
    wait_for(lambda: course.walkthrough.step == 2, what="step 3")
    wait_for(lambda: page.get_by_text("Row 1.", exact=False).count() > 0, what="row 1's text")
    page.wait_for_timeout(2000)
    assert changed(with_x, canvas_pixels(page)) > 0.002, "row 1's parameters are not drawn"
