"""Headless Chromium from Debian, driven by playwright (never a downloaded browser)."""

from __future__ import annotations

import contextlib
import os
import time
from typing import Callable, Iterator

import numpy as np
import pytest

CHROMIUM = os.environ.get("UR10_TEACH_CHROMIUM", "/usr/bin/chromium")
ARGS = [
    "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--disable-quic",
    "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync",
]
VIEWPORT = {"width": 1280, "height": 800}
#: Several live tabs share two cores of software WebGL: keep them small.
SMALL_VIEWPORT = {"width": 900, "height": 640}
CONNECTED = "svg.tabler-icon-cloud-check"


def launch(playwright):
    if not os.path.exists(CHROMIUM):
        pytest.fail(f"{CHROMIUM} not found: install Debian's chromium (apt-get install -y chromium; scripts/test.sh does)")
    return playwright.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)


def wait_for(condition: Callable[[], object], timeout: float = 30.0, what: str = "condition") -> object:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


def step_slider(page, handle, key: str, target: float, limit: int = 200) -> None:
    """Press arrow keys on a viser slider's thumb until the browser shows ``target``.

    ``key`` is the direction to start in. Pressing a fixed number of times is not enough on a
    loaded machine: a key event can land while the panel is re-rendering and the thumb has
    lost focus, and a press can show a moment late. So each press waits (up to a second)
    for the value it moves, and an overshoot is walked back with the opposite key. The test
    stays about the server following the browser, not about keyboard timing.
    """
    thumb = page.locator(f"{dom_id(handle)} [role=slider]")
    opposite = {"ArrowRight": "ArrowLeft", "ArrowLeft": "ArrowRight"}
    increases = key == "ArrowRight"
    for _ in range(limit):
        value = float(thumb.get_attribute("aria-valuenow"))
        if abs(value - target) < 1e-9:
            return
        thumb.focus()
        thumb.press(key if (value < target) == increases else opposite[key])
        deadline = time.monotonic() + 1.0
        while float(thumb.get_attribute("aria-valuenow")) == value and time.monotonic() < deadline:
            time.sleep(0.02)
    raise AssertionError(f"slider still at {thumb.get_attribute('aria-valuenow')} after {limit} presses, wanted {target}")


def dom_id(handle) -> str:
    """The DOM id viser gives a GUI element (its uuid)."""
    return f"[id='{handle._impl.uuid}']"


def set_checkbox(page, handle, value: bool, timeout: float = 15.0) -> None:
    """Click a viser checkbox, as a student does, until the server holds ``value``.

    A click can land while the panel is still moving (sliding back from its folded strip, a
    folder unfolding) and miss the box; playwright's ``check()`` then fails although nothing
    in the app is wrong (seen once in CI). So a box the browser still shows unchanged after
    a second is clicked again; a box that shows the new value is never clicked twice. What
    counts is the value the server received, not the box's look.
    """
    box = page.locator(dom_id(handle))
    deadline = time.monotonic() + timeout
    while handle.value != value:
        if time.monotonic() > deadline:
            raise AssertionError(f"the server still holds {handle.value!r} for {handle.label!r} after {timeout} s of clicks")
        if box.is_checked() != value:
            box.click()
        settle = time.monotonic() + 1.0
        while handle.value != value and time.monotonic() < settle:
            time.sleep(0.02)


def choose(page, dropdown, option: str) -> None:
    """Pick ``option`` in a viser dropdown, with the mouse."""
    page.locator(dom_id(dropdown)).click()
    page.get_by_role("option", name=option, exact=True).click()
    page.wait_for_timeout(200)


def text_field(page, handle):
    """The <input> of a viser text field (its label, not the input, carries the handle's uuid)."""
    return page.locator(f"label[for='{handle._impl.uuid}']").locator("xpath=ancestor::div[2]").locator("input").first


def project(camera, point, box) -> tuple[float, float]:
    """Pixel of a world point in the canvas, from the camera the browser reported (OpenCV convention)."""
    w, x, y, z = camera.wxyz
    R = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])
    p = R.T @ (np.asarray(point) - camera.position)
    focal = (box["height"] / 2) / np.tan(camera.fov / 2)
    return box["x"] + box["width"] / 2 + focal * p[0] / p[2], box["y"] + box["height"] / 2 + focal * p[1] / p[2]


def canvas_pixels(page) -> np.ndarray:
    """The 3D view as an (H, W, 3) array, from a real screenshot of the page."""
    import io

    from PIL import Image

    box = page.locator("canvas").first.bounding_box()  # the panel is docked beside it, not over it
    png = page.screenshot(clip=box, scale="css")
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def changed(before: np.ndarray, after: np.ndarray) -> float:
    """The share of the canvas that changed visibly between two pictures."""
    return float(changed_mask(before, after).mean())


def changed_mask(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    return np.abs(after.astype(int) - before.astype(int)).sum(axis=-1) > 60


def where_changed(before: np.ndarray, after: np.ndarray) -> str:
    """Where two pictures differ, for an assertion message: the share and the box around it."""
    mask = changed_mask(before, after)
    if not mask.any():
        return "nothing changed"
    rows, cols = np.nonzero(mask)
    return (f"{mask.mean():.2%} of the canvas changed, within x {cols.min()}–{cols.max()}, "
            f"y {rows.min()}–{rows.max()} of {mask.shape[1]} × {mask.shape[0]}")


def settled_canvas(page, timeout: float = 30.0, interval_ms: int = 1000) -> np.ndarray:
    """The 3D view once it stops changing: two screenshots ``interval_ms`` apart that agree.

    A fixed wait is not enough on a loaded machine (the whole browser suite shares two
    cores of software WebGL): a scene still arriving would show up as a change later.
    """
    deadline = time.monotonic() + timeout
    last = canvas_pixels(page)
    while True:
        page.wait_for_timeout(interval_ms)
        now = canvas_pixels(page)
        if changed(last, now) < 0.0005:
            return now
        if time.monotonic() > deadline:
            raise AssertionError(f"the 3D view did not settle in {timeout} s: {where_changed(last, now)}")
        last = now


def labelled_input(page, label: str):
    """The <input> of the text field whose label reads ``label``."""
    return page.locator("label", has_text=label).locator("xpath=ancestor::div[2]").locator("input").first


@contextlib.contextmanager
def teacher_and_student(app) -> Iterator[tuple]:
    """Two browsers on a classroom server (``--shared``), each in a process of its own.

    Yields (teacher page, student page, teacher's member, student's member), the members
    being ``app.classroom``'s, both still watching; closes both browsers after.
    """
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browsers = [launch(playwright), launch(playwright)]
        try:
            pages = []
            for browser in browsers:
                page = browser.new_page(viewport=SMALL_VIEWPORT)
                page.goto(f"http://127.0.0.1:{app.port}")
                page.wait_for_selector(CONNECTED, timeout=30_000)
                pages.append(page)
            wait_for(lambda: len(app.classroom.members) == 2, what="both browsers")
            yield (*pages, *app.classroom.members.values())
        finally:
            for browser in browsers:
                browser.close()


def ask_to_present(page, code: str) -> None:
    """Type the join code and press "Become presenter", as a teacher does."""
    labelled_input(page, "Join code").fill(code)
    page.wait_for_timeout(200)
    page.get_by_role("button", name="Become presenter").click()
