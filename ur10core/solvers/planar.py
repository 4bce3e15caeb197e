"""Closed-form IK of the lecture notes' small arms (docs/kinematics.md §7.3).

Each of these arms has fewer than six joints, so it reaches only part of a pose; ``task``
says which part, and FK(IK(T)) matches T there:

* :class:`PlanarElbow` (2R, standard DH, moving in the plane z = 0): the position in the
  plane, elbow down (θ2 ≥ 0) or up: 2 slots.
* :class:`Scara` (RRP + roll, standard DH with α2 = π): the position and the yaw about the
  vertical; its tool always points straight down. 2 slots (elbow left / right).
* :class:`Cylindrical` (RPP): the position; two slots, the stroke d3 the radius (slot 0) or
  θ1 turned by π and the stroke negative (slot 1, beyond a real arm's range: flagged by
  ``within_limits``).
"""

from __future__ import annotations

import math

import numpy as np

from ..branches import ORIENTATION, OUT_OF_PLANE, TOO_CLOSE, TOO_FAR, empty_branches, mm_apart, wrap
from ..dh import DHTable
from ..tolerances import CHOICE_TOLERANCE, LENGTH_TOLERANCE


def _two_link(x: np.ndarray, y: np.ndarray, a1: float, a2: float, down: bool):
    """θ1, θ2 of a planar 2R arm reaching (x, y), clipped at the boundary; and where it is out of reach."""
    r = np.hypot(x, y)
    too_far, too_close = r > a1 + a2 + LENGTH_TOLERANCE, r < abs(a1 - a2) - LENGTH_TOLERANCE
    span = np.clip(r, abs(a1 - a2), a1 + a2)  # c2 = ±1 beyond either limit, and r² of a far target does not overflow
    c2 = np.clip((span * span - a1 * a1 - a2 * a2) / (2 * a1 * a2), -1.0, 1.0)
    theta2 = np.arccos(c2) * (1.0 if down else -1.0)
    theta1 = np.arctan2(y, x) - np.arctan2(a2 * np.sin(theta2), a1 + a2 * np.cos(theta2))
    return wrap(theta1), theta2, too_far, too_close, r


def _reach_words(failure: int, detail: float, a1: float, a2: float, what: str,
                 origin: str = "the first joint's axis") -> str:
    """Why a two-link arm of ``a1`` then ``a2`` does not reach ``what``, ``detail`` m from ``origin`` ("" if it does)."""
    if failure == TOO_FAR:
        at, bound, off = mm_apart(detail, a1 + a2)
        return f"{what} is {at} mm from {origin}; the two links reach at most {bound} mm ({off} mm short)"
    if failure == TOO_CLOSE:
        at, bound, off = mm_apart(detail, abs(a1 - a2))
        return (f"{what} is {at} mm from {origin}; folded, the two links come no closer than {bound} mm "
                f"({off} mm too close)")
    return ""


class PlanarElbow:
    """The two-link planar elbow (standard DH rows (a1, 0, 0, θ1), (a2, 0, 0, θ2))."""

    task = "position"
    labels = ("elbow down (θ2 ≥ 0)", "elbow up (θ2 ≤ 0)")

    def __init__(self, table: DHTable) -> None:
        rows = table.rows
        if table.joint_types != "RR" or any(row.alpha or row.d or row.theta for row in rows):
            raise ValueError("the planar elbow solver takes two revolute rows (a_i, 0, 0, θ_i), standard DH")
        self.a1, self.a2 = rows[0].a, rows[1].a

    def explain(self, failure: int, detail: float) -> str:
        if failure == OUT_OF_PLANE:
            return f"the target is {1000 * detail:.1f} mm off the plane z = 0 the arm moves in"
        return _reach_words(failure, detail, self.a1, self.a2, "the target") or "no branch reaches this pose"

    def solve(self, T: np.ndarray, hint: np.ndarray | None) -> dict[str, np.ndarray]:
        out = empty_branches((len(T),), 2, 2)
        x, y, z = T[:, 0, 3], T[:, 1, 3], T[:, 2, 3]
        off_plane = np.abs(z) > LENGTH_TOLERANCE
        for slot in (0, 1):
            theta1, theta2, too_far, too_close, r = _two_link(x, y, self.a1, self.a2, slot == 0)
            ok = ~(too_far | too_close | off_plane)
            out["q"][ok, slot] = np.stack([theta1, theta2], axis=-1)[ok]
            out["valid"][:, slot] = ok
            out["singular"][:, slot] = ok & (np.abs(np.sin(theta2)) <= 1e-12)
            out["failure"][:, slot] = np.where(off_plane, OUT_OF_PLANE, np.where(too_far, TOO_FAR, np.where(too_close, TOO_CLOSE, 0)))
            out["detail"][:, slot] = np.where(off_plane, np.abs(z), r)
        return out


