"""Headless Chromium from Debian, driven by playwright (never a downloaded browser).

Everything here waits on a condition: the value the server holds, text on the page, or a
3D view that has settled or changed. A loaded machine (both cores held by busy loops,
software WebGL) only makes the waits longer; :data:`~ur10dev.waiting.HANG_TIMEOUT` is
reached by a hang alone.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import time
from typing import Iterator
from urllib.parse import urlparse

import numpy as np
import pytest

from .waiting import HANG_TIMEOUT, wait_for

CHROMIUM = os.environ.get("UR10_TEACH_CHROMIUM", "/usr/bin/chromium")
ARGS = [
    "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--disable-quic",
    "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync",
]
VIEWPORT = {"width": 1280, "height": 800}
#: Several live tabs share two cores of software WebGL: keep them small.
SMALL_VIEWPORT = {"width": 900, "height": 640}
CONNECTED = "svg.tabler-icon-cloud-check"
#: Playwright's own waits take milliseconds.
HANG_TIMEOUT_MS = int(1000 * HANG_TIMEOUT)
#: Seconds after which a key press that has not shown on a slider is taken as lost.
LOST_PRESS = 10.0
#: Seconds a browser may show a change the server does not hold before it is taken as lost on its way (a message
#: takes milliseconds; undoing and redoing a change that was only late does no harm: the last one sent stands).
LOST_CHANGE = 3.0
#: Below this share of changed pixels two pictures of the 3D view are the same picture.
SAME_PICTURE = 0.0005
#: Frames a second a test page draws while nothing asks for more. viser redraws the 3D view every
#: frame, changed or not, and software WebGL spends about 0.2 s of CPU on each: at the display's
#: rate a page would hold both cores, and the server and the test with them. A check that needs
#: the newest picture asks for frames (:func:`drawn_frames`), which are drawn at once.
IDLE_FPS = 1
_FRAMES_ON_DEMAND = f"""(() => {{
    const frame = window.requestAnimationFrame.bind(window), cancel = window.cancelAnimationFrame.bind(window);
    const interval = {1000 / IDLE_FPS}, waiting = new Map();
    let drawn = -1, next = 0, ids = 0;
    window.__framesAsked = 0;
    window.requestAnimationFrame = callback => {{
        const id = ++ids;
        const tick = now => {{
            if (now !== drawn) {{
                if (now < next && window.__framesAsked <= 0) {{ waiting.set(id, frame(tick)); return; }}
                drawn = now;
                next = now + interval;
                window.__framesAsked -= 1;
            }}
            waiting.delete(id);
            callback(now);
        }};
        waiting.set(id, frame(tick));
        return id;
    }};
    window.cancelAnimationFrame = id => {{ if (waiting.has(id)) {{ cancel(waiting.get(id)); waiting.delete(id); }} }};
}})();"""


def launch(playwright):
    if not os.path.exists(CHROMIUM):
        pytest.fail(f"{CHROMIUM} not found: install Debian's chromium (apt-get install -y chromium; scripts/test.sh does)")
    return playwright.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)


#: A phone, as playwright's device descriptors give one (an iPhone's Safari); its window's size is given apart.
PHONE = {"user_agent": "Mozilla/5.0 (iPhone; CPU iPhone OS 17_5 like Mac OS X) AppleWebKit/605.1.15 (KHTML, like Gecko) "
                       "Version/17.5 Mobile/15E148 Safari/604.1", "is_mobile": True, "has_touch": True}


def open_app(browser, url: str, viewport: dict = VIEWPORT, zoom: float = 1.0, device: dict | None = None):
    """A page of the app in a fresh context of ``browser``, recording every request it makes (``page.requests``).

    ``zoom`` is the browser's zoom (1.5 = 150 %): fewer CSS pixels in the same window, each drawn larger.
    ``device``: what else the browser says and does (:data:`PHONE`).
    """
    page = browser.new_page(viewport={"width": round(viewport["width"] / zoom), "height": round(viewport["height"] / zoom)},
                            device_scale_factor=zoom, **(device or {}))
    page.requests, page.console = [], []
    page.on("request", lambda request: page.requests.append(request.url))
    page.on("websocket", lambda socket: page.requests.append(socket.url))
    page.on("console", lambda message: page.console.append(message.text))
    page.add_init_script(_FRAMES_ON_DEMAND)
    page.goto(url)
    wait_for(lambda: page.locator(CONNECTED).count() > 0, what="the page to connect")
    return page


def dismiss_software_notice(page) -> None:
    """Close viser's "Software WebGL rendering detected" notice, which covers the 3D view's top left corner."""
    notice = page.locator(".mantine-Notification-root", has_text="Software WebGL")
    if notice.count():
        # the button's own click, not a pointer's: while software WebGL still draws, playwright never finds it
        # "stable" enough to click (the README's screenshots were taken with the notice on)
        notice.locator("button").first.dispatch_event("click")
        wait_for(lambda: notice.count() == 0, what="the software-rendering notice to close")


def foreign_requests(page, url: str) -> list[str]:
    """What ``page`` asked of any host but the app's own (the app works offline: this must be empty)."""
    own = urlparse(url).netloc
    return [r for r in page.requests if urlparse(r).netloc != own and not r.startswith(("data:", "blob:"))]


