"""Gravity loads (docs/kinematics.md §8.5) against roboticstoolbox-python and the potential energy."""

from __future__ import annotations

import numpy as np
import pytest
import roboticstoolbox as rtb  # test-only reference: a missing test extra fails here, loudly

from ur10core import Arm, dynamics
from ur10core.controller import CONTROLLER_OFFSET, FLANGE_TURN
from ur10core.dynamics import GRAVITY, MASSES, UR10_MASSES, ur_standard_table

pytestmark = pytest.mark.core


def random_joints(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-np.pi, np.pi, (n, 6))


@pytest.mark.parametrize("name", ["course", "ur10", "ur10e"])
def test_urs_standard_chain_is_the_arm(name):
    """The chain the masses hang on ends at the arm's own flange (turned by π about z, as the controller's)."""
    arm = Arm.preset(name)
    q = random_joints(200, 1)
    np.testing.assert_allclose(ur_standard_table(arm).fk(q), arm.fk(q) @ FLANGE_TURN, atol=1e-12)


def urs_ur10e() -> rtb.DHRobot:
    """A roboticstoolbox-python DH robot from UR's published UR10e table, masses and centres of mass."""
    a, d = (0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0), (0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655)
    alpha = (np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0)
    masses = (7.369, 13.051, 3.989, 2.1, 1.98, 0.615)
    centres = ((0.021, 0.0, 0.027), (0.38, 0.0, 0.158), (0.24, 0.0, 0.068), (0.0, 0.007, 0.018), (0.0, 0.007, 0.018),
               (0.0, 0.0, -0.026))
    return rtb.DHRobot([rtb.RevoluteDH(d=d[j], a=a[j], alpha=alpha[j], m=masses[j], r=centres[j]) for j in range(6)])


@pytest.mark.parametrize("name, robot", [("ur10", rtb.models.DH.UR10), ("ur10e", urs_ur10e)])
@pytest.mark.parametrize("payload", [0.0, 5.0])
def test_gravity_torques_match_roboticstoolbox_gravload(name, robot, payload):
    """roboticstoolbox-python's DH UR10 carries UR's published masses, in the controller's angles; the UR10e is
    built from UR's published table (the ur10e had no masses until 2026-12-04: no gravity, no release)."""
    robot = robot()
    robot.payload(payload, [0.0, 0.0, 0.0])
    arm = Arm.preset(name)
    q = random_joints(300, 2)
    expected = np.array([robot.gravload(qq + CONTROLLER_OFFSET) for qq in q])
    np.testing.assert_allclose(arm.gravity_torques(q, payload), expected, atol=1e-9)


@pytest.mark.parametrize("name", ["course", "ur10", "ur10e"])
def test_gravity_torques_are_the_gradient_of_the_potential_energy(name):
    arm, masses = Arm.preset(name), MASSES[name]
    table = ur_standard_table(arm)

    def energy(q: np.ndarray, payload: float) -> float:
        frames = table.frames(q)
        centres = np.einsum("jab,jb->ja", frames[1:, :3, :3], masses.centres) + frames[1:, :3, 3]
        return GRAVITY * (masses.masses @ centres[:, 2] + payload * frames[6, 2, 3])

    h = 1e-6
    for q in random_joints(30, 3):
        numeric = [(energy(q + h * e, 2.0) - energy(q - h * e, 2.0)) / (2 * h) for e in np.eye(6)]
        np.testing.assert_allclose(arm.gravity_torques(q, 2.0), numeric, atol=1e-6)


def test_gravity_needs_published_masses_and_a_sensible_payload():
    with pytest.raises(ValueError, match="no link masses for 'kr210'"):
        Arm.preset("kr210").gravity_torques(np.zeros(6))
    for payload in (-1.0, float("nan"), "5"):
        with pytest.raises(ValueError, match="payload_kg"):
            Arm.preset("ur10").gravity_torques(np.zeros(6), payload)
    assert Arm.preset("ur10").gravity_torques(np.zeros((4, 3, 6))).shape == (4, 3, 6)


