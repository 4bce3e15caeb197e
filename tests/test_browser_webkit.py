"""Safari's engine: the app in WebKit (Debian's WebKitGTK, driven through its own WebDriver by Selenium).

Students on a Mac open the page in Safari. viser's client is the same page there; what the app puts in it (its
style, the element that reports the screen, the panel's markdown and number boxes) is checked here in WebKit too.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import subprocess
from typing import Iterator
from urllib.parse import urlparse

import numpy as np
import pytest

from ur10teach.serving.gate import browser_of
from ur10dev.browser import CONNECTED, LostOnItsWay, dom_id
from ur10dev.waiting import HANG_TIMEOUT, wait_for

pytestmark = pytest.mark.browser

WEBKIT_DRIVER = shutil.which("WebKitWebDriver")
XVFB = shutil.which("Xvfb")


@contextlib.contextmanager
def virtual_screen() -> Iterator[str]:
    """An X display of its own (Xvfb; WebKitGTK has no headless mode): its name, once it takes clients."""
    read, write = os.pipe()
    screen = subprocess.Popen([XVFB, "-displayfd", str(write), "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                              pass_fds=(write,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write)
    try:
        with os.fdopen(read) as told:  # Xvfb writes the display's number once it is ready (an empty line: it failed)
            number = told.readline().strip()
        assert number, "Xvfb did not start"
        yield f":{number}"
    finally:
        screen.terminate()
        screen.wait(HANG_TIMEOUT)


@contextlib.contextmanager
def webkit(url: str) -> Iterator:
    """A WebKit window (1100 × 760) on ``url``, connected to the app."""
    from selenium import webdriver
    from selenium.webdriver.common.by import By
    from selenium.webdriver.webkitgtk.options import Options
    from selenium.webdriver.webkitgtk.service import Service

    with virtual_screen() as display:
        # WebKit takes the page's language from the environment, and a bare "C" locale (a CI machine's) is no
        # language tag: viser's number formatting raised on it and the page stayed blank. A Mac always has one.
        env = {**os.environ, "DISPLAY": display, "LANGUAGE": "en_US", "LANG": "en_US.UTF-8", "LC_ALL": "en_US.UTF-8",
               "LIBGL_ALWAYS_SOFTWARE": "1"}
        driver = webdriver.WebKitGTK(options=Options(), service=Service(executable_path=WEBKIT_DRIVER, env=env))
        try:
            driver.set_window_size(1100, 760)
            driver.get(url)
            wait_for(lambda: driver.find_elements(By.CSS_SELECTOR, CONNECTED), what="the WebKit page to connect")
            yield driver
        finally:
            driver.quit()


def canvas_pixels(driver) -> np.ndarray:
    """The 3D view as drawn (H, W, 3): the window's screenshot cut to viser's canvas."""
    from PIL import Image

    box = driver.execute_script("""const c = [...document.querySelectorAll('canvas')]
        .sort((a, b) => b.clientWidth * b.clientHeight - a.clientWidth * a.clientHeight)[0].getBoundingClientRect();
        return [c.left, c.top, c.right, c.bottom, window.devicePixelRatio];""")
    shot = Image.open(io.BytesIO(driver.get_screenshot_as_png())).convert("RGB")
    left, top, right, bottom = (round(v * box[4]) for v in box[:4])
    return np.asarray(shot.crop((left, top, min(right, shot.width), min(bottom, shot.height)))).astype(int)


@pytest.mark.skipif(not (WEBKIT_DRIVER and XVFB), reason="no WebKitWebDriver or Xvfb here (scripts/test.sh installs "
                                                         "Debian's webkit2gtk-driver and xvfb)")
def test_in_safari_s_engine_a_student_sees_the_arm_and_moves_a_joint(light_app):
    """The panel, the arm drawn, the page's screen reported, a joint moved with the keyboard, joints typed, and the
    page reloaded finding its arm (by the cookie the page was given)."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    app = light_app
    with webkit(f"http://127.0.0.1:{app.port}") as driver:
        wait_for(lambda: len(app.sessions) == 1, what="the WebKit page's session")
        (client_id, session), = app.sessions.items()
        shown = lambda: driver.execute_script("return document.body.innerText")  # noqa: E731
        wait_for(lambda: "UR10 kinematics (course)" in shown(), what="the panel's title in WebKit")

        # the page says its ratio and that its window is wide, as Chromium's does: its labels are placed for it
        wait_for(lambda: app.screens.of(client_id) == (1.0, False), what="the WebKit page's screen reported")

        def coloured() -> int:  # the ghosts' and the gizmo's colours, drawn by WebGL (the 3D labels are black on white)
            pixels = canvas_pixels(driver)
            return int((pixels.max(axis=-1) - pixels.min(axis=-1) > 80).sum())

        wait_for(lambda: coloured() > 5000, what="the arm's coloured ghosts drawn by WebKit's WebGL")

        # nothing asked of any host but the app's (a class network often has no internet)
        asked = driver.execute_script("return performance.getEntriesByType('resource').map(e => e.name)")
        assert asked and all(urlparse(name).netloc == f"127.0.0.1:{app.port}" for name in asked if "://" in name
                             and not name.startswith(("data:", "blob:"))), asked

        # θ1 two degrees up with the keyboard: the server's arm follows, and the page's summary says so
        thumb, lost = driver.find_element(By.CSS_SELECTOR, f"{dom_id(session.joints.sliders[0])} [role=slider]"), LostOnItsWay()

        def at_32() -> bool:  # a press at a time until the thumb shows 32°; a value never received is sent again
            if abs(np.degrees(session.state.q[0]) - 32.0) < 1e-6:
                return True
            shown_value = float(thumb.get_attribute("aria-valuenow"))
            if shown_value < 32.0:
                thumb.send_keys(Keys.ARROW_RIGHT)
            elif lost(True):
                thumb.send_keys(Keys.ARROW_LEFT)
            return False

        wait_for(at_32, what="θ1 at 32° from WebKit's keys")
        wait_for(lambda: "base 32.00°" in shown(), what="the joint summary")

        # all six typed in the box (its label carries the handle's id) and set: the arm goes there
        typed = "0, -90, 90, 0, 90, 0"
        box = driver.find_element(By.XPATH, f"//label[@for='{session.joints.typed._impl.uuid}']/ancestor::div[2]//input")
        box.clear()
        box.send_keys(typed)
        lost = LostOnItsWay()

        def held() -> bool:  # typing the server never received is typed again
            if session.joints.typed.value == typed:
                return True
            if lost(box.get_attribute("value") == typed):
                box.send_keys(Keys.BACK_SPACE, typed[-1])
            return False

        wait_for(held, what="the typed joints to reach the server")
        driver.find_element(By.CSS_SELECTOR, dom_id(session.joints.apply_typed)).click()
        wait_for(lambda: np.allclose(np.degrees(session.state.q), [0, -90, 90, 0, 90, 0]), what="the typed joints set")

        # narrowed as a phone's (viser's sheet over the canvas): the page says so, and the camera is told (which then
        # frames the arm above the sheet: in Chromium, test_in_a_narrow_window_the_arm_is_seen_above_the_panel)
        driver.set_window_size(400, 800)
        wait_for(lambda: app.screens.of(client_id) == (1.0, True), what="the narrow WebKit window reported")
        wait_for(lambda: session.camera.narrow, what="the camera told the window is narrow")

        # the page reloaded: the server knows the browser again by the cookie it gave the page, and its arm is back
        assert len(browser_of(session.client).split(" ")) == 2, "no cookie came back with WebKit's websocket"
        driver.refresh()
        wait_for(lambda: any(k != client_id and np.allclose(np.degrees(s.state.q), [0, -90, 90, 0, 90, 0])
                             for k, s in app.sessions.items()), what="the arm as it was, after WebKit's reload")