def dom_id(handle) -> str:
    """The DOM id viser gives a GUI element (its uuid)."""
    return f"[id='{handle._impl.uuid}']"


class LostOnItsWay:
    """Whether the browser has shown a value the server does not hold for :data:`LOST_CHANGE` s: a change the server
    never received (the browser holds it already, so doing it again sends nothing; it must be undone and redone).
    Call it with whether they disagree at each look; it says so once, then starts counting again."""

    def __init__(self) -> None:
        self.since: float | None = None

    def __call__(self, disagree: bool) -> bool:
        if not disagree:
            self.since = None
        elif self.since is None:
            self.since = time.monotonic()
        elif time.monotonic() - self.since > LOST_CHANGE:
            self.since = None
            return True
        return False


def lose_the_next_value(client, handle) -> None:
    """The next value ``handle``'s widget sends from the browser is lost on its way (to test the helpers below):
    viser's handler looks the widget of each value up by its uuid in the client's table, and ignores a value whose
    widget it does not find (the gate looks it up too, before, to check the value's type)."""

    class LosesOne(dict):
        lost = False

        def get(self, uuid, default=None):
            if uuid == handle._impl.uuid and not self.lost and sys._getframe(1).f_code.co_name == "_handle_gui_updates":
                self.lost = True
                return default
            return super().get(uuid, default)

    client.gui._gui_input_handle_from_uuid = LosesOne(client.gui._gui_input_handle_from_uuid)


def step_slider(page, handle, key: str, target: float, limit: int = 200) -> None:
    """Press arrow keys on a viser slider's thumb until the browser shows ``target``, then wait for the server.

    ``key`` is the direction to start in. Each press is waited for before the next; a press
    that has not shown after :data:`LOST_PRESS` s was lost (the thumb lost focus while the
    panel re-rendered) and is made again; an overshoot is walked back. A last press the server
    never received (:class:`LostOnItsWay`) is undone and made again.
    """
    thumb = page.locator(f"{dom_id(handle)} [role=slider]")
    opposite = {"ArrowRight": "ArrowLeft", "ArrowLeft": "ArrowRight"}
    increases = key == "ArrowRight"
    lost = LostOnItsWay()
    for _ in range(limit):
        value = float(thumb.get_attribute("aria-valuenow"))
        if abs(value - target) < 1e-9:
            held = lambda: abs(handle.value - target) < 1e-9  # noqa: E731
            if wait_for(lambda: held() or lost(True), what=f"the server to hold {target} for {handle.label!r}") and held():
                return
            top = abs(float(thumb.get_attribute("aria-valuemax")) - target) < 1e-9
            thumb.focus()  # the last press never reached the server: a step away, and back on the next round
            thumb.press("ArrowLeft" if top else "ArrowRight")
            continue
        thumb.focus()
        thumb.press(key if (value < target) == increases else opposite[key])
        with contextlib.suppress(AssertionError):  # not shown: the press was lost, and is made again
            wait_for(lambda: float(thumb.get_attribute("aria-valuenow")) != value, timeout=LOST_PRESS, what="the press")
    raise AssertionError(f"slider still at {thumb.get_attribute('aria-valuenow')} after {limit} presses, wanted {target}")


