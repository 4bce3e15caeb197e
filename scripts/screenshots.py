"""The README's screenshots, taken in headless Chromium from Debian: python scripts/screenshots.py

Writes docs/images/eight_ghosts.png (the home pose, every branch numbered),
docs/images/lecture_mode.png (``--lecture``: big type, the panel beside the arm),
docs/images/wrist_singularity.png (the arm on the wrist singularity, its overlay and gauges),
docs/images/branch_count_map.png (the map in the arm's plane, the ghosts hidden) and
docs/images/kr210_dh_frames.png (the KR210 with its DH frames and row 3 drawn on it) and
docs/images/desktop_arm_branches.png (the desktop arm on its IK target, its other branches as ghosts).
``python scripts/screenshots.py kr210_dh_frames.png`` takes only the ones named.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from playwright.sync_api import sync_playwright  # noqa: E402

from ur10teach.serving.server import TeachingServer  # noqa: E402
from ur10dev.browser import CONNECTED, dom_id, launch, wait_for  # noqa: E402

OUT = ROOT / "docs" / "images"
WINDOW = {"width": 1280, "height": 720}


def show_the_map(page, session) -> None:
    session.ik_target.show_ghosts.value = False
    page.get_by_text("Reachable with this orientation", exact=True).first.click()
    page.locator(dom_id(session.reach_map.enabled)).check()
    wait_for(lambda: session.reach_map.image is not None, what="the map")


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
    pick_arm(page, session, "KUKA KR210 (spherical wrist)").dh_table.highlight.value = "row 3"


def show_the_desktop_arm(page, session) -> None:
    import numpy as np

    from ur10core.orientation import transform_from_quaternion

    desktop = pick_arm(page, session, "The course's 3-DOF desktop arm")
    goal = desktop.arm.fk(np.radians([25.0, -35.0, 60.0]))  # where all four branches reach
    desktop.apply(lambda state: state.move_target(transform_from_quaternion(np.array([1.0, 0, 0, 0]), goal[:3, 3])))
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
            browser = launch(playwright)
            page = browser.new_page(viewport=WINDOW)
            page.goto(f"http://127.0.0.1:{server.port}")
            page.wait_for_selector(CONNECTED, state="attached", timeout=30_000)
            wait_for(lambda: server.sessions, what="the session")
            session = next(iter(server.sessions.values()))
            wait_for(lambda: session.drawing.branches.numbers.placed, what="the numbers")
            if prepare is not None:
                prepare(page, session)
            page.wait_for_timeout(8000)  # the real meshes take a while to draw in software WebGL
            for close in page.get_by_role("button").filter(has=page.locator("svg.tabler-icon-x")).all():
                close.click()  # the software-WebGL notice
            page.wait_for_timeout(1000)
            page.screenshot(path=str(OUT / name))
            browser.close()
    finally:
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
    for name in sys.argv[1:] or SHOTS:
        shoot(name, **SHOTS[name])
