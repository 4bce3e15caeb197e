"""Shared fixtures: the presets, reproducible random joint vectors and poses, and servers."""

from __future__ import annotations

import numpy as np
import pytest

from ur10core import Arm


@pytest.fixture(scope="session")
def course() -> Arm:
    return Arm.preset("course")


@pytest.fixture(scope="session", params=Arm.PRESETS)
def any_arm(request) -> Arm:
    return Arm.preset(request.param)


def random_joints(n: int, seed: int = 0) -> np.ndarray:
    """n joint vectors uniform in (-π, π]^6."""
    return -np.random.default_rng(seed).uniform(-np.pi, np.pi, (n, 6))


def wrapped_difference(a, b) -> np.ndarray:
    """|a − b| modulo 2π, in [0, π]."""
    return np.abs(np.remainder(np.asarray(a) - np.asarray(b) + np.pi, 2 * np.pi) - np.pi)


@pytest.fixture
def app():
    """A server in independent mode on a free port, in this process."""
    from app.server import TeachingServer

    server = TeachingServer(port=0)
    yield server
    server.stop()


@pytest.fixture
def classroom():
    """A server in shared demo mode (``--shared``) on a free port, in this process."""
    from app.server import TeachingServer

    server = TeachingServer(port=0, shared=True)
    yield server
    server.stop()


@pytest.fixture(autouse=True)
def collect_garbage_after_server_tests(request):
    """Finalise what a test's servers left behind (asyncio tasks whose errors nobody read) now.

    On CPython 3.11 a collection that runs inside ``ast.parse`` (pytest rewriting an
    import) and finalises such a task, which formats a traceback and so parses too,
    corrupts the parser's recursion counter: https://github.com/python/cpython/issues/106905.
    Only tests that run servers leave such tasks.
    """
    yield
    if any(request.node.get_closest_marker(name) for name in ("server", "browser")):
        import gc

        gc.collect()


@pytest.fixture(scope="module")
def playwright():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        yield playwright


@pytest.fixture
def open_page(playwright, request):
    """Opens the app in a fresh browser, like one student's laptop; closes them after the test.

    ``open_page(known=0, viewport=VIEWPORT, zoom=1.0, server=None)`` → (page, the browser's
    session): ``known`` sessions exist already, ``zoom`` is the browser's zoom (1.5 = 150 %),
    and the server is the ``app`` fixture's unless given (it must be in independent mode).
    One browser process per page: tabs of one process share its software-GPU process, and
    a second tab starves while the first renders.
    """
    from tests.browser_support import CONNECTED, VIEWPORT, dom_id, launch, wait_for

    browsers = []

    def open_page(known: int = 0, viewport: dict = VIEWPORT, zoom: float = 1.0, server=None):
        server = server or request.getfixturevalue("app")
        browser = launch(playwright)
        browsers.append(browser)
        # the browser's zoom: fewer CSS pixels in the same window, each drawn larger
        page = browser.new_page(viewport={"width": round(viewport["width"] / zoom), "height": round(viewport["height"] / zoom)},
                                device_scale_factor=zoom)
        console: list[str] = []
        page.on("console", lambda message: console.append(message.text))
        page.goto(f"http://127.0.0.1:{server.port}")
        try:
            wait_for(lambda: len(server.sessions) > known, timeout=30, what="the server to set up the client")
            session = list(server.sessions.values())[known]
            page.wait_for_selector(dom_id(session.joints.sliders[0]), timeout=30_000)  # the panel is drawn
            page.wait_for_selector(CONNECTED, state="attached", timeout=30_000)  # a loaded CI machine has taken over 10 s
        except Exception as error:
            raise AssertionError(f"page never became ready ({error}); browser console: {console[-20:]}") from None
        page.wait_for_timeout(1500)  # let the first frames render
        return page, session

    yield open_page
    for browser in browsers:
        browser.close()
