"""Class challenges end to end: a presenter and thirty headless students, every built-in kind, the projector's numbers exact."""

from __future__ import annotations

import asyncio
import codecs
import dataclasses
import functools
import itertools
import math
import re
import time
import types

import numpy as np
import pytest

from ur10core import Arm, challenges as C
from ur10core.dh import DHTable
from ur10core.orientation import zyx_euler
from ur10teach.features.branch_labels import JOIN
from ur10teach.features.arm_picker import ARM_CHOICES
from ur10teach.features.challenge import GOAL_RADIUS, GOAL_ROOT, SOLVED_MARK, WORKING_DOT
from ur10teach.style import UR10_SIZE
from ur10teach.features.course_arms.editor import CONVENTIONS
from ur10teach.features.joint_panel import display_text, rate_label, typed_label
from ur10teach.serving.gate import address_of
from ur10teach.serving.challenge_run import ChallengeRun, clean_nickname, spreadsheet_safe, summary_markdown
from ur10teach.serving.classroom import PRESENTER
from ur10teach.view import HELD_BACK
from ur10dev.viser_client import ViserClient, messages
from ur10dev.waiting import HANG_TIMEOUT

from .server_support import become_presenter, drag_a_little, until, url
from .test_faults import without_failures

pytestmark = pytest.mark.server

STUDENTS = 30
SCARA = next(label for label, name in ARM_CHOICES.items() if name == "scara")
#: What each student does in each challenge: "right", a wrong answer of group "a" or "b", "idle" (never touches
#: it) or "leave" (answers wrong, group "a", then closes the browser; back from the same computer afterwards).
PLAN = ["right"] * 9 + ["a"] * 7 + ["b"] * 5 + ["idle"] * 3 + ["leave"] * 3 + ["right", "a", "b"]
KIND_TITLES = {"reach": "Reach it elbow down", "singularity": "Wrist singularity, tool up high",
               "branch_count": "Four branches only", "numbers": "Where is the flange?",
               "velocity": "Straight up", "dh_table": "Type the UR10's DH table"}
GROUPS = {"reach": ("elbow up instead of elbow down", "tool too high"),
          "singularity": ("elbow instead of wrist", "tool below 500 mm"),
          "branch_count": ("8 branches instead of 4", "0 branches instead of 4"),
          "numbers": ("y has the wrong sign", "x, y, z are in metres, not mm"),
          "velocity": ("wrong sign", "not moving"),
          "dh_table": ("row 2: α has the wrong sign", "wrong joints")}


def board_numbers(text: str) -> dict | None:
    """What the projector's board says: the counts, and each mistake's count (None for another markdown)."""
    counts = re.search(r"\*\*(\d+)\*\* solved · \*\*(\d+)\*\* working · \*\*(\d+)\*\* joined", text)
    if counts is None:
        return None
    solved, working, joined = (int(v) for v in counts.groups())
    away = re.search(r"\((\d+) away\)", text)
    groups = {g.strip(): int(n) for n, g in re.findall(r"^\| (\d+) \| (.+) \|$", text, re.M)}
    return {"solved": solved, "working": working, "joined": joined, "away": int(away.group(1)) if away else 0, "groups": groups}


def table_text(table) -> str:
    return "\n".join(f"{1000 * r.a:.4f} {math.degrees(r.alpha):.6f} {1000 * r.d:.4f} {math.degrees(r.theta):.6f} "
                     f"{r.joint or 'F'}" for r in table.rows)


def pose_text(T: np.ndarray) -> str:
    return " ".join(f"{v:.6f}" for v in [*(1000 * T[:3, 3]), *np.degrees(zyx_euler(T[:3, :3]))])


class Answers:
    """What a student types or sets, through the panel as a browser would, for each kind and plan."""

    def __init__(self, server) -> None:
        self.room = server.classroom
        self.arm = server.arm

    def challenge(self, kind: str) -> C.Challenge:
        return next(c for c in self.room.challenges.offered if c.title == KIND_TITLES[kind])

    async def give(self, client: ViserClient, member, kind: str, plan: str) -> None:
        arm, challenge = self.arm, self.challenge(kind)
        wrong = {"a": 0, "leave": 0, "b": 1}.get(plan)
        if kind in ("reach", "singularity"):
            if kind == "reach":
                goal = arm.fk(challenge.joints)
                if plan == "b":
                    goal[2, 3] += 0.03
                q = (C.solution(challenge, arm)[0] if plan == "right" else
                     np.array(challenge.joints) if wrong == 0 else arm.ik(goal).q[1])  # slot 2: elbow down, 30 mm high
            else:
                q = np.radians([[30, 80, -40, 50, 0, 80], [30, 80, 0, 50, 60, 80], [30, -30, 20, 50, 0, 80]][
                    0 if plan == "right" else 1 + wrong])
            # the panel shows the joints it last drew there: once it shows the arm's own, it will not overwrite the typing
            await until(lambda: client.gui.get(typed_label(arm), {}).get("value") == display_text(arm, member.session.state.q),
                        what="the panel's joints up to date")
            await client.set_gui(typed_label(arm), " ".join(f"{v:.9f}" for v in np.degrees(q)))
            await client.set_gui("Set these values", True)
            await until(lambda: np.allclose(member.session.state.q, q, atol=1e-6), what="the typed joints")
        elif kind == "branch_count":
            T = arm.fk(challenge.joints)
            T[:3, 3] = {"right": (0.0, -1.1, 0.2), 0: (0.6, -0.16, 0.5), 1: (3.0, 0.0, 0.5)}[plan if plan == "right" else wrong]
            await client.set_gui("Target x y z (mm), α β γ (°)", pose_text(T))
            await client.set_gui("Move target here", True)
            await until(lambda: np.allclose(member.session.state.last.target[:3, 3], T[:3, 3], atol=1e-6), what="the typed target")
        elif kind == "numbers":
            p = C.expected_numbers(challenge, arm)
            typed = p if plan == "right" else p * [1, -1, 1] if wrong == 0 else p / 1000
            await client.set_gui("Your numbers (x, y, z)", " ".join(f"{v:.6f}" for v in typed))
        elif kind == "velocity":
            if plan != "b":  # "b": never moves a slider
                q = member.session.state.q
                rates = np.degrees(arm.joint_rates(q, [0, 0, 0.1, 0, 0, 0]).qdot) * (1 if plan == "right" else -1)
                for k, rate in enumerate(rates):
                    await client.set_gui(rate_label(arm, k), round(float(rate), 1))
                await until(lambda: np.allclose(np.degrees(member.session.velocity.joint_rates()), np.round(rates, 1), atol=1e-9),
                            what="the joint rates")
        elif kind == "dh_table":
            rows = list(arm.dh.rows)
            if plan != "right" and wrong == 0:
                rows[1] = (rows[1].a, -rows[1].alpha, rows[1].d, rows[1].theta, rows[1].joint)
            if wrong == 1:
                rows = rows[:5]
            await client.set_gui("Your DH table (a α d θ type, mm and °)", table_text(DHTable(rows, arm.dh.convention)))
            await client.set_gui("Convention", next(k for k, v in CONVENTIONS.items() if v == arm.dh.convention))
        await client.set_gui("Check my answer", True)


def test_thirty_students_every_kind_and_the_projector_counts_exactly(classroom):
    answers = Answers(classroom)
    room = classroom.classroom
    assert room.challenges.offered == C.builtin()

    async def scenario():
        teacher = await ViserClient(url(classroom)).connect()
        await become_presenter(teacher, classroom)
        addresses = [f"127.0.0.{10 + k}" for k in range(STUDENTS)]
        students = [await ViserClient(url(classroom), local_address=a).connect() for a in addresses]

        def member_of(k: int):
            return next((m for m in list(room.members.values()) if address_of(m.client) == addresses[k]), None)

        for kind in ("numbers", "reach", "singularity", "branch_count", "velocity", "dh_table"):
            challenge = answers.challenge(kind)
            await teacher.set_gui("Challenge", challenge.title)
            await teacher.set_gui("Start the challenge", True)
            await until(lambda: room.challenges.run is not None and room.challenges.run.challenge is challenge and not room.challenges.run.ended
                        and all(m.card is not None and m.session is not None and m.session.built
                                for m in room.members.values() if m is not room.presenter), what=f"every card of {kind}")
            # every student's browser shows the task
            await until(lambda: all(s.shown(challenge.text[:30]) for s in students), what="the task on every screen")
            await asyncio.gather(*(answers.give(s, member_of(k), kind, plan if plan != "leave" else "a")
                                   for k, (s, plan) in enumerate(zip(students, PLAN)) if plan != "idle"))
            await until(lambda: room.challenges.run.summary().checked == STUDENTS - PLAN.count("idle"), what=f"every check of {kind}")
            leaving = [k for k, plan in enumerate(PLAN) if plan == "leave"]
            kept = {k: member_of(k).student for k in leaving}
            for k in leaving:
                await students[k].close()
            right, a, b = PLAN.count("right"), PLAN.count("a") + len(leaving), PLAN.count("b")
            expected = {"solved": right, "working": a + b, "joined": STUDENTS, "away": len(leaving),
                        "groups": {GROUPS[kind][0]: a, GROUPS[kind][1]: b}}
            await until(lambda: any(board_numbers(t) == expected for t in teacher.shown(f"### {challenge.title}")),
                        what=f"the projector's exact counts for {kind}: {expected}, shown {teacher.shown('### ')}")
            # each student read what is off, specifically
            for k, plan in enumerate(PLAN):
                if plan in ("right", "a", "b"):
                    verdicts = students[k].shown("(check 1)")
                    assert verdicts and ("✓ Solved" in verdicts[0]) == (plan == "right"), (kind, k, verdicts)
            if challenge.is_pose:  # every student here is named in 3D on the projector (names at one spot read as one)
                here = {member_of(k).student.name for k in range(STUDENTS) if k not in leaving}

                def named() -> set[str]:  # what the server has drawn in the presenter's scene
                    tools = room.presenter.tools
                    return set() if tools is None or tools.names is None else {
                        name for label in tools.names.labels if label.visible for name in label.text.replace("\n", JOIN).split(JOIN)}

                solved_names = {SOLVED_MARK + member_of(k).student.name for k, plan in enumerate(PLAN) if plan == "right"}
                await until(lambda: named() == (here - {name.removeprefix(SOLVED_MARK) for name in solved_names}) | solved_names,
                            what="the students' names in 3D, a solved one marked")
                # a dot at each tool: green for the solved, drawn larger than the orange ones (a crowd of working
                # students round the target covered the green dots there), and larger than the target's ball
                tools = room.presenter.tools
                def dots(cloud) -> int:
                    return len(cloud.points) if cloud.visible else 0

                await until(lambda: (dots(tools.solved), dots(tools.working)) == (right, STUDENTS - len(leaving) - right),
                            what="a dot per student, of their colour")
                assert tools.solved.point_size > max(tools.working.point_size, 2 * GOAL_RADIUS)
            # back from the same computers: the attempt is theirs again
            for k in leaving:
                students[k] = await ViserClient(url(classroom), local_address=addresses[k]).connect()
            await until(lambda: all(member_of(k) is not None and member_of(k).student is kept[k] for k in leaving),
                        what="the returning students' attempts")
            assert all(kept[k].attempts == 1 and kept[k].verdict.group == GROUPS[kind][0] for k in leaving)
            await until(lambda: all(students[k].shown("(check 1)") for k in leaving), what="their verdict shown again")
            await teacher.set_gui("End and show the solution", True)
            await until(lambda: room.challenges.run.ended and all(s.shown("The challenge has ended") for s in students),
                        what="the end on every screen")
            if challenge.is_pose:  # every arm moved to the solution
                q, _ = C.solution(challenge, classroom.arm)
                assert all(np.allclose(member_of(k).session.state.q, q) for k in range(STUDENTS))
                assert np.allclose(room.state.q, q)
            rows = room.challenges.run.results_csv().decode("utf-8-sig").splitlines()
            assert len(rows) == 1 + STUDENTS and rows[0] == "student,nickname,attempts,solved,seconds_to_solve,final_answer"
            assert sum(",yes," in row for row in rows) == PLAN.count("right")
        for client in (teacher, *students):
            await client.close()

    asyncio.run(scenario())


