"""What J does (docs/kinematics.md §8): each checked against an independent construction."""

from __future__ import annotations

import numpy as np
import pytest

from ur10core import Arm
from ur10core.differential import DAMPING_THRESHOLD, MAX_DAMPING
from ur10core.serial import PRESETS

pytestmark = pytest.mark.core

ARMS = ["course", "ur10", *PRESETS]


def random_joints(arm, n: int, seed: int) -> np.ndarray:
    low, high = arm.limits.T
    return np.random.default_rng(seed).uniform(np.maximum(low, -np.pi), np.minimum(high, np.pi), (n, arm.n_joints))


def skew_vector(S: np.ndarray) -> np.ndarray:
    return 0.5 * np.array([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]])


@pytest.mark.parametrize("name", ARMS)
def test_the_tool_twist_is_the_rate_of_change_of_the_tool_pose(name):
    """v = dp/dt and [ω]× = Ṙ Rᵀ, by central differences of FK along q + t q̇."""
    arm = Arm.preset(name)
    rng = np.random.default_rng(2)
    h = 1e-6
    for q in random_joints(arm, 50, 1):
        qdot = rng.normal(size=arm.n_joints)
        twist = arm.tool_twist(q, qdot)
        ahead, behind = arm.fk(q + h * qdot), arm.fk(q - h * qdot)
        np.testing.assert_allclose(twist[:3], (ahead[:3, 3] - behind[:3, 3]) / (2 * h), atol=1e-7)
        omega = skew_vector((ahead[:3, :3] - behind[:3, :3]) / (2 * h) @ arm.fk(q)[:3, :3].T)
        np.testing.assert_allclose(twist[3:], omega, atol=1e-7)


@pytest.mark.parametrize("name", ["course", "kr210", "stanford", "elbow"])
def test_joint_rates_give_the_twist_back_away_from_singularities(name):
    arm = Arm.preset(name)
    q = random_joints(arm, 400, 3)
    qdot = np.random.default_rng(4).normal(size=q.shape)
    twist = arm.tool_twist(q, qdot)
    rates = arm.joint_rates(q, twist)
    calm = np.linalg.svd(arm.jacobian(q), compute_uv=False)[:, -1] > DAMPING_THRESHOLD
    assert calm.mean() > 0.5
    np.testing.assert_array_equal(rates.damping[calm], 0.0)
    np.testing.assert_allclose(rates.qdot[calm], qdot[calm], atol=1e-9)
    np.testing.assert_allclose(rates.achieved[calm], twist[calm], atol=1e-9)


@pytest.mark.parametrize("name", ["three_dof", "planar_elbow", "cylindrical", "scara"])
def test_an_arm_that_controls_less_than_a_pose_gets_rates_for_what_it_controls(name):
    """Asked for a velocity (ω = 0 for the rest), the desktop arm moved its tool at 84 of 100 mm/s: the least
    squares over all six rows traded v for an ω = 0 it cannot hold. The rates now give exactly the v (and a
    SCARA's yaw rate) asked, by central differences of FK along q + t q̇, away from singularities."""
    arm = Arm.preset(name)
    controlled = {"position": [0, 1, 2], "position and yaw": [0, 1, 2, 5]}[arm.task]
    rng = np.random.default_rng(8)
    h, checked = 1e-6, 0
    for q in random_joints(arm, 40, 9):
        if arm.smallest_singular_value(q) < 0.05 or (arm.planar and np.linalg.svd(arm.jacobian(q)[:2], compute_uv=False)[-1] < 0.05):
            continue
        asked = arm.tool_twist(q, rng.normal(size=arm.n_joints))  # a twist the arm can give
        asked[[k for k in range(6) if k not in controlled]] = 0.0  # the rest asked to be zero, as a student types it
        rates = arm.joint_rates(q, asked)
        ahead, behind = arm.fk(q + h * rates.qdot), arm.fk(q - h * rates.qdot)
        np.testing.assert_allclose((ahead[:3, 3] - behind[:3, 3]) / (2 * h), asked[:3], atol=1e-7)
        if 5 in controlled:  # the yaw rate: ω_z from Ṙ Rᵀ
            omega = skew_vector((ahead[:3, :3] - behind[:3, :3]) / (2 * h) @ arm.fk(q)[:3, :3].T)
            assert omega[2] == pytest.approx(asked[5], abs=1e-7)
        checked += 1
    assert checked >= 10


