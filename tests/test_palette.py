"""The eight ghost colours stay apart for colour-blind students and on a washed-out projector (ur10dev/colour_vision.py)."""

from __future__ import annotations

import numpy as np

from ur10teach.style import ALUMINIUM, GHOST_OPACITY, JOINT_CAP_GREY, SLOT_COLORS
from ur10dev.colour_vision import MIN_DELTA_E, cielab, closest_pair, linear, seen

def test_a_pure_colour_is_where_cielab_puts_it():
    np.testing.assert_allclose(cielab(linear([255, 255, 255])), [100, 0, 0], atol=0.05)
    np.testing.assert_allclose(cielab(linear([255, 0, 0])), [53.24, 80.09, 67.20], atol=0.3)  # the textbook value


def test_a_deutan_eye_confuses_red_and_green():
    """The simulation works: the classic confusion pair comes out close, and not for normal vision."""
    red, green = (200, 80, 40), (110, 110, 40)
    assert np.linalg.norm(seen(red, "deutan") - seen(green, "deutan")) < 0.4 * np.linalg.norm(seen(red, "normal") - seen(green, "normal"))


def test_every_two_ghosts_are_apart():
    distance, a, b, vision, washed = closest_pair(SLOT_COLORS, GHOST_OPACITY)
    assert distance >= MIN_DELTA_E, f"ghosts {a} and {b} differ by ΔE {distance:.1f} ({vision}, washed {washed})"


def test_the_old_palette_fails():
    """The check can fail: the palette before issue 15, at its 0.35 opacity."""
    old = [(0, 114, 178), (86, 180, 233), (0, 158, 115), (117, 112, 179), (230, 159, 0), (240, 228, 66),
           (204, 121, 167), (213, 94, 0)]
    assert closest_pair(old, 0.35)[0] < 1.0


def test_the_solid_arm_is_neutral():
    """Grey body and caps: the arm cannot be mistaken for a ghost of any colour."""
    for rgb in (ALUMINIUM, JOINT_CAP_GREY):
        _, a, b = cielab(linear(rgb))
        assert np.hypot(a, b) < 6, f"{rgb} is tinted"
    for rgb in SLOT_COLORS:
        _, a, b = seen(rgb, "normal", GHOST_OPACITY)
        assert np.hypot(a, b) > 12, f"ghost colour {rgb} is too grey to tell from the arm"
