"""Gravity loads of the UR10 from UR's published link masses and centres of mass (docs/kinematics.md §8.5).

UR gives each link's mass and centre of mass in its *standard-DH* link frame, the
controller's convention (docs/kinematics.md §6). :func:`ur_standard_table` builds that chain
for a UR-family arm with the course's joint angles as input, so the masses sit where UR
puts them whatever convention the student's angles are in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .dh import DHRow, DHTable

#: Standard gravity (m/s²), acting along −z of the base frame.
GRAVITY = 9.81


@dataclass(frozen=True)
class LinkMasses:
    """Each link's mass and centre of mass, links 1…6 (docs/kinematics.md §8.5)."""

    masses: np.ndarray  #: (6,) kg
    centres: np.ndarray  #: (6, 3) m, in the link's standard-DH frame (UR's convention)
    source: str


#: UR's published parameters for the UR10 (CB3): also roboticstoolbox-python's ``UR10`` model.
UR10_MASSES = LinkMasses(
    masses=np.array([7.1, 12.7, 4.27, 2.0, 2.0, 0.365]),
    centres=np.array([[0.021, 0.0, 0.027], [0.38, 0.0, 0.158], [0.24, 0.0, 0.068],
                      [0.0, 0.007, 0.018], [0.0, 0.007, 0.018], [0.0, 0.0, -0.026]]),
    source="UR's published masses and centres of mass for the UR10",
)

#: Per preset. The course's arm has UR10 link lengths to within a millimetre: it carries the
#: UR10's masses (the course's own CAD masses come without centres of mass).
MASSES = {"ur10": UR10_MASSES, "course": UR10_MASSES}


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
    if not (isinstance(payload_kg, (int, float)) and math.isfinite(payload_kg) and 0.0 <= payload_kg <= 1000.0):
        raise ValueError(f"payload_kg must be a number of kilograms from 0 to 1000, got {payload_kg!r:.40}")
    masses = link_masses(arm)
    frames = ur_standard_table(arm).frames(q)  # (..., 7, 4, 4)
    centres = np.einsum("...jab,jb->...ja", frames[..., 1:, :3, :3], masses.centres) + frames[..., 1:, :3, 3]
    weights = GRAVITY * masses.masses
    # the payload: one more mass at the flange origin
    centres = np.concatenate([centres, frames[..., 6:, :3, 3]], axis=-2)
    weights = np.append(weights, GRAVITY * payload_kg)
    axes, origins = frames[..., :6, :3, 2], frames[..., :6, :3, 3]  # joint i turns about z_{i−1} through o_{i−1}
    tau = np.zeros(frames.shape[:-3] + (6,))
    for i in range(6):
        lever = centres[..., i:, :] - origins[..., i:i + 1, :]  # only the links beyond joint i move with it
        lift = np.cross(axes[..., i:i + 1, :], lever)[..., 2]  # ∂z_c/∂q_i
        tau[..., i] = (lift * weights[i:]).sum(axis=-1)
    return tau