def test_near_the_wrist_singularity_the_rates_blow_up_unless_damped():
    """A tool twist along the direction the arm is losing at s5 = ε needs joint rates ~ 1/ε undamped;
    damped, they stay within |twist|/(2λ), the bound of σ/(σ² + λ²)."""
    arm = Arm.preset("course")
    for epsilon in (1e-2, 1e-4, 1e-6):
        q = np.radians([10, -60, 80, -110, 0, 30])
        q[4] = epsilon
        U, sigma, _ = np.linalg.svd(arm.jacobian(q))
        twist = 0.1 * U[:, -1]
        undamped = np.linalg.pinv(arm.jacobian(q)) @ twist
        rates = arm.joint_rates(q, twist)
        assert np.linalg.norm(undamped) > 0.01 / epsilon
        assert 0 < rates.damping <= MAX_DAMPING
        assert np.linalg.norm(rates.qdot) <= np.linalg.norm(twist) / (2 * rates.damping) + 1e-12


def test_an_arm_with_fewer_joints_gets_the_least_squares_rates():
    """A SCARA cannot roll its tool about x: it gets the rates of the closest twist it can give."""
    arm = Arm.preset("scara")
    q = np.array([0.3, 1.0, 0.1, 0.2])
    twist = np.array([0.05, -0.02, 0.01, 0.2, 0.0, 0.1])
    rates = arm.joint_rates(q, twist)
    J = arm.jacobian(q)
    np.testing.assert_allclose(rates.qdot, np.linalg.lstsq(J, twist, rcond=None)[0], atol=1e-12)
    np.testing.assert_allclose(rates.achieved[3], 0.0, atol=1e-12)  # no roll


@pytest.mark.parametrize("name", ARMS)
def test_static_torques_are_each_axis_moment_of_the_wrench(name):
    """τ_i = z_i · ((p − o_i) × F + M) for a revolute joint, z_i · F for a prismatic one (the moment of
    the wrench about joint i's axis), and τ · q̇ equals the power of the wrench for any rates."""
    arm = Arm.preset(name)
    rng = np.random.default_rng(5)
    for q in random_joints(arm, 20, 6):
        force, moment = rng.normal(size=3) * 100, rng.normal(size=3) * 10
        tau = arm.static_torques(q, force, moment)
        frames = arm.frames(q)
        if name in ("course", "ur10"):
            axes, points = frames[1:, :3, 2], frames[1:, :3, 3]
        else:
            axes, points = arm.dh.joint_axes(frames)
        tool = arm.fk(q)[:3, 3]
        for i, kind in enumerate(arm.joint_types):
            expected = axes[i] @ (np.cross(tool - points[i], force) + moment) if kind == "R" else axes[i] @ force
            assert tau[i] == pytest.approx(expected, abs=1e-9)
        qdot = rng.normal(size=arm.n_joints)
        assert tau @ qdot == pytest.approx(np.concatenate([force, moment]) @ arm.tool_twist(q, qdot), abs=1e-9)


def held_map(J: np.ndarray, moved: slice, held: slice) -> np.ndarray:
    """J[moved] over the rates that leave J[held] still: J[moved] N Nᵀ, N an orthonormal basis of that null
    space from the eigenvectors of AᵀA (the core uses a pseudo-inverse: an independent construction)."""
    out = []
    for Jk in J:
        A = Jk[held]
        w, V = np.linalg.eigh(A.T @ A)
        N = V[:, w < 1e-10 * max(w.max(), 1.0)]
        out.append(Jk[moved] @ N @ N.T)
    return np.array(out)