async def a_student_in(classroom, title: str, address: str) -> tuple[ViserClient, ViserClient, object]:
    """A teacher presenting, one student from ``address``, the challenge ``title`` started: (teacher, student, the
    student's member) once the student has the task."""
    room = classroom.classroom
    teacher = await ViserClient(url(classroom)).connect()
    await become_presenter(teacher, classroom)
    student = await ViserClient(url(classroom), local_address=address).connect()
    await teacher.set_gui("Challenge", title)
    await teacher.set_gui("Start the challenge", True)
    await until(lambda: any(m.card is not None for m in room.members.values()), what="the card")
    return teacher, student, next(m for m in room.members.values() if m.card is not None)


def test_a_student_back_before_the_server_noticed_they_had_gone_keeps_their_number_and_attempt():
    """A page whose websocket dropped retries every second, and is often back before the server notices its old
    connection has died (viser's websockets ping every 20 s and wait 20 s more). It joined as a new student: the
    board counted one student twice, and the attempt and the arm as left were not theirs (until 2026-12-05)."""
    from ur10teach.serving.gate import Gate
    from ur10teach.serving.server import TeachingServer

    classroom = TeachingServer(port=0, shared=True, gate=Gate(trust_loopback=False))  # loopback addresses stand for laptops
    room = classroom.classroom

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Where is the flange?", "127.0.0.9")
        attempt = member.student
        await student.set_gui("Your numbers (x, y, z)", "1 2 3")
        await until(lambda: member.card.typed().get("numbers") == "1 2 3", what="the typing on the server")
        student.freeze()  # off the network: its old connection answers nothing, and nothing has told the server
        again = await ViserClient(url(classroom), local_address="127.0.0.9").connect()
        await until(lambda: any(m.student is attempt and m.client.client_id == int(again.gizmo_owner or -1)
                                for m in room.members.values()), what="the same student back")
        assert len(room.challenges.run.students) == 1 and attempt.connected
        await until(lambda: (again.gui.get("Your numbers (x, y, z)") or {}).get("value") == "1 2 3", what="their typing back")
        for client in (teacher, again):
            await client.close()
        student.abort()

    asyncio.run(scenario())
    classroom.stop()


def test_students_behind_one_address_each_keep_their_own_attempt_and_none_takes_the_presenters_role(monkeypatch):
    """A class behind a router's NAT reaches the server from one address. Known by it alone, a student whose Wi-Fi
    dropped came back to the attempt of whoever else had left from there (their answer typed, their checks, their
    "Solved"), a new student joined as one who had left, and the first browser there after the presenter's had gone
    became the presenter, without the join code (until 2026-12-06). Each browser now has its own cookie."""
    from ur10teach.serving import gate
    from ur10teach.serving.server import TeachingServer

    monkeypatch.setattr(gate, "NEW_CONNECTION_BURST", 10)  # (the pace of one address's arrivals is not tested here)
    classroom = TeachingServer(port=0, shared=True, gate=gate.Gate(trust_loopback=False))  # loopback addresses stand for laptops
    room, nat = classroom.classroom, "127.0.0.9"
    cookie = {name: f"ur10teach_browser={name * 22}" for name in "apsb"}

    def member_with(client):
        return next((m for m in list(room.members.values()) if m.client.client_id == int(client.gizmo_owner or -1)), None)

    async def scenario():
        teacher = await ViserClient(url(classroom), local_address=nat, cookie=cookie["p"]).connect()
        await become_presenter(teacher, classroom)
        ada = await ViserClient(url(classroom), local_address=nat, cookie=cookie["a"]).connect()
        await teacher.set_gui("Challenge", "Where is the flange?")
        await teacher.set_gui("Start the challenge", True)
        await until(lambda: (member_with(ada) or types.SimpleNamespace(card=None)).card is not None, what="Ada's card")
        attempt = member_with(ada).student
        await answer(ada, member_with(ada), "1 2 3", 1)
        await ada.close()
        await until(lambda: not attempt.connected, what="Ada away")
        bo = await ViserClient(url(classroom), local_address=nat, cookie=cookie["b"]).connect()
        await until(lambda: (member_with(bo) or types.SimpleNamespace(card=None)).card is not None, what="Bo's card")
        assert member_with(bo).student is not attempt and member_with(bo).student.attempts == 0
        await until(lambda: "Your numbers (x, y, z)" in bo.gui, what="Bo's answer box")
        assert not bo.gui["Your numbers (x, y, z)"].get("value")  # not Ada's "1 2 3"
        again = await ViserClient(url(classroom), local_address=nat, cookie=cookie["a"]).connect()
        await until(lambda: (member_with(again) or types.SimpleNamespace(student=None)).student is attempt, what="Ada's attempt back")
        await until(lambda: (again.gui.get("Your numbers (x, y, z)") or {}).get("value") == "1 2 3", what="Ada's typing back")
        # the presenter's browser leaves: another browser from there watches; the presenter's own presents again
        await teacher.close()
        await until(lambda: room.presenter is None, what="the presenter gone")
        other = await ViserClient(url(classroom), local_address=nat, cookie=cookie["s"]).connect()
        await until(lambda: (member_with(other) or types.SimpleNamespace(card=None)).card is not None,
                    what="the other browser set up, a student of the challenge")
        assert room.presenter is None and member_with(other).role != PRESENTER
        back = await ViserClient(url(classroom), local_address=nat, cookie=cookie["p"]).connect()
        await until(lambda: room.presenter is not None and room.presenter is member_with(back), what="the presenter back")
        for client in (bo, again, other, back):
            await client.close()

    asyncio.run(scenario())
    classroom.stop()


def saving_class(folder):
    """A class whose challenges' results are saved in ``folder``, and its clock, which the test moves (``now[0]``)."""
    from ur10teach.serving.server import TeachingServer

    classroom, now = TeachingServer(port=0, shared=True, results=folder), [1000.0]
    classroom.classroom.challenges.clock = lambda: now[0]
    return classroom, now


async def answer(student, member, typed: str, attempts: int) -> None:
    """``student`` types ``typed`` for a numbers challenge and checks it: their ``attempts``-th check."""
    await student.set_gui("Your numbers (x, y, z)", typed)
    await until(lambda: member.card.typed().get("numbers") == typed, what="the typing on the server")
    await student.set_gui("Check my answer", True)
    await until(lambda: member.student.attempts == attempts, what=f"check {attempts}")


def test_each_challenges_results_are_kept_on_the_servers_computer_as_students_check_as_it_ends_and_as_the_server_stops(
        tmp_path, caplog):
    """A teacher who had not pressed *Download results* lost the class's results when the next challenge started or
    the server stopped (until 2026-12-06). Each run's file is now written to the results folder (``--results``),
    named after the challenge and the time it started: as students check, every 30 s at most (a laptop that dies
    mid-lesson loses no more), as it ends, and as the server stops with it still running. The console names it
    the first time and at the end. *Download results* gives the same file under the same name."""
    from ur10teach.serving.class_challenges import SAVE_EVERY

    caplog.set_level("INFO", logger="ur10teach.serving.class_challenges")
    folder = tmp_path / "results"
    classroom, now = saving_class(folder)
    room = classroom.classroom

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Where is the flange?", "127.0.0.9")
        await student.set_gui("Your nickname (up to 20 characters)", "Zoë")
        await until(lambda: member.student.nickname == "Zoë", what="the nickname")
        first = room.challenges.run
        path = folder / first.file_name
        assert first.file_name.startswith("challenge-where-is-the-flange-20") and not folder.exists()
        await answer(student, member, "1 2 3", 1)
        await until(lambda: path.exists(), what="the results file, as the first check is made")
        assert "\r\n1,Zoë,1,no,,1 2 3\r\n" in path.read_bytes().decode("utf-8-sig")
        now[0] += 5.0
        await answer(student, member, "4 5 6", 2)
        assert "1,Zoë,1,no,,1 2 3" in path.read_bytes().decode("utf-8-sig")  # not again within 30 s
        now[0] += SAVE_EVERY
        await answer(student, member, "7 8 9", 3)
        await until(lambda: "1,Zoë,3,no,,7 8 9" in path.read_bytes().decode("utf-8-sig"), what="the file written again")
        await teacher.set_gui("End and show the solution", True)
        # the console names the file twice: at the first check and at the end (not at every check)
        await until(lambda: first.ended and caplog.text.count("results of 'Where is the flange?' saved") == 2,
                    what="the file written as the challenge ended")
        assert path.read_bytes() == first.results_csv()
        await until(lambda: teacher.shown(f"Results saved on the server's computer as *{first.file_name}*"),
                    what="the file's name on the board")
        await teacher.set_gui("Download results (CSV)", True)
        await until(lambda: any(len(data) == len(first.results_csv()) for _, data in teacher.received.downloads.values()),
                    what="the download")
        assert [(name, bytes(data)) for name, data in teacher.received.downloads.values()] == [(first.file_name, first.results_csv())]
        await teacher.set_gui("Challenge", "Reach it elbow down")
        await teacher.set_gui("Start the challenge", True)
        # the run is made before its students are enlisted, each in turn: the student is in it once their card is
        await until(lambda: room.challenges.running and room.challenges.run is not first
                    and member.student in room.challenges.run.students.values(), what="the student in the second challenge")
        for client in (teacher, student):
            await client.close()
        return first, room.challenges.run

    first, second = asyncio.run(scenario())
    classroom.stop()  # with the second challenge still running, and no check made in it
    assert sorted(path.name for path in folder.iterdir()) == sorted([first.file_name, second.file_name])
    assert first.file_name != second.file_name and (folder / second.file_name).read_bytes() == second.results_csv()


def test_results_that_cannot_be_saved_are_said_so_on_the_teachers_board(tmp_path):
    """A results folder the server cannot write in (a USB stick pulled out, a file of that name, a folder the
    teacher may not write in) was told of on the console only, which the class's projector does not show: the
    teacher found no file after the lesson. The board says so, and why, until a save succeeds."""
    from ur10teach.serving.class_challenges import SAVE_EVERY

    folder = tmp_path / "results"
    folder.write_text("a file where the folder should be")
    classroom, now = saving_class(folder)
    room = classroom.classroom

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Where is the flange?", "127.0.0.9")
        run = room.challenges.run
        await answer(student, member, "1 2 3", 1)
        said = await until(lambda: teacher.shown("**The results could not be saved**"), what="the board to say so")
        assert f"File exists: {folder}" in said[0] and "*Download results (CSV)* still gives them" in said[0]
        folder.unlink()  # the teacher mends it
        now[0] += SAVE_EVERY
        await answer(student, member, "4 5 6", 2)
        await until(lambda: (folder / run.file_name).exists() and not teacher.shown("could not be saved"),
                    what="the results saved, and the board's warning gone")
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: teacher.shown(f"Results saved on the server's computer as *{run.file_name}*"),
                    what="the file's name on the board")
        for client in (teacher, student):
            await client.close()

    try:
        asyncio.run(scenario())
    finally:
        classroom.stop()