def set_checkbox(page, handle, value: bool) -> None:
    """Click a viser checkbox, as a student does, until the server holds ``value``.

    A click can land while the panel is still moving (sliding back from its folded strip, a
    folder unfolding) and miss the box. So a box the browser still shows unchanged a moment
    later is clicked again; a box that shows the new value is clicked twice more (off, on) only
    once the server has not received it (:class:`LostOnItsWay`). What counts is the value the
    server received, not the box's look.
    """
    box = page.locator(dom_id(handle))
    lost = LostOnItsWay()

    def clicked_through() -> bool:
        if handle.value == value:
            return True
        shown = box.is_checked() == value
        if not shown or lost(shown):  # (a click the server never received is undone, then made again)
            box.click()
        with contextlib.suppress(AssertionError):
            wait_for(lambda: handle.value == value, timeout=1.0)
        return handle.value == value

    wait_for(clicked_through, what=f"the server to hold {value!r} for {handle.label!r}")


def choose(page, dropdown, option: str) -> None:
    """Pick ``option`` in a viser dropdown, with the mouse, and wait until the server holds it.

    A dropdown clicked while its folder is still unfolding opens its list out of sight, or not at
    all; an open list closes when the panel beside it is rebuilt (a formula typeset, a folder
    filled). So the list is opened and the option clicked again until the server holds it.

    A pick the server never received leaves the browser's box showing ``option``, and clicking
    it again sends nothing: the server's choice is picked back first (:class:`LostOnItsWay`), as a
    student would. (A CI run most likely waited two minutes on such a box, 2026-12-06.)
    """
    lost = LostOnItsWay()

    def in_the_list(label: str) -> bool:
        """Open the list if it is closed and click ``label``; whether the click landed."""
        choice = page.get_by_role("option", name=label, exact=True)
        if not choice.is_visible():
            page.locator(dom_id(dropdown)).click()
            with contextlib.suppress(Exception):
                choice.wait_for(state="visible", timeout=1000 * LOST_PRESS)
        with contextlib.suppress(Exception):  # the list may have closed since it showed
            choice.click(timeout=1000 * LOST_PRESS)
            return True
        return False

    def picked() -> bool:
        if dropdown.value == option:
            return True
        held = dropdown.value
        if lost(_box_text(page, dropdown) == option) and in_the_list(held):
            wait_for(lambda: _box_text(page, dropdown) == held, what=f"the box back on {held!r}")
        if _box_text(page, dropdown) != option:
            in_the_list(option)
        with contextlib.suppress(AssertionError):
            wait_for(lambda: dropdown.value == option, timeout=1.0)
        return dropdown.value == option

    try:
        wait_for(picked, what=f"the server to hold {option!r}, picked in the open list")
    except AssertionError as error:
        raise AssertionError(f"{error}; the server holds {dropdown.value!r}, the browser's box shows "
                             f"{_box_text(page, dropdown)!r}; its console: {getattr(page, 'console', [])[-10:]}") from None


def _box_text(page, dropdown) -> str | None:
    """What a viser dropdown's box shows in the browser (None while it is not on the page)."""
    return page.evaluate("id => document.getElementById(id)?.value ?? null", dropdown._impl.uuid)


def text_field(page, handle):
    """The <input> of a viser text field (its label, not the input, carries the handle's uuid)."""
    return page.locator(f"label[for='{handle._impl.uuid}']").locator("xpath=ancestor::div[2]").locator("input").first


def type_text(page, handle, text: str) -> None:
    """Type ``text`` into a text field, as a student does, and wait until the server holds it.

    (viser's panel sends one message per 50 ms and keeps only the newest: a button pressed
    at once after typing could carry the typing away.) Typing the server never received
    (:class:`LostOnItsWay`) is typed again.
    """
    field = text_field(page, handle)
    lost = LostOnItsWay()

    def typed() -> bool:
        if handle.value == text:
            return True
        if field.input_value() != text or lost(True):
            if field.input_value() == text:  # never received: a fill of what the field holds would send nothing
                field.fill(text + " ")
            field.fill(text)
            field.press("Enter")
        with contextlib.suppress(AssertionError):
            wait_for(lambda: handle.value == text, timeout=1.0)
        return handle.value == text

    wait_for(typed, what=f"the server to hold {text!r} for {handle.label!r}")


def _press_until(press, done, what: str) -> None:
    """``press()`` until ``done()`` holds, waiting a few seconds after each: a press may land while
    its folder is still opening, or while the panel is being redrawn, and do nothing."""

    def pressed() -> bool:
        if done():
            return True
        press()
        with contextlib.suppress(AssertionError):
            wait_for(done, timeout=10.0)
        return bool(done())

    wait_for(pressed, what=what)


