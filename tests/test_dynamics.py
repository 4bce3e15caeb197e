"""Gravity loads (docs/kinematics.md §8.5) against roboticstoolbox-python and the potential energy."""

from __future__ import annotations

import numpy as np
import pytest

from ur10core import Arm
from ur10core.controller import CONTROLLER_OFFSET, FLANGE_TURN
from ur10core.dynamics import GRAVITY, UR10_MASSES, ur_standard_table

rtb = pytest.importorskip("roboticstoolbox")


def random_joints(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-np.pi, np.pi, (n, 6))


@pytest.mark.parametrize("name", ["course", "ur10", "ur10e"])
def test_urs_standard_chain_is_the_arm(name):
    """The chain the masses hang on ends at the arm's own flange (turned by π about z, as the controller's)."""
    arm = Arm.preset(name)
    q = random_joints(200, 1)
    np.testing.assert_allclose(ur_standard_table(arm).fk(q), arm.fk(q) @ FLANGE_TURN, atol=1e-12)


@pytest.mark.parametrize("payload", [0.0, 5.0])
def test_gravity_torques_match_roboticstoolbox_gravload(payload):
    """roboticstoolbox-python's DH UR10 carries UR's published masses, in the controller's angles."""
    robot = rtb.models.DH.UR10()
    robot.payload(payload, [0.0, 0.0, 0.0])
    arm = Arm.preset("ur10")
    q = random_joints(300, 2)
    expected = np.array([robot.gravload(qq + CONTROLLER_OFFSET) for qq in q])
    np.testing.assert_allclose(arm.gravity_torques(q, payload), expected, atol=1e-9)


@pytest.mark.parametrize("name", ["course", "ur10"])
def test_gravity_torques_are_the_gradient_of_the_potential_energy(name):
    arm = Arm.preset(name)
    table = ur_standard_table(arm)

    def energy(q: np.ndarray, payload: float) -> float:
        frames = table.frames(q)
        centres = np.einsum("jab,jb->ja", frames[1:, :3, :3], UR10_MASSES.centres) + frames[1:, :3, 3]
        return GRAVITY * (UR10_MASSES.masses @ centres[:, 2] + payload * frames[6, 2, 3])

    h = 1e-6
    for q in random_joints(30, 3):
        numeric = [(energy(q + h * e, 2.0) - energy(q - h * e, 2.0)) / (2 * h) for e in np.eye(6)]
        np.testing.assert_allclose(arm.gravity_torques(q, 2.0), numeric, atol=1e-6)


def test_gravity_needs_published_masses_and_a_sensible_payload():
    with pytest.raises(ValueError, match="no link masses for 'ur10e'"):
        Arm.preset("ur10e").gravity_torques(np.zeros(6))
    with pytest.raises(ValueError, match="no link masses for 'kr210'"):
        Arm.preset("kr210").gravity_torques(np.zeros(6))
    for payload in (-1.0, float("nan"), "5"):
        with pytest.raises(ValueError, match="payload_kg"):
            Arm.preset("ur10").gravity_torques(np.zeros(6), payload)
    assert Arm.preset("ur10").gravity_torques(np.zeros((4, 3, 6))).shape == (4, 3, 6)
