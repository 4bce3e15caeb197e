"""The README's screenshots, taken in headless Chromium from Debian: python scripts/screenshots.py

Writes docs/images/eight_ghosts.png (the home pose, every branch numbered),
docs/images/lecture_mode.png (``--lecture``: big type, the panel beside the arm),
docs/images/wrist_singularity.png (the arm on the wrist singularity, its overlay and gauges),
docs/images/branch_count_map.png (the map in the arm's plane, the ghosts hidden) and
docs/images/kr210_dh_frames.png (the KR210 with its DH frames and row 3 drawn on it) and
docs/images/desktop_arm_branches.png (the desktop arm on its IK target, its other branches as ghosts) and
docs/images/challenge_projector.png (the projector during a class challenge, eight students at it).
``python scripts/screenshots.py kr210_dh_frames.png`` takes only the ones named.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from playwright.sync_api import sync_playwright  # noqa: E402

from ur10teach.serving.server import TeachingServer  # noqa: E402
from ur10dev.browser import CONNECTED, dismiss_software_notice, dom_id, launch, settled_canvas, wait_for  # noqa: E402

OUT = ROOT / "docs" / "images"
WINDOW = {"width": 1280, "height": 720}


def show_the_map(page, session) -> None:
    session.ik_target.show_ghosts.value = False
    page.get_by_text("Reachable with this orientation", exact=True).first.click()
    page.locator(dom_id(session.reach_map.enabled)).check()
    wait_for(lambda: session.reach_map.image is not None, what="the map")
    page.get_by_text("Branches that reach each point", exact=False).first.scroll_into_view_if_needed()  # its key too


def pick_arm(page, session, label: str):
    """Choose ``label`` in the arm picker, as a student does; the new arm's session once its sliders show."""
    from ur10dev.browser import choose

    choose(page, session.arm_picker.dropdown, label)
    server = SERVER["now"]
    wait_for(lambda: any(s.choice == label for s in server.sessions.values()), what=label)
    picked = next(iter(server.sessions.values()))
    page.wait_for_selector(dom_id(picked.joints.sliders[0]), timeout=30_000)
    return picked


def show_the_kr210(page, session) -> None:
    pick_arm(page, session, "KR210 (spherical wrist)").dh_table.highlight.value = "row 3"


def show_the_desktop_arm(page, session) -> None:
    import numpy as np

    from ur10core.orientation import transform_from_quaternion

    desktop = pick_arm(page, session, "3-DOF desktop arm")
    goal = desktop.arm.fk(np.radians([25.0, -35.0, 60.0]))  # where all four branches reach
    # "typed": as a typed target moves it, the gizmo goes with it (a drag's, "target", is where the hand left it)
    desktop.apply(lambda state: state.move_target(transform_from_quaternion(np.array([1.0, 0, 0, 0]), goal[:3, 3]), cause="typed"))
    wait_for(lambda: int(desktop.state.last.solution.valid.sum()) == 4, what="its four branches")


def show_a_singularity(page, session) -> None:
    """The wrist singularity with its overlay on: axes 4 and 6 in line, the gauges in the open folder."""
    page.get_by_text("Singularities", exact=True).first.click()
    page.locator(dom_id(session.singularities.enabled)).check()
    wait_for(lambda: session.drawing.overlay.enabled, what="the overlay")
    session.apply(lambda state: state.place_in_singularity("wrist"))


#: the server of the screenshot being taken (a ``prepare`` may need it)
SERVER: dict = {}


def shoot(name: str, lecture: bool, prepare=None) -> None:
    server = SERVER["now"] = TeachingServer(port=0, lecture=lecture)
    try:
        with sync_playwright() as playwright:
            browser, page = open_page(playwright, server)
            wait_for(lambda: server.sessions, what="the session")
            session = next(iter(server.sessions.values()))
            wait_for(lambda: session.drawing.branches.numbers.placed, what="the numbers")
            if prepare is not None:
                prepare(page, session)
            photograph(page, name)
            browser.close()
    finally:
        server.stop()


