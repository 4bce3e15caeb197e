"""The UR family's dynamics: gravity loads (docs/kinematics.md §8.5), and the recursive Newton–Euler
equations with the mass matrix, Coriolis terms and forward dynamics (§8.8).

UR gives each link's mass and centre of mass in its *standard-DH* link frame, the
controller's convention (docs/kinematics.md §6). :func:`ur_standard_table` builds that chain
for a UR-family arm with the course's joint angles as input, so the masses sit where UR
puts them whatever convention the student's angles are in.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ._validate import as_float_array, check_finite, vectors
from .dh import DHRow, DHTable
from .differential import cross

#: Standard gravity (m/s²), acting along −z of the base frame.
GRAVITY = 9.81
#: Largest turn of any joint (rad) in one Runge–Kutta step of :func:`release`.
MAX_SUBSTEP_TURN = 0.1


@dataclass(frozen=True)
class LinkMasses:
    """Each link's mass and centre of mass, links 1…6 (docs/kinematics.md §8.5)."""

    masses: np.ndarray  #: (6,) kg
    centres: np.ndarray  #: (6, 3) m, in the link's standard-DH frame (UR's convention)
    inertias: np.ndarray  #: (6, 3, 3) kg·m², about the centre of mass, axes of the link frame
    source: str


#: UR's published masses and centres of mass for the UR10 (CB3), with the inertias of
#: roboticstoolbox-python's DH ``UR10`` model (UR publishes none), so both describe one arm.
UR10_MASSES = LinkMasses(
    masses=np.array([7.1, 12.7, 4.27, 2.0, 2.0, 0.365]),
    centres=np.array([[0.021, 0.0, 0.027], [0.38, 0.0, 0.158], [0.24, 0.0, 0.068],
                      [0.0, 0.007, 0.018], [0.0, 0.007, 0.018], [0.0, 0.0, -0.026]]),
    inertias=np.array([
        [[0.0341, 0.0, -0.0043], [0.0, 0.0353, 0.0001], [-0.0043, 0.0001, 0.0216]],
        [[0.0281, 0.0001, -0.0156], [0.0001, 0.7707, 0.0], [-0.0156, 0.0, 0.7694]],
        [[0.0101, 0.0001, 0.0092], [0.0001, 0.3093, 0.0], [0.0092, 0.0, 0.3065]],
        [[0.003, 0.0, 0.0], [0.0, 0.0022, -0.0002], [0.0, -0.0002, 0.0026]],
        [[0.003, 0.0, 0.0], [0.0, 0.0022, -0.0002], [0.0, -0.0002, 0.0026]],
        [[0.0, 0.0, 0.0], [0.0, 0.0004, 0.0], [0.0, 0.0, 0.0003]],
    ]),
    source="UR's published masses and centres of mass for the UR10; inertias of roboticstoolbox-python's UR10",
)

#: UR's published masses for the UR10e; its centres of mass are published as the UR10's, in the
#: UR10e's own link frames. UR publishes no inertias: the UR10's are kept.
UR10E_MASSES = LinkMasses(masses=np.array([7.369, 13.051, 3.989, 2.1, 1.98, 0.615]), centres=UR10_MASSES.centres,
                          inertias=UR10_MASSES.inertias,
                          source="UR's published masses and centres of mass for the UR10e; inertias as the UR10's")

#: Per preset. The course's arm has UR10 link lengths to within a millimetre: it carries the
#: UR10's masses (the course's own CAD masses come without centres of mass).
MASSES = {"ur10": UR10_MASSES, "course": UR10_MASSES, "ur10e": UR10E_MASSES}


def ur_standard_table(arm) -> DHTable:
    """UR's standard-DH chain of a UR-family ``Arm``, taking the *course's* joint angles.

    Rows (a, α, d, θ offset): (0, π/2, d1, 0), (−a2, 0, 0, π), (−a3, 0, 0, 0), (0, π/2, d4, 0),
    (0, −π/2, d5, 0), (0, 0, d6, 0): the shoulder's offset π is the controller's
    ``q_controller = q_course + (0, π, 0, 0, 0, 0)`` (docs/kinematics.md §6).
    """
    half = math.pi / 2
    rows = [DHRow(0.0, half, arm.d1, 0.0, "R"), DHRow(-arm.a2, 0.0, 0.0, math.pi, "R"),
            DHRow(-arm.a3, 0.0, 0.0, 0.0, "R"), DHRow(0.0, half, arm.d4, 0.0, "R"),
            DHRow(0.0, -half, arm.d5, 0.0, "R"), DHRow(0.0, 0.0, arm.d6, 0.0, "R")]
    return DHTable(rows, "standard")


