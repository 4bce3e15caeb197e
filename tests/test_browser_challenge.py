"""A class challenge in real browsers: the presenter starts one, a student solves it, another does not, the projector shows both."""

from __future__ import annotations

import numpy as np
import pytest

from ur10teach.features.joint_panel import display_text
from ur10teach.serving.classroom import EXPLORER
from ur10teach.serving.gate import Gate
from ur10dev.browser import (
    HANG_TIMEOUT_MS, ask_to_present, canvas_changed, choose, class_browsers, click, dom_id, settled_canvas, type_text,
)
from ur10dev.waiting import wait_for

pytestmark = pytest.mark.browser


def test_a_presenter_and_two_students_run_a_reach_challenge(tmp_path):
    from ur10teach.serving.server import TeachingServer

    app = TeachingServer(port=0, shared=True, light=True, gate=Gate(trust_loopback=False))  # the projector types the code
    room = app.classroom
    try:
        with class_browsers(app, 3) as (pages, members):
            teacher, ada, bo = pages
            teacher_member, ada_member, bo_member = members
            ask_to_present(teacher, teacher_member, room.code, lambda: teacher_member.desk is not None,
                           "the presenter's Challenge folder")
            desk = teacher_member.desk
            teacher.wait_for_selector(dom_id(desk.picker), timeout=HANG_TIMEOUT_MS)
            choose(teacher, desk.picker, "Reach the target")
            # a time limit typed, then the box emptied: the class gets the limit the teacher's page still shows
            limit = teacher.locator(dom_id(desk.minutes)).locator("xpath=..")  # the slider and its number box
            limit.locator("input.mantine-NumberInput-input").fill("5")
            wait_for(lambda: desk.minutes.value == 5, what="the time limit typed")
            limit.locator("input.mantine-NumberInput-input").fill("")
            shown = float(limit.locator("[role=slider]").get_attribute("aria-valuenow"))
            click(teacher, desk.start, lambda: room.challenges.run is not None, "Start the challenge")
            assert room.challenges.run.time_limit == 60 * shown == 300

            # both students get their own arm and the task
            for page, member in ((ada, ada_member), (bo, bo_member)):
                wait_for(lambda: member.role == EXPLORER and member.card is not None, what="the student's card")
                wait_for(lambda: page.get_by_text("Put the tool on the orange target").count() > 0, what="the task on screen")

            # Ada names herself and types the target's joints; the server checks her arm, not her word
            type_text(ada, ada_member.card.nickname, "Ada")
            joints = ada_member.session.joints
            target_q = np.array(room.challenges.run.challenge.joints)
            type_text(ada, joints.typed, display_text(room.challenges.run.arm, target_q))
            click(ada, joints.apply_typed, lambda: np.allclose(ada_member.session.state.q, target_q, atol=1e-3), "Set these values")
            click(ada, ada_member.card.check, lambda: ada_member.student.attempts > 0, "Check my answer")
            wait_for(lambda: ada.get_by_text("✓ Solved: your tool is on the target").count() > 0, what="Ada's verdict")

            # Bo checks where his arm is: told how far off, and which way
            click(bo, bo_member.card.check, lambda: bo_member.student.attempts > 0, "Check my answer")
            wait_for(lambda: bo.get_by_text("Your tool is").count() > 0, what="Bo's verdict")
            assert bo.get_by_text("✓ Solved").count() == 0
            group = bo_member.student.verdict.group
            assert group.startswith("tool ")

            # the projector: the counts, the mistake, and both students' tools named in 3D
            wait_for(lambda: teacher.get_by_text("1 solved · 1 working · 2 joined").count() > 0, what="the projector's counts")
            wait_for(lambda: teacher.get_by_text(group).count() > 0, what="the projector's wrong answer")
            def named_tools():  # what the projector's scene is sent: a dot and a 3D name per student, at their tool
                tools = teacher_member.tools
                if tools is None or tools.names is None:
                    return None
                names = {text for _, text, _ in tools.names.placed}
                return tools.names.placed if names == {"✓ Ada", "student 2"} else None  # she has solved it

            wait_for(named_tools, what="the students' names by their tools")
            solved, working = teacher_member.tools.solved, teacher_member.tools.working
            assert solved.visible and working.visible and len(solved.points) == len(working.points) == 1
            # her dot at her tool, his at his (viser keeps a point cloud's points as float16)
            np.testing.assert_allclose(solved.points[0], ada_member.session.state.last.flange[:3, 3], atol=1e-3)
            np.testing.assert_allclose(working.points[0], bo_member.session.state.last.flange[:3, 3], atol=1e-3)
            shown = settled_canvas(teacher)
            teacher.screenshot(path=str(tmp_path / "projector.png"))
            # her green dot shows round the target's ball: hiding it changes the picture
            solved.visible = False
            canvas_changed(teacher, shown, 0.0002, "Ada's green dot to go")
            solved.visible = True

            # the end: everyone is shown the solution, and every arm moves to it
            click(teacher, desk.end, lambda: room.challenges.run.ended, "End and show the solution")
            for page, member in ((ada, ada_member), (bo, bo_member)):
                wait_for(lambda: page.get_by_text("The challenge has ended").count() > 0, what="the end on the student's screen")
                wait_for(lambda: np.allclose(member.session.state.q, target_q), what="the student's arm on the solution")
            wait_for(lambda: teacher.get_by_text("Ended").count() > 0, what="the end on the projector")
    finally:
        app.stop()


def test_the_script_takes_the_readmes_projector_screenshot(tmp_path, monkeypatch):
    """``scripts/screenshots.py`` is run by hand to retake the README's pictures, so nothing else noticed when it
    broke: until 2026-12-03 its projector shot called ``ask_to_present`` as it was before the helper took what to
    wait for, and failed. It takes the shot here, into a folder of the test's own."""
    from PIL import Image

    import scripts.screenshots as screenshots

    monkeypatch.setattr(screenshots, "OUT", tmp_path)
    screenshots.shoot_a_challenge("projector.png")
    pixels = np.asarray(Image.open(tmp_path / "projector.png").convert("RGB"), dtype=float)
    assert pixels.shape == (screenshots.WINDOW["height"], screenshots.WINDOW["width"], 3)
    assert pixels.std() > 20, "a blank picture"