class Scara:
    """RRP + roll: rows (a1, 0, d1, θ1), (a2, π, 0, θ2), (0, 0, d3, 0) prismatic, (0, 0, d4, θ4)."""

    task = "position and yaw"
    labels = ("elbow right (θ2 ≥ 0)", "elbow left (θ2 ≤ 0)")

    def __init__(self, table: DHTable) -> None:
        rows = table.rows
        if table.joint_types != "RRPR" or abs(rows[1].alpha - math.pi) > 1e-12:
            raise ValueError("the SCARA solver takes an RRPR standard table with α2 = π")
        self.a1, self.a2 = rows[0].a, rows[1].a
        self.height = rows[0].d  # the tool's z is d1 − d3 − d4 (+ the stroke's offset)
        self.drop = rows[2].d + rows[3].d

    def explain(self, failure: int, detail: float) -> str:
        if failure == ORIENTATION:
            return (f"a SCARA's tool always points straight down; this pose's tool axis is "
                    f"{math.degrees(detail):.2f}° from it")
        return _reach_words(failure, detail, self.a1, self.a2, "the target") or "no branch reaches this pose"

    def solve(self, T: np.ndarray, hint: np.ndarray | None) -> dict[str, np.ndarray]:
        out = empty_branches((len(T),), 2, 4)
        x, y, z = T[:, 0, 3], T[:, 1, 3], T[:, 2, 3]
        tilt = np.arctan2(np.hypot(T[:, 0, 2], T[:, 1, 2]), -T[:, 2, 2])  # from straight down
        tilted = tilt > LENGTH_TOLERANCE  # radians: moves a 1 m tool by at most this many metres
        yaw = np.arctan2(T[:, 1, 0], T[:, 0, 0])  # R = Rz(θ1 + θ2 − θ4) Rx(π)
        for slot in (0, 1):
            theta1, theta2, too_far, too_close, r = _two_link(x, y, self.a1, self.a2, slot == 0)
            ok = ~(too_far | too_close | tilted)
            stroke = self.height - z - self.drop
            theta4 = wrap(theta1 + theta2 - yaw)
            out["q"][ok, slot] = np.stack([theta1, theta2, stroke, theta4], axis=-1)[ok]
            out["valid"][:, slot] = ok
            out["singular"][:, slot] = ok & (np.abs(np.sin(theta2)) <= 1e-12)
            out["failure"][:, slot] = np.where(tilted, ORIENTATION, np.where(too_far, TOO_FAR, np.where(too_close, TOO_CLOSE, 0)))
            out["detail"][:, slot] = np.where(tilted, tilt, r)
        return out


class Cylindrical:
    """RPP: rows (0, 0, d1, θ1), (0, −π/2, d2, 0) prismatic, (0, 0, d3, 0) prismatic."""

    task = "position"
    labels = ("stroke forward", "stroke reversed")

    def __init__(self, table: DHTable) -> None:
        rows = table.rows
        if table.joint_types != "RPP" or abs(rows[1].alpha + math.pi / 2) > 1e-12 or rows[1].theta or rows[2].theta:
            raise ValueError("the cylindrical solver takes the RPP standard table (0, 0, d1, θ1), (0, −π/2, d2, 0), (0, 0, d3, 0)")
        self.base = rows[0].d
        self.lift_offset = rows[1].d
        self.stroke_offset = rows[2].d

    def explain(self, failure: int, detail: float) -> str:
        return "no branch reaches this pose"

    def solve(self, T: np.ndarray, hint: np.ndarray | None) -> dict[str, np.ndarray]:
        out = empty_branches((len(T),), 2, 3)
        x, y, z = T[:, 0, 3], T[:, 1, 3], T[:, 2, 3]
        rho = np.hypot(x, y)  # x = −s1 d3, y = c1 d3
        hint1 = np.zeros(len(T)) if hint is None else hint[:, 0]
        for slot, stroke in ((0, rho), (1, -rho)):
            theta1 = np.arctan2(-x, y) + math.pi * slot
            # near the column θ1 barely moves the tool: the hint's wherever it moves it by at most the tolerance
            theta1 = np.where(rho * np.abs(wrap(theta1 - hint1)) <= CHOICE_TOLERANCE, hint1, theta1)
            out["q"][:, slot] = np.stack([wrap(theta1), z - self.base - self.lift_offset, stroke - self.stroke_offset], axis=-1)
            out["valid"][:, slot] = True
            out["singular"][:, slot] = rho <= LENGTH_TOLERANCE
        return out