def link_masses(arm) -> LinkMasses:
    """The masses an arm's gravity loads use; ``ValueError`` for an arm without published ones."""
    masses = MASSES.get(getattr(arm, "name", None))
    if masses is None:
        raise ValueError(f"no link masses for {getattr(arm, 'name', arm)!r}: gravity loads are known for "
                         f"{', '.join(sorted(MASSES))}")
    return masses


def gravity_torques(arm, q: np.ndarray, payload_kg: float = 0.0) -> np.ndarray:
    """The joint torques (N·m) that hold a UR-family arm still against gravity, (..., 6).

    τ_i = Σ_j m_j g · (∂p_cj/∂q_i)_z: the rate at which joint i lifts each mass, the
    gradient of the potential energy Σ m_j g z_cj (docs/kinematics.md §8.5). For a revolute
    joint about z through o, ∂p/∂q = z × (p − o). ``payload_kg`` sits at the flange origin.
    The same sense as roboticstoolbox-python's ``gravload``.
    """
    payload_kg = _check_payload(payload_kg)
    masses = link_masses(arm)
    frames = ur_standard_table(arm).frames(q)  # (..., 7, 4, 4)
    centres = _centres(frames, masses)
    weights = GRAVITY * masses.masses
    # the payload: one more mass at the flange origin
    centres = np.concatenate([centres, frames[..., 6:, :3, 3]], axis=-2)
    weights = np.append(weights, GRAVITY * payload_kg)
    axes, origins = frames[..., :6, :3, 2], frames[..., :6, :3, 3]  # joint i turns about z_{i−1} through o_{i−1}
    tau = np.zeros(frames.shape[:-3] + (6,))
    for i in range(6):
        lever = centres[..., i:, :] - origins[..., i:i + 1, :]  # only the links beyond joint i move with it
        lift = cross(axes[..., i:i + 1, :], lever)[..., 2]  # ∂z_c/∂q_i
        tau[..., i] = (lift * weights[i:]).sum(axis=-1)
    return tau


def centres_of_mass(arm, q: np.ndarray) -> np.ndarray:
    """Each link's centre of mass in the base frame (m), (..., 6, 3), at the course's joints ``q`` (..., 6): UR's
    published centres, each in its link's frame of UR's standard DH table (docs/kinematics.md §8.5).

    >>> from ur10core import Arm
    >>> (1000 * centres_of_mass(Arm.preset("ur10"), np.zeros(6))[2]).round(1)  # the forearm's, stretched out
    array([944.3, -68. , 127.3])
    """
    return _centres(ur_standard_table(arm).frames(np.asarray(q, dtype=float)), link_masses(arm))


def _centres(frames: np.ndarray, masses: LinkMasses) -> np.ndarray:
    """Each link's centre of mass in the base frame, (..., 6, 3), from UR's standard-DH frames (..., 7, 4, 4)."""
    return np.einsum("...jab,jb->...ja", frames[..., 1:, :3, :3], masses.centres) + frames[..., 1:, :3, 3]


