"""The course's other arms (docs/kinematics.md §7.5): their DH tables, limits and solvers.

``Arm.preset(name)`` builds an :class:`ur10core.Arm` from one of :data:`PRESETS`: the
course's KR210 and Stanford arm, the lecture notes' SCARA, elbow arm, planar elbow and
cylindrical arm (alone and with a spherical wrist). Also here: the KR210's URDF frame, the
KR210 report's slip in its IK (:func:`report_slip`), and the part of a target an arm that
controls less than a whole pose can follow (:func:`project_target`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ._validate import homogeneous_transform
from .dh import MODIFIED, STANDARD
from .solvers.planar import Cylindrical, PlanarElbow, Scara
from .solvers.spherical_wrist import ArticulatedArm, CylindricalArm, StanfordArm

_PI = math.pi
_DEG = math.pi / 180


@dataclass(frozen=True)
class _Preset:
    description: str
    rows: tuple
    convention: str
    limits: tuple  # (low, high) per joint: radians or metres
    solver: type
    joint_names: tuple[str, ...]


def _degrees(*pairs) -> tuple:
    return tuple((low * _DEG, high * _DEG) for low, high in pairs)


#: docs/kinematics.md §7.5: where each number comes from.
PRESETS: dict[str, _Preset] = {
    "kr210": _Preset(
        "KUKA KR210 (the course's pick-and-place report): spherical wrist, gripper frame G",
        ((0, 0, 0.75, 0, "R"), (0.35, -_PI / 2, 0, -_PI / 2, "R"), (1.25, 0, 0, 0, "R"),
         (-0.054, -_PI / 2, 1.50, 0, "R"), (0, _PI / 2, 0, 0, "R"), (0, -_PI / 2, 0, 0, "R"),
         (0, 0, 0.303, 0, None)),
        MODIFIED, _degrees((-185, 185), (-45, 85), (-210, 65), (-350, 350), (-125, 125), (-350, 350)),
        ArticulatedArm, ("A1", "A2", "A3", "A4", "A5", "A6")),
    "stanford": _Preset(
        "Stanford arm (the course's MATLAB GUI report): RRP + spherical wrist, d2 = 6.375 in",
        ((0, -_PI / 2, 0, 0, "R"), (0, _PI / 2, 0.161925, 0, "R"), (0, 0, 0, 0, "P"),
         (0, -_PI / 2, 0, 0, "R"), (0, _PI / 2, 0, 0, "R"), (0, 0, 0, 0, "R")),
        STANDARD, _degrees((-170, 170), (-170, 170)) + ((0.0, 0.762),) + _degrees((-170, 170), (-170, 170), (-170, 170)),
        StanfordArm, ("θ1", "θ2", "d3", "θ4", "θ5", "θ6")),
    "elbow": _Preset(
        "Articulated (elbow) arm with a spherical wrist, as in the DH lecture notes",
        ((0, _PI / 2, 0.6, 0, "R"), (0.5, 0, 0, 0, "R"), (0, _PI / 2, 0, 0, "R"),
         (0, -_PI / 2, 0.45, 0, "R"), (0, _PI / 2, 0, 0, "R"), (0, 0, 0.1, 0, "R")),
        STANDARD, _degrees((-170, 170), (-90, 150), (-150, 150), (-180, 180), (-120, 120), (-180, 180)),
        ArticulatedArm, ("θ1", "θ2", "θ3", "θ4", "θ5", "θ6")),
    "scara": _Preset(
        "SCARA (RRP + roll), the numbers of an Omron/Adept Cobra 600",
        ((0.325, 0, 0.387, 0, "R"), (0.275, _PI, 0, 0, "R"), (0, 0, 0, 0, "P"), (0, 0, 0, 0, "R")),
        STANDARD, _degrees((-105, 105), (-157.5, 157.5)) + ((0.0, 0.21),) + _degrees((-360, 360)),
        Scara, ("θ1", "θ2", "d3", "θ4")),
    "planar_elbow": _Preset(
        "Two-link planar elbow (RR), links 500 mm and 400 mm",
        ((0.5, 0, 0, 0, "R"), (0.4, 0, 0, 0, "R")),
        STANDARD, _degrees((-180, 180), (-180, 180)),
        PlanarElbow, ("θ1", "θ2")),
    "cylindrical": _Preset(
        "Three-link cylindrical arm (RPP): base column 300 mm, lift d2, reach d3",
        ((0, 0, 0.3, 0, "R"), (0, -_PI / 2, 0, 0, "P"), (0, 0, 0, 0, "P")),
        STANDARD, _degrees((-180, 180)) + ((0.0, 0.7), (0.1, 0.6)),
        Cylindrical, ("θ1", "d2", "d3")),
    "cylindrical_wrist": _Preset(
        "Cylindrical arm (RPP) with a spherical wrist, as in the DH lecture notes: d6 = 100 mm",
        ((0, 0, 0.3, 0, "R"), (0, -_PI / 2, 0, 0, "P"), (0, 0, 0, 0, "P"),
         (0, -_PI / 2, 0, 0, "R"), (0, _PI / 2, 0, 0, "R"), (0, 0, 0.1, 0, "R")),
        STANDARD, _degrees((-180, 180)) + ((0.0, 0.7), (0.1, 0.6)) + _degrees((-180, 180), (-120, 120), (-180, 180)),
        CylindricalArm, ("θ1", "d2", "d3", "θ4", "θ5", "θ6")),
}


#: docs/kinematics.md §7.5: the KR210 simulation model (URDF, ROS/Gazebo) puts its gripper frame
#: differently: R_DH = R_URDF · Rz(π) · Ry(−π/2). The URDF frame's x axis is the DH frame's z (the approach).
KR210_URDF_TURN = np.array([[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]) @ np.array(
    [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])


def kr210_from_urdf(T) -> np.ndarray:
    """A KR210 gripper pose read in the URDF (ROS/Gazebo) convention, as the DH table's G frame, (..., 4, 4).

    >>> T = kr210_from_urdf(np.eye(4))
    >>> T[:3, 2].tolist()   # the DH approach axis z_G is the URDF's x
    [1.0, 0.0, 0.0]
    """
    T = homogeneous_transform(T).copy()
    T[..., :3, :3] = T[..., :3, :3] @ KR210_URDF_TURN
    return T


def kr210_to_urdf(T) -> np.ndarray:
    """The inverse of :func:`kr210_from_urdf`: a DH gripper pose in the URDF convention, (..., 4, 4)."""
    T = homogeneous_transform(T).copy()
    T[..., :3, :3] = T[..., :3, :3] @ KR210_URDF_TURN.T
    return T


__all__ = ["KR210_URDF_TURN", "PRESETS", "ReportSlip", "kr210_from_urdf", "kr210_to_urdf", "project_target", "report_slip"]


class ReportSlip(NamedTuple):
    """What :func:`report_slip` finds for one target."""

    distance: float  #: √(WC_x² + WC_y²) − a1 (m): how far the wrist centre is beyond the shoulder, horizontally
    radicand: float  #: WC_x² + WC_y² − a1, with a1's number in metres: what the report takes the square root of
    reached: np.ndarray | None  #: (4, 4) the tool pose the slipped joints reach; None where ``slipped`` is NaN
    q: np.ndarray | None  #: (6,) those joints, on the asked branch's elbow and wrist; None where it cannot reach
    right: np.ndarray | None  #: (6,) the joints on that branch that reach ``T`` itself; None where it does not

    @property
    def slipped(self) -> float:
        """√(radicand): the distance as the report has it (m); NaN where the radicand is negative."""
        return math.sqrt(self.radicand) if self.radicand >= 0.0 else math.nan

    @property
    def gap(self) -> float:
        """How far the report's gripper ends from the target (m): |slipped − distance|, NaN where it has none."""
        return abs(self.slipped - self.distance)