def test_a_results_file_the_teacher_has_open_in_a_spreadsheet_is_saved_beside_it(tmp_path, caplog, monkeypatch):
    """A spreadsheet on Windows locks the file it shows: replacing it raises PermissionError. The later saves all
    failed, the board still said "Results saved ... as" that file, and it held the results of when it was opened.
    They now go to a file beside it, which the board and the console name. (Linux has no such lock: the test
    raises the error Windows raises.)"""
    import pathlib

    from ur10teach.serving.class_challenges import SAVE_EVERY

    folder = tmp_path / "results"
    classroom, now = saving_class(folder)
    room = classroom.classroom
    locked, replace = [], pathlib.Path.replace

    def replace_unless_locked(self, target):
        if pathlib.Path(target) in locked:
            raise PermissionError(13, "The process cannot access the file because it is being used by another process")
        return replace(self, target)

    monkeypatch.setattr(pathlib.Path, "replace", replace_unless_locked)

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Where is the flange?", "127.0.0.9")
        run = room.challenges.run
        opened = folder / run.file_name
        await answer(student, member, "1 2 3", 1)
        await until(lambda: opened.exists(), what="the results file")
        locked.append(opened)  # the teacher opens it in a spreadsheet
        now[0] += SAVE_EVERY
        await answer(student, member, "4 5 6", 2)
        beside = folder / f"{opened.stem}-2.csv"
        await until(lambda: beside.exists() and "1,,2,no,,4 5 6" in beside.read_bytes().decode("utf-8-sig"),
                    what="the results saved beside the open file")
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: run.ended and beside.read_bytes() == run.results_csv(), what="the end's results beside it")
        await until(lambda: teacher.shown(f"Results saved on the server's computer as *{beside.name}*"),
                    what="the new name on the board")
        for client in (teacher, student):
            await client.close()
        return opened, beside

    opened, beside = asyncio.run(scenario())
    classroom.stop()
    assert "1,,1,no,,1 2 3" in opened.read_bytes().decode("utf-8-sig")  # as the spreadsheet has it
    assert f"{opened.name} is open in another program: the results of 'Where is the flange?' are saved as " \
           f"{beside.name} from now on" in caplog.text
    assert sorted(path.name for path in folder.iterdir()) == sorted([opened.name, beside.name])  # no .part left


def test_a_challenge_started_while_the_last_one_is_still_ending_waits_for_its_end_and_its_results_file(tmp_path, caplog):
    """viser runs each click's callback on a thread of its own. The end shows every arm its solution, one after
    another, and a start pressed meanwhile (its button is back as soon as the run is marked ended) took the run
    from under it: the end then wrote the new run's results file, and the ended run's file kept only what the
    checks had written, at most every 30 s; the end went on showing solutions on cards the start had taken away
    (until 2026-12-06). A start now waits for the end to finish."""
    import threading


    folder = tmp_path / "results"
    classroom, now = saving_class(folder)
    room = classroom.classroom
    starts, ending, go_on = [], threading.Event(), threading.Event()

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Where is the flange?", "127.0.0.9")
        first = room.challenges.run
        for attempt, typed in enumerate(("1 2 3", "4 5 6"), 1):  # the second within 30 s: not written as it is made
            await student.set_gui("Your numbers (x, y, z)", typed)
            await until(lambda: member.card.typed().get("numbers") == typed, what="the typing on the server")
            await student.set_gui("Check my answer", True)
            await until(lambda: member.student.attempts == attempt, what=f"check {attempt}")
            now[0] += 5.0  # (one check a second)
        card, shown = member.card, member.card.ended

        def slow_to_show(words):  # the end, showing this student the solution, takes a while
            ending.set()
            go_on.wait(HANG_TIMEOUT)
            shown(words)

        card.ended = slow_to_show
        start = room.challenges.start
        room.challenges.start = lambda *args: (starts.append(1), start(*args))
        await teacher.set_gui("End and show the solution", True)
        await until(ending.is_set, what="the end under way")
        await teacher.set_gui("Challenge", "Reach it elbow down")
        await teacher.set_gui("Start the challenge", True)
        await until(lambda: starts, what="the start pressed")
        go_on.set()
        await until(lambda: room.challenges.running and room.challenges.run is not first
                    and member.card is not None and member.card is not card, what="the second challenge, with its card")
        assert (folder / first.file_name).read_bytes() == first.results_csv()
        assert "1,,2,no,,4 5 6" in first.results_csv().decode("utf-8-sig")
        assert not any("Not accepted" in title for title, _ in teacher.received.notifications)
        for client in (teacher, student):
            await client.close()

    without_failures(scenario, caplog)
    classroom.stop()


def test_a_double_click_on_start_end_or_check_is_one_press(classroom, monkeypatch):
    """A teacher who double-clicked *Start the challenge* saw "a challenge is running: end it first" on the
    projector as the challenge started, and a double click on *End and show the solution*, "no challenge is
    running"; a student who double-clicked *Check my answer*, "one check a second, please" under the verdict
    (each click is a press to viser). The second press of a double click is now let go."""
    from ur10teach.serving import class_challenges

    room = classroom.classroom
    room.challenges.clock = itertools.count(0.0, 10.0).__next__  # (a check's pace is not what is tested here)
    outcomes = {"start": [], "end": [], "check": []}

    def counted(name):
        method = getattr(room.challenges, name)

        def press(*args):
            try:
                method(*args)
                outcomes[name].append("taken")
            except ValueError as why:
                outcomes[name].append(str(why))
                raise

        setattr(room.challenges, name, press)

    async def double_click(client: ViserClient, button: str, name: str) -> None:
        await until(lambda: client.gui.get(button, {}).get("visible"), what=f"{button!r} shown")
        await client.set_gui(button, True)
        await client.set_gui(button, True)  # within the same fraction of a second
        await until(lambda: len(outcomes[name]) == 2, what=f"both presses of {button!r} handled")
        assert outcomes[name] == ["taken", "taken"], outcomes[name]

    async def scenario():
        teacher = await ViserClient(url(classroom)).connect()
        await become_presenter(teacher, classroom)
        student = await ViserClient(url(classroom), local_address="127.0.0.9").connect()
        counted("start"), counted("end"), counted("check")
        monkeypatch.setattr(class_challenges, "DOUBLE_PRESS", 60.0)  # (a loaded machine may run the two apart)
        await teacher.set_gui("Challenge", "Where is the flange?")
        await double_click(teacher, "Start the challenge", "start")
        member = await until(lambda: next((m for m in room.members.values() if m.card is not None), None), what="the card")
        await student.set_gui("Your numbers (x, y, z)", "1 2 3")
        await until(lambda: member.card.typed().get("numbers") == "1 2 3", what="the typing on the server")
        await double_click(student, "Check my answer", "check")
        assert member.student.attempts == 1 and not student.shown("one check a second")
        await double_click(teacher, "End and show the solution", "end")
        run = room.challenges.run
        assert run.ended and not teacher.shown("end it first") and not teacher.shown("no challenge is running")
        monkeypatch.setattr(class_challenges, "DOUBLE_PRESS", -1.0)  # a press long after: the teacher's next
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: len(outcomes["end"]) == 3, what="a press of End on its own")
        assert outcomes["end"][-1] == "no challenge is running"
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_the_reach_targets_name_hangs_towards_the_middle_of_each_browsers_canvas(classroom):
    """The target's name hung to its right: with the target in the right half of a browser's canvas (the presenter's
    in lecture mode, a narrow window), "challenge target" ran under the panel, cut off (until 2026-12-06). It now
    hangs on the side towards the canvas's middle, for each browser's camera as it moves."""
    from ur10teach.features.branch_labels import ScreenView
    from ur10dev.viser_client import CAMERA

    room = classroom.classroom

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Reach it elbow down", "127.0.0.9")
        presenter = room.presenter
        for client, someone in ((teacher, presenter), (student, member)):
            await until(lambda: someone.goal is not None, what="the target drawn")
            target = someone.goal.pose[:3, 3]
            sides = set()
            for position in [(0.0, -3.0, 1.0), (0.0, 3.0, 1.0), (3.0, 0.0, 1.0), (-3.0, 0.0, 1.0)]:
                camera = dataclasses.replace(CAMERA, position=position, look_at=(0.0, 0.0, 0.5))
                await client.send(camera)
                right = ScreenView(position, (0.0, 0.0, 0.5), fov=CAMERA.fov, height=CAMERA.image_height,
                                   width=CAMERA.image_width).to_screen(target[None])[0][0, 0] > 0
                side = "bottom-right" if right else "bottom-left"
                await until(lambda: someone.goal.label.anchor == side, what=f"the name hung {side} from {position}")
                sides.add(side)
            assert sides == {"bottom-left", "bottom-right"}  # the four cameras put it on both sides
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_results_that_cannot_be_saved_are_said_so_on_the_console_and_not_claimed_on_the_board(classroom, tmp_path, caplog):
    blocked = tmp_path / "a file, not a folder"
    blocked.write_text("")
    classroom.results = blocked
    room = classroom.classroom

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Where is the flange?", "127.0.0.9")
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: teacher.shown("The challenge has ended") or teacher.shown("**Ended**"), what="the end")
        await until(lambda: "could not save the results of 'Where is the flange?'" in caplog.text, what="the warning")
        assert not room.challenges.run.saved and not teacher.shown("Results saved")
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("title, box, typed", [
    ("Where is the flange?", "Your numbers (x, y, z)", "1 2"),
    ("Type the UR10's DH table", "Your DH table (a α d θ type, mm and °)", "0 90 128 0 R"),
    ("Straight up", "θ̇2 shoulder (°/s)", 10.0),  # a velocity task's answer: rates, set without moving the arm
])
def test_a_student_typing_an_answer_is_counted_working_on_the_projector(classroom, title, box, typed):
    """Typing at an answer made a student "working" on the server, but the projector's board was not asked to redraw:
    with numbers to type, the class showed 0 working until someone pressed "Check my answer". Joint rates set for a
    velocity task did not count at all."""

    async def scenario():
        teacher, student, member = await a_student_in(classroom, title, "127.0.0.9")

        def working():
            boards = [board_numbers(text) for text in teacher.markdown.values()]
            return next((board["working"] for board in boards if board is not None), None)

        await until(lambda: working() == 0, what="the board")
        await student.set_gui(box, typed)
        await until(lambda: member.student.acted, what="the typing")
        await until(lambda: working() == 1, what="the student counted working on the board")
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_a_students_rate_sliders_count_only_in_a_velocity_challenge_and_are_hooked_once(classroom):
    """A rate slider was hooked to the board each time a velocity challenge began, and the hooks stayed: a student
    kept through several gained one per challenge, and moving a rate slider in a later challenge of another kind
    counted them working on the projector."""
    room = classroom.classroom

    def turn(slider) -> None:
        """What viser does on a student's change: every callback of the slider (run here, in order)."""
        for callback in list(slider._impl.update_cb):
            callback(types.SimpleNamespace(client=None, client_id=None, target=slider))

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Straight up", "127.0.0.11")
        slider = member.session.velocity.sliders[1]
        hooked = len(slider._impl.update_cb)
        turn(slider)
        assert member.student.acted  # in a velocity challenge, rates are the answer
        for title in ("Straight up", "Where is the flange?"):
            before = member.student
            await teacher.set_gui("End and show the solution", True)
            await until(lambda: room.challenges.run.ended, what="the challenge over")
            await teacher.set_gui("Challenge", title)
            await teacher.set_gui("Start the challenge", True)
            await until(lambda: member.student not in (None, before) and member.card is not None, what=f"the task {title!r}")
            assert member.session.velocity.sliders[1] is slider and len(slider._impl.update_cb) == hooked
        turn(slider)
        assert not member.student.acted  # rates are no answer to where the flange is
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_a_client_cannot_claim_solved_and_checks_are_paced(classroom):
    room = classroom.classroom
    room.challenges.clock = lambda: 100.0  # time stands still: a second check is always within the second

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Where is the flange?", "127.0.0.7")
        # whatever a client sends to any widget of its card, saying "solved", changes nothing on the server
        await until(lambda: student.shown("Where is the flange"), what="the task")
        for uuid in list(student.markdown):
            await student.send(messages.GuiUpdateMessage(uuid, {"value": "✓ Solved", "_markdown": "✓ Solved"}))
        await student.set_gui("Your nickname (up to 20 characters)", "<b>Bo</b>\x07\u202e and a very long tail")
        await student.set_gui("Check my answer", True)  # nothing typed yet: refused beside the button, not counted
        await until(lambda: student.shown("the box is empty; type 3 numbers in it"), what="the refusal of an empty answer")
        assert member.student.attempts == 0
        await student.set_gui("Your numbers (x, y, z)", "1 2 3")
        await student.set_gui("Check my answer", True)
        await until(lambda: member.student.attempts == 1, what="the first check")
        assert member.student.solved_after is None and member.student.nickname == "<b>Bo</b> and a very l"[:20]
        # a second check within the second is refused beside the button, and not counted (another answer typed
        # first: pressed again at once, with nothing changed, it is a double click's second press, let go)
        await student.set_gui("Your numbers (x, y, z)", "1 2 4")
        await until(lambda: member.card.typed().get("numbers") == "1 2 4", what="the typing on the server")
        await student.set_gui("Check my answer", True)
        await until(lambda: student.shown("One check a second"), what="the refusal")
        assert member.student.attempts == 1 and room.challenges.run.summary().solved == 0
        # only the presenter ends it
        await student.send(messages.GuiUpdateMessage(teacher.gui["End and show the solution"]["uuid"], {"value": True}))
        # one connection's messages are handled in order: once the next one has been, the forged one has been too
        await student.set_gui("Your nickname (up to 20 characters)", "Bo")
        await until(lambda: member.student.nickname == "Bo", what="the student's next message")
        assert not room.challenges.run.ended
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_the_teacher_takes_the_nicknames_off_the_projector(classroom):
    """A nickname the teacher would rather not show is on the projector by that student's tool as soon as it is
    typed. *Nicknames on the projector* off names every tool by its student's number, at once, for the rest of
    the class; the results file keeps the nicknames, and ticking it again brings them back."""
    room = classroom.classroom

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Reach the target", "127.0.0.12")
        await student.set_gui("Your nickname (up to 20 characters)", "Not for the class")
        await until(lambda: member.student.nickname == "Not for the class", what="the nickname")
        await drag_a_little(student, member.session)

        def projected() -> set[str]:
            tools = room.presenter.tools
            return set() if tools is None or tools.names is None else {
                name for label in tools.names.labels if label.visible for name in label.text.replace("\n", JOIN).split(JOIN)}

        numbered = f"student {member.student.number}"
        await until(lambda: projected() == {"Not for the class"}, what="the nickname on the projector")
        await teacher.set_gui("Nicknames on the projector", False)
        await until(lambda: projected() == {numbered}, what="the student's number in its place")
        assert not room.challenges.nicknames and "Not for the class" in room.challenges.run.results_csv().decode("utf-8-sig")
        dot = np.array(room.presenter.tools.working.points)
        await drag_a_little(student, member.session)  # the projector redrawn as the student works: still the number
        await until(lambda: not np.array_equal(room.presenter.tools.working.points, dot), what="the student's dot moved")
        assert projected() == {numbered}
        await teacher.set_gui("Nicknames on the projector", True)
        await until(lambda: projected() == {"Not for the class"}, what="the nickname back")
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_the_projectors_tools_taken_away_while_the_board_is_drawn_are_drawn_again_next_time(classroom, monkeypatch, caplog):
    """The board is drawn on the panel refresher's thread; a new challenge's start (or a hand-over) takes the
    projector's dots and names away on another: it removes them, then lets go of them. Removed between the board's
    look at them and its drawing, the drawing raised viser's "Cannot assign to 'points' on a removed
    PointCloudHandle": an error and its traceback on the teacher's console (a monkey starting and ending challenges
    found it, 2026-12-06). Here that happens once, mid-drawing; the drawing after the start has let go makes them anew."""
    room = classroom.classroom
    flanges, render = ChallengeRun.flanges, room.challenges._render_board
    taken: list = []

    def removed_mid_drawing(run, *args, **kwargs):  # (called by the drawing alone)
        found = flanges(run, *args, **kwargs)
        if not taken and len(found[0]):  # a student's dot to draw
            taken.append(room.presenter.tools)
            taken[0].remove()  # the start's step_out, on its own thread
        return found

    def drawn_then_let_go(member) -> None:
        try:
            render(member)
        finally:
            if taken and member.tools is taken[0]:
                member.tools = None  # the start's step_out, done

    def drawn_anew() -> bool:
        tools = room.presenter.tools
        return bool(taken) and tools is not None and tools is not taken[0] and tools.working.visible

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Reach the target", "127.0.0.13")
        monkeypatch.setattr(ChallengeRun, "flanges", removed_mid_drawing)
        monkeypatch.setattr(room.challenges, "_render_board", drawn_then_let_go)
        deadline = time.monotonic() + HANG_TIMEOUT
        while not drawn_anew():  # each drag asks for a drawing: the one it is taken in, and the next
            assert time.monotonic() < deadline, "the student's dot was not drawn anew"
            await drag_a_little(student, member.session)
        for client in (teacher, student):
            await client.close()

    without_failures(scenario, caplog)