def _locator(page, element):
    """``element`` (a viser handle, or a playwright locator) as a playwright locator."""
    from playwright.sync_api import Locator

    return element if isinstance(element, Locator) else page.locator(dom_id(element))


def click(page, button, done, what: str) -> None:
    """Click ``button`` (a viser handle, or a playwright locator) until ``done()`` holds: a single click
    may land while the panel above it grows (a text filled in, a folder opening) and hit nothing."""
    _press_until(_locator(page, button).click, done, what)


def unfold(page, title: str, widget) -> None:
    """Open a folded folder by its title, as a student does, until ``widget`` (a viser handle, or a
    playwright locator) shows (a CI run once waited two minutes on a single click that opened nothing)."""
    _press_until(lambda: page.get_by_text(title, exact=True).first.click(), _locator(page, widget).is_visible,
                 f"the {title} folder open")


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


def drag_the_gizmo(page, session, gate, finger: bool = False) -> None:
    """Grab one of the gizmo's arrows with the mouse (or a ``finger``, on a touch screen) and pull, until a drag
    reaches the server.

    Each try ends in one of two ways the server sees: the gizmo's drag ended (the arrow was
    under the pointer), or the camera moved (the pointer orbited the view instead).
    """
    box = page.locator("canvas").first.bounding_box()
    flange = session.state.last.flange
    size = session.ik_target.gizmo.scale  # the arrows' length, sized to the arm
    touch = page.context.new_cdp_session(page) if finger else None

    def press(kind: str, u: float | None = None, v: float | None = None) -> None:
        if touch is not None:
            points = [] if kind == "up" else [{"x": u, "y": v}]
            touch.send("Input.dispatchTouchEvent", {"type": {"down": "touchStart", "move": "touchMove", "up": "touchEnd"}[kind],
                                                    "touchPoints": points})
        elif kind == "move":
            page.mouse.move(u, v)
        else:
            getattr(page.mouse, kind)()

    for axis, share in [(0, 0.75), (0, 0.6), (1, 0.75), (2, 0.75), (0, 0.9)]:
        u, v = project(session.client.camera, flange[:3, 3] + share * size * flange[:3, axis], box)
        drags, cameras = gate.passed["TransformControlsDragEndMessage"], gate.passed["ViewerCameraMessage"]
        # the gizmo reads the pointer once a frame: each move is given a drawn frame
        if touch is None:
            press("move", u, v)
            drawn_frames(page, 2)
        press("down", u, v)
        drawn_frames(page, 2)
        for step in range(1, 11):
            press("move", u - 3 * step, v + 2 * step)
            drawn_frames(page, 1)
        press("up")
        wait_for(lambda: gate.passed["TransformControlsDragEndMessage"] > drags
                 or gate.passed["ViewerCameraMessage"] > cameras, what="the server to hear the drag or the orbit")
        if gate.passed["TransformControlsDragEndMessage"] > drags:
            wait_for(lambda: session.state.last.cause in ("target", "dropped"), what="the drag applied")
            return
    raise AssertionError("no arrow of the gizmo was under the pointer")


def neighbourhood(pixels: np.ndarray, u: float, v: float, box: dict, radius: int = 4) -> np.ndarray:
    """The (2r+1)² pixels around page point (u, v), from a canvas screenshot."""
    x, y = int(round(u - box["x"])), int(round(v - box["y"]))
    return pixels[max(y - radius, 0): y + radius + 1, max(x - radius, 0): x + radius + 1].reshape(-1, 3)


# ---------------------------------------------------------------------------- the 3D view


def canvas_pixels(page) -> np.ndarray:
    """The 3D view as an (H, W, 3) array, from a real screenshot of the page."""
    from PIL import Image

    box = page.locator("canvas").first.bounding_box()  # the panel is docked beside it, not over it
    png = page.screenshot(clip=box, scale="css")
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def changed(before: np.ndarray, after: np.ndarray) -> float:
    """The share of the canvas that changed visibly between two pictures."""
    return float(changed_mask(before, after).mean())


