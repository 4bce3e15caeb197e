"""Shared fixtures: the presets, reproducible random joint vectors and poses, and servers."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from ur10core import Arm


def urs_own_solver():
    """The ``ur_analytic_ik`` module (UR's official numbers, test-only). It has wheels up to Python 3.11 only
    (pyproject.toml): from 3.12 its tests are skipped, before that they need it."""
    if sys.version_info >= (3, 12):
        return pytest.importorskip("ur_analytic_ik")
    import ur_analytic_ik
    return ur_analytic_ik


def pytest_collection_modifyitems(config, items):
    """ur10core's doctests are core tests: their numbers come from its backend."""
    for item in items:
        if isinstance(item, pytest.DoctestItem):
            item.add_marker(pytest.mark.core)


@pytest.fixture(scope="session")
def course() -> Arm:
    return Arm.preset("course")


@pytest.fixture(scope="session", params=Arm.UR_PRESETS)
def any_arm(request) -> Arm:
    return Arm.preset(request.param)


def random_joints(n: int, seed: int = 0) -> np.ndarray:
    """n joint vectors uniform in (-π, π]^6."""
    return -np.random.default_rng(seed).uniform(-np.pi, np.pi, (n, 6))


def typed_copy(arm: Arm, with_limits: bool = False) -> Arm:
    """A student's copy of a preset: its DH table typed in (``Arm.from_dh``, numerical IK), with the preset's joint
    limits or the editor's defaults."""
    rows = [(r.a, r.alpha, r.d, r.theta, r.joint) for r in arm.dh.rows]
    return Arm.from_dh(rows, arm.dh.convention, limits=arm.limits if with_limits else None)


def wrapped_difference(a, b) -> np.ndarray:
    """|a − b| modulo 2π, in [0, π]."""
    return np.abs(np.remainder(np.asarray(a) - np.asarray(b) + np.pi, 2 * np.pi) - np.pi)


@pytest.fixture
def app():
    """A server in independent mode on a free port, in this process."""
    from ur10teach.serving.server import TeachingServer

    server = TeachingServer(port=0)
    yield server
    server.stop()


@pytest.fixture
def light_app():
    """A server in independent mode with the light view (``--light``): what the browser tests open.

    Software WebGL draws the default shading at one or two frames a second on two cores,
    the light view at 15–35: the browser suite checks what is drawn, and the screenshots
    come many times faster.
    """
    from ur10teach.serving.server import TeachingServer

    server = TeachingServer(port=0, light=True)
    yield server
    server.stop()


@pytest.fixture
def classroom():
    """A server in shared demo mode (``--shared``) on a free port, in this process."""
    from ur10teach.serving.server import TeachingServer

    server = TeachingServer(port=0, shared=True)
    yield server
    server.stop()


@pytest.fixture
def laptop_classroom():
    """:func:`classroom`, its browsers standing for students' laptops (loopback is not the server's own computer, whose
    page would present as it opened): a page presents only once it enters the join code."""
    from ur10teach.serving.gate import Gate
    from ur10teach.serving.server import TeachingServer

    server = TeachingServer(port=0, shared=True, gate=Gate(trust_loopback=False))
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

    ``open_page(known=0, viewport=SMALL_VIEWPORT, zoom=1.0, server=None, drawn=True, device=None)`` → (page, the
    browser's session), once the panel is drawn and (``drawn``) the 3D view has settled:
    ``known`` sessions exist already, ``zoom`` is the browser's zoom (1.5 = 150 %), ``device`` a phone
    (``ur10dev.browser.PHONE``) or the like, and the
    server is the ``light_app`` fixture's unless given (it must be in independent mode). One browser process per page:
    tabs of one process share its software-GPU process, and a second tab starves while the
    first renders. Every page must stay offline: a request to any other host fails the test.
    """
    from ur10dev.browser import (
        HANG_TIMEOUT_MS, SMALL_VIEWPORT, dismiss_software_notice, dom_id, foreign_requests, launch, open_app, settled_canvas,
    )
    from ur10dev.waiting import wait_for

    opened = []

    def open_page(known: int = 0, viewport: dict = SMALL_VIEWPORT, zoom: float = 1.0, server=None, drawn: bool = True,
                  device: dict | None = None):
        server = server or request.getfixturevalue("light_app")
        url = f"http://127.0.0.1:{server.port}"
        browser = launch(playwright)
        page = open_app(browser, url, viewport, zoom, device)
        opened.append((browser, page, url))
        try:
            wait_for(lambda: len(server.sessions) > known, what="the server to set up the client")
            session = list(server.sessions.values())[known]
            page.wait_for_selector(dom_id(session.joints.sliders[0]), timeout=HANG_TIMEOUT_MS)  # the panel is drawn
            if drawn:
                settled_canvas(page)
                dismiss_software_notice(page)
                settled_canvas(page)
        except Exception as error:
            raise AssertionError(f"page never became ready ({error}); browser console: {page.console[-20:]}") from None
        return page, session

    yield open_page
    foreign = [r for _, page, url in opened for r in foreign_requests(page, url)]
    for browser, _, _ in opened:
        browser.close()
    assert not foreign, f"requests that leave the app's host: {foreign}"