def test_on_the_ur10e_the_holding_challenge_gives_and_checks_the_ur10es_masses():
    """The ur10e had no link masses until 2026-12-04 (no holding challenge there); the task's terms gave the
    CB3 UR10's masses on any preset, where the check took the preset's. The preview, the student's task and the
    projector now give the masses the check takes (test_challenges works the answer from them by hand)."""
    from ur10teach.serving.server import TeachingServer

    app = TeachingServer(preset="ur10e", port=0, shared=True)
    room, arm = app.classroom, app.arm
    challenge = next(c for c in app.challenges if c.title == "Holding itself up")

    async def scenario():
        first = await ViserClient(url(app)).connect()  # the teacher's preview before starting
        await become_presenter(first, app)
        await first.set_gui("Challenge", challenge.title)
        await until(lambda: first.shown("links of (7.369, 13.051, 3.989, 2.1, 1.98, 0.615) kg"), what="the preview")
        teacher, student, _ = await a_student_in(app, challenge.title, "127.0.0.8")
        await until(lambda: student.shown("links of (7.369, 13.051"), what="the student's task, on the UR10e")
        assert room.challenges.run.arm is arm and "7.369" in summary_markdown(room.challenges.run)
        answer = " ".join(f"{t:.3f}" for t in C.expected_numbers(challenge, arm))
        await until(lambda: any(label.startswith("Your numbers") for label in student.gui), what="the answer box")
        await student.set_gui(next(label for label in student.gui if label.startswith("Your numbers")), answer)
        await student.set_gui("Check my answer", True)
        await until(lambda: student.shown("Solved: every number is right"), what="the answer worked from the terms, right")
        for client in (first, teacher, student):
            await client.close()

    try:
        asyncio.run(scenario())
    finally:
        app.stop()


def test_run_bookkeeping_bounds_and_time_limit():
    now = [0.0]
    challenge = next(c for c in C.builtin() if c.kind == "numbers")
    from ur10core import Arm

    arm = Arm.preset("course")
    run = ChallengeRun(challenge, arm, time_limit=60, clock=lambda: now[0])
    ada = run.join("10.0.0.1")
    right = C.Answer(numbers=C.expected_numbers(challenge, arm))
    now[0] = 12.46
    assert run.check(ada, right).solved
    with pytest.raises(ValueError, match="one check a second"):
        run.check(ada, right)
    now[0] = 61.0
    with pytest.raises(ValueError, match="time is up"):
        run.check(ada, right)
    assert run.summary().seconds_left == 0.0 and run.summary().solved == 1
    # the board: the time while it runs, not once it has ended; a results file not saved, either way
    assert "**Time is up.**" in summary_markdown(run)
    run.unsaved = "No space left on device: /media/usb/results"
    assert "**Time is up.**" in summary_markdown(run) and "could not be saved**: No space left" in summary_markdown(run)
    run.ended = True
    assert "**Ended**" in summary_markdown(run) and "Time is up" not in summary_markdown(run)
    assert "could not be saved" in summary_markdown(run)
    run.unsaved = None
    assert clean_nickname("a\nb\tc\u200bd") == "a b cd" and len(clean_nickname("x" * 100)) == 20
    # a name's own marks are kept (Thai's vowel and tone, Tibetan's stack, an accent typed apart from its letter);
    # a pile of them on one letter, which a 3D label draws as a blot over its neighbour, is cut to three
    for name in ("ญิ่ง", "བསྒྲུབས", "Nguyễn", "क्षितिज"):
        assert clean_nickname(name) == name
    assert clean_nickname("Zoe\u0308") == "Zoë" and clean_nickname("B" + "\u0301" * 19 + "o") == "B" + "\u0301" * 3 + "o"
    assert spreadsheet_safe("=HYPERLINK(1)") == "'=HYPERLINK(1)" and spreadsheet_safe("Ada") == "Ada"
    # the results file opens in Excel with "Zoë" as typed: UTF-8 marked as such (Excel reads unmarked files as ANSI);
    # the seconds to solve are whole, which no decimal mark of any country turns into another number or a date
    run.rename(ada, "Zoë")
    results = run.results_csv()
    assert results.startswith(codecs.BOM_UTF8) and "\r\n1,Zoë,1,yes,12," in results.decode("utf-8-sig")
    # one computer's departed attempt goes back to it, and only to it
    run.leave(ada, {"numbers": "1 2 3"})
    bo = run.join("10.0.0.2")
    assert bo is not ada and run.join("10.0.0.1") is ada and ada.kept == {"numbers": "1 2 3"}
    from ur10teach.serving import challenge_run

    # browsers behind one address (a router's NAT) are told apart by their cookies: each finds its own attempt
    ada_here, cy = run.join("10.0.0.1 " + "a" * 22), run.join("10.0.0.1 " + "c" * 22)
    assert ada_here is not ada and cy is not ada_here
    run.leave(ada_here, {"numbers": "4 5 6"})
    assert run.join("10.0.0.1 " + "d" * 22) is not ada_here and run.join("10.0.0.1 " + "a" * 22) is ada_here
    # one address holds at most eight attempts: a page sending new cookies does not fill the board, it takes over
    # the attempt away longest, as any browser from that address did before
    crowd = ChallengeRun(challenge, arm, clock=lambda: now[0])
    browsers = [crowd.join(f"10.2.0.1 {str(k) * 22}") for k in range(challenge_run.CONNECTIONS_PER_ADDRESS)]
    for k, student in enumerate(browsers):
        now[0] = 100.0 + k
        crowd.leave(student, {})
    assert crowd.join("10.2.0.1 " + "x" * 22) is browsers[0] and crowd.join("10.2.0.1 " + "y" * 22) is browsers[1]
    assert len(crowd.students) == challenge_run.CONNECTIONS_PER_ADDRESS and crowd.join("10.2.0.2") not in browsers
    small = ChallengeRun(challenge, arm)
    for k in range(challenge_run.MAX_STUDENTS):
        small.join(f"10.1.{k // 250}.{k % 250}")
    with pytest.raises(ValueError, match="already has"):
        small.join("10.9.9.9")


async def presenting_a_reach_challenge(classroom) -> ViserClient:
    """A teacher presenting, the built-in reach challenge started (students who connect now join it on arrival)."""
    reach = next(c for c in classroom.classroom.challenges.offered if c.kind == "reach")
    teacher = await ViserClient(url(classroom)).connect()
    await become_presenter(teacher, classroom)
    await teacher.set_gui("Challenge", reach.title)
    await teacher.set_gui("Start the challenge", True)
    await until(lambda: classroom.classroom.challenges.running, what="the reach challenge")
    return teacher


