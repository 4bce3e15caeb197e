"""The course's other arms in real headless Chromium: the picker, an arm with its DH frames, a typed table, the walkthrough."""

from __future__ import annotations

import numpy as np
import pytest
from ur10teach.serving.gate import BROWSER_COOKIE, browser_of
from ur10dev.browser import (
    HANG_TIMEOUT_MS, a_site_linking_to, canvas_changed, choose, click, dom_id, lose_the_next_value, set_checkbox, settled_canvas, step_slider, unfold,
)
from ur10dev.waiting import wait_for

pytestmark = pytest.mark.browser


def pick(page, app, client_id: int, label: str):
    """Choose ``label`` in this browser's "Arm" dropdown once a change is allowed; returns the new session."""
    current = app.sessions[client_id]
    wait_for(lambda: app.can_switch(client_id), what="the arm to be ready for a change")
    choose(page, current.arm_picker.dropdown, label)
    wait_for(lambda: app.sessions.get(client_id) not in (current, None) and app.sessions[client_id].built, what=f"the {label}'s session")
    session = app.sessions[client_id]
    page.wait_for_selector(dom_id(session.joints.sliders[0]), timeout=HANG_TIMEOUT_MS)
    return session


def test_the_course_arms_in_the_picker(open_page, light_app):
    """The KR210 with its DH frames and det J's factors on the arm, a table a student types, and the
    elbow arm's DH walkthrough, one after the other in one browser; then the page reloaded finds them again."""
    app = light_app
    page, session = open_page()
    client_id = next(k for k, v in app.sessions.items() if v is session)

    # the KR210: the panel shows the branches, det J's factors with their meaning, and the DH table
    before = settled_canvas(page)
    # each of this browser's first pick, click and press reaches the server only when made again (a CI run once
    # lost a pick: the helpers undo and redo a change the browser shows and the server does not hold)
    lose_the_next_value(session.client, session.arm_picker.dropdown)
    kr210 = pick(page, app, client_id, "KR210 (spherical wrist)")
    wait_for(lambda: page.get_by_text("reach this target", exact=False).count() > 0, what="the branch table")
    assert page.get_by_text("shoulder front, elbow up, wrist not flipped").count() >= 1
    assert page.get_by_text("the wrist centre is on axis 1", exact=False).count() >= 1
    assert page.get_by_text("As defined (modified DH)", exact=False).count() >= 1
    with_frames = canvas_changed(page, before, 0.02, "the KR210 drawn in place of the UR10")
    # the DH frames' x axes (red) and z axes (blue) are on screen, and go when switched off (the renderer's
    # colour management shifts every colour a little, so the test compares two pictures, not one colour)
    unfold(page, "DH table", kr210.dh_table.show_frames)
    lose_the_next_value(kr210.client, kr210.dh_table.show_frames)
    set_checkbox(page, kr210.dh_table.show_frames, False)
    wait_for(lambda: not kr210.drawing.dh_frames.x_axes.visible and not kr210.drawing.dh_frames.z_axes.visible, what="the frames hidden")
    canvas_changed(page, with_frames, 0.003, "the frames' axes to go")
    # the first slider turns joint 1, in degrees, and the skeleton follows
    lose_the_next_value(kr210.client, kr210.joints.sliders[0])
    step_slider(page, kr210.joints.sliders[0], "ArrowRight", 1.0)
    wait_for(lambda: abs(np.degrees(kr210.state.last.q[0]) - 1.0) < 1e-6, what="A1 at 1°")
    # det J's factors drawn on the arm: axis 1, the links, axes 4 and 6, each named in 3D
    plain = settled_canvas(page)
    unfold(page, "Singularities", kr210.singularities.enabled)
    set_checkbox(page, kr210.singularities.enabled, True)
    wait_for(lambda: kr210.drawing.overlay.lines["wrist"].visible, what="the factors drawn")
    with_factors = canvas_changed(page, plain, 0.003, "the singular geometry to show")
    # viser draws 3D labels on the canvas, not as page text: the label shows if hiding it changes the picture
    wait_for(lambda: "shoulder" in kr210.drawing.overlay.labels, what="the names placed")
    kr210.drawing.overlay.labels["shoulder"].visible = False
    canvas_changed(page, with_factors, 0.0003, "the shoulder factor's 3D label to go")

    # a table of the student's own: a SCARA, its prismatic joint in millimetres, its branches found numerically
    editor = pick(page, app, client_id, "Your own DH table")
    label = f"label[for='{editor.editor.rows._impl.uuid}']"  # a text field's label carries its uuid
    page.wait_for_selector(label, timeout=HANG_TIMEOUT_MS)
    before = settled_canvas(page)
    rows = page.locator(label).locator("xpath=ancestor::div[2]").locator("textarea").first
    typed_rows = "400 0 300 0 R\n350 180 0 0 R\n0 0 100 0 P"
    rows.fill(typed_rows)
    wait_for(lambda: editor.editor.rows.value == typed_rows, what="the server to hold the typed rows")
    wait_for(lambda: app.can_switch(client_id), what="the arm to be ready for a change")
    click(page, editor.editor.build, lambda: app.sessions.get(client_id) is not editor
          and getattr(app.sessions.get(client_id), "arm", None) is not None
          and app.sessions[client_id].arm.joint_types == "RRP" and app.sessions[client_id].built, "the typed arm")
    typed = app.sessions[client_id]
    page.wait_for_selector(dom_id(typed.joints.sliders[2]), timeout=HANG_TIMEOUT_MS)
    assert page.get_by_text("joint 3 (mm)", exact=True).count() == 1  # the prismatic joint, in millimetres
    canvas_changed(page, before, 0.005, "the typed arm drawn")
    click(page, typed.search.button, lambda: typed.state.last.solution is not None, "the numerical search")
    wait_for(lambda: page.get_by_text("found numerically 1", exact=True).count() > 0, what="the branches in the table")

    # the elbow arm's DH walkthrough: the z axes alone, the x axes back, then row 1's parameters drawn
    elbow = pick(page, app, client_id, "Elbow arm + spherical wrist")
    next_button = page.get_by_role("button", name="Next ▶")
    unfold(page, "DH walkthrough", next_button)  # folded by default
    frames = settled_canvas(page)
    click(page, next_button, lambda: elbow.walkthrough.step == 0, "step 1")
    wait_for(lambda: not elbow.drawing.dh_frames.x_axes.visible, what="the x axes hidden")
    wait_for(lambda: page.get_by_text("Step 1 — the z axes", exact=False).count() > 0, what="step 1's text")
    z_only = canvas_changed(page, frames, 0.002, "the x axes to go")
    click(page, next_button, lambda: elbow.walkthrough.step == 1, "step 2")
    wait_for(lambda: elbow.drawing.dh_frames.x_axes.visible, what="the x axes back")
    with_x = canvas_changed(page, z_only, 0.002, "the x axes to come back")
    click(page, next_button, lambda: elbow.walkthrough.step == 2, "step 3")  # row 1's θ1 and α1 (d1 too: a1 = 0 is listed, not drawn)
    wait_for(lambda: page.get_by_text("Row 1.", exact=False).count() > 0, what="row 1's text")
    canvas_changed(page, with_x, 0.002, "row 1's parameters drawn")

    # the page reloaded (viser makes it a new client): the elbow arm is back, and so is the typed table
    page.reload()
    wait_for(lambda: any(k != client_id and s.built and s.choice == "Elbow arm + spherical wrist"
                         for k, s in app.sessions.items()), what="the elbow arm back after the reload")
    client_id = next(k for k, s in app.sessions.items() if s.choice == "Elbow arm + spherical wrist")
    # known by the cookie its page was given, which Chromium's websocket sent back: not by its address alone
    assert browser_of(app.sessions[client_id].client).startswith("127.0.0.1 ")
    wait_for(lambda: page.get_by_text("Your arms are as this browser left them.", exact=True).count() > 0, what="the welcome back")
    page.wait_for_selector(dom_id(app.sessions[client_id].joints.sliders[0]), timeout=HANG_TIMEOUT_MS)
    typed_back = pick(page, app, client_id, "Your own DH table")
    assert typed_back.arm.joint_types == "RRP" and typed_back.editor.rows.value == typed_rows

    # the app opened again from a link on another site (a course's page): the page still sends its cookie, and is
    # not given a new one (with SameSite=Strict it was, and the browser lost its arms)
    cookie = [c["value"] for c in page.context.cookies() if c["name"] == BROWSER_COOKIE]
    with a_site_linking_to(page.url) as course_page:
        page.goto(course_page)
        page.click("#app")
        page.wait_for_load_state()
    page.requests[:] = [request for request in page.requests if not request.startswith(course_page)]  # (the test's, not the app's)
    assert len(cookie) == 1 and [c["value"] for c in page.context.cookies() if c["name"] == BROWSER_COOKIE] == cookie