def energies(arm, q, qd, payload_kg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Kinetic and potential energy (J) of a UR-family arm at joints ``q`` turning at ``qd``, each (...,).

    The two terms of the Lagrangian L = T − V (docs/kinematics.md §8.8), from each link's own motion:

        T = Σ_j ½ m_j |v_cj|² + ½ ω_jᵀ R_j I_j R_jᵀ ω_j,   V = g Σ_j m_j z_cj

    with ω_j = Σ_{i≤j} z_{i−1} q̇_i and v_cj = Σ_{i≤j} z_{i−1} × (p_cj − o_{i−1}) q̇_i.
    Lagrange's equations d/dt ∂L/∂q̇ − ∂L/∂q = τ are then Newton–Euler's: T = ½ q̇ᵀ M(q) q̇
    (:func:`mass_matrix`) and ∂V/∂q = g(q) (:func:`gravity_torques`). Let go with no
    friction, T + V stays constant (:func:`release`). ``payload_kg`` sits at the flange origin.
    ``ValueError`` as :func:`inverse_dynamics`, or for an arm without link masses.

    >>> from ur10core import Arm
    >>> T, V = energies(Arm.preset("ur10"), np.zeros(6), [1.0, 0, 0, 0, 0, 0])  # the base turning at 1 rad/s
    >>> round(float(T), 2), round(float(V), 1)
    (6.11, 38.4)
    """
    q, qd = np.broadcast_arrays(*_joint_arrays(q=q, qd=qd))
    links = with_payload(link_masses(arm), _check_payload(payload_kg))
    frames = ur_standard_table(arm).frames(q)
    centres = _centres(frames, links)
    axes, origins = frames[..., :6, :3, 2], frames[..., :6, :3, 3]  # joint i turns about z_{i−1} through o_{i−1}
    kinetic, spin = np.zeros(q.shape[:-1]), np.zeros(q.shape[:-1] + (3,))
    for j in range(6):
        spin = spin + axes[..., j, :] * qd[..., j:j + 1]  # ω_j, in the base frame
        levers = centres[..., j:j + 1, :] - origins[..., :j + 1, :]
        velocity = (cross(axes[..., :j + 1, :], levers) * qd[..., :j + 1, None]).sum(axis=-2)
        own = np.einsum("...ba,...b->...a", frames[..., j + 1, :3, :3], spin)  # R_jᵀ ω_j: in the link's axes
        kinetic = kinetic + 0.5 * links.masses[j] * (velocity * velocity).sum(axis=-1) \
            + 0.5 * np.einsum("...a,ab,...b->...", own, links.inertias[j], own)
    return kinetic, GRAVITY * (centres[..., 2] * links.masses).sum(axis=-1)


def _check_payload(payload_kg) -> float:
    if not (isinstance(payload_kg, (int, float)) and math.isfinite(payload_kg) and 0.0 <= payload_kg <= 1000.0):
        raise ValueError(f"payload_kg must be a number of kilograms from 0 to 1000, got {payload_kg!r:.40}")
    return float(payload_kg)


def with_payload(masses: LinkMasses, payload_kg: float) -> LinkMasses:
    """Link 6 with a point mass at the flange origin: combined mass, centre and inertia (parallel axes)."""
    if payload_kg == 0.0:
        return masses
    m, r, inertia = masses.masses[5], masses.centres[5], masses.inertias[5]
    total = m + payload_kg
    centre = m * r / total  # the payload sits at the origin of frame 6

    def shifted(mass: float, offset: np.ndarray) -> np.ndarray:
        return mass * (offset @ offset * np.eye(3) - np.outer(offset, offset))

    combined = inertia + shifted(m, r - centre) + shifted(payload_kg, -centre)
    return LinkMasses(np.append(masses.masses[:5], total), np.vstack([masses.centres[:5], centre]),
                      np.concatenate([masses.inertias[:5], combined[None]]), masses.source)


def _joint_arrays(**named) -> list[np.ndarray]:
    """Each named value as finite (..., 6) floats whose leading shapes broadcast; ``ValueError`` naming the culprit."""
    arrays = [vectors(value, name, 6) for name, value in named.items()]
    try:
        np.broadcast_shapes(*(array.shape for array in arrays))
    except ValueError:
        shapes = ", ".join(f"{name} {array.shape}" for name, array in zip(named, arrays))
        raise ValueError(f"{', '.join(named)} must have shapes that broadcast together, got {shapes}") from None
    return arrays


def _gravity(gravity, leading: tuple[int, ...]) -> np.ndarray:
    """``gravity`` (m/s²) as finite floats broadcast with the joints' leading shape ``leading``."""
    gravity = as_float_array(gravity, "gravity")
    check_finite(gravity, "gravity")
    try:
        np.broadcast_shapes(gravity.shape, leading)
    except ValueError:
        raise ValueError(f"gravity must be a number or broadcast with the joints' leading shape {leading}, "
                         f"got shape {gravity.shape}") from None
    return gravity


def inverse_dynamics(arm, q, qd, qdd, gravity=GRAVITY, payload_kg: float = 0.0) -> np.ndarray:
    """τ = M(q) q̈ + C(q, q̇) q̇ + g(q), (..., 6) N·m, by the recursive Newton–Euler equations (docs/kinematics.md §8.8).

    Outward, each link's angular velocity and acceleration and its centre's acceleration
    (gravity enters as an upward acceleration of the base); inward, the force and moment each
    link passes to the one before it, whose component along the joint axis is τ. In UR's
    standard-DH link frames (:func:`ur_standard_table`), with the course's angles.
    ``gravity`` (m/s², along −z) may differ per pose: an array broadcast with the leading shape.
    ``ValueError`` for joints that are not finite (..., 6) arrays, or shapes that do not broadcast.
    """
    q, qd, qdd = _joint_arrays(q=q, qd=qd, qdd=qdd)
    gravity = _gravity(gravity, np.broadcast_shapes(q.shape, qd.shape, qdd.shape)[:-1])
    return _newton_euler(arm, q, qd, qdd, gravity, payload_kg)


def _newton_euler(arm, q, qd, qdd, gravity, payload_kg: float) -> np.ndarray:
    """:func:`inverse_dynamics` of validated arrays."""
    table = ur_standard_table(arm)
    q, qd, qdd = np.broadcast_arrays(q, qd, qdd)
    q, qd, qdd = (np.broadcast_to(v, np.broadcast_shapes(q.shape, np.shape(gravity) + (6,))) for v in (q, qd, qdd))
    links = with_payload(link_masses(arm), _check_payload(payload_kg))
    rows = table.rows
    alpha = np.array([row.alpha for row in rows])
    a = np.array([row.a for row in rows])
    d = np.array([row.d for row in rows])
    theta = q + np.array([row.theta for row in rows])
    c, s = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    # R_i = Rz(θ_i) Rx(α_i): frame i in frame i−1
    R = np.stack([np.stack([c, -s * ca, s * sa], -1), np.stack([s, c * ca, -c * sa], -1),
                  np.stack([np.zeros_like(c), np.broadcast_to(sa, c.shape), np.broadcast_to(ca, c.shape)], -1)], -2)
    Rt = np.swapaxes(R, -1, -2)
    pstar = np.stack([a, d * sa, d * ca], -1)  # frame i's origin from frame i−1's, in frame i
    z = np.array([0.0, 0.0, 1.0])
    batch = q.shape[:-1]
    w, wd = np.zeros(batch + (3,)), np.zeros(batch + (3,))
    vd = np.broadcast_to(np.asarray(gravity, dtype=float)[..., None] * z, batch + (3,))
    forces, moments = [], []

    def rotate(M: np.ndarray, v: np.ndarray) -> np.ndarray:
        return np.einsum("...ij,...j->...i", M, v)

    for i in range(6):
        wd = rotate(Rt[..., i, :, :], wd + z * qdd[..., i:i + 1] + cross(w, z * qd[..., i:i + 1]))
        w = rotate(Rt[..., i, :, :], w + z * qd[..., i:i + 1])
        vd = cross(wd, pstar[i]) + cross(w, cross(w, pstar[i])) + rotate(Rt[..., i, :, :], vd)
        r = links.centres[i]
        centre_acceleration = cross(wd, r) + cross(w, cross(w, r)) + vd
        inertia = links.inertias[i]
        forces.append(links.masses[i] * centre_acceleration)
        moments.append(rotate(inertia, wd) + cross(w, rotate(inertia, w)))
    tau = np.empty(batch + (6,))
    f, n = np.zeros(batch + (3,)), np.zeros(batch + (3,))
    for i in reversed(range(6)):
        if i == 5:
            n = cross(pstar[i] + links.centres[i], forces[i]) + moments[i]
            f = forces[i]
        else:
            Rn = R[..., i + 1, :, :]
            n = rotate(Rn, n + cross(rotate(np.swapaxes(Rn, -1, -2), pstar[i]), f)) \
                + cross(pstar[i] + links.centres[i], forces[i]) + moments[i]
            f = rotate(Rn, f) + forces[i]
        tau[..., i] = np.einsum("...i,...i->...", n, rotate(Rt[..., i, :, :], z))
    return tau


def mass_matrix(arm, q, payload_kg: float = 0.0) -> np.ndarray:
    """M(q), (..., 6, 6): column j is the torque for q̈ = e_j at rest without gravity (docs/kinematics.md §8.8)."""
    (q,) = _joint_arrays(q=q)
    unit = np.eye(6)
    columns = _newton_euler(arm, q[..., None, :], np.zeros(6), unit, 0.0, payload_kg)
    return np.swapaxes(columns, -1, -2)


def coriolis_torques(arm, q, qd, payload_kg: float = 0.0) -> np.ndarray:
    """C(q, q̇) q̇, (..., 6): the centrifugal and Coriolis torques of moving joints (docs/kinematics.md §8.8)."""
    q, qd = _joint_arrays(q=q, qd=qd)
    return _newton_euler(arm, q, qd, np.zeros(6), 0.0, payload_kg)


def forward_dynamics(arm, q, qd, tau, payload_kg: float = 0.0) -> np.ndarray:
    """q̈ = M⁻¹ (τ − C q̇ − g), (..., 6): how the joints accelerate under torques ``tau``.

    One Newton–Euler pass over seven problems at once: M's six columns (q̈ = e_j, at rest,
    no gravity) and the bias C q̇ + g (q̈ = 0). ``ValueError`` as :func:`inverse_dynamics`.
    """
    return _forward(arm, *_joint_arrays(q=q, qd=qd, tau=tau), payload_kg)


@functools.lru_cache(maxsize=64)
def _chain(arm, payload_kg: float) -> tuple:
    """What one pose's Newton–Euler pass needs of ``arm`` that no joint changes: the UR standard table's
    (cos α, sin α, θ offset) and its links' origins p*, masses, centres, inertias and their cross-product matrices."""
    table = ur_standard_table(arm)
    links = with_payload(link_masses(arm), _check_payload(payload_kg))
    alpha = np.array([row.alpha for row in table.rows])
    ca, sa = np.cos(alpha), np.sin(alpha)
    a, d = np.array([row.a for row in table.rows]), np.array([row.d for row in table.rows])
    pstar = np.stack([a, d * sa, d * ca], -1)
    return (ca, sa, np.array([row.theta for row in table.rows]), pstar, links.masses, links.centres,
            np.swapaxes(links.inertias, -1, -2), [_times(p) for p in pstar], [_times(r) for r in links.centres],
            [_times(p + r) for p, r in zip(pstar, links.centres)])


def _one_pose_forward(arm, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, payload_kg: float) -> np.ndarray:
    """:func:`_forward` of one state (6,) each: :func:`_newton_euler`'s recursion on its seven problems as (7, 3) rows.

    The rows share q, so each link's rotation is made once and the constant cross products
    are matrix products (the gravity drop calls this a thousand times a second of motion).
    """
    ca, sa, theta0, pstar, masses, centres, inertias_t, times_p, times_r, times_pr = _chain(arm, payload_kg)
    theta = q + theta0
    c, s = np.cos(theta), np.sin(theta)
    R = np.empty((6, 3, 3))  # R_i = Rz(θ_i) Rx(α_i): frame i in frame i−1
    R[:, 0, 0], R[:, 0, 1], R[:, 0, 2] = c, -s * ca, s * sa
    R[:, 1, 0], R[:, 1, 1], R[:, 1, 2] = s, c * ca, -c * sa
    R[:, 2, 0], R[:, 2, 1], R[:, 2, 2] = 0.0, sa, ca
    rates = np.zeros(7)
    w, wd, vd = np.zeros((7, 3)), np.zeros((7, 3)), np.zeros((7, 3))
    vd[6, 2] = GRAVITY  # rows 0–5: q̈ = e_j at rest without gravity (M's columns); row 6: q̇ and gravity (the bias)
    forces, moments = [], []
    for i in range(6):
        rates[6] = qd[i]
        spun = wd.copy()  # ω̇ + z q̈ + ω × z q̇, with ω × z = (ω_y, −ω_x, 0)
        spun[i, 2] += 1.0
        spun[:, 0] += w[:, 1] * rates
        spun[:, 1] -= w[:, 0] * rates
        w = w.copy()
        w[:, 2] += rates
        wd, w = spun @ R[i], w @ R[i]
        w_squared = (w * w).sum(axis=1)[:, None]
        vd = wd @ times_p[i] + w * (w @ pstar[i])[:, None] - pstar[i] * w_squared + vd @ R[i]
        centre_acceleration = wd @ times_r[i] + w * (w @ centres[i])[:, None] - centres[i] * w_squared + vd
        forces.append(masses[i] * centre_acceleration)
        spin = w @ inertias_t[i]
        moments.append(wd @ inertias_t[i] + cross(w, spin))
    torques = np.empty((7, 6))
    n = moments[5] - forces[5] @ times_pr[5]
    f = forces[5]
    torques[:, 5] = n @ R[5, 2]
    for i in reversed(range(5)):
        Rn = R[i + 1]
        n = (n - f @ _times(Rn.T @ pstar[i])) @ Rn.T - forces[i] @ times_pr[i] + moments[i]
        f = f @ Rn.T + forces[i]
        torques[:, i] = n @ R[i, 2]
    return np.linalg.solve(torques[:6].T, tau - torques[6])


def _times(v: np.ndarray) -> np.ndarray:
    """K with ``x @ K = x × v`` for rows x (so ``v × x = −x @ K``)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _forward(arm, q, qd, tau, payload_kg: float) -> np.ndarray:
    """:func:`forward_dynamics` of validated arrays (the simulation's inner loop)."""
    if q.shape == qd.shape == (6,) and np.shape(tau) == (6,):
        return _one_pose_forward(arm, q, qd, np.asarray(tau, dtype=float), payload_kg)
    q, qd = np.broadcast_arrays(q, qd)
    rates = np.concatenate([np.zeros(q.shape[:-1] + (6, 6)), qd[..., None, :]], axis=-2)
    accelerations = np.concatenate([np.eye(6), np.zeros((1, 6))])
    gravity = np.append(np.zeros(6), GRAVITY)
    torques = _newton_euler(arm, q[..., None, :], rates, accelerations, gravity, payload_kg)
    M, bias = np.swapaxes(torques[..., :6, :], -1, -2), torques[..., 6, :]
    return np.linalg.solve(M, (tau - bias)[..., None])[..., 0]


@dataclass(frozen=True)
class Motion:
    """A simulated motion: times (m,), joints and joint rates (m, 6)."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray


def release(arm, q0, duration: float = 2.0, dt: float = 0.01, payload_kg: float = 0.0, stop=None) -> Motion:
    """The arm let go at rest at ``q0``, every joint free (no torque, no friction), under gravity.

    The course's gravity-drop simulation (docs/kinematics.md §8.8), sampled every ``dt``
    and integrated with the classical fourth-order Runge–Kutta method in steps that turn no
    joint more than :data:`MAX_SUBSTEP_TURN`. ``stop(q)``, if given, ends the motion at the
    first sample where it is true (that sample included): the floor, say
    (:func:`ur10core.workspace.through_floor`).
    """
    if not (isinstance(duration, (int, float)) and 0.0 < duration <= 60.0):
        raise ValueError(f"duration must be from 0 to 60 s, got {duration!r:.40}")
    if not (isinstance(dt, (int, float)) and 1e-4 <= dt <= 0.05):
        raise ValueError(f"dt must be from 0.0001 to 0.05 s, got {dt!r:.40}")
    q = np.array(q0, dtype=float)
    if q.shape != (6,) or not np.isfinite(q).all():
        raise ValueError(f"q0 must be six finite joint angles, got {q0!r:.80}")
    steps = int(round(duration / dt))
    qs, qds = np.empty((steps + 1, 6)), np.empty((steps + 1, 6))
    qd = np.zeros(6)
    qs[0], qds[0] = q, qd
    rest = np.zeros(6)

    def rates(position: np.ndarray, velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return velocity, _forward(arm, position, velocity, rest, payload_kg)

    for k in range(steps):
        # a fast-spinning wrist turns a radian or more in 10 ms, where a fixed step of RK4 drifted by
        # 0.1–1 J: each sample is reached in substeps that turn no joint more than MAX_SUBSTEP_TURN
        substeps = max(1, math.ceil(float(np.abs(qd).max()) * dt / MAX_SUBSTEP_TURN))
        h = dt / substeps
        for _ in range(substeps):
            k1 = rates(q, qd)
            k2 = rates(q + h / 2 * k1[0], qd + h / 2 * k1[1])
            k3 = rates(q + h / 2 * k2[0], qd + h / 2 * k2[1])
            k4 = rates(q + h * k3[0], qd + h * k3[1])
            q = q + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            qd = qd + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        qs[k + 1], qds[k + 1] = q, qd
        if stop is not None and stop(q):
            steps = k + 1
            break
    return Motion(np.arange(steps + 1) * dt, qs[:steps + 1], qds[:steps + 1])