def report_slip(arm, T, slot: int, q_current) -> ReportSlip:
    """Where the KR210 report's inverse kinematics puts the tool for the target ``T`` (4, 4) (docs/kinematics.md §7.3).

    The report takes the wrist centre's horizontal distance beyond the shoulder as
    √(WC_x² + WC_y² − a1) where it is √(WC_x² + WC_y²) − a1 (a length taken from an area:
    the units give it away). Every later step is right for the distance it is given, so the
    arm puts its wrist centre where that distance is the true one: on the same half-plane
    through axis 1 and at the same height, ρ' = √(ρ² − a1) + a1 from the axis (ρ =
    √(WC_x² + WC_y²)), and its wrist still turns the tool as asked. ``reached`` is ``T``
    moved out by ρ' − ρ. The report solves the shoulder-front branches only: ``q`` is the
    shoulder-front branch with the elbow and wrist of ``slot`` (0..7, ``4 shoulder + 2 elbow
    + wrist``), turned next to ``q_current`` (6,); None where it does not reach ``reached``.
    ``right`` is the same branch's joints for ``T``, to set the two side by side.

    >>> from ur10core import Arm
    >>> kr210 = Arm.preset("kr210")
    >>> T = np.eye(4); T[:3, 3] = (2.0, 0.0, 1.5); T[:3, :3] = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]  # gripper along x
    >>> slip = report_slip(kr210, T, 0, np.zeros(6))   # the wrist centre 1.697 m out: 1.347 m beyond the shoulder
    >>> round(slip.distance, 3), round(slip.radicand, 3), round(slip.slipped, 3), round(slip.gap, 3)
    (1.347, 2.53, 1.591, 0.244)
    >>> round(float(slip.reached[0, 3] - T[0, 3]), 3)   # moved out along x, where the wrist centre is
    0.244
    >>> np.allclose(kr210.fk(slip.q), slip.reached), np.degrees(slip.q - slip.right).round(1).tolist()  # θ2, θ3 off
    (True, [0.0, 11.0, -11.4, 0.0, -0.4, 0.0])
    """
    if not isinstance(arm.solver, ArticulatedArm) or arm.solver.plane["u0"] == 0.0:
        raise ValueError(f"the {arm.name!r} arm has no shoulder offset a1 decoupled at its wrist centre: the slip "
                         "changes nothing for it")
    if isinstance(slot, bool) or not isinstance(slot, (int, np.integer)) or not 0 <= slot < 8:
        raise ValueError(f"slot must be 0..7, got {slot!r}")
    T = homogeneous_transform(T)
    if T.shape != (4, 4):
        raise ValueError(f"T must be one 4 × 4 pose, got shape {T.shape}")
    a1 = arm.solver.plane["u0"]
    centre = T[:3, 3] + T[:3, :3] @ arm.solver.centre_in_tool
    rho = math.hypot(centre[0], centre[1])
    front = slot % 4
    target = arm.ik(T, hint=q_current)
    right = target.take(front, q_current) if target.valid[front] else None
    if rho * rho < a1:  # the report's code stops here: the square root of a negative number
        return ReportSlip(rho - a1, rho * rho - a1, None, None, right)
    outward = centre[:2] / rho if rho > 0.0 else np.array([1.0, 0.0])
    reached = T.copy()
    reached[:2, 3] += (math.sqrt(rho * rho - a1) + a1 - rho) * outward
    solution = arm.ik(reached, hint=q_current)
    q = solution.take(front, q_current) if solution.valid[front] else None
    return ReportSlip(rho - a1, rho * rho - a1, reached, q, right)