def test_the_target_and_the_students_tools_show_with_the_challenges_arm_only(classroom):
    """A teacher who showed the class the KR210 during a UR10 reach challenge had the UR10's target and the students'
    tools drawn over it, where its world put them: the target by the KR210's base, the tools a third of its size.
    The projector's names also kept clear of the labels of the drawing they were made with, gone after the change.
    They now show over the challenge's arm only, made again for its drawing, and the board says where they went; a
    student working on their own UR10 keeps the target (until 2026-12-07). Once it has ended, the target is drawn
    again for those who had it only: not for a browser that came after the end."""
    from ur10teach.features.arm_picker import CUSTOM, UR10, choice_of
    from ur10teach.features.challenge import goal_pose

    room = classroom.classroom
    kr210 = choice_of("kr210")

    async def scenario():
        teacher = await presenting_a_reach_challenge(classroom)
        student = await ViserClient(url(classroom)).connect()
        member = next(m for m in list(room.members.values()) if m is not room.presenter)
        await until(lambda: member.card is not None and member.session is not None and member.session.built,
                    what="the student's card")
        await drag_a_little(student, member.session)
        presenter, run = room.presenter, room.challenges.run

        def over_the_ur10() -> bool:
            tools = presenter.tools
            return (room.choice == UR10 and presenter.goal is not None and GOAL_ROOT in teacher.received.nodes
                    and tools is not None and tools.working.visible and not teacher.shown("The class is shown"))

        await until(over_the_ur10, what="the target and the student's tool on the projector")
        before = presenter.tools
        elsewhere = {kr210: f"the {kr210}", CUSTOM: "the presenter's DH table"}  # (a typed table, as the board names it)
        for label in (kr210, CUSTOM, UR10):  # (the picker is made anew for each arm: the one pressed is the one the page holds)
            await until(lambda: room.can_switch() and presenter.picker is not None and teacher.gui.get(
                "Which arm", {}).get("uuid") == presenter.picker.dropdown._impl.uuid, what="the class's arm ready for a change")
            await teacher.set_gui("Which arm", label)
            if label in elsewhere:
                await until(lambda: room.choice == label and presenter.goal is None and presenter.tools is None
                            and GOAL_ROOT not in teacher.received.nodes and teacher.shown(
                                f"The class is shown {elsewhere[label]}: the students' tools and the target show with the {UR10}"),
                            what="the projector without the UR10's target and tools, and the board saying so")
                assert member.goal is not None and GOAL_ROOT in student.received.nodes  # the student's own UR10 keeps it
        await until(over_the_ur10, what="the target and the tools back over the UR10")
        assert presenter.tools is not before  # made for the drawing shown now
        assert np.allclose(presenter.goal.pose, goal_pose(run.challenge, run.arm, room.drawing.world))
        # ended, its target stays with those who had it; a browser that comes after the end is not given it
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: run.ended, what="the end")
        late = await ViserClient(url(classroom)).connect()
        newcomer = next(m for m in list(room.members.values()) if m is not room.presenter and m is not member)
        for label, shown in ((kr210, lambda: presenter.goal is None), (UR10, lambda: presenter.goal is not None)):
            await until(lambda: presenter.picker is not None and teacher.gui.get("Which arm", {}).get("uuid")
                        == presenter.picker.dropdown._impl.uuid and room.can_switch(), what="the class's arm ready for a change")
            await teacher.set_gui("Which arm", label)
            await until(lambda: room.choice == label and shown(), what=f"the {label} shown")
        assert newcomer.goal is None and member.goal is not None
        for client in (teacher, student, late):
            await client.close()

    asyncio.run(scenario())


def test_a_velocity_challenge_ended_while_the_class_sees_another_arm_is_solved_on_its_own(classroom):
    """The joint rates a velocity challenge's end shows depend on the arm's pose: the class's, if it is the
    challenge's arm. Shown the KR210, its joints were read as the UR10's (until 2026-12-07); now the UR10's home."""
    from ur10teach.features.arm_picker import choice_of

    room = classroom.classroom
    velocity = next(c for c in room.challenges.offered if c.kind == "velocity" and c.arm == "ur10")

    async def scenario():
        teacher = await ViserClient(url(classroom)).connect()
        await become_presenter(teacher, classroom)
        await teacher.set_gui("Challenge", velocity.title)
        await teacher.set_gui("Start the challenge", True)
        await until(lambda: room.challenges.running, what="the velocity challenge")
        run = room.challenges.run
        await until(room.can_switch, what="the class's arm ready for a change")
        await teacher.set_gui("Which arm", choice_of("kr210"))
        # (the presenter's folders are made anew for the arm shown: the button pressed is the one the page now holds)
        await until(lambda: room.choice == choice_of("kr210") and room.presenter.desk is not None and teacher.gui.get(
            "End and show the solution", {}).get("uuid") == room.presenter.desk.end._impl.uuid, what="the KR210 shown")
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: run.ended and run.solution_words, what="the end")
        assert run.solution_words == C.solution(velocity, run.arm)[1]
        await teacher.close()

    asyncio.run(scenario())


def test_a_student_who_goes_back_to_watching_keeps_the_target_and_is_told_the_end(classroom):
    """Going back to the presenter's arm clears the student's own scene: the reach target is drawn again. A student
    watching when the teacher ends the challenge is shown the end and the solution, as one exploring is."""

    async def scenario():
        teacher = await presenting_a_reach_challenge(classroom)
        student = await ViserClient(url(classroom)).connect()
        await until(lambda: GOAL_ROOT in student.received.nodes, what="the target on the student's screen")
        # each button's panel is drawn after the scene is changed: once the next button is there, so is the scene
        for button, then in (("Back to the presenter's arm", "Explore on my own"), ("Explore on my own", "Back to the presenter's arm"),
                             ("Back to the presenter's arm", "Explore on my own")):
            await student.set_gui(button, True)
            await until(lambda: then in student.gui, what=then)
            assert GOAL_ROOT in student.received.nodes, button
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: student.shown("The challenge has ended"), what="the end on the student's screen")
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_a_student_back_from_watching_finds_their_target_where_they_left_it_out_of_reach(classroom):
    """A student who left their target beyond the arm's reach, went back to watching and explored again found the
    arm as they left it and their target there too (not on the tool, where a target in reach goes with the arm)."""
    room = classroom.classroom

    async def scenario():
        teacher = await presenting_a_reach_challenge(classroom)
        student = await ViserClient(url(classroom)).connect()
        await until(lambda: any(m.student is not None and m.session is not None for m in room.members.values()),
                    what="the student's own arm")
        member = next(m for m in room.members.values() if m.student is not None)
        session = member.session
        far = session.state.last.target.copy()
        far[:3, 3] = (2.5, 0.4, 0.9)  # 2.6 m from the base: beyond the UR10's 1.3 m
        session.apply(lambda state: state.move_target(far, cause="typed"))
        left = session.state.last
        assert not left.reachable
        for button, then in (("Back to the presenter's arm", "Explore on my own"),
                             ("Explore on my own", "Back to the presenter's arm")):
            await student.set_gui(button, True)
            await until(lambda: then in student.gui, what=then)
        back = member.session.state.last
        assert member.session is not session and np.array_equal(back.q, left.q)
        np.testing.assert_allclose(back.target, far, atol=1e-12)
        assert not back.reachable
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_a_student_who_goes_back_to_watching_as_the_challenge_starts_is_given_it(classroom, monkeypatch, caplog):
    """The start gives each watching student their own arm, then the task. A student's "Back to the presenter's
    arm", handled on its own thread, can land in between: the start then read the arm just taken away, and the
    teacher's console showed "could not give browser 4 the challenge" and an AttributeError's traceback, the
    student was never shown the target nor counted on the projector (a protocol-level monkey found it,
    2026-12-06). Here the press lands there every time."""
    room = classroom.classroom
    explore = room.explore

    def explored_then_back(member) -> None:
        explore(member)
        room.rejoin(member)  # the student's press, between the two

    async def scenario():
        teacher = await ViserClient(url(classroom)).connect()
        await become_presenter(teacher, classroom)
        student = await ViserClient(url(classroom), local_address="127.0.0.20").connect()
        await until(lambda: "Explore on my own" in student.gui, what="the student watching")
        monkeypatch.setattr(room, "explore", explored_then_back)
        reach = next(c for c in room.challenges.offered if c.kind == "reach")
        await teacher.set_gui("Challenge", reach.title)
        await teacher.set_gui("Start the challenge", True)
        await until(lambda: GOAL_ROOT in student.received.nodes and student.shown(reach.text[:30]),
                    what="the target and the task on the watching student's screen")
        await until(lambda: any((board_numbers(t) or {}).get("joined") == 1 for t in teacher.shown(f"### {reach.title}")),
                    what="the student counted on the projector")
        for client in (teacher, student):
            await client.close()

    without_failures(scenario, caplog)


def test_a_presenters_panel_taken_away_by_a_hand_over_holds_nothing_back(classroom):
    """A start holds back what of the presenter's panel would answer the task once the classroom's lock is let go,
    and a hand-over on another thread may take that panel away first: holding back on it raised viser's "Cannot
    assign to 'visible' on a removed GuiMarkdownHandle", the teacher read "Something went wrong" and no student was
    given the task (a monkey handing over and starting challenges found it, 2026-12-06). A panel taken away holds
    nothing back; one being taken away is, under the arm's lock, once the holding back is done."""
    room = classroom.classroom

    async def scenario():
        first = await ViserClient(url(classroom)).connect()
        await become_presenter(first, classroom)
        taken = room.presenter.session
        second = await ViserClient(url(classroom)).connect()
        await become_presenter(second, classroom)
        await until(lambda: taken.closed and room.presenter.session is not taken, what="the hand-over")
        taken.hold_back("det_j")  # the start's, landing after the hand-over
        assert all(view.held is None for view in taken.panel_views)
        for client in (first, second):
            await client.close()

    asyncio.run(scenario())


def test_a_challenge_picked_as_a_hand_over_takes_the_folder_away_is_not_an_error(classroom):
    """The presenter picked a challenge as another browser took over presenting: the preview was written into the
    folder the hand-over had just removed, and the teacher's console showed "callback failed" and viser's "Cannot
    assign to 'content' on a removed GuiMarkdownHandle" (a monkey with eight students handing over found it)."""
    room = classroom.classroom

    async def scenario():
        first = await ViserClient(url(classroom)).connect()
        await become_presenter(first, classroom)
        await until(lambda: room.presenter.desk is not None, what="the presenter's Challenge folder")
        desk = room.presenter.desk
        second = await ViserClient(url(classroom)).connect()
        await become_presenter(second, classroom)
        await until(lambda: desk.closed and room.presenter.desk is not desk, what="the hand-over")
        desk._preview()  # the pick's callback, run after the hand-over
        for client in (first, second):
            await client.close()

    asyncio.run(scenario())


def test_a_student_works_on_the_challenge_arm_whatever_the_class_is_shown(classroom):
    """The teacher shows the class another arm while a UR10 challenge runs: a student who comes late, or explores
    again after watching, gets the challenge's arm, not the one on the projector, and as they left it."""
    room = classroom.classroom

    async def scenario():
        teacher = await presenting_a_reach_challenge(classroom)
        await teacher.set_gui("Which arm", SCARA)
        await until(lambda: room.choice == SCARA and room.presenter.session is not None, what="the SCARA on the projector")
        student = await ViserClient(url(classroom)).connect()
        member = next(m for m in list(room.members.values()) if m is not room.presenter)
        await until(lambda: member.card is not None and member.session is not None and member.session.built,
                    what="the late student's card")
        assert member.session.arm == room.challenges.run.arm
        target = await drag_a_little(student, member.session)
        await until(lambda: np.allclose(member.session.state.last.target[:3, 3], target[:3, 3]), what="the student's drag")
        q = member.session.state.q
        for button, then in (("Back to the presenter's arm", "Explore on my own"), ("Explore on my own", "Back to the presenter's arm")):
            await student.set_gui(button, True)
            await until(lambda: then in student.gui, what=then)
        # their own arm again, as they left it
        assert member.session.arm == room.challenges.run.arm and np.allclose(member.session.state.q, q)
        await student.set_gui("Check my answer", True)
        await until(lambda: student.shown("(check 1)"), what="the verdict")
        assert not any(title == "Not accepted" for title, _ in student.received.notifications)
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_a_presenter_who_takes_over_a_reach_challenge_shows_its_target(classroom):
    """The teacher hands over mid-challenge (another laptop on the projector): its screen shows the target too."""
    room = classroom.classroom

    async def scenario():
        teacher = await presenting_a_reach_challenge(classroom)
        other = await ViserClient(url(classroom)).connect()
        await until(lambda: GOAL_ROOT in other.received.nodes and GOAL_ROOT in teacher.received.nodes, what="the target on both screens")
        await teacher.set_gui("Stop presenting", True)
        await until(lambda: room.presenter is None, what="no presenter")
        await other.set_gui("Back to the presenter's arm", True)  # a student explores; a watcher may present
        await become_presenter(other, classroom)
        await until(lambda: "End and show the solution" in other.gui, what="the new presenter's challenge folder")
        assert GOAL_ROOT in other.received.nodes
        for client in (teacher, other):
            await client.close()

    asyncio.run(scenario())


