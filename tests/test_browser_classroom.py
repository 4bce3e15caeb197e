"""Shared demo mode in real browsers: the presenter moves the arm, a student watches, explores, comes back."""

from __future__ import annotations

import numpy as np
import pytest

from app.classroom import EXPLORER, PRESENTER, VIEWER

from .browser_support import ask_to_present, dom_id, step_slider, teacher_and_student, wait_for

pytestmark = pytest.mark.browser


def test_presenter_and_student(classroom, tmp_path):
    app = classroom
    with teacher_and_student(app) as (teacher, student, teacher_member, student_member):
        # a wrong code is refused in the browser; the right one makes a presenter
        ask_to_present(student, "AAA-AAA")
        wait_for(lambda: student.get_by_text("that is not the join code").count() > 0, what="the refusal")
        ask_to_present(teacher, app.classroom.code)
        wait_for(lambda: teacher_member.role == PRESENTER and teacher_member.session is not None, what="the presenter")
        wait_for(lambda: teacher.get_by_text("You are presenting").count() > 0, what="the presenter's status")

        # the presenter moves a joint; the student's live panel follows
        session = teacher_member.session
        teacher.wait_for_selector(dom_id(session.joints.sliders[0]), timeout=30_000)
        step_slider(teacher, session.joints.sliders[0], "ArrowRight", 35.0)
        wait_for(lambda: abs(np.degrees(app.classroom.state.q[0]) - 35.0) < 1e-6, what="the presenter's move")
        wait_for(lambda: student.get_by_text("base 35.00°").count() > 0, what="the student's live panel")
        assert student.locator("[role=slider]").count() == 0  # watching: nothing to move

        # the student explores on their own copy, starting from the class's pose
        student.get_by_role("button", name="Explore on my own").click()
        wait_for(lambda: student_member.role == EXPLORER and student_member.session is not None, what="exploring")
        own = student_member.session
        student.wait_for_selector(dom_id(own.joints.sliders[1]), timeout=30_000)
        np.testing.assert_allclose(own.state.q, app.classroom.state.q)
        step_slider(student, own.joints.sliders[1], "ArrowLeft", 42.0)
        wait_for(lambda: abs(np.degrees(own.state.q[1]) - 42.0) < 1e-6, what="the student's own move")
        assert abs(np.degrees(app.classroom.state.q[1]) - 45.0) < 1e-6  # the class's arm did not move

        # and comes back to the class
        student.get_by_role("button", name="Back to the presenter's arm").click()
        wait_for(lambda: student_member.role == VIEWER and student_member.session is None, what="coming back")
        wait_for(lambda: student.locator("[role=slider]").count() == 0, what="the private panel to go")
        student.screenshot(path=str(tmp_path / "student.png"))


def test_the_class_is_shown_a_scara_and_an_explorer_keeps_their_own(classroom, tmp_path):
    """The presenter picks the SCARA: the student's screen shows it in place of the UR10, with its
    live panel. Exploring it, the student keeps their own arm on screen when the class goes back
    to the UR10 (the shared UR10 is hidden in that one browser)."""
    from app.arm_picker import SWITCH_INTERVAL, UR10
    from app.course_arms.session import CourseArmSession

    from .browser_support import changed, choose, settled_canvas, where_changed

    app = classroom
    with teacher_and_student(app) as (teacher, student, teacher_member, student_member):
        ask_to_present(teacher, app.classroom.code)
        wait_for(lambda: teacher_member.picker is not None, what="the presenter's picker")
        watching_ur10 = settled_canvas(student)

        teacher.wait_for_timeout(1000 * SWITCH_INTERVAL)
        choose(teacher, teacher_member.picker.dropdown, "SCARA (RRP + roll)")
        wait_for(lambda: isinstance(teacher_member.session, CourseArmSession), what="the class's SCARA")
        wait_for(lambda: student.get_by_text("SCARA (RRP + roll)").count() > 0, what="the student's live panel")
        student.wait_for_timeout(1000)
        watching_scara = settled_canvas(student)
        assert changed(watching_ur10, watching_scara) > 0.02, "the student's screen did not change arm"

        student.get_by_role("button", name="Explore on my own").click()
        wait_for(lambda: isinstance(student_member.session, CourseArmSession), what="the student's own SCARA")
        student.wait_for_timeout(1000)
        exploring = settled_canvas(student)
        wait_for(lambda: teacher_member.picker.dropdown.value == "SCARA (RRP + roll)", what="the picker")
        choose(teacher, teacher_member.picker.dropdown, UR10)
        wait_for(lambda: app.classroom.course is None, what="the class's UR10")
        student.wait_for_timeout(1000)
        still_exploring = settled_canvas(student)
        student.screenshot(path=str(tmp_path / "explorer.png"))
        # the class's UR10 would cover a good part of the view (about a third when it replaced the
        # SCARA above); the explorer's own arm stays as it was
        assert changed(exploring, still_exploring) < 0.005, (
            f"the class's UR10 showed over the explorer's own arm: {where_changed(exploring, still_exploring)}")