def project_target(arm, T, current) -> np.ndarray:
    """The part of a target pose ``T`` (4, 4) the arm can follow (``arm.task``), the rest from its
    own tool pose ``current`` (4, 4).

    A SCARA keeps its tool axis (down, the preset's) and takes only the target's yaw, the turn of
    its x axis about z; an arm that places only a position keeps its own orientation; an arm that
    moves in a plane (the planar elbow, in z = 0: ``Arm.planar``) stays in it (docs/kinematics.md §7.5).
    """
    out = np.array(T, dtype=float)
    if out.shape != (4, 4) or not np.isfinite(out).all():
        raise ValueError(f"T must be one finite 4 × 4 pose, got shape {out.shape}")
    if arm.task == "position and yaw":  # its own orientation turned about z by the yaw between them
        now = np.asarray(current, dtype=float)
        turn = math.atan2(out[1, 0], out[0, 0]) - math.atan2(now[1, 0], now[0, 0])
        c, s = math.cos(turn), math.sin(turn)
        out[:3, :3] = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ now[:3, :3]
    elif arm.task == "position":
        out[:3, :3] = np.asarray(current, dtype=float)[:3, :3]
        if arm.planar:
            out[2, 3] = np.asarray(current, dtype=float)[2, 3]  # the plane its tool never leaves
    return out
