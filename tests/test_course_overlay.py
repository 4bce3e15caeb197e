"""A course arm's singularities in 3D: each factor's drawing degenerates exactly where the factor vanishes
(the desktop arm's too: it had no overlay until 2026-12-07)."""

from __future__ import annotations

import numpy as np
import pytest

from ur10teach.features.singularity import factor_geometry
from ur10core import Arm
from ur10core.serial import PRESETS


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


#: Drawings that close a distance (the last segment's length goes to zero); the others show two
#: lines that become parallel (wrist axes 4 and 6; the Stanford arm's boom and axis 1) or in line (the links).
DISTANCES = {("kr210", "shoulder"), ("elbow", "shoulder"), ("stanford", "stroke"), ("cylindrical", "reach"),
             ("cylindrical_wrist", "reach"), ("three_dof", "reach")}


def degeneracy(arm: str, factor: str, segments: np.ndarray) -> float:
    """0 when the drawing shows the singularity."""
    if (arm, factor) in DISTANCES:
        start, end = segments[-1]
        return float(np.linalg.norm(end - start))
    first, second = (_unit(b - a) for a, b in segments)
    return float(np.linalg.norm(np.cross(first, second)))


def singular_joints(arm: Arm, factor: int, q0: np.ndarray) -> np.ndarray:
    """``q0`` with one joint moved so that factor ``factor`` of det J is zero (bisection on a sign change).

    Limits aside: the geometry holds beyond them (the cylindrical arm's stroke stops short of its axis).
    """
    for joint in range(arm.n_joints):
        grid = np.linspace(-np.pi, np.pi, 2001) if arm.joint_types[joint] == "R" else np.linspace(-1.0, 1.0, 2001)
        q = np.repeat(q0[None], len(grid), axis=0)
        q[:, joint] = grid
        values = arm.singularity_factors(q)[:, factor]
        exact = np.flatnonzero(values == 0.0)
        if len(exact):
            return q[exact[0]]
        changes = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))
        if len(changes):
            low, high = grid[changes[0]], grid[changes[0] + 1]
            for _ in range(80):
                middle = 0.5 * (low + high)
                q_mid = q0.copy()
                q_mid[joint] = middle
                if np.sign(arm.singularity_factors(q_mid)[factor]) == np.sign(values[changes[0]]):
                    low = middle
                else:
                    high = middle
            q_mid[joint] = 0.5 * (low + high)
            return q_mid
    raise AssertionError(f"no joint makes factor {factor} of {arm.name} vanish")


@pytest.mark.parametrize("name", [*sorted(PRESETS), "three_dof"])
def test_each_drawing_degenerates_where_its_factor_vanishes(name):
    arm = Arm.preset(name)
    home = arm.specs.home
    drawn = factor_geometry(arm, home, arm.frames(home), 1.0)
    assert len(drawn) == len(arm.singularity_factors(home))
    for k, (factor, segments) in enumerate(drawn.items()):
        assert degeneracy(name, factor, segments) > 1e-2, f"{name} {factor}: degenerate at home"
        q = singular_joints(arm, k, home)
        assert abs(arm.singularity_factors(q)[k]) < 1e-9
        singular = factor_geometry(arm, q, arm.frames(q), 1.0)[factor]
        assert degeneracy(name, factor, singular) < 1e-6, f"{name} {factor}: the drawing does not show the singularity"


@pytest.mark.parametrize("kind", ["shoulder", "elbow", "wrist"])
def test_the_ur_familys_drawing_degenerates_where_its_factor_vanishes(kind):
    """The UR10's: P5 on the drawn d4 cylinder, P4 on a drawn reach circle, axes 4 and 6 parallel, exactly at
    each singularity (each point is the centre of its cross, the last three segments)."""
    arm = Arm.preset("ur10")
    home = arm.specs.home

    def degeneracy(q: np.ndarray) -> float:
        segments = factor_geometry(arm, q, arm.frames(q), 1.0)[kind]
        point = segments[-3:].mean(axis=(0, 1))
        if kind == "shoulder":  # P5's distance from axis 1 against the drawn cylinder's (a ring's vertex)
            radius = np.linalg.norm(segments[0, 0, :2])
            return abs(float(np.linalg.norm(point[:2])) - radius)
        if kind == "elbow":  # P4's distance from the drawn circles' centre against each circle's radius
            circles = segments[:-3, 0].reshape(2, -1, 3)
            centre = circles[0].mean(axis=0)
            return min(abs(float(np.linalg.norm(point - centre) - np.linalg.norm(circle[0] - centre))) for circle in circles)
        first, second = (_unit(b - a) for a, b in segments)
        return float(np.linalg.norm(np.cross(first, second)))

    assert degeneracy(home) > 1e-2
    singular = arm.singular_configuration(kind, home)
    assert degeneracy(singular) < 1e-9


@pytest.mark.parametrize("name", [*sorted(set(PRESETS) - {"ur10", "ur10e", "course"}), "three_dof"])
def test_each_overlay_fits_the_screen_the_arm_is_framed_on(name):
    """Axis 1 was drawn 0.9 of the reach up from the shoulder: on the KR210, 3.5 m, off the top of the screen the
    arm is framed on (the Stanford arm's and the desktop arm's too). It now ends above the wrist centre's height."""
    import viser

    from ur10teach.features.camera import arm_points, framed_view, views_for
    from ur10teach.features.drawings import arm_drawing
    from ur10teach.state import ArmState

    arm = Arm.preset(name)
    snapshot = ArmState(arm).last
    server = viser.ViserServer(port=0, verbose=False)
    try:
        drawing = arm_drawing(server.scene, arm, snapshot)
    finally:
        server.stop()
    view = framed_view(arm_points(drawing.framed(snapshot), drawing.body_radius), views_for(arm)["Course figure"])
    ends = np.concatenate(list(factor_geometry(arm, snapshot.q, snapshot.frames, drawing.size).values())).reshape(-1, 3)
    pixels, _ = view.to_screen(ends @ drawing.world[:3, :3].T + drawing.world[:3, 3])  # from the canvas's centre
    assert (np.abs(pixels) <= [view.width / 2, view.height / 2]).all(), np.abs(pixels).max(axis=0)
