"""ur10teach.features.camera.framing: every point in the canvas, and no farther back than needed."""

from __future__ import annotations

import numpy as np
import pytest

from ur10teach.features.camera import VIEWS, arm_points, framing
from ur10teach.state import ArmState


def projected(points, position, look_at, fov, aspect) -> np.ndarray:
    """Normalised device coordinates (x, y in [-1, 1] on the canvas), built independently of framing()."""
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    relative = points - position
    depth = relative @ forward
    assert (depth > 0).all(), "a point behind the camera"
    t = np.tan(fov / 2)
    return np.stack([(relative @ right) / (depth * t * aspect), (relative @ up) / (depth * t)], axis=1)


@pytest.mark.parametrize("aspect", [0.5, 1.0, 1024 / 768 * 0.6, 2.4])
@pytest.mark.parametrize("view", list(VIEWS))
def test_the_arm_fills_the_canvas(course, aspect, view):
    rng = np.random.default_rng(len(view))
    for _ in range(20):
        q = rng.uniform(-np.pi, np.pi, 6)
        points = arm_points(ArmState(course, q).last)
        fov = np.radians(rng.uniform(30, 70))
        position, look_at = framing(points, VIEWS[view], fov, aspect, margin=0.08)
        ndc = projected(points, position, look_at, fov, aspect)
        assert np.abs(ndc).max() <= 0.92 + 1e-9  # inside, by the margin
        assert np.abs(ndc).max() >= 0.92 - 1e-6  # and as large as it can be


def test_arm_points_hold_the_target_and_every_joint(course):
    snapshot = ArmState(course).last
    points = arm_points(snapshot)
    for centre in [*snapshot.frames[:, :3, 3], snapshot.target[:3, 3]]:
        assert np.linalg.norm(points - centre, axis=1).min() < 0.2


@pytest.mark.parametrize("aspect", [390 / 844, 390 / 664, 0.9])
@pytest.mark.parametrize("view", list(VIEWS))
def test_on_an_upright_phone_the_arm_fills_the_band_above_the_panel(course, aspect, view):
    """A phone's panel covers the canvas below its top 40 %: every point of the arm, the nearest and the farthest,
    is inside that band by the margin, and as large as the band allows (the plain centring, sunk by one amount for
    every depth, put near points above the canvas's top)."""
    top, margin = 0.4, 0.08
    high, low = 1 - margin * top, 1 - 2 * top + margin * top  # the band, in the canvas's -1..1
    rng = np.random.default_rng(len(view))
    for _ in range(20):
        points = arm_points(ArmState(course, rng.uniform(-np.pi, np.pi, 6)).last)
        fov = np.radians(rng.uniform(30, 70))
        position, look_at = framing(points, VIEWS[view], fov, aspect, margin=margin, top=top)
        x, y = projected(points, position, look_at, fov, aspect).T
        assert np.abs(x).max() <= 1 - margin + 1e-9 and low - 1e-9 <= y.min() and y.max() <= high + 1e-9
        assert np.abs(x).max() >= 1 - margin - 1e-6 or (y.min() <= low + 1e-6 and y.max() >= high - 1e-6)
