"""ur10core.specs: each preset's published numbers and start pose; project_target for the arms that
control only part of a pose."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur10core import Arm
from ur10core.serial import PRESETS, project_target
from ur10core.specs import ArmSpecs, torque_map

EVERY_PRESET = Arm.PRESETS


def test_the_ur10s_numbers_are_the_courses():
    """docs/kinematics.md §1: 120 °/s for base and shoulder, 180 °/s for the rest, 10 kg; §8.5: joint
    sizes 4, 4, 3, 2, 2, 2 rated 330, 330, 150, 56, 56, 56 N·m; §3: the three worked poses."""
    for name in Arm.UR_PRESETS:
        specs = Arm.preset(name).specs
        np.testing.assert_allclose(np.degrees(specs.speed_limits), [120, 120, 180, 180, 180, 180])
        np.testing.assert_array_equal(specs.torque_ratings, [330, 330, 150, 56, 56, 56])
        assert specs.payload_kg == 10.0
        np.testing.assert_allclose(np.degrees(specs.poses["stretched"]), [45, 90, 0, -90, 0, 60])
        np.testing.assert_allclose(np.degrees(specs.poses["zero"]), 0.0)
        np.testing.assert_allclose(specs.home, specs.poses["arbitrary"])


@pytest.mark.parametrize("name", EVERY_PRESET)
def test_every_preset_starts_within_its_limits_and_away_from_its_singularities(name):
    arm = Arm.preset(name)
    home = arm.specs.home
    assert home.shape == (arm.n_joints,)
    assert ((np.asarray(arm.limits)[:, 0] <= home) & (home <= np.asarray(arm.limits)[:, 1])).all()
    factors = np.asarray(arm.singularity_factors(home), dtype=float)
    assert (np.abs(factors) > 1e-3).all(), f"{name} starts at a singularity: {factors}"
    home[0] += 1.0
    assert arm.specs.home[0] != home[0]  # a copy: a caller cannot move the preset's home


def test_presets_without_published_numbers_say_so():
    for name in (*PRESETS, "three_dof"):
        specs = Arm.preset(name).specs
        assert specs.speed_limits is None and specs.torque_ratings is None and specs.payload_kg is None


def test_a_typed_table_starts_at_20_degrees_and_mid_stroke_within_its_limits():
    arm = Arm.from_dh([(0.0, 0.4, 0.0, math.pi / 2), (0.0, 0.0, 0.3, 0.0), (0.0, 0.1, 0.0, 0.0)],
                      joint_types="RRP", limits=[(-math.pi, math.pi), (0.0, 0.2), (0.1, 0.5)])
    np.testing.assert_allclose(arm.specs.home, [math.radians(20), 0.2, 0.3])


def test_specs_refuse_a_pose_list_without_home():
    with pytest.raises(ValueError, match="'home'"):
        ArmSpecs({"zero": np.zeros(6)})


def test_the_torque_map_marks_the_largest_norm_of_jt_f():
    arm = Arm.preset("course")
    force = np.array([0.0, 0.0, -50.0])
    points, norms, worst = torque_map(arm, force, n=500)
    _, _, q = arm.sample_workspace(500, seed=3, return_joints=True)
    np.testing.assert_allclose(points, arm.fk(q)[:, :3, 3], atol=1e-12)
    np.testing.assert_allclose(norms, np.linalg.norm(arm.jacobian(q).swapaxes(-1, -2) @ np.r_[force, 0, 0, 0], axis=-1))
    assert norms[worst] == norms.max()


def _pose(yaw: float, tilt: float, position) -> np.ndarray:
    cz, sz, cx, sx = math.cos(yaw), math.sin(yaw), math.cos(tilt), math.sin(tilt)
    T = np.eye(4)
    T[:3, :3] = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]]) @ np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    T[:3, 3] = position
    return T


def test_a_scara_takes_only_the_targets_yaw_with_its_tool_pointing_down():
    arm = Arm.preset("scara")
    target = _pose(0.7, 0.4, (0.3, 0.2, 0.1))
    followed = project_target(arm, target, arm.fk(arm.specs.home))
    np.testing.assert_allclose(followed[:3, 3], target[:3, 3])
    np.testing.assert_allclose(followed[:3, 2], [0, 0, -1], atol=1e-12)  # the tool's z points down
    assert math.isclose(math.atan2(followed[1, 0], followed[0, 0]), math.atan2(target[1, 0], target[0, 0]))
    np.testing.assert_allclose(followed[:3, :3] @ followed[:3, :3].T, np.eye(3), atol=1e-12)


def test_a_position_arm_keeps_its_own_orientation_and_the_planar_elbow_its_plane():
    current = _pose(0.2, 0.1, (0.5, 0.0, 0.0))
    target = _pose(1.0, 0.9, (0.3, 0.2, 0.15))
    cylindrical = project_target(Arm.preset("cylindrical"), target, current)
    np.testing.assert_allclose(cylindrical[:3, :3], current[:3, :3])
    np.testing.assert_allclose(cylindrical[:3, 3], target[:3, 3])
    planar = project_target(Arm.preset("planar_elbow"), target, current)
    np.testing.assert_allclose(planar[:3, 3], [0.3, 0.2, 0.0])
    for full in ("kr210", "course"):  # a full pose: all of it
        np.testing.assert_allclose(project_target(Arm.preset(full), target, current), target)
    with pytest.raises(ValueError, match="4 × 4"):
        project_target(Arm.preset("scara"), np.eye(3), current)
