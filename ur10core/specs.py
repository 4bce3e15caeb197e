"""What is known of each preset beyond its DH table: joint speed limits, torque ratings, rated
payload, named poses and how high it stands (docs/kinematics.md §1, §7.5, §8.5).

Every arm of the core reads its own as ``arm.specs`` (:class:`ArmSpecs`). A preset the
makers publish nothing for has ``None`` where a number would be; a typed table has only a
start pose.

Example
-------
>>> from ur10core import Arm
>>> arm = Arm.preset("course")
>>> np.degrees(arm.specs.speed_limits).round().tolist()      # docs/kinematics.md §1
[120.0, 120.0, 180.0, 180.0, 180.0, 180.0]
>>> np.degrees(arm.specs.home).round().tolist()               # the course's arbitrary pose, §3
[30.0, 45.0, 26.0, 50.0, 60.0, 80.0]
>>> Arm.preset("scara").specs.torque_ratings is None
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ._validate import as_float_array, check_finite


@dataclass(frozen=True)
class ArmSpecs:
    """An arm's published numbers and named poses.

    Attributes
    ----------
    poses : dict of str to ndarray, shape (n,)
        Named joint vectors (rad, and m for a prismatic joint). ``"home"`` is where the arm
        starts: away from every singularity, so that all its branches show.
    speed_limits : ndarray, shape (n,), or None
        Each joint's largest speed (rad/s, or m/s for a prismatic joint).
    torque_ratings : ndarray, shape (n,), or None
        Each joint's rated torque (N·m).
    payload_kg : float or None
        The rated payload at the flange.
    base_height : float
        How high its base frame's origin stands above the floor, along its vertical (m): 0 for
        an arm whose table starts on the floor, more for one whose table starts at the shoulder.
    """

    poses: dict[str, np.ndarray]
    speed_limits: np.ndarray | None = None
    torque_ratings: np.ndarray | None = None
    payload_kg: float | None = None
    base_height: float = 0.0
    #: the names of :attr:`poses` a student may pick (the home pose is always there)
    names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        if "home" not in self.poses:
            raise ValueError(f"an arm's poses must include 'home', got {', '.join(self.poses) or 'none'}")
        object.__setattr__(self, "names", tuple(self.poses))

    @property
    def home(self) -> np.ndarray:
        """(n,) where the arm starts."""
        return self.poses["home"].copy()


def _degrees(*values: float) -> np.ndarray:
    return np.radians(np.array(values, dtype=float))


#: The course's worked poses of the UR10 (docs/kinematics.md §3); it starts in the arbitrary one.
_UR_POSES = {"zero": _degrees(0, 0, 0, 0, 0, 0), "stretched": _degrees(45, 90, 0, -90, 0, 60),
             "arbitrary": _degrees(30, 45, 26, 50, 60, 80)}
#: UR's published UR10 numbers (docs/kinematics.md §1, §8.5), used for the UR10e as well: the
#: same joint speeds and joint sizes (4, 4, 3, 2, 2, 2).
_UR10 = dict(speed_limits=_degrees(120, 120, 180, 180, 180, 180),
             torque_ratings=np.array([330.0, 330.0, 150.0, 56.0, 56.0, 56.0]), payload_kg=10.0)

_SPECS = {
    **{name: ArmSpecs({**_UR_POSES, "home": _UR_POSES["arbitrary"]}, **_UR10) for name in ("course", "ur10", "ur10e")},
    # the course's other arms (docs/kinematics.md §7.5): each starts away from its singularities
    "kr210": ArmSpecs({"home": np.array([0.0, math.radians(15), math.radians(-30), math.radians(20),
                                          math.radians(40), math.radians(10)])}),
    # the report's table starts at the shoulder: 0.412 m up, as in Corke's model of Scheinman's arm (its d1)
    "stanford": ArmSpecs({"home": np.array([math.radians(30), math.radians(60), 0.254, math.radians(20),
                                             math.radians(40), math.radians(10)]),
                          # the report's own FK example, its GUI's default input: every angle 100°, d3 = 10 in
                          "report's example": np.array([*_degrees(100, 100), 0.254, *_degrees(100, 100, 100)])},
                         base_height=0.412),
    "elbow": ArmSpecs({"home": _degrees(20, 40, 60, 20, 40, 10)}),
    "scara": ArmSpecs({"home": np.array([math.radians(30), math.radians(60), 0.1, math.radians(20)])}),
    "planar_elbow": ArmSpecs({"home": _degrees(30, 60)}),
    "cylindrical": ArmSpecs({"home": np.array([math.radians(30), 0.35, 0.35])}),
    "cylindrical_wrist": ArmSpecs({"home": np.array([math.radians(30), 0.35, 0.35, *_degrees(20, 40, 10)])}),
    # the desktop arm starts where the course's drawing path starts (docs/kinematics.md §8.6); the course gives
    # its shoulder no pedestal: this one keeps every pose within the joint ranges above the floor
    "three_dof": ArmSpecs({"home": _degrees(0, 0, 135)}, base_height=1.5),
}


def specs_of(arm) -> ArmSpecs:
    """``arm``'s :class:`ArmSpecs`: its preset's, or for a typed table a start pose of 20° on each
    revolute joint (zero is often stretched out) and mid-stroke on each prismatic one, within its limits."""
    if arm.name in _SPECS and len(_SPECS[arm.name].home) == arm.n_joints:
        return _SPECS[arm.name]
    limits = np.asarray(arm.limits, dtype=float)
    revolute = np.array([kind == "R" for kind in arm.joint_types])
    home = np.where(revolute, np.clip(math.radians(20), limits[:, 0], limits[:, 1]), limits.mean(axis=1))
    return ArmSpecs({"home": home})


class HasSpecs:
    """``arm.specs`` for every arm of the core (it has ``name``, ``n_joints``, ``joint_types`` and ``limits``)."""

    @property
    def specs(self) -> ArmSpecs:
        """The arm's published numbers and named poses (:func:`specs_of`)."""
        return specs_of(self)