def test_the_challenge_target_is_sized_once_by_a_students_lecture_mode():
    """With ``--lecture``, a student's 3D labels are sized for lecture mode as soon as their arm is built (they waited
    for the student's first change), and the target's label is sized once and follows their own switch (it was sized
    twice: 3.58 for 2.24, and 2.24 out of lecture mode)."""
    from ur10teach.serving.server import TeachingServer
    from ur10teach.style import LECTURE_LABEL_MIN, label_scale

    app = TeachingServer(port=0, shared=True, light=True, lecture=True)

    async def scenario():
        teacher = await presenting_a_reach_challenge(app)
        student = await ViserClient(url(app)).connect()
        member = next(m for m in list(app.classroom.members.values()) if m is not app.classroom.presenter)
        await until(lambda: member.goal is not None and member.session is not None and member.session.built, what="the target")
        numbers = [label for pool in member.session.drawing.label_sets for label in pool.labels]  # made out of lecture mode's size
        await until(lambda: min(label.font_screen_scale for label in numbers) >= LECTURE_LABEL_MIN
                    and member.goal.label.font_screen_scale == label_scale(1.4, True), what="the student's 3D labels sized once")
        for lecture in (False, True):
            await student.set_gui("Lecture mode", lecture)
            await until(lambda: member.goal.label.font_screen_scale == label_scale(1.4, lecture),
                        what=f"the target's label at {label_scale(1.4, lecture)}, lecture mode {lecture}")
            assert member.goal.label.font_screen_scale == label_scale(1.4, lecture)
        for client in (teacher, student):
            await client.close()

    try:
        asyncio.run(scenario())
    finally:
        app.stop()


def test_the_placed_labels_keep_clear_of_the_challenge_targets_name(classroom):
    """A student's arm on the KR210's target: its DH axes' names and branch numbers are placed apart from the
    target's name, and so are the students' names on the projector. Until 2026-12-03 "z6" sat on "challenge
    target", and the projector's names kept clear of a "challenge target" at the world's origin."""
    from ur10teach.features.branch_labels import boxes, obstacle, overlapping
    from ur10teach.features.camera import arm_points, framed_view

    def box(view, world_position, text, scale, anchor):
        return boxes(view.to_screen(np.asarray(world_position, dtype=float)[None])[0], [text], scale, anchor)[0]

    def goal_name(goal):  # where the target's name is in the world: at its frame's origin, the label hangs under it
        return goal.frame.position, goal.label.text, goal.label.font_screen_scale, goal.label.anchor

    def clashes(pools, goal_box, view):  # the placed labels over the target's name, on the screen they are placed for
        return [text for pool in pools for _, text, position in pool.placed
                if overlapping(box(view, position @ pool.world[:3, :3].T + pool.world[:3, 3], text,
                                   pool.labels[0].font_screen_scale, "bottom-center"), goal_box, gap=0.0)]

    async def scenario():
        room = classroom.classroom
        teacher = await ViserClient(url(classroom)).connect()
        await become_presenter(teacher, classroom)
        await teacher.set_gui("Challenge", "KR210: reach, wrist flipped")
        await teacher.set_gui("Start the challenge", True)
        await until(lambda: room.challenges.running, what="the KR210 challenge")
        student = await ViserClient(url(classroom)).connect()
        member = next(m for m in list(room.members.values()) if m is not room.presenter)
        await until(lambda: member.goal is not None and member.session is not None and member.session.built, what="the target")
        session = member.session
        # the target grows with the arm, as its drawing does: a UR10's 2 cm ball is a speck beside a 3.9 m KR210
        scale = session.drawing.size / UR10_SIZE
        assert scale > 2.5 and member.goal.frame.origin_radius == pytest.approx(GOAL_RADIUS * scale)
        target_q = np.array(room.challenges.run.challenge.joints)
        session.apply(lambda state: state.set_joints(target_q))  # the tool on the target, the DH frames around it
        goal = goal_name(member.goal)
        pools = session.drawing.label_sets
        await until(lambda: any(text == "z6" for pool in pools for _, text, _ in pool.placed)
                    and np.allclose(session.state.last.q, target_q), what="the student's labels placed at the target")
        # the camera the student's browser frames the arm with (the headless client reports a fixed one)
        view = framed_view(arm_points(session.drawing.framed(session.state.last), session.drawing.body_radius))
        for pool in pools:  # as a camera move places them
            pool.view = lambda: view
            pool.place()
        assert not clashes(pools, box(view, *goal), view), "over the target's name in the student's own scene"

        await student.set_gui("Check my answer", True)  # the projector names the student by their tool, at the target
        presenter = room.presenter

        def named():
            names = presenter.tools.names if presenter.tools is not None else None
            return names if names is not None and names.placed else None

        names = await until(named, what="the student's name on the projector")
        names.view = lambda: view
        names.place()
        assert not clashes((names,), box(view, *goal_name(presenter.goal)), view), "over the target's name on the projector"
        kept_clear_of = [entry for entry in map(obstacle, names.fixed()) if entry is not None and entry[1] == "challenge target"]
        assert len(kept_clear_of) == 1 and np.allclose(kept_clear_of[0][0], presenter.goal.frame.position, atol=1e-6), \
            f"the projector's names keep clear of a target's name at {kept_clear_of}, not at the target"
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_a_singularity_challenge_is_not_answered_by_the_singularity_buttons(classroom):
    """*Put the arm on the: elbow* answered *Elbow singularity* in one click. While a singularity challenge runs,
    a student's buttons are taken away and the folder says why (a forged click is refused, the arm stays), and the
    presenter's too (the projector would show the class the answer); they are back at its end."""

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Elbow singularity", "127.0.0.8")
        buttons = member.session.singularities.demo
        await until(lambda: student.gui.get("Put the arm on the", {}).get("visible") is False
                    and student.shown(HELD_BACK), what="the buttons off")
        await until(lambda: teacher.gui.get("Put the arm on the", {}).get("visible") is False
                    and teacher.shown(HELD_BACK), what="the presenter's buttons off")
        q = member.session.state.q
        await student.send(messages.GuiUpdateMessage(buttons._impl.uuid, {"value": "elbow"}))
        refusal = member.session.singularities.refusal.line  # below the buttons' place
        await until(lambda: refusal.visible and HELD_BACK[:40] in refusal.content, what="the refusal")
        assert np.array_equal(member.session.state.q, q) and member.session.state.last.cause != "singularity"
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: student.gui.get("Put the arm on the", {}).get("visible") is True
                    and teacher.gui.get("Put the arm on the", {}).get("visible") is True, what="the buttons back")
        await student.set_gui("Put the arm on the", "wrist")
        await until(lambda: member.session.state.last.cause == "singularity", what="the wrist button working again")
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


#: A built-in numbers challenge → the readouts of a panel on its arm that would give its answer.
HELD_READOUTS = {
    "Where is the flange?": lambda s: [s.readouts.pose],
    "IK step 1: both shoulders": lambda s: [s.decoupling.steps, s.ik_target.branches],
    "det J by hand": lambda s: [s.singularities.gauges, s.ellipsoids.lengths],
    "Holding a weight": lambda s: [s.statics.bars],
    "Holding itself up": lambda s: [s.statics.bars],
    "KR210: its wrist centre": lambda s: [s.decoupling.readout, s.lessons[1].readout],
    "Desktop arm: tool velocity": lambda s: [s.velocity.readout, s.lessons[1].readout],
}


@pytest.mark.parametrize("title", HELD_READOUTS)
def test_a_numbers_challenges_answer_cannot_be_read_off_a_panel(classroom, title, caplog):
    """*Where is the flange?* was answered by typing its joints and copying the Tool pose folder; each numbers
    quantity had such a readout (det J's gauges, the torque bars, the branch table's θ1, WC, v). While one runs,
    those readouts say why they are off, in the student's panel and in the presenter's, which the projector
    shows, even with the student's arm at the task's joints (and for θ1, the other shoulder's branch cannot be
    chosen: the joint panel would show it); they are back at its end."""
    room = classroom.classroom

    async def scenario():
        teacher, student, member = await a_student_in(classroom, title, "127.0.0.9")
        challenge, session, presenter = room.challenges.run.challenge, member.session, room.presenter.session
        shown = {"torque": "Show the torques", "gravity_torque": "Show the torques", "det_j": "Show at the tool"}
        if challenge.quantity in shown:  # the bars and the ellipsoids' lengths show once asked for
            for client in (teacher, student):
                await client.set_gui(shown[challenge.quantity], True)
        readouts = [*HELD_READOUTS[title](session), *HELD_READOUTS[title](presenter)]
        await until(lambda: all(HELD_BACK in readout.content for readout in readouts), what="the readouts held back")
        arm, given = session.arm, " ".join(f"{v:.6f}" for v in np.degrees(challenge.joints))
        await student.set_gui(typed_label(arm), given)
        await student.set_gui("Set these values", True)
        await until(lambda: np.allclose(session.state.q, challenge.joints)
                    and student.gui.get(typed_label(arm), {}).get("value") == display_text(arm, session.state.q),
                    what="the task's joints, and the panel drawn at them")
        assert all(HELD_BACK in readout.content for readout in readouts)
        if title == "Desktop arm: tool velocity":  # the course path's plot gives v at t = 4 s too
            assert session.lessons[1].velocity.visible is False
        plots = [view.singularities.plot for view in (session, presenter) if view.singularities.plot is not None]
        if title == "det J by hand":  # the factors' plot gives |s3| and |s5| (their scale is 1), hovered
            assert not any(plot.visible for plot in plots)
        if title == "Where is the flange?":  # an arm made again (back from watching, or a new presenter's) holds it back too
            await student.set_gui("Back to the presenter's arm", True)
            await until(lambda: member.session is None and "Explore on my own" in student.gui, what="watching")
            await student.set_gui("Explore on my own", True)
            await until(lambda: member.session is not None and member.session is not session, what="a new arm")
            await until(lambda: member.session.readouts.pose.content == HELD_BACK, what="its Tool pose held back")
            readouts = [*HELD_READOUTS[title](member.session), *HELD_READOUTS[title](presenter)]  # the old arm's are gone
        if title == "IK step 1: both shoulders":  # another branch chosen would show its θ1 in the joint panel
            await until(lambda: student.gui.get("Use branch", {}).get("visible") is False, what="Use branch off")
            await student.send(messages.GuiUpdateMessage(session.ik_target.branch_buttons._impl.uuid, {"value": "5"}))
            line = session.ik_target.branch_refusal.line  # (below the buttons, which a browser no longer shows)
            await until(lambda: line.visible and HELD_BACK in student.markdown.get(line._impl.uuid, ""), what="the refusal")
            assert np.allclose(session.state.q, challenge.joints)
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: not any(HELD_BACK in readout.content for readout in readouts), what="the readouts back")
        assert all(plot.visible for plot in plots)
        for client in (teacher, student):  # and no redraw refused anything on its way
            assert all(HELD_BACK in body for _, body in client.received.notifications), client.received.notifications
            await client.close()

    without_failures(scenario, caplog)


def recording(handle, texts: list, now, message, buffers) -> None:
    """A headless browser's ``_handle`` that first keeps every text of ``message`` in ``texts``, as (its widget's
    uuid, the text); not the uuids, names and owners themselves."""
    def strings(value) -> None:
        if isinstance(value, str):
            texts.append((message.get("uuid"), value))
        elif isinstance(value, dict):
            for key, item in value.items():
                if not key.endswith(("uuid", "name", "owner")):
                    strings(item)
        elif isinstance(value, (list, tuple)):
            for item in value:
                strings(item)

    strings({key: value for key, value in message.items() if key != "type"})
    handle(now, message, buffers)


#: An arm the class is shown, and joints at which no joint value reads as one of the tool's coordinates.
POSE_SHOWN = {"UR10 (the app's arm)": [20, -70, 100, -30, 60, 10], "Stanford arm (RRP + wrist)": [35, 70, 304, 40, 65, 40],
              "KR210 (spherical wrist)": [20, 10, -20, 30, 40, 50]}