def random_motion(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(-np.pi, np.pi, (n, 6)), rng.normal(size=(n, 6)), rng.normal(size=(n, 6))


@pytest.mark.parametrize("payload", [0.0, 3.0])
def test_newton_euler_matches_roboticstoolbox(payload):
    """τ = M q̈ + C q̇ + g against rtb's rne, M against its inertia, C q̇ against its coriolis, q̈ against its accel."""
    from ur10core import dynamics

    robot = rtb.models.DH.UR10()
    robot.payload(payload, [0.0, 0.0, 0.0])
    arm = Arm.preset("ur10")
    q, qd, qdd = random_motion(60, 4)
    controller = q + CONTROLLER_OFFSET
    np.testing.assert_allclose(dynamics.inverse_dynamics(arm, q, qd, qdd, payload_kg=payload),
                               [robot.rne(a, b, c) for a, b, c in zip(controller, qd, qdd)], atol=1e-9)
    np.testing.assert_allclose(dynamics.mass_matrix(arm, q, payload), [robot.inertia(a) for a in controller], atol=1e-9)
    np.testing.assert_allclose(dynamics.coriolis_torques(arm, q, qd, payload),
                               [robot.coriolis(a, b) @ b for a, b in zip(controller, qd)], atol=1e-9)
    tau = qdd * 20.0
    np.testing.assert_allclose(dynamics.forward_dynamics(arm, q, qd, tau, payload),
                               [robot.accel(a, b, c) for a, b, c in zip(controller, qd, tau)], atol=1e-8)
    for k in range(10):  # one state at a time: the gravity drop's own path (its seven problems as rows)
        np.testing.assert_allclose(dynamics.forward_dynamics(arm, q[k], qd[k], tau[k], payload),
                                   robot.accel(controller[k], qd[k], tau[k]), atol=1e-8)


@pytest.mark.parametrize("payload", [0.0, 3.0])
def test_lagranges_energies_are_newton_eulers_mass_matrix_and_gravity(payload):
    """T from each link's own motion is ½ q̇ᵀ M q̇ with roboticstoolbox's M; V's gradient is the gravity load;
    V is the masses' height (docs §8.8). Batch shapes broadcast; an arm without masses is refused."""
    robot = rtb.models.DH.UR10()
    robot.payload(payload, [0.0, 0.0, 0.0])
    arm = Arm.preset("ur10")
    q, qd, _ = random_motion(100, 6)
    kinetic, potential = dynamics.energies(arm, q, qd, payload)
    inertia = np.array([robot.inertia(a) for a in q + CONTROLLER_OFFSET])
    np.testing.assert_allclose(kinetic, 0.5 * np.einsum("ni,nij,nj->n", qd, inertia, qd), rtol=1e-9, atol=1e-9)
    frames = ur_standard_table(arm).frames(q)
    centres = np.einsum("njab,jb->nja", frames[:, 1:, :3, :3], UR10_MASSES.centres) + frames[:, 1:, :3, 3]
    np.testing.assert_allclose(potential, GRAVITY * (centres[..., 2] @ UR10_MASSES.masses + payload * frames[:, 6, 2, 3]),
                               atol=1e-9)
    h = 1e-6
    for k in range(10):
        numeric = [(dynamics.energies(arm, q[k] + h * e, qd[k], payload)[1]
                    - dynamics.energies(arm, q[k] - h * e, qd[k], payload)[1]) / (2 * h) for e in np.eye(6)]
        np.testing.assert_allclose(arm.gravity_torques(q[k], payload), numeric, atol=1e-6)
    assert dynamics.energies(arm, q[:4, None, :], qd[None, :5, :])[0].shape == (4, 5)
    assert dynamics.energies(arm, q[0], np.zeros(6))[0] == 0.0
    with pytest.raises(ValueError, match="no link masses for 'kr210'"):
        dynamics.energies(Arm.preset("kr210"), np.zeros(6), np.zeros(6))
    with pytest.raises(ValueError, match="qd"):
        dynamics.energies(arm, np.zeros(6), np.zeros(5))


def test_the_mass_matrix_is_symmetric_positive_definite_and_gravity_is_its_static_part():
    from ur10core import dynamics

    arm = Arm.preset("course")
    q, qd, _ = random_motion(100, 5)
    M = dynamics.mass_matrix(arm, q)
    np.testing.assert_allclose(M, np.swapaxes(M, -1, -2), atol=1e-12)
    assert (np.linalg.eigvalsh(M)[:, 0] > 0).all()
    np.testing.assert_allclose(dynamics.inverse_dynamics(arm, q, 0 * q, 0 * q), arm.gravity_torques(q), atol=1e-9)
    # the kinetic energy's rate: q̇ · (M q̈ + C q̇) − ½ q̇ · Ṁ q̇ = q̇ · M q̈ (skew-symmetry of Ṁ − 2C), by differences
    h = 1e-6
    for k in range(10):
        dM = (dynamics.mass_matrix(arm, q[k] + h * qd[k]) - dynamics.mass_matrix(arm, q[k] - h * qd[k])) / (2 * h)
        assert qd[k] @ dynamics.coriolis_torques(arm, q[k], qd[k]) == pytest.approx(0.5 * qd[k] @ dM @ qd[k], abs=1e-6)


@pytest.mark.parametrize("start", [[0, -60, 0, -90, 0, 0],
                                   # issue 30, bug 5: the wrists spin at about 150 rad/s; at a fixed 10 ms it drifted 1 J
                                   [108.7, 152.5, -84.2, 14.0, -20.6, 155.2]])
def test_a_released_arm_keeps_its_energy(start):
    """Let go with no friction, the arm swings: kinetic plus potential energy stays within 1 mJ (docs §8.8)."""
    from ur10core import dynamics

    arm = Arm.preset("course")
    motion = dynamics.release(arm, np.radians(start), duration=1.0, dt=0.01)
    table = ur_standard_table(arm)

    def energy(q: np.ndarray, qd: np.ndarray) -> float:
        frames = table.frames(q)
        centres = np.einsum("jab,jb->ja", frames[1:, :3, :3], UR10_MASSES.centres) + frames[1:, :3, 3]
        return 0.5 * qd @ dynamics.mass_matrix(arm, q) @ qd + GRAVITY * UR10_MASSES.masses @ centres[:, 2]

    energies = [energy(q, qd) for q, qd in zip(motion.q, motion.qd)]
    assert np.ptp(energies) < 1e-3
    np.testing.assert_allclose(sum(dynamics.energies(arm, motion.q, motion.qd)), energies, atol=1e-9)  # what the app plots
    assert np.abs(motion.q[-1] - motion.q[0]).max() > 0.3  # and it did fall
    with pytest.raises(ValueError, match="dt must be"):
        dynamics.release(arm, np.zeros(6), dt=1.0)


@pytest.mark.parametrize("call", [
    lambda arm, bad: dynamics.mass_matrix(arm, bad),
    lambda arm, bad: dynamics.forward_dynamics(arm, bad, np.zeros(6), np.zeros(6)),
    lambda arm, bad: dynamics.forward_dynamics(arm, np.zeros(6), np.zeros(6), bad),
    lambda arm, bad: dynamics.inverse_dynamics(arm, np.zeros(6), bad, np.zeros(6)),
    lambda arm, bad: dynamics.coriolis_torques(arm, np.zeros(6), bad),
])
def test_dynamics_refuses_what_is_not_six_finite_joint_values(call):
    """NaN in gave NaN out silently, and a wrong shape numpy's broadcast error (an issue's fuzz)."""
    arm = Arm.preset("ur10")
    with pytest.raises(ValueError, match="non-finite"):
        call(arm, np.array([0.0, np.nan, 0.0, 0.0, 0.0, 0.0]))
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 6\)"):
        call(arm, np.zeros(5))
    with pytest.raises(ValueError, match="real numbers"):
        call(arm, ["a"] * 6)


def test_dynamics_names_shapes_that_do_not_broadcast():
    arm = Arm.preset("ur10")
    with pytest.raises(ValueError, match=r"q, qd, qdd must have shapes that broadcast together, got q \(3, 6\), qd \(2, 6\)"):
        dynamics.inverse_dynamics(arm, np.zeros((3, 6)), np.zeros((2, 6)), np.zeros(6))
    with pytest.raises(ValueError, match="gravity must be a number or broadcast"):
        dynamics.inverse_dynamics(arm, np.zeros((3, 6)), np.zeros(6), np.zeros(6), gravity=np.ones(4))
    with pytest.raises(ValueError, match="gravity contains a non-finite"):
        dynamics.inverse_dynamics(arm, np.zeros(6), np.zeros(6), np.zeros(6), gravity=np.inf)