def torque_map(arm, force, n: int = 20_000, seed: int = 3) -> tuple[np.ndarray, np.ndarray, int]:
    """Where holding ``force`` (3,) N at the flange takes the most joint torque (docs/kinematics.md §8.3).

    The course's statics exercise for its 3-DOF arm, on any arm with a sampled workspace:
    ``n`` random joint vectors within the limits. Returns the flange positions (n, 3),
    ‖Jᵀ F‖ at each (n,) in N·m, and the index of the largest.
    """
    points, _, q = arm.sample_workspace(n, seed=seed, return_joints=True)
    norms = np.linalg.norm(arm.static_torques(q, force), axis=-1)
    return points, norms, int(np.argmax(norms))


#: The most joints :func:`torque_grid` spans (``steps ** n`` poses).
GRID_JOINTS = 3


@dataclass(frozen=True)
class WorstPose:
    """Where in the joint ranges a tool force needs the largest joint torques (docs/kinematics.md §8.6)."""

    q: np.ndarray  #: (n,) the joints there
    torques: np.ndarray  #: (n,) τ = J_vᵀ F there (N·m)
    norm: float  #: ‖τ‖ there
    samples: int  #: joint vectors searched


def torque_grid(arm, force, steps: int = 41) -> tuple[np.ndarray, np.ndarray]:
    """(q (steps**n, n), ‖J_vᵀ F‖ at each (steps**n,)) on a grid of ``steps`` values per joint over ``arm.limits``.

    For an arm of at most :data:`GRID_JOINTS` joints. ``force`` (3,) is in N, in the base
    frame. The tool positions, for drawing the map the course draws over the workspace, are
    ``arm.fk(q)[..., :3, 3]``.
    """
    force = as_float_array(force, "force")
    if force.shape != (3,):
        raise ValueError(f"force must be three numbers (N), got shape {force.shape}")
    check_finite(force, "force")
    if not 2 <= steps <= 201:
        raise ValueError(f"steps must be from 2 to 201, got {steps}")
    if arm.n_joints > GRID_JOINTS:
        raise ValueError(f"a grid over every joint is for an arm of at most {GRID_JOINTS} joints; "
                         f"the {arm.name} arm has {arm.n_joints}")
    axes = [np.linspace(low, high, steps) for low, high in arm.limits]
    q = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, arm.n_joints)
    return q, np.linalg.norm(arm.static_torques(q, force), axis=-1)


def largest_torque(arm, force, steps: int = 41, grid=None, refinements: int = 6) -> WorstPose:
    """The largest ‖J_vᵀ F‖ over the joint ranges: the best of :func:`torque_grid`, then refined.

    The course's statics exercise (docs/kinematics.md §8.6): which configuration needs the
    most torque to hold ``force`` (N, base frame) at the tool. Each refinement searches 11
    values per joint across one step of the last grid either side of its best (within the
    limits), a fifth of that step apart: six leave the pose within 5⁻⁶ of a first step
    (on the desktop arm's 41-value grid, 0.0003°). The tests find ‖τ‖ within 1e-9 of the
    closed forms. ``grid``: :func:`torque_grid`'s result, where the caller has it.

    Example: pushing sideways, the desktop arm's base holds the most, stretched across the force.

    >>> from ur10core import Arm
    >>> from ur10core.three_dof import FOREARM, UPPER_ARM
    >>> arm = Arm.preset("three_dof")
    >>> worst = largest_torque(arm, [10.0, 0.0, 0.0])
    >>> round(worst.norm, 6) == round(10 * (UPPER_ARM + FOREARM), 6), np.degrees(np.abs(worst.q)).round(2).tolist()
    (True, [90.0, 0.0, 180.0])
    """
    q, norms = torque_grid(arm, force, steps) if grid is None else grid
    best, samples = q[int(np.argmax(norms))], len(q)
    low, high = arm.limits.T
    step = (high - low) / (steps - 1)
    for _ in range(refinements):
        axes = [np.linspace(max(lo, c - h), min(hi, c + h), 11) for c, h, lo, hi in zip(best, step, low, high)]
        near = np.concatenate([[best], np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, arm.n_joints)])
        best = near[int(np.argmax(np.linalg.norm(arm.static_torques(near, force), axis=-1)))]
        samples, step = samples + len(near), step / 5
    torques = arm.static_torques(best, force)
    return WorstPose(best, torques, float(np.linalg.norm(torques)), samples)