def given_away(texts: list, shown_before: set, given: list) -> list:
    """The texts of ``texts`` (``recording``'s, from the start of a challenge) that give away what ``given``'s
    patterns match. Only one is let pass: in a widget shown before the start and sent :data:`HELD_BACK` after it
    (a redraw under way as the challenge started, with what that screen already showed)."""
    held_at = {uuid: at for at, (uuid, text) in reversed(list(enumerate(texts))) if text == HELD_BACK}  # the first
    return [text for at, (uuid, text) in enumerate(texts) if any(pattern.search(text) for pattern in given)
            and not (uuid in shown_before and at < held_at.get(uuid, -1))]


@pytest.mark.parametrize("label", POSE_SHOWN)
def test_a_question_about_the_pose_shown_is_answered_on_no_screen(classroom, label):
    """A question about the pose shown is asked at the joints the class's arm stands at, and the class's live panel,
    last in every browser's panel (the projector's too), showed that arm's tool pose and det J's factors: *Pose
    shown: tool position* was answered there (until 2026-12-05), and by the decoupling folder, which starts from p:
    the Stanford arm's tool frame is its wrist centre ("WC = p"), and the UR10's P5 is p moved 92 mm along z6. The
    KR210's gripper box was filled with p, and filled again when its convention was switched. A student's arm, made
    as the challenge started, was sent its tool pose and then held back. While it runs, no browser is sent p, to
    0.1 mm or to the mm, in any panel or box, and det J's gauges are off likewise; both are back at its end."""
    from ur10core.serial import kr210_to_urdf
    from ur10dev.viser_client import HELD_BACK_START
    from ur10teach.style import number

    assert HELD_BACK.startswith(HELD_BACK_START)  # (a browser whose tool pose is held back is ready all the same)
    room = classroom.classroom

    async def scenario():
        teacher = await ViserClient(url(classroom)).connect()
        await become_presenter(teacher, classroom)
        student = await ViserClient(url(classroom), local_address="127.0.0.7").connect()
        if room.choice != label:
            await teacher.set_gui("Which arm", label)
            await until(lambda: room.choice == label and room.presenter.session is not None
                        and room.presenter.session.built, what="the class shown the arm")
        arm = room.state.arm
        # the new arm's box and button on the teacher's screen, not the last arm's of the same names (the server has
        # built them; their messages may still be on the way, and what is sent to a removed widget is lost)
        joints = room.presenter.session.joints
        await until(lambda: all(teacher.gui.get(name, {}).get("uuid") == widget._impl.uuid for name, widget in
                                ((typed_label(arm), joints.typed), ("Set these values", joints.apply_typed))),
                    what="the new arm's joint panel on the teacher's screen")
        await teacher.set_gui(typed_label(arm), " ".join(str(v) for v in POSE_SHOWN[label]))
        await teacher.set_gui("Set these values", True)
        q = arm.joints([np.radians(v) if kind == "R" else v / 1000 for v, kind in zip(POSE_SHOWN[label], arm.joint_types)])
        await until(lambda: np.allclose(room.state.q, q), what="the class's arm at the pose")
        await teacher.set_gui("Show singularity overlay", True)
        live = room.live
        await until(lambda: live.gauges.visible and live.flange.content.startswith("| n |"), what="the live panel in full")
        p = 1000 * arm.fk(q)[:3, 3]
        given = [re.compile(rf"(?<![\d.]){re.escape(number(abs(v), '.1f'))}(?!\d)") for v in p] + \
                [re.compile(rf"(?<![\d.]){re.escape(number(abs(v), '.0f'))}(?![\d.])") for v in p]

        await teacher.set_gui("Challenge", "Pose shown: tool position")
        sent = {teacher: [], student: []}  # every text each browser is sent from here on: a panel made now is made held
        shown_before = {client: set(client.markdown) for client in sent}
        for client, texts in sent.items():
            client._handle = functools.partial(recording, client._handle, texts)
        await teacher.set_gui("Start the challenge", True)
        member = await until(lambda: next((m for m in room.members.values() if m.card is not None), None), what="the card")
        held = [live.flange] + [view for session in (member.session, room.presenter.session)
                                for view in (session.readouts.pose, session.decoupling.steps if arm.name in Arm.UR_PRESETS
                                             else session.decoupling.readout,
                                             *(lesson.readout for lesson in session.lessons if "position" in lesson.answers))]
        for client in (teacher, student):
            await until(lambda: all(client.markdown.get(m._impl.uuid) == HELD_BACK for m in held if m._impl.uuid in client.markdown),
                        what="the readouts held back on the screen")
            # (a panel's redraw under way as Start arrives may come after it, with what the screen already showed)
            shown = given_away(sent[client], shown_before[client], given)
            assert not shown, shown
            if arm.name == "kr210":  # (its gripper's box, filled with the target's pose in either convention)
                await client.set_gui("ROS/Gazebo gripper convention", True)
        if arm.name == "kr210":
            await until(lambda: all(session.lessons[0].urdf.value for session in (member.session, room.presenter.session)),
                        what="the gripper shown in the URDF convention")
            for client in (teacher, student):
                assert "x y z (mm) roll pitch yaw (°)" in client.gui
                shown = given_away(sent[client], shown_before[client], given)
                assert not shown, shown
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: live.flange.content.startswith("| n |"), what="the class's tool pose back")
        if arm.name == "kr210":  # the box filled again
            await until(lambda: member.session.lessons[0].typed.value.startswith(number(1000 * kr210_to_urdf(arm.fk(q))[0, 3], ".1f")),
                        what="the gripper's box filled again")

        await teacher.set_gui("Challenge", "Pose shown: det J")
        await teacher.set_gui("Start the challenge", True)
        await until(lambda: room.challenges.running and live.gauges.content == HELD_BACK, what="the live gauges held back")
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: live.gauges.content != HELD_BACK, what="the gauges back")
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_a_student_joining_a_dh_table_challenge_is_not_sent_the_table(classroom):
    """A student's arm is made as the challenge starts. Its *DH table* folder was made with the table in it and then
    hidden: hidden in the panel, but sent to the browser (until 2026-12-05). A panel made while a challenge runs is
    made with what it asks held back, and the table comes at the end."""
    from ur10teach.features.dh_table import dh_table_markdown

    room = classroom.classroom

    async def scenario():
        teacher = await ViserClient(url(classroom)).connect()
        await become_presenter(teacher, classroom)
        student = await ViserClient(url(classroom), local_address="127.0.0.7").connect()
        rows = [line for line in dh_table_markdown(room.state.arm.dh).splitlines()[2:]]  # the table's rows
        sent: list = []
        student._handle = functools.partial(recording, student._handle, sent)
        await teacher.set_gui("Challenge", "Type the UR10's DH table")
        await teacher.set_gui("Start the challenge", True)
        member = await until(lambda: next((m for m in room.members.values() if m.card is not None), None), what="the card")
        table = member.session.dh_table.table
        await until(lambda: student.markdown.get(member.session.dh_table.held_back._impl.uuid) == HELD_BACK, what="the folder held back")
        assert not [text for _, text in sent if any(row in text for row in rows)]
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: all(row in student.markdown.get(table._impl.uuid, "") for row in rows), what="the table at the end")
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_the_buttons_that_would_answer_a_velocity_a_branch_count_or_a_dh_table_are_off_while_it_runs(classroom):
    """*Find the joint rates* gave *Straight up*'s rates for "0 0 100"; the branch-count map drew where *Four branches
    only* holds; the DH table folder, its row on the arm and the walkthrough's rows gave *Type the UR10's DH table*.
    While each runs they are taken away from the student (a forged click is refused and changes nothing) and from
    the presenter; the walkthrough still walks through the procedure, without the rows' values; all is back at
    the end."""
    room = classroom.classroom

    async def refused(student, handle, value, count: int) -> None:
        await student.send(messages.GuiUpdateMessage(handle._impl.uuid, {"value": value}))
        await until(lambda: sum(HELD_BACK in body for _, body in student.received.notifications) == count, what="the refusal")

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Straight up", "127.0.0.10")
        velocity = member.session.velocity
        for session, client in ((member.session, student), (room.presenter.session, teacher)):
            await until(lambda: client.gui.get("Find the joint rates", {}).get("visible") is False
                        and session.velocity.held_back.content == HELD_BACK, what="Find the joint rates off")
        await student.send(messages.GuiUpdateMessage(velocity.solve._impl.uuid, {"value": True}))
        await until(lambda: "Off while the class challenge" in velocity.refusal.line.content, what="the refusal, beside it")
        assert velocity.rates.content == ""
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: student.gui.get("Find the joint rates", {}).get("visible") is True, what="it back")
        await student.set_gui("Find the joint rates", True)
        await until(lambda: "°/s" in velocity.rates.content, what="the rates found again")

        await teacher.set_gui("Challenge", "Four branches only")
        await teacher.set_gui("Start the challenge", True)
        reach_map = member.session.reach_map
        await until(lambda: student.gui.get("Show branch-count map", {}).get("visible") is False
                    and teacher.gui.get("Show branch-count map", {}).get("visible") is False, what="the map's switch off")
        await refused(student, reach_map.enabled, True, 1)
        assert reach_map.enabled.value is False and reach_map.computed == 0 and reach_map.image is None
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: student.gui.get("Show branch-count map", {}).get("visible") is True, what="the switch back")

        await teacher.set_gui("Challenge", "Type the UR10's DH table")
        await teacher.set_gui("Start the challenge", True)
        table, walkthrough = member.session.dh_table, member.session.walkthrough
        await until(lambda: table.table.visible is False and table.highlight.visible is False
                    and room.presenter.session.dh_table.table.visible is False
                    and student.gui.get("Show a row on the arm", {}).get("visible") is False, what="the table off")
        await refused(student, table.highlight, "row 2", 2)
        assert table.highlight.value == "none" and table._frames.highlight_row is None
        for _ in range(3):  # z axes, x axes, row 1: its words, without its values
            await student.set_gui("Step", "Next ▶")
        await until(lambda: "Row 1" in walkthrough.text.content, what="the walkthrough at row 1")
        assert "Row 1:" not in walkthrough.text.content and walkthrough._frames.highlight_row is None
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: table.table.visible is True and student.gui.get("Show a row on the arm", {}).get("visible") is True,
                    what="the table back")
        await student.set_gui("Step", "Next ▶")  # row 2, with its values
        await until(lambda: "Row 2: θ" in walkthrough.text.content and walkthrough._frames.highlight_row == 2,
                    what="the rows' values back")
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_the_desktop_arms_heaviest_pose_is_found_by_the_student_not_by_its_search(classroom):
    """The course's statics exercise as a class challenge, on its own arm: while it runs, the desktop arm's search
    and the Forces folder's ‖τ‖ map (each marks the answer) are taken away and a forged click is refused; the
    student's ‖τ‖ is checked against the refined search, the projector counts how close each student came,
    and the end puts every arm on the largest ‖τ‖ and gives the buttons back."""

    room = classroom.classroom
    room.challenges.clock = itertools.count(0.0, 10.0).__next__  # each check a while after the last: none is paced

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Desktop arm: heaviest pose", "127.0.0.8")
        session = member.session
        assert session.arm.name == "three_dof"
        await until(lambda: "Top (x–z plane)" in member.camera.direction.options, what="its views named in its axes (y up)")
        await until(lambda: teacher.shown("*largest torque, on 3-DOF desktop arm*"), what="the arm named as the picker names it")
        search, mapped = session.lessons[2].search, session.statics.mapped
        await until(lambda: student.gui.get("Find the pose that needs the largest ‖τ‖", {}).get("visible") is False
                    and student.gui.get(mapped.label, {}).get("visible") is False
                    and len(student.shown(HELD_BACK)) == 2, what="the search and the map off, saying why")
        await until(lambda: student.shown("**Given:** F = (20, 0, 0) N at the tool, in the base frame."), what="the task's force")
        q = session.state.q
        await student.send(messages.GuiUpdateMessage(search._impl.uuid, {"value": True}))
        await student.send(messages.GuiUpdateMessage(mapped._impl.uuid, {"value": True}))
        lines = (session.lessons[2].refusal.line, session.statics.map_refusal.line)  # each below its button
        await until(lambda: all(line.visible and HELD_BACK[:40] in line.content for line in lines), what="both refused")
        assert np.array_equal(session.state.q, q) and session.statics._map is None and not session.lessons[2]._map
        assert mapped.value is False

        async def check(degrees) -> None:
            await until(lambda: student.gui.get(typed_label(session.arm), {}).get("value") == display_text(session.arm, session.state.q),
                        what="the panel's joints up to date")
            await student.set_gui(typed_label(session.arm), " ".join(str(v) for v in degrees))
            await student.set_gui("Set these values", True)
            await until(lambda: np.allclose(session.state.q, np.radians(degrees)), what="the typed joints")
            attempts = member.student.attempts
            await student.set_gui("Check my answer", True)
            await until(lambda: member.student.attempts == attempts + 1, what="the check")

        await check([0, 0, 90])  # forearm up: only the upper arm's 1.35 m is across the force
        assert "under half the largest" in member.student.verdict.group
        # the projector's dots grow with the arm shown, as its drawing does (2.6 m across)
        tools = await until(lambda: room.presenter.tools, what="the class's tools on the projector")
        assert tools.working.point_size == pytest.approx(WORKING_DOT * room.drawing.size / UR10_SIZE)
        assert tools.working.point_size > 1.8 * WORKING_DOT
        await until(lambda: any("under half the largest" in t for t in teacher.shown("### Desktop arm")), what="the group on the board")
        await check([-90, 0, 180])  # stretched, turned across the force: the base holds 20 N × (l5 + l1)
        assert member.student.solved_after is not None
        await teacher.set_gui("End and show the solution", True)
        worst, _ = C.solution(room.challenges.run.challenge, session.arm)
        await until(lambda: np.allclose(session.state.q, worst) and student.gui.get(mapped.label, {}).get("visible") is True
                    and student.gui.get("Find the pose that needs the largest ‖τ‖", {}).get("visible") is True,
                    what="the arm on the answer, the buttons back")
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_a_time_limit_beyond_its_range_is_refused_as_it_is_typed(classroom):
    """Found by a monkey in a real browser: the teacher typed 99999 in the time limit's box and pressed Enter. The
    slider showed its end, 120, while the server kept 99999, refused only once the challenge was started."""
    room = classroom.classroom
    label = "Time limit (min, 0: none)"

    async def scenario():
        teacher = await ViserClient(url(classroom)).connect()
        await become_presenter(teacher, classroom)
        desk = await until(lambda: next((m.desk for m in room.members.values() if m.desk is not None), None), what="the desk")
        await teacher.set_gui(label, 10)
        # accepted, not only held: viser runs the check on its thread pool, and a check of 10 run after 99999 came
        # read 99999 and put back the limit accepted before 10 (a CI run on a busy machine)
        await until(lambda: desk.minutes.value == getattr(desk.minutes, "_accepted_value", None) == 10, what="the limit typed")
        await teacher.set_gui(label, 99999)
        await until(lambda: teacher.shown("from 0 to 120, got 99999"), what="the refusal beside the limit")
        await until(lambda: teacher.gui[label]["value"] == desk.minutes.value == 10, what="the limit put back")
        await teacher.close()

    asyncio.run(scenario())


