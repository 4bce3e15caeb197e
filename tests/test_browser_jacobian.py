"""The Jacobian's panels in real headless Chromium: forces and gravity, the ellipsoids, velocities."""

from __future__ import annotations

import numpy as np
import pytest

from .browser_support import canvas_pixels, dom_id, wait_for
from .test_browser_course_arms import changed

pytestmark = pytest.mark.browser


def unfold(page, title: str, widget) -> None:
    """Open a folded folder by its title, as a student does, until ``widget`` shows."""
    if not page.locator(dom_id(widget)).is_visible():
        page.get_by_text(title, exact=True).first.click()
        page.locator(dom_id(widget)).wait_for(state="visible", timeout=10_000)


def test_forces_ellipsoids_and_velocities_show_in_the_browser(open_page):
    page, session = open_page()
    # forces and gravity: the bars, with each joint's rating, and the arrow on the canvas
    unfold(page, "Forces and gravity", session.statics.enabled)
    before = canvas_pixels(page)
    page.locator(dom_id(session.statics.enabled)).check()
    wait_for(lambda: session.statics.bars.visible, what="the torque bars")
    wait_for(lambda: page.get_by_text("rated 330", exact=False).count() >= 2, what="the bars in the page")
    assert page.locator(".torque-bar").count() == 6
    page.wait_for_timeout(2000)
    with_force = canvas_pixels(page)
    assert changed(before, with_force) > 0.0003, "the force arrow and its label did not show"
    # the ellipsoids at the flange
    unfold(page, "Manipulability ellipsoids", session.ellipsoids.enabled)
    page.locator(dom_id(session.ellipsoids.enabled)).check()
    wait_for(lambda: session.ellipsoids.velocity.visible, what="the ellipsoids")
    wait_for(lambda: page.get_by_text("Velocity ellipsoid", exact=False).count() > 0, what="their lengths")
    page.wait_for_timeout(2000)
    with_ellipsoids = canvas_pixels(page)
    assert changed(with_force, with_ellipsoids) > 0.003, "the ellipsoids did not show"
    # velocities: a typed flange velocity gets its joint rates in the page
    unfold(page, "Velocities", session.velocity.solve)
    page.locator(dom_id(session.velocity.solve)).click()
    wait_for(lambda: page.get_by_text("within its speed limit", exact=False).count() > 0, what="the joint rates")
    assert np.isfinite(session.velocity.joint_rates()).all()