def open_page(playwright, server: TeachingServer):
    """A browser on ``server``'s page, once connected: (browser, page)."""
    browser = launch(playwright)
    page = browser.new_page(viewport=WINDOW)
    page.goto(f"http://127.0.0.1:{server.port}")
    page.wait_for_selector(CONNECTED, state="attached", timeout=30_000)
    return browser, page


def photograph(page, name: str) -> None:
    """The page once its 3D view has settled (the real meshes take a while in software WebGL), without
    viser's notice about software rendering."""
    settled_canvas(page)
    dismiss_software_notice(page)
    settled_canvas(page)
    page.screenshot(path=str(OUT / name))


#: A class of eight for the projector's screenshot: (nickname, what their arm does: "target" solves it, else an offset in m)
CLASS = (("Ada", "target"), ("Bo", "target"), ("", (0.0, 0.0, 0.06)), ("Chen", (0.0, 0.0, 0.09)), ("", (0.05, 0.0, 0.0)),
         ("Dee", "target"), ("", (0.0, -0.12, 0.04)), ("Eli", (0.0, 0.0, 0.05)))


def shoot_a_challenge(name: str) -> None:
    """The projector during *Reach the target*: eight headless students, five of whom have it wrong so far."""
    import asyncio
    import threading

    import numpy as np

    from ur10dev.browser import ask_to_present
    from ur10dev.viser_client import ViserClient

    server = TeachingServer(port=0, shared=True)
    room, leave = server.classroom, threading.Event()

    async def students() -> None:
        clients = [await ViserClient(f"http://127.0.0.1:{server.port}", local_address=f"127.0.0.{20 + k}").connect()
                   for k in range(len(CLASS))]
        await asyncio.to_thread(leave.wait)
        for client in clients:
            await client.close()

    thread = threading.Thread(target=asyncio.run, args=(students(),))
    try:
        with sync_playwright() as playwright:
            browser, page = open_page(playwright, server)
            wait_for(lambda: room.members, what="the projector")
            teacher = next(iter(room.members.values()))
            thread.start()
            wait_for(lambda: len(room.members) == 1 + len(CLASS), what="the class")
            ask_to_present(page, teacher, room.code, lambda: teacher.desk is not None, "the Challenge folder")
            room.challenges.start(teacher, next(c for c in room.challenges.offered if c.title == "Reach the target"), 600.0)
            members = [m for m in room.members.values() if m is not teacher]
            wait_for(lambda: all(m.card is not None for m in members), what="every student's card")
            arm, goal = room.challenges.run.arm, np.array(room.challenges.run.challenge.joints)
            for member, (nickname, doing) in zip(members, CLASS):
                room.challenges.run.rename(member.student, nickname)
                target = arm.fk(goal)
                if doing != "target":
                    target[:3, 3] += doing
                q = arm.ik(target).nearest(goal).q
                member.session.apply(lambda state: state.set_joints(q))
                room.challenges.check(member)
            page.get_by_text("Classroom", exact=True).first.click()  # folded: the board near the top
            wait_for(lambda: page.get_by_text("3 solved").count() > 0, what="the board")
            photograph(page, name)
            browser.close()
    finally:
        leave.set()
        if thread.is_alive():
            thread.join()
        server.stop()


SHOTS = {
    "eight_ghosts.png": dict(lecture=False),
    "lecture_mode.png": dict(lecture=True),
    "wrist_singularity.png": dict(lecture=False, prepare=show_a_singularity),
    "branch_count_map.png": dict(lecture=False, prepare=show_the_map),
    "kr210_dh_frames.png": dict(lecture=False, prepare=show_the_kr210),
    "desktop_arm_branches.png": dict(lecture=False, prepare=show_the_desktop_arm),
}

if __name__ == "__main__":
    OUT.mkdir(parents=True, exist_ok=True)
    for name in sys.argv[1:] or [*SHOTS, "challenge_projector.png"]:
        if name == "challenge_projector.png":
            shoot_a_challenge(name)
        else:
            shoot(name, **SHOTS[name])
