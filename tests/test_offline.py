"""Offline: the page a student opens asks nothing of any host but the app's own."""

from __future__ import annotations

from urllib.parse import urlparse

import pytest
from playwright.sync_api import sync_playwright

from app.server import TeachingServer

from .browser_support import CONNECTED, VIEWPORT, dom_id, launch, set_checkbox, wait_for

pytestmark = pytest.mark.browser


@pytest.mark.parametrize("shared", [False, True], ids=["independent", "shared"])
def test_every_request_stays_on_the_app_host(shared):
    app = TeachingServer(port=0, shared=shared)
    own = f"127.0.0.1:{app.port}"
    requests: list[str] = []
    try:
        with sync_playwright() as playwright:
            browser = launch(playwright)
            page = browser.new_page(viewport=VIEWPORT)
            page.on("request", lambda request: requests.append(request.url))
            page.on("websocket", lambda socket: requests.append(socket.url))
            page.goto(f"http://{own}")
            page.wait_for_selector(CONNECTED, timeout=30_000)
            if not shared:
                # exercise what could pull in fonts, MathML helpers or plots from a CDN
                wait_for(lambda: len(app.sessions) == 1, what="the session")
                session = next(iter(app.sessions.values()))
                page.wait_for_selector(dom_id(session.singularity.enabled), timeout=30_000)
                set_checkbox(page, session.singularity.enabled, True)
                wait_for(lambda: page.locator("math").count() > 0, what="the formula")
                set_checkbox(page, session.workspace.enabled, True)
                wait_for(lambda: session.workspace._cloud is not None, timeout=30, what="the cloud")
            page.wait_for_timeout(3000)
            browser.close()
    finally:
        app.stop()
    assert requests, "the page made no requests at all?"
    foreign = [url for url in requests if urlparse(url).netloc != own and not url.startswith(("data:", "blob:"))]
    assert not foreign, f"requests that leave the app's host: {foreign}"
    assert any(url.startswith("ws://") for url in requests)  # the live connection is to the app too