@pytest.mark.parametrize("name", ["course", "kr210", "scara", "planar_elbow", "three_dof"])
def test_ellipsoid_axes_are_the_eigenvectors_of_the_velocity_map(name):
    """Axes and lengths against the eigen-decomposition of M Mᵀ, M the map of joint rates to tool
    velocities that the arm's task leaves (the other half held still, from an eigenbasis of its null space)."""
    arm = Arm.preset(name)
    q = random_joints(arm, 100, 7)
    translation, rotation = arm.ellipsoids(q)
    J = arm.jacobian(q)
    task = getattr(arm, "task", "pose")
    maps = {"pose": (held_map(J, slice(0, 3), slice(3, 6)), held_map(J, slice(3, 6), slice(0, 3))),
            "position and yaw": (held_map(J, slice(0, 3), slice(5, 6)), J[:, 3:, :]),
            "position": (J[:, :3, :], J[:, 3:, :])}[task]
    for ellipsoid, M in zip((translation, rotation), maps):
        A = M @ np.swapaxes(M, -1, -2)
        np.testing.assert_allclose(np.swapaxes(ellipsoid.axes, -1, -2) @ ellipsoid.axes, np.broadcast_to(np.eye(3), A.shape), atol=1e-12)
        np.testing.assert_allclose(A @ ellipsoid.axes, ellipsoid.axes * ellipsoid.velocity[:, None, :] ** 2, atol=1e-8)
        np.testing.assert_allclose(np.sort(np.linalg.eigvalsh(A), axis=-1), np.sort(ellipsoid.velocity**2, axis=-1), atol=1e-8)
        finite = ellipsoid.velocity > 1e-12
        np.testing.assert_allclose(ellipsoid.force[finite] * ellipsoid.velocity[finite], 1.0)


@pytest.mark.parametrize("kind", ["shoulder", "elbow", "wrist"])
def test_at_each_ur10_singularity_one_ellipsoid_flattens(kind):
    """The lost twist direction shows: one of the two held-still ellipsoids loses an axis, and its force
    ellipsoid stretches without bound along it (J_v and J_ω alone would not show it: the wrist hides it)."""
    arm = Arm.preset("course")
    home = np.radians([30, 45, 26, 50, 60, 80])
    away = min(min(e.velocity) for e in arm.ellipsoids(home))
    on = arm.singular_configuration(kind, home)
    translation, rotation = arm.ellipsoids(on)
    assert away > 0.05
    assert min(translation.velocity.min(), rotation.velocity.min()) < 1e-6
    assert max(translation.force.max(), rotation.force.max()) > 1e5


@pytest.mark.parametrize("name", PRESETS)
def test_on_a_singularity_a_lost_axis_is_zero_and_its_force_axis_endless_not_rounding(name):
    """The SVD gives the axis a singularity takes away as rounding, 1e-17 m/s, not 0; its force axis was then 1e17 N,
    and the panel read "semi-axes 0.911, 0.132, 3.46e-17" and "8.79e+15 N per N·m, drawn at 1.05e-13 mm" (the
    desktop arm's; until 2026-12-05, on every arm's singularity buttons). Within 1e-12 of the longest it is 0, and its
    force axis ∞, as where J has fewer columns than the ellipsoid has axes."""
    arm = Arm.preset(name)
    flattened = 0
    for kind in arm.factor_names:
        try:
            on = arm.singular_configuration(kind, arm.specs.home)
        except ValueError:  # no pose within the limits is on it (the cylindrical arms' reach)
            continue
        for ellipsoid in arm.ellipsoids(on):
            small = ellipsoid.velocity <= 1e-12 * ellipsoid.velocity.max()
            np.testing.assert_array_equal(ellipsoid.velocity[small], 0.0)
            assert np.isinf(ellipsoid.force[small]).all() and np.isfinite(ellipsoid.force[~small]).all()
            flattened += int(small.any())
    assert flattened or name in ("cylindrical", "cylindrical_wrist"), "no singularity of this arm flattens an ellipsoid"
    # near one, an axis is small, not zero: what a student dragging towards it sees shrink
    from ur10core.differential import _ellipsoid

    near = _ellipsoid(np.diag([2.0, 1e-11, 1e-17]))
    assert near.velocity.tolist() == [2.0, 1e-11, 0.0]
    np.testing.assert_allclose(near.force, [0.5, 1e11, np.inf])