def changed_mask(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    if before.shape != after.shape:
        return np.ones(after.shape[:2], bool)
    return np.abs(after.astype(int) - before.astype(int)).sum(axis=-1) > 60


def where_changed(before: np.ndarray, after: np.ndarray) -> str:
    """Where two pictures differ, for an assertion message: the share and the box around it."""
    mask = changed_mask(before, after)
    if not mask.any():
        return "nothing changed"
    rows, cols = np.nonzero(mask)
    return (f"{mask.mean():.2%} of the canvas changed, within x {cols.min()}–{cols.max()}, "
            f"y {rows.min()}–{rows.max()} of {mask.shape[1]} × {mask.shape[0]}")


def drawn_frames(page, count: int = 3) -> None:
    """Have the page draw ``count`` more frames now, and wait until it has (each draws what has arrived)."""
    page.evaluate("""n => new Promise(done => {
        window.__framesAsked = Math.max(window.__framesAsked, 0) + n;
        const next = k => k ? requestAnimationFrame(() => next(k - 1)) : done();
        next(n);
    })""", count)


def settled_canvas(page, timeout: float = HANG_TIMEOUT) -> np.ndarray:
    """The 3D view once it stops changing: two pictures, a few drawn frames apart, that agree.

    A fixed wait is not enough on a loaded machine (two cores of software WebGL): a scene
    still arriving would show up as a change later.
    """
    last = canvas_pixels(page)
    result: list[np.ndarray] = []

    def agrees() -> bool:
        nonlocal last
        drawn_frames(page)
        now = canvas_pixels(page)
        if changed(last, now) < SAME_PICTURE:
            result.append(now)
            return True
        last = now
        return False

    wait_for(agrees, timeout, what="the 3D view to settle")
    return result[0]


def canvas_changed(page, before: np.ndarray, at_least: float, what: str) -> np.ndarray:
    """The settled 3D view once at least ``at_least`` of it differs from ``before``; fails naming ``what``."""
    found: list[np.ndarray] = []

    def differs() -> bool:
        now = settled_canvas(page)
        if changed(before, now) >= at_least:
            found.append(now)
            return True
        differs.last = now
        return False

    differs.last = before
    try:
        wait_for(differs, what=what)
    except AssertionError:
        raise AssertionError(f"{what}: {where_changed(before, differs.last)} (wanted {at_least:.2%})") from None
    return found[0]


# ---------------------------------------------------------------------------- the classroom


@contextlib.contextmanager
def class_browsers(app, count: int = 2, viewport: dict = SMALL_VIEWPORT, device: dict | None = None) -> Iterator[tuple[list, list]]:
    """``count`` browsers on a classroom server (``--shared``), each in a process of its own (``device``: a
    :data:`PHONE`'s, say).

    Yields (pages, members) in the order they joined, the members being ``ur10teach.serving.classroom``'s,
    all still watching (on a server whose gate trusts loopback the first would present: the teacher's own
    computer's); closes the browsers after, and fails if any page asked anything of another host.
    """
    from playwright.sync_api import sync_playwright

    url = f"http://127.0.0.1:{app.port}"
    with sync_playwright() as playwright:
        browsers = [launch(playwright) for _ in range(count)]
        try:
            pages = []
            for browser in browsers:  # one at a time: the members' order is the pages'
                pages.append(open_app(browser, url, viewport, device=device))
                wait_for(lambda: len(app.classroom.members) == len(pages), what="the browser to join")
            yield pages, list(app.classroom.members.values())
            for page in pages:
                assert not foreign_requests(page, url), f"requests that leave the app's host: {foreign_requests(page, url)}"
        finally:
            for browser in browsers:
                browser.close()


@contextlib.contextmanager
def teacher_and_student(app) -> Iterator[tuple]:
    """Two browsers on a classroom server: (teacher page, student page, teacher's member, student's member)."""
    with class_browsers(app, 2) as (pages, members):
        yield (*pages, *members)


def ask_to_present(page, member, code: str, done, what: str) -> None:
    """Type the join code and press "Become presenter", as a teacher does, until ``done()`` holds; a page on the
    server's own computer that found nobody presenting presents already, and only waits for it."""
    from ur10teach.serving.classroom import PRESENTER

    wait_for(lambda: member.role == PRESENTER or member.join_code is not None, what="the page's role")
    if member.role == PRESENTER:
        wait_for(done, what=what)
        return
    type_text(page, member.join_code, code)
    click(page, page.get_by_role("button", name="Become presenter"), done, what)


@contextlib.contextmanager
def a_site_linking_to(url: str) -> Iterator[str]:
    """The address of a page on another site ("localhost", not 127.0.0.1: another host is another site to a browser)
    with one link, ``#app``, to ``url``: a course's page a student follows the app's link from."""
    import http.server
    import threading

    body = f'<a id="app" href="{url}">the app</a>'.encode()

    class Page(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args) -> None:
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Page)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://localhost:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()