def test_the_presenter_asks_the_class_about_the_pose_it_is_shown(classroom):
    """A question thought of in the lecture, with no file: the teacher puts the class's arm somewhere and asks where
    its tool is, then asks the class to reach that pose. The numbers are asked at the joints shown (p checked
    against the DH table's own product); the reach sends the class's arm home first, since every student's arm
    starts where it is; asked again from home, it is refused, saying why."""
    room = classroom.classroom
    room.challenges.clock = itertools.count(0.0, 10.0).__next__
    shown = [20, -70, 100, -30, 60, 10]

    async def scenario():
        teacher = await ViserClient(url(classroom)).connect()
        await become_presenter(teacher, classroom)
        student = await ViserClient(url(classroom), local_address="127.0.0.7").connect()
        arm = room.state.arm
        await teacher.set_gui(typed_label(arm), " ".join(str(v) for v in shown))
        await teacher.set_gui("Set these values", True)
        await until(lambda: np.allclose(room.state.q, np.radians(shown)), what="the class's arm at the pose")
        await teacher.set_gui("Challenge", "Pose shown: wrist centre")  # the UR10 has no spherical wrist
        await until(lambda: teacher.shown("Not about the arm shown: the wrist centre is where a spherical wrist's three axes meet, and this arm "
                                          "has none: the last three axes do not meet"), what="why not")
        await teacher.set_gui("Challenge", "Pose shown: tool position")
        given = "**Given:** q = (20°, -70°, 100°, -30°, 60°, 10°)"
        await until(lambda: any("asked of the class's arm as it stands when you start" in t for t in teacher.shown(given)),
                    what="the preview, at the joints shown")
        await teacher.set_gui(typed_label(arm), " ".join(str(v) for v in [25, *shown[1:]]))  # moved after it was picked
        await teacher.set_gui("Set these values", True)
        await until(lambda: teacher.shown("**Given:** q = (25°, -70°"), what="the preview following the class's arm")
        await teacher.set_gui(typed_label(arm), " ".join(str(v) for v in shown))
        await teacher.set_gui("Set these values", True)
        await until(lambda: teacher.shown(given), what="the preview back at the joints shown")
        await teacher.set_gui("Start the challenge", True)
        member = await until(lambda: next((m for m in room.members.values() if m.card is not None), None), what="the card")
        await until(lambda: student.shown(given), what="the joints given to the student")
        # and on the projector, under the board's title: what the class was asked, at the joints it was shown
        await until(lambda: any(given in t and "joined" in t for t in teacher.shown("### Pose shown: tool position")),
                    what="the task's terms on the board")
        assert np.allclose(room.state.q, np.radians(shown))  # a numbers task leaves the class's arm where it is
        p = 1000 * arm.dh.fk(np.radians(shown))[:3, 3]
        await student.set_gui("Your numbers (x, y, z)", " ".join(f"{v:.3f}" for v in p))
        await student.set_gui("Check my answer", True)
        await until(lambda: member.student.solved_after is not None, what="solved")
        await teacher.set_gui("End and show the solution", True)
        # (viser runs each click on a thread of its own: a start sent at once could come first, and be refused)
        await until(lambda: room.challenges.run.ended, what="the challenge over")

        await teacher.set_gui("Challenge", "Pose shown: reach it")
        await teacher.set_gui("Start the challenge", True)
        home = arm.specs.home
        await until(lambda: member.card is not None and member.card.challenge.title == "Pose shown: reach it"
                    and np.allclose(room.state.q, home) and np.allclose(member.session.state.q, home),
                    what="the class's arm, and so the student's, gone home")
        assert np.allclose(np.degrees(member.card.challenge.joints), shown)
        await until(lambda: student.gui.get(typed_label(arm), {}).get("value") == display_text(arm, member.session.state.q),
                    what="the panel's joints up to date")
        await student.set_gui(typed_label(arm), " ".join(str(v) for v in shown))
        await student.set_gui("Set these values", True)
        await until(lambda: np.allclose(member.session.state.q, np.radians(shown)), what="the student's joints")
        attempts = member.student.attempts
        await student.set_gui("Check my answer", True)
        await until(lambda: member.student.attempts == attempts + 1, what="the check")
        assert member.student.verdict.solved
        await teacher.set_gui("End and show the solution", True)
        await until(lambda: not room.challenges.running, what="the end")

        await until(lambda: np.allclose(room.state.q, np.radians(shown)), what="the class's arm on the solution")
        await teacher.set_gui(typed_label(arm), " ".join(f"{v:.9f}" for v in np.degrees(home)))
        await teacher.set_gui("Set these values", True)
        await until(lambda: np.allclose(room.state.q, home), what="the class's arm at home: the pose shown is home")
        await teacher.set_gui("Challenge", "Pose shown: reach it")
        await teacher.set_gui("Start the challenge", True)
        await until(lambda: teacher.shown("on the answer, and so is its home pose, where it would go instead: move it off the answer first"), what="the refusal")
        assert not room.challenges.running
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())


def test_the_projector_frames_a_students_tool_that_has_left_its_view_unless_the_teacher_has_turned_it(classroom):
    """A class spread over the workspace had most of its tools off the projector's canvas in lecture mode, their
    names piled at its edge. The projector's camera now frames them all again when one leaves the view, unless the
    teacher has moved the camera since it was framed."""
    from ur10core.orientation import from_frame
    from ur10teach.features.branch_labels import ScreenView

    async def scenario():
        teacher, student, member = await a_student_in(classroom, "Reach the target", "127.0.0.9")
        presenter, world, arm = classroom.classroom.presenter, classroom.classroom.drawing.world, member.session.arm

        def seen(point) -> bool:  # on the projector's canvas
            view = ScreenView.of(presenter.client.camera)
            pixels, depth = view.to_screen(np.asarray(point)[None])
            return bool(depth[0] > 0 and (np.abs(pixels[0]) <= (view.width / 2, view.height / 2)).all())

        def tool_out_of_view(seed: int) -> tuple[np.ndarray, np.ndarray]:
            """Joints whose tool is off the canvas, the one nearest the middle of the view: a farther one (the first
            found, on a busy host) widened the view to the whole workspace, leaving nothing out of it to try next."""
            q = arm.sample_joints(5000, seed=seed)
            tools = from_frame(world, arm.fk(q)[:, :3, 3])
            view = ScreenView.of(presenter.client.camera)
            pixels, depth = view.to_screen(tools)
            out = np.flatnonzero((depth <= 0) | (np.abs(pixels) > (view.width / 2, view.height / 2)).any(axis=-1))
            k = out[np.argmin(np.linalg.norm(tools[out] - np.asarray(view.look_at), axis=-1))]
            return q[k], tools[k]

        def dot_at(tool) -> bool:
            tools = presenter.tools
            return tools is not None and tools.working.visible and np.allclose(tools.working.points, tool, atol=3e-3)

        def camera(position, look_at, width: int = 1280, height: int = 800):  # what the projector's browser reports
            return messages.ViewerCameraMessage(wxyz=(0.0, 0.0, 0.0, 1.0), position=position, fov=0.87, near=0.01, far=100.0,
                                                image_height=height, image_width=width, look_at=look_at, up_direction=(0, 0, 1.0))

        await teacher.send(camera((2.1, -1.9, 1.4), (0.2, 0.0, 0.5), 1920, 1080))  # its canvas, on the projector
        await until(lambda: not np.allclose(presenter.client.camera.position, (2.1, -1.9, 1.4)), what="the projector framed")
        q, tool = tool_out_of_view(1)
        member.session.apply(lambda state: state.set_joints(q))
        await until(lambda: dot_at(tool) and seen(tool), what="the projector framing the student's tool")
        # elsewhere out of view: framed again, with where the class has been (the camera settles, not hops)
        earlier = tool
        q, tool = tool_out_of_view(3)
        member.session.apply(lambda state: state.set_joints(q))
        await until(lambda: dot_at(tool) and seen(tool), what="the projector framing the student's new place")
        assert seen(earlier), "the projector lost where the student was before"
        # the teacher turns the camera to a view of their own: it stays, wherever the student goes
        turned = camera((0.9, -0.6, 0.8), (0.4, 0.0, 0.6), 1920, 1080)
        await teacher.send(turned)
        await until(lambda: np.allclose(presenter.client.camera.position, turned.position), what="the teacher's own view")
        q, tool = tool_out_of_view(2)
        member.session.apply(lambda state: state.set_joints(q))
        await until(lambda: dot_at(tool), what="the student's dot moved on the projector")
        assert np.allclose(presenter.client.camera.position, turned.position) and not seen(tool)
        for client in (teacher, student):
            await client.close()

    asyncio.run(scenario())