@pytest.mark.parametrize("kind", ["shoulder", "elbow", "wrist"])
def test_at_a_singularity_the_ellipsoids_are_still_those_of_the_held_map(kind):
    """Where the held rows lose rank too (the rank decision is the core's own, from one SVD), the
    lengths still match the eigenvalues of the independently built held map."""
    arm = Arm.preset("course")
    on = arm.singular_configuration(kind, np.radians([30, 45, 26, 50, 60, 80]))[None]
    J = arm.jacobian(on)
    translation, rotation = arm.ellipsoids(on)
    for ellipsoid, M in zip((translation, rotation), (held_map(J, slice(0, 3), slice(3, 6)), held_map(J, slice(3, 6), slice(0, 3)))):
        A = M @ np.swapaxes(M, -1, -2)
        np.testing.assert_allclose(np.sort(np.linalg.eigvalsh(A), axis=-1), np.sort(ellipsoid.velocity**2, axis=-1), atol=1e-8)
        np.testing.assert_allclose(A @ ellipsoid.axes, ellipsoid.axes * ellipsoid.velocity[:, None, :] ** 2, atol=1e-8)


@pytest.mark.parametrize("name, joint", [("planar_elbow", 1), ("scara", 1)])
def test_the_velocity_ellipsoid_flattens_as_the_elbow_stretches(name, joint):
    """Stretched, the links cannot move the tool along themselves: the thinnest velocity axis goes to zero
    along the arm, and the force ellipsoid grows without bound there (the links hold that force alone)."""
    arm = Arm.preset(name)
    q = np.array([0.4, 0.0, 0.1, 0.0][: arm.n_joints])
    thinnest = []
    for angle in (1.0, 0.3, 0.03, 1e-5):
        q[joint] = angle
        translation, _ = arm.ellipsoids(q)
        thinnest.append(translation.velocity[translation.velocity > 0].min())  # the planar arm has no z at all
    assert all(a > b for a, b in zip(thinnest, thinnest[1:])) and thinnest[-1] < 1e-4
    radial = arm.fk(q)[:3, 3] * [1, 1, 0]
    axis = translation.axes[:, list(translation.velocity).index(thinnest[-1])]
    assert abs(axis @ radial) / np.linalg.norm(radial) > 1 - 1e-6
    assert translation.force[list(translation.velocity).index(thinnest[-1])] > 1e4


def test_shapes_broadcast_and_bad_input_is_refused():
    arm = Arm.preset("course")
    q = np.zeros((4, 6))
    assert arm.tool_twist(q, np.ones(6)).shape == (4, 6)
    assert arm.joint_rates(q[0], np.ones((3, 6))).qdot.shape == (3, 6)
    assert arm.static_torques(q, [0, 0, -10]).shape == (4, 6)
    assert arm.ellipsoids(q)[0].axes.shape == (4, 3, 3)
    for call, words in ((lambda: arm.tool_twist(np.zeros(6), np.ones(5)), "qdot must have shape"),
                        (lambda: arm.joint_rates(np.zeros(6), [0, 0, np.nan, 0, 0, 0]), "twist contains a non-finite"),
                        (lambda: arm.static_torques(np.zeros(6), [1, 2]), "force must have shape"),
                        (lambda: arm.static_torques(np.zeros(6), [1, 2, 3], [1j, 0, 0]), "moment must be real")):
        with pytest.raises(ValueError, match=words):
            call()
