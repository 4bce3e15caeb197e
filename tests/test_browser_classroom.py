"""Shared demo mode in real browsers: the presenter moves the arm, a student watches, explores, comes back;
the presenter shows the class a SCARA, and an explorer keeps their own arm when the class moves on."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from ur10teach.serving.classroom import EXPLORER, PRESENTER, VIEWER
from ur10teach.serving.gate import Gate
from ur10dev.browser import (
    HANG_TIMEOUT_MS, PHONE, ask_to_present, changed, choose, class_browsers, click, dom_id, settled_canvas, step_slider,
    teacher_and_student, where_changed,
)
from ur10dev.waiting import wait_for

from .test_browser_lecture_hall import overlaps, steady, steady_boxes
from .test_browser_readability import above_the_panel, key_points

pytestmark = pytest.mark.browser


def test_a_class_follows_the_presenter_and_a_student_explores(tmp_path):
    from ur10teach.features.arm_picker import UR10
    from ur10teach.serving.server import TeachingServer

    app = TeachingServer(port=0, shared=True, light=True, gate=Gate(trust_loopback=False))  # the projector types the code
    try:
        with teacher_and_student(app) as (teacher, student, teacher_member, student_member):
            # a wrong code is refused in the browser; the right one makes a presenter
            ask_to_present(student, student_member, "AAA-AAA",
                           lambda: student.get_by_text("that is not the join code").count() > 0, "the refusal")
            ask_to_present(teacher, teacher_member, app.classroom.code, lambda: teacher_member.role == PRESENTER, "the presenter")
            wait_for(lambda: teacher_member.session is not None, what="the presenter's arm")
            wait_for(lambda: teacher.get_by_text("You are presenting").count() > 0, what="the presenter's status")

            # the presenter moves a joint; the student's live panel follows
            session = teacher_member.session
            teacher.wait_for_selector(dom_id(session.joints.sliders[0]), timeout=HANG_TIMEOUT_MS)
            step_slider(teacher, session.joints.sliders[0], "ArrowRight", 32.0)
            wait_for(lambda: abs(np.degrees(app.classroom.state.q[0]) - 32.0) < 1e-6, what="the presenter's move")
            wait_for(lambda: student.get_by_text("base 32.00°").count() > 0, what="the student's live panel")
            assert student.locator("[role=slider]").count() == 0  # watching: nothing to move

            # the student explores on their own copy, starting from the class's pose, and comes back
            click(student, student.get_by_role("button", name="Explore on my own"),
                  lambda: student_member.role == EXPLORER and student_member.session is not None, "exploring")
            own = student_member.session
            student.wait_for_selector(dom_id(own.joints.sliders[1]), timeout=HANG_TIMEOUT_MS)
            np.testing.assert_allclose(own.state.q, app.classroom.state.q)
            step_slider(student, own.joints.sliders[1], "ArrowLeft", 44.0)
            wait_for(lambda: abs(np.degrees(own.state.q[1]) - 44.0) < 1e-6, what="the student's own move")
            assert abs(np.degrees(app.classroom.state.q[1]) - 45.0) < 1e-6  # the class's arm did not move
            click(student, student.get_by_role("button", name="Back to the presenter's arm"),
                  lambda: student_member.role == VIEWER and student_member.session is None, "coming back")
            wait_for(lambda: student.locator("[role=slider]").count() == 0, what="the private panel to go")

            # the presenter shows the class the SCARA: the student's screen changes arm, with its live panel
            watching_ur10 = settled_canvas(student)
            wait_for(app.classroom.can_switch, what="the class's arm to be ready for a change")
            choose(teacher, teacher_member.picker.dropdown, "SCARA (RRP + roll)")
            wait_for(lambda: teacher_member.session is not None and teacher_member.session.arm.name == "scara",
                     what="the class's SCARA")
            wait_for(lambda: student.get_by_text("SCARA (RRP + roll)").count() > 0, what="the student's live panel")
            wait_for(lambda: changed(watching_ur10, settled_canvas(student)) > 0.02, what="the student's screen to change arm")

            # exploring the SCARA, the student keeps their own arm on screen when the class goes back to the UR10
            click(student, student.get_by_role("button", name="Explore on my own"),
                  lambda: student_member.session is not None and student_member.session.built, "the student's own SCARA")
            steady(student_member.session)  # its labels placed for the student's camera, which has come to rest
            exploring = settled_canvas(student)
            wait_for(app.classroom.can_switch, what="the class's arm to be ready for a change")
            choose(teacher, teacher_member.picker.dropdown, UR10)
            wait_for(lambda: app.classroom.choice == UR10, what="the class's UR10")
            # the class's UR10 reaches the student's browser, hidden there by a node of the student's own
            # (viser draws a client's node over the shared one of the same name)
            steady(student_member.session)  # its own labels at rest again, as before the switch
            still_exploring = settled_canvas(student)
            student.screenshot(path=str(tmp_path / "explorer.png"))
            # the class's UR10 would cover a good part of the view (about a third when it replaced the
            # SCARA above); the explorer's own arm stays as it was, but for a label or an edge redrawn a
            # pixel apart (0.58 % changed once on a loaded machine, scattered over the arm)
            assert changed(exploring, still_exploring) < 0.03, (
                f"the class's UR10 showed over the explorer's own arm: {where_changed(exploring, still_exploring)}")
    finally:
        app.stop()


def test_a_phone_watching_the_class_sees_the_arm_above_the_panel():
    """A phone's page in the classroom, once settled: the class's arm above the panel. Its camera is framed as the
    page joins, and viser's page may put it back at the initial camera as its 3D view mounts, late on a phone. That
    happened in seven of eight probe runs here (not in this test's runs so far), and the arm stood under the panel;
    the server test of it is ``test_a_page_that_puts_its_camera_back_at_the_start_is_framed_again``."""
    from ur10teach.serving.server import TeachingServer

    app = TeachingServer(port=0, shared=True, light=True, gate=Gate(trust_loopback=False))  # a student's phone
    try:
        with class_browsers(app, 1, {"width": 390, "height": 664}, PHONE) as ([page], [member]):
            assert member.camera.phone
            explore = page.get_by_role("button", name="Explore on my own")
            explore.wait_for(timeout=HANG_TIMEOUT_MS)
            settled_canvas(page)  # (the framing arrives before the 3D view has mounted: the arm as it then settles)
            wait_for(lambda: above_the_panel(page, member.client.camera, key_points(app.classroom), explore),
                     what="the class's arm framed above the panel")
            # its branch numbers apart: the class's labels placed for its camera (until 2026-12-07 the class's
            # larger screens' placing, which crowded "arm: 5" onto "2" and "4" here)
            boxes = steady_boxes(page, SimpleNamespace(client=member.client, refresher=app.refresher))
            assert len(boxes) >= 6 and not overlaps(boxes), overlaps(boxes)
    finally:
        app.stop()