def test_a_click_on_a_ghost_puts_the_arm_on_its_branch(open_page, light_app):
    """The IK folder says: click a ghost to put the arm on its branch. In the browser, on the UR10's mesh ghosts and
    on the balls at a line-drawn ghost's joints (viser reports no click on a line: until 2026-12-05 a click on the
    Stanford arm's ghosts did nothing)."""
    from ur10core import Arm
    from ur10teach.features.branch_labels import ScreenView

    from .server_support import a_ghost_to_take

    app = light_app
    page, session = open_page()
    client_id = next(k for k, v in app.sessions.items() if v is session)
    canvas = page.locator("canvas").first.bounding_box()

    def click_at(point: np.ndarray, session) -> None:
        """Click where the browser's camera shows ``point`` (world, m)."""
        settled_canvas(page)
        (x, y), = ScreenView.of(session.client.camera).to_screen(np.asarray(point, dtype=float)[None])[0]
        page.mouse.click(canvas["x"] + canvas["width"] / 2 + x, canvas["y"] + canvas["height"] / 2 - y)

    snapshot = session.state.last
    slot = int(np.flatnonzero(session.drawing.branches.shown)[0])
    click_at(snapshot.ghost_frames[slot, 2:4, :3, 3].mean(axis=0), session)  # the middle of its forearm
    wait_for(lambda: session.state.last.slot == slot, what=f"the UR10 on branch {slot + 1}")

    q, slot = a_ghost_to_take(Arm.preset("stanford"))
    stanford = pick(page, app, client_id, "Stanford arm (RRP + wrist)")
    stanford.apply(lambda state: state.set_joints(q, cause="typed"))
    drawing = stanford.drawing
    balls = lambda: drawing.ghost_joints.batched_scales.reshape(-1, drawing.joints_per_ghost)  # noqa: E731
    wait_for(lambda: balls()[slot].any(), what=f"ghost {slot + 1}'s joints drawn")
    ball = drawing.ghost_joints.batched_positions[slot * drawing.joints_per_ghost + int(np.argmax(balls()[slot]))]
    click_at(ball @ drawing.world[:3, :3].T + drawing.world[:3, 3], stanford)
    wait_for(lambda: stanford.state.last.slot == slot, what=f"the Stanford arm on branch {slot + 1}")
