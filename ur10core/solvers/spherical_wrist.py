"""Pieper's decoupling for arms with a spherical wrist (docs/kinematics.md §7.3).

When the last three joint axes meet in one point, the wrist centre WC, the pose splits in
two: joints 1–3 place WC (``WC = p − R c``, with c the fixed offset from WC to the tool
in the tool frame), joints 4–6 then turn the tool to ``R3_6 = R0_3ᵀ R``.

* :class:`Wrist` reads the wrist's axes from the DH table and writes ``R3_6`` as a ZYZ
  Euler product; θ5 = 0 (axes 4 and 6 aligned) fixes only θ4 ± θ6, and θ4 is then the hint's.
* :class:`ArticulatedArm` (KR210, the elbow arm): θ1 towards WC or turned by π (shoulder
  front / back), the law of cosines in the arm's plane (elbow up / down), the wrist
  flipped or not: 8 slots, ``k = 4 shoulder + 2 elbow + wrist``. The plane geometry —
  shoulder, upper arm, forearm and their angles — is read from the table's own FK, so
  the same code serves both arms and any table of their shape.
* :class:`StanfordArm` (RRP + wrist): θ1 from the shoulder offset d2 (two choices), θ2
  and the stroke to WC (forward, or reversed: θ2 + π and the stroke negative), the wrist
  flipped or not: 8 slots, ``k = 4 reversed + 2 shoulder + wrist``. A reversed stroke is
  beyond a real arm's range (d3 ≥ 0), so those slots come flagged by ``within_limits``.
* :class:`CylindricalArm` (RPP + wrist): WC is the cylindrical arm's tool point, placed by its
  closed form (stroke forward, or θ1 + π and the stroke reversed), the wrist flipped or not:
  4 slots, ``k = 2 reversed + wrist``.

Where the compiled kernel is built, the articulated and Stanford arms solve in C (``wrist_ik``,
``_solve_one``'s steps, docs/kinematics.md §7.3); the numpy code here is the method and the fallback.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .. import ik as _ik
from .._backend import kernels
from .._validate import as_float_array, homogeneous_transform, poses_and_hints, refuse_pose
from ..branches import (
    INSIDE_OFFSET,
    TOO_CLOSE,
    TOO_FAR,
    IKSolution,
    empty_branches,
    mm_apart,
    wrap,
)
from ..dh import MODIFIED, STANDARD, DHTable
from ..orientation import zyz_euler
from ..tolerances import (
    CHOICE_TOLERANCE,
    LENGTH_TOLERANCE,
    LIMIT_TOLERANCE,
    SIDE_TOLERANCE,
    SQUARE_ROUNDING,
    STRETCHED_TOLERANCE,
    WRIST_TOLERANCE,
    WRIST_TURN_TOLERANCE,
)
from .planar import Cylindrical

_TAU = 2.0 * math.pi


def _wrap1(angle: float) -> float:
    """One angle in (−π, π], as :func:`ur10core.branches.wrap` (Python's % is numpy's remainder)."""
    return -((-angle + math.pi) % _TAU) + math.pi


def _rx(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    if abs(c) < 1e-15:
        c = 0.0
    if abs(s) < 1e-15:
        s = 0.0
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rz(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class Wrist:
    """The spherical wrist of ``table``: its last three joints (revolute, consecutive rows).

    ``R_pre`` is the orientation before the wrist's first row (a function of joints 1–3);
    ``R_preᵀ R = P Rz(θ4) Rx(β1) Rz(θ5) Rx(β2) Rz(θ6) Q`` with β1, β2 = ±π/2, and since
    ``Rx(β1) Rz(θ5) = Ry(−s θ5) Rx(β1)`` (s = sign β1) this is
    ``P Rz(θ4) Ry(−s θ5) Rz(±θ6) Rx(β1 + β2) Q``: a ZYZ Euler product between fixed rotations.
    """

    def __init__(self, table: DHTable) -> None:
        rows = table.rows
        if table.n_joints < 6 or table.joint_types[-3:] != "RRR":
            raise ValueError("a spherical wrist needs six joints, the last three revolute")
        j4, j5, j6 = table.joint_rows[-3:]
        if (j5, j6) != (j4 + 1, j4 + 2):
            raise ValueError("the wrist's three rows must follow each other")
        self.first_row = j4
        tool_rows = rows[j6 + 1:]
        if table.convention == MODIFIED:
            self.P = _rx(rows[j4].alpha)
            beta1, beta2 = rows[j5].alpha, rows[j6].alpha
            Q = np.eye(3)
            for row in tool_rows:
                Q = Q @ _rx(row.alpha) @ _rz(row.theta)
        else:
            self.P = np.eye(3)
            beta1, beta2 = rows[j4].alpha, rows[j5].alpha
            Q = _rx(rows[j6].alpha)
            for row in tool_rows:
                Q = Q @ _rz(row.theta) @ _rx(row.alpha)
        if not (abs(abs(beta1) - math.pi / 2) < 1e-12 and abs(abs(beta2) - math.pi / 2) < 1e-12):
            raise ValueError("a spherical wrist's consecutive axes must be perpendicular (twists of ±π/2)")
        self.s5 = -math.copysign(1.0, beta1)  # Ry(s5 θ5) in the ZYZ product
        self.s6 = 1.0 if abs(beta1 + beta2) < 1e-12 else -1.0
        self.post = _rx(beta1 + beta2) @ Q  # W = Pᵀ R_preᵀ R postᵀ = Rz(θ4) Ry(s5 θ5) Rz(s6 θ6)
        self.offsets = np.array([rows[j].theta for j in (j4, j5, j6)])
        self._offsets = self.offsets.tolist()

    def solve(self, R_pre: np.ndarray, R: np.ndarray, hint4: np.ndarray, flip: bool,
              arm_rounding: np.ndarray | float = 0.0):
        """θ4, θ5, θ6 and whether θ4 is fixed loosely or chosen (:func:`_loose`), for (N, 3, 3) rotations; ``flip``
        picks θ5 ≤ 0. ``arm_rounding`` (N,): how well joints 1–3 fix R_pre (rad)."""
        W = self.P.T @ np.swapaxes(R_pre, -1, -2) @ R @ self.post.T
        sin_b = np.hypot(W[:, 0, 2], W[:, 1, 2])
        sign_theta5 = (-1.0 if flip else 1.0) * self.s5  # b = s5 θ5: flipped (θ5 ≤ 0) takes b of sign −s5
        b = np.arctan2(sign_theta5 * sin_b, W[:, 2, 2])
        a = np.arctan2(sign_theta5 * W[:, 1, 2], sign_theta5 * W[:, 0, 2])
        row_hint = hint4 + self.offsets[0]
        # keep the hint's θ4 wherever turning θ4 (and θ6 against it) to it changes R by less than the tolerance
        turn = np.abs(wrap(a - row_hint))
        chosen = sin_b * turn <= WRIST_TURN_TOLERANCE
        a = np.where(chosen, row_hint, a)
        ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
        # c exactly from a and b: Rz(c) = Ry(b)ᵀ Rz(a)ᵀ W
        c = np.arctan2(-sa * W[:, 0, 0] + ca * W[:, 1, 0], cb * (ca * W[:, 0, 0] + sa * W[:, 1, 0]) - sb * W[:, 2, 0])
        theta4 = wrap(a - self.offsets[0])
        theta5 = wrap(b * self.s5 - self.offsets[1])
        theta6 = wrap(c * self.s6 - self.offsets[2])
        return theta4, theta5, theta6, _loose(sin_b, chosen & (turn > LIMIT_TOLERANCE), arm_rounding)

    def solve_one(self, R_pre: np.ndarray, R: np.ndarray, hint4: float,
                  arm_rounding: float = 0.0) -> list[tuple[float, float, float, bool]]:
        """:meth:`solve` for one (3, 3) pair, in floats: (θ4, θ5, θ6, loose) not flipped, then flipped."""
        W = (self.P.T @ R_pre.T @ R @ self.post.T).tolist()
        sin_b = math.hypot(W[0][2], W[1][2])
        row_hint = hint4 + self._offsets[0]
        out = []
        for flip in (False, True):
            sign = (-1.0 if flip else 1.0) * self.s5
            b = math.atan2(sign * sin_b, W[2][2])
            a = math.atan2(sign * W[1][2], sign * W[0][2])
            turn = abs(_wrap1(a - row_hint))
            chosen = sin_b * turn <= WRIST_TURN_TOLERANCE
            if chosen:
                a = row_hint
            ca, sa, cb, sb = math.cos(a), math.sin(a), math.cos(b), math.sin(b)
            c = math.atan2(-sa * W[0][0] + ca * W[1][0], cb * (ca * W[0][0] + sa * W[1][0]) - sb * W[2][0])
            out.append((_wrap1(a - self._offsets[0]), _wrap1(b * self.s5 - self._offsets[1]),
                        _wrap1(c * self.s6 - self._offsets[2]), bool(_loose(sin_b, chosen and turn > LIMIT_TOLERANCE, arm_rounding))))
        return out


def _loose(sin_b, chosen_afar, arm_rounding):
    """Whether θ4 is fixed loosely or not at all, from the sine of θ5 (Wrist.solve's b), whether the hint's θ4 was
    kept more than :data:`LIMIT_TOLERANCE` from the pose's own, and how well joints 1–3 are fixed (rad): the wrist
    singular (sin b to WRIST_TOLERANCE), θ4 fixed less well than LIMIT_TOLERANCE (it carries the rounding of W's
    entries, SQUARE_ROUNDING and the arm's, over sin b), or a value the pose leaves free chosen. A slot so flagged is
    searched and settled within the limits (docs/kinematics.md §7.3)."""
    return (sin_b <= WRIST_TOLERANCE) | (sin_b * LIMIT_TOLERANCE <= SQUARE_ROUNDING + arm_rounding) | chosen_afar


def _wrist_offset(table: DHTable, wrist: Wrist) -> np.ndarray:
    """c: the wrist centre in the tool frame, constant for a spherical wrist (checked at two poses)."""
    offsets = []
    for q in (np.zeros(table.n_joints), np.linspace(0.3, 1.9, table.n_joints)):
        frames = table.frames(q)
        centre = frames[wrist.first_row + 1, :3, 3]  # both conventions: the origin after the wrist's first row
        tool = frames[-1]
        offsets.append(tool[:3, :3].T @ (centre - tool[:3, 3]))
    if np.abs(offsets[0] - offsets[1]).max() > 1e-12:
        raise ValueError("the last three axes do not meet in one point: not a spherical wrist")
    return offsets[0]


def _pose_parts(centre_in_tool: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The tool's rotation (N, 3, 3) and the wrist centre WC = p + R c (N, 3)."""
    R = T[:, :3, :3]
    return R, T[:, :3, 3] + R @ centre_in_tool


def _wrist_slots(table: DHTable, wrist: Wrist, out: dict, R: np.ndarray, hint: np.ndarray | None,
                 arm_rounding: np.ndarray | None = None) -> None:
    """Joints 4–6 for every even slot whose joints 1–3 are set: the wrist not flipped there, flipped in the next.
    ``arm_rounding`` (N, slots): how well joints 1–3 are fixed there (rad), where it can matter.

    All arm slots of all poses go through the wrist at once (one FK of joints 1–3, one
    solve per flip): a single pose then costs a few dozen array operations, not a hundred.
    """
    q, valid, singular = out["q"], out["valid"], out["singular"]
    n = table.n_joints
    hint4 = np.zeros(len(R)) if hint is None else hint[:, n - 3]
    arm_valid = valid[:, 0::2]  # (N, arm slots)
    pose, arm_slot = np.nonzero(arm_valid)
    if not len(pose):
        return
    base = 2 * arm_slot
    full = np.zeros((len(pose), n))
    full[:, : n - 3] = q[pose, base, : n - 3]
    R_pre = table.frames(full)[:, wrist.first_row, :3, :3]
    rounding = 0.0 if arm_rounding is None else arm_rounding[pose, base]
    for flip in (False, True):
        t4, t5, t6, loose = wrist.solve(R_pre, R[pose], hint4[pose], flip, rounding)
        k = base + int(flip)
        q[pose, k, : n - 3] = full[:, : n - 3]
        q[pose, k, n - 3:] = np.stack([t4, t5, t6], axis=-1)
        valid[pose, k] = True
        singular[pose, k] = singular[pose, base] | loose


def _wrist_slots_one(table: DHTable, wrist: Wrist, out: dict, R: np.ndarray, hint: list[float] | None,
                     arm_rounding: list[float] | None = None) -> None:
    """:func:`_wrist_slots` for one pose (``out`` of batch 1, R (3, 3)): the wrist in floats, slot by slot."""
    q, valid, singular = out["q"][0], out["valid"][0], out["singular"][0]
    n = table.n_joints
    bases = [k for k in range(0, len(valid), 2) if valid[k]]
    if not bases:
        return
    hint4 = 0.0 if hint is None else hint[n - 3]
    full = np.zeros((len(bases), n))
    full[:, : n - 3] = q[bases, : n - 3]
    for base, R_pre in zip(bases, table.frames(full)[:, wrist.first_row, :3, :3]):
        rounding = 0.0 if arm_rounding is None else arm_rounding[base]
        for flip, (t4, t5, t6, loose) in enumerate(wrist.solve_one(R_pre, R, hint4, rounding)):
            q[base + flip, n - 3:] = (t4, t5, t6)
            q[base + flip, : n - 3] = q[base, : n - 3]
            valid[base + flip] = True
            singular[base + flip] = singular[base] or loose


#: The compiled kernel's solver of these arms (``None`` on the numpy backend: :meth:`Arm.ik` then runs the numpy code).
_WRIST_IK = getattr(kernels, "wrist_ik", None)
_ARTICULATED, _STANFORD = 0, 1  # the kernel's WRIST_ARTICULATED, WRIST_STANFORD


class _CompiledWristArm:
    """What the two solvers share: the compiled kernel's path (``_kernels.c``, ``wrist_ik``), one pose or many.

    The kernel follows ``_solve_one`` step for step; the geometry it needs is one float
    array (:meth:`compiled_geometry`), the layout of the kernel's ``WristArm``.
    """

    table: DHTable
    wrist: Wrist
    centre_in_tool: np.ndarray

    def _arm_numbers(self) -> tuple[int, list[float]]:
        raise NotImplementedError

    def compiled_geometry(self) -> np.ndarray:
        """[kind, standard, rows before the wrist, c (3), P (9), post (9), s5, s6, offsets (3), the arm's numbers (10),
        then (cos α, sin α, θ offset, revolute joint or −1) for each row before the wrist]."""
        kind, numbers = self._arm_numbers()
        table, wrist = self.table, self.wrist
        rows = []
        joint = 0
        for k, row in enumerate(table.rows[: wrist.first_row]):
            rows += [table._ca[k], table._sa[k], row.theta, joint if row.joint == "R" else -1]
            joint += row.joint is not None
        header = [kind, float(table.convention == STANDARD), wrist.first_row, *self.centre_in_tool, *wrist.P.ravel(),
                  *wrist.post.ravel(), wrist.s5, wrist.s6, *wrist.offsets, *numbers, *[0.0] * (10 - len(numbers))]
        return np.array(header + rows, dtype=float)

    def _compiled_ik(self, arm, T, hint=None) -> IKSolution:
        """:meth:`Arm.ik` on the compiled kernel: poses validated there, blocks of poses on the pool."""
        T = as_float_array(T, "T")
        if hint is not None:
            hint = arm.joints(hint, "hint")
        one = T.shape == (4, 4) and (hint is None or hint.shape == (6,))  # a drag's one pose: nothing to broadcast
        if not one and (T.ndim < 2 or T.shape[-2:] != (4, 4)):
            homogeneous_transform(T)  # raises: wrong shape
        batch = () if one else T.shape[:-2]
        if hint is not None and not one:
            batch = poses_and_hints(T, hint)
            hint = np.broadcast_to(hint, batch + (6,))
        flat = np.ascontiguousarray(T if one else np.broadcast_to(T, batch + (4, 4))).reshape(-1, 16)
        if hint is not None:
            hint = np.ascontiguousarray(hint).reshape(-1, 6)
        n = len(flat)
        q, detail = np.empty((n, 8, 6)), np.empty((n, 8))
        valid, singular, failure = np.empty((n, 8), bool), np.empty((n, 8), bool), np.empty((n, 8), np.int8)

        def run(start: int) -> int:
            block = slice(start, start + _ik.BLOCK)
            bad = _WRIST_IK(flat[block], None if hint is None else hint[block], self._geometry,
                            q[block], valid[block], singular[block], failure[block], detail[block])
            return -1 if bad < 0 else start + bad

        bad = _ik.in_blocks(n, run)
        if bad >= 0:
            refuse_pose(T, bad, batch)
        return IKSolution(q.reshape(batch + (8, 6)), valid.reshape(batch + (8,)), failure.reshape(batch + (8,)), arm,
                          detail=detail.reshape(batch + (8,)), singular=singular.reshape(batch + (8,)))

    def _use_the_kernel(self) -> None:
        """Solve on the compiled kernel where it is built (``ik`` is what :class:`Arm` calls); else numpy."""
        self._geometry = self.compiled_geometry()
        self.ik = self._compiled_ik if _WRIST_IK is not None else None


def _planar_frame(table: DHTable) -> dict[str, float]:
    """The articulated arm's plane at θ1 = 0, read from the table's FK (checked, not assumed).

    In plane coordinates (u along x, w = σ z), with σ chosen so that joint 2 turns
    counter-clockwise: the shoulder S, the upper arm ``a2 (cos(θ2 + o2), sin(θ2 + o2))``
    and the wrist centre ``Rot(θ2 + o2) (a2 + L cos(s3 θ3 + φ), L sin(s3 θ3 + φ))``.
    """
    q0 = np.zeros(table.n_joints)
    frames = table.frames(q0)
    axes, points = table.joint_axes(frames)
    axis1, axis2, axis3 = axes[:3]
    if np.abs(axis1 - (0, 0, 1)).max() > 1e-12 or np.hypot(*points[0, :2]) > 1e-12:
        raise ValueError("joint 1 must turn about the base z axis")
    if abs(axis2[2]) > 1e-12 or abs(axis2[0]) > 1e-12 or np.abs(np.cross(axis2, axis3)).max() > 1e-12:
        raise ValueError("joints 2 and 3 must be horizontal and parallel (along y at θ1 = 0)")
    sigma = 1.0 if axis2[1] < 0 else -1.0  # about −y, turning x towards z is counter-clockwise in (x, z)
    s3 = float(np.sign(axis3 @ axis2))
    wrist_row = table.joint_rows[3] + 1
    plane = lambda p: np.array([p[0], sigma * p[2]])  # noqa: E731
    S = plane(points[1])
    if abs(frames[wrist_row, 1, 3]) > 1e-12 or abs(points[1][1]) > 1e-12:
        raise ValueError("the wrist centre must stay in the plane of axis 1 (no lateral offset)")
    # the elbow: where axis 3 meets the plane
    E = plane(points[2])
    upper = E - S
    a2 = float(np.hypot(*upper))
    o2 = float(math.atan2(upper[1], upper[0]))
    W = plane(frames[wrist_row, :3, 3]) - S
    c, s = math.cos(-o2), math.sin(-o2)
    x, y = c * W[0] - s * W[1], s * W[0] + c * W[1]
    L = float(math.hypot(x - a2, y))
    phi = float(math.atan2(y, x - a2))
    return dict(u0=float(S[0]), w0=float(S[1]), sigma=sigma, a2=a2, o2=o2, L=L, phi=phi, s3=s3)


class ArticulatedArm(_CompiledWristArm):
    """RRR with a vertical axis 1, parallel axes 2 and 3, and a spherical wrist: 8 slots."""

    task = "pose"
    labels = tuple(
        f"shoulder {shoulder}, elbow {elbow}, wrist {wrist}"
        for shoulder in ("front", "back") for elbow in ("up", "down") for wrist in ("not flipped", "flipped")
    )

    def __init__(self, table: DHTable) -> None:
        if table.joint_types != "RRRRRR":
            raise ValueError("an articulated arm has six revolute joints")
        self.table = table
        self.wrist = Wrist(table)
        self.centre_in_tool = _wrist_offset(table, self.wrist)
        self.plane = _planar_frame(table)
        p = self.plane
        self.reach = (abs(p["a2"] - p["L"]), p["a2"] + p["L"])
        self._use_the_kernel()

    def _arm_numbers(self) -> tuple[int, list[float]]:
        p = self.plane
        return _ARTICULATED, [p[key] for key in ("u0", "w0", "sigma", "a2", "o2", "L", "phi", "s3")] + list(self.reach)

    def explain(self, failure: int, detail: float) -> str:
        near, far = self.reach
        if failure == TOO_FAR:
            at, bound, off = mm_apart(detail, far)
            return (f"the wrist centre is {at} mm from the shoulder joint; upper arm and forearm "
                    f"reach at most {bound} mm ({off} mm short)")
        if failure == TOO_CLOSE:
            at, bound, off = mm_apart(detail, near)
            return (f"the wrist centre is {at} mm from the shoulder joint; folded, the arm "
                    f"cannot come closer than {bound} mm ({off} mm too close)")
        return "no branch reaches this pose"

    def solve(self, T: np.ndarray, hint: np.ndarray | None) -> dict[str, np.ndarray]:
        if len(T) == 1:
            return self._solve_one(T[0], None if hint is None else hint[0].tolist())
        N = len(T)
        out = empty_branches((N,), 8, 6)
        q, valid, singular = out["q"], out["valid"], out["singular"]
        p = self.plane
        R, centre = _pose_parts(self.centre_in_tool, T)
        rho = np.hypot(centre[:, 0], centre[:, 1])
        hint = np.zeros((N, 6)) if hint is None else hint
        towards = np.arctan2(centre[:, 1], centre[:, 0])
        hint_beta = wrap(p["s3"] * (hint[:, 2]) + p["phi"])
        hint_reach = np.sqrt(p["a2"] ** 2 + p["L"] ** 2 + 2 * p["a2"] * p["L"] * np.cos(hint_beta))
        near, far = self.reach
        for shoulder in (0, 1):
            theta1 = wrap(towards + shoulder * math.pi)
            # near axis 1, θ1 barely moves WC: the hint's θ1 wherever it moves WC by at most the tolerance
            chosen1 = rho * np.abs(wrap(theta1 - hint[:, 0])) <= CHOICE_TOLERANCE
            theta1 = np.where(chosen1, hint[:, 0], theta1)
            u = np.cos(theta1) * centre[:, 0] + np.sin(theta1) * centre[:, 1] - p["u0"]
            w = p["sigma"] * centre[:, 2] - p["w0"]
            r = np.hypot(u, w)
            cos_beta = (r * r - p["a2"] ** 2 - p["L"] ** 2) / (2 * p["a2"] * p["L"])
            too_far, too_close = r > far + LENGTH_TOLERANCE, r < near - LENGTH_TOLERANCE
            ok = ~(too_far | too_close)
            for elbow in (0, 1):
                slot = 4 * shoulder + 2 * elbow
                out["failure"][:, slot:slot + 2] = np.where(too_far, TOO_FAR, np.where(too_close, TOO_CLOSE, 0))[:, None]
                out["detail"][:, slot:slot + 2] = r[:, None]
                # elbow up: the elbow above the shoulder–wrist-centre line (sin β of sign −σ reaching forward)
                sign = -p["sigma"] * (1.0 if (elbow == 0) == (shoulder == 0) else -1.0)
                beta = sign * np.arccos(np.clip(cos_beta, -1.0, 1.0))
                # stretched or folded, β is fixed only to √rounding: the hint's wherever it reaches within the tolerance
                same_side = (sign * np.sin(hint_beta) >= 0) | (np.abs(np.sin(hint_beta)) <= SIDE_TOLERANCE)
                chosen3 = same_side & (np.abs(hint_reach - r) <= CHOICE_TOLERANCE)
                beta = np.where(chosen3, hint_beta, beta)
                x = p["a2"] + p["L"] * np.cos(beta)
                y = p["L"] * np.sin(beta)
                theta2 = np.arctan2(w, u) - np.arctan2(y, x) - p["o2"]
                theta3 = (beta - p["phi"]) * p["s3"]
                q[ok, slot, :3] = np.stack([theta1, wrap(theta2), wrap(theta3)], axis=-1)[ok]
                valid[ok, slot] = True
                # singular where the pose leaves a value free: WC on axis 1, the elbow stretched or folded
                singular[ok, slot] = ((rho <= LENGTH_TOLERANCE) | (np.abs(np.sin(beta)) <= STRETCHED_TOLERANCE))[ok]
        _wrist_slots(self.table, self.wrist, out, R, hint)
        return out

    def _solve_one(self, T: np.ndarray, hint: list[float] | None) -> dict[str, np.ndarray]:
        """:meth:`solve` for one pose in floats: a drag's IK without a hundred small array operations.

        Step for step the same decisions (tests/test_serial_arms.py holds the two to each other).
        """
        out = empty_branches((1,), 8, 6)
        q, valid, singular, failure, detail = (out[key][0] for key in ("q", "valid", "singular", "failure", "detail"))
        p = self.plane
        a2, L = p["a2"], p["L"]
        R = T[:3, :3]
        cx, cy, cz = (T[:3, 3] + R @ self.centre_in_tool).tolist()
        rho = math.hypot(cx, cy)
        h = hint or [0.0] * 6
        towards = math.atan2(cy, cx)
        hint_beta = _wrap1(p["s3"] * h[2] + p["phi"])
        hint_reach = math.sqrt(a2 ** 2 + L ** 2 + 2 * a2 * L * math.cos(hint_beta))
        near, far = self.reach
        for shoulder in (0, 1):
            theta1 = _wrap1(towards + shoulder * math.pi)
            if rho * abs(_wrap1(theta1 - h[0])) <= CHOICE_TOLERANCE:
                theta1 = h[0]
            u = math.cos(theta1) * cx + math.sin(theta1) * cy - p["u0"]
            w = p["sigma"] * cz - p["w0"]
            r = math.hypot(u, w)
            cos_beta = (r * r - a2 ** 2 - L ** 2) / (2 * a2 * L)
            too_far, too_close = r > far + LENGTH_TOLERANCE, r < near - LENGTH_TOLERANCE
            for elbow in (0, 1):
                slot = 4 * shoulder + 2 * elbow
                failure[slot:slot + 2] = TOO_FAR if too_far else TOO_CLOSE if too_close else 0
                detail[slot:slot + 2] = r
                if too_far or too_close:
                    continue
                sign = -p["sigma"] * (1.0 if (elbow == 0) == (shoulder == 0) else -1.0)
                beta = sign * math.acos(min(max(cos_beta, -1.0), 1.0))
                same_side = sign * math.sin(hint_beta) >= 0 or abs(math.sin(hint_beta)) <= SIDE_TOLERANCE
                if same_side and abs(hint_reach - r) <= CHOICE_TOLERANCE:
                    beta = hint_beta
                x, y = a2 + L * math.cos(beta), L * math.sin(beta)
                theta2 = math.atan2(w, u) - math.atan2(y, x) - p["o2"]
                q[slot, :3] = (theta1, _wrap1(theta2), _wrap1((beta - p["phi"]) * p["s3"]))
                valid[slot] = True
                singular[slot] = rho <= LENGTH_TOLERANCE or abs(math.sin(beta)) <= STRETCHED_TOLERANCE
        _wrist_slots_one(self.table, self.wrist, out, R, hint)
        return out


def _arm_rounding(rho, u, stroke):
    """How well the Stanford arm's θ1 and θ2 are fixed together (rad), from the wrist centre's distance ρ from axis 1,
    its reach u along the arm and the stroke (floats or arrays, u and the stroke not 0): u, from u² = ρ² − d2², is
    known to about SQUARE_ROUNDING ρ²/|u|, θ1 to that over ρ and θ2 to that over the stroke. The wrist's W carries it."""
    return SQUARE_ROUNDING * rho * (rho + stroke) / (abs(u) * stroke)


class StanfordArm(_CompiledWristArm):
    """RRP + spherical wrist (standard DH as in docs/kinematics.md §7.5): 8 slots, the last four with the stroke reversed."""

    task = "pose"
    labels = tuple(f"shoulder {shoulder}, wrist {wrist}{stroke}" for stroke in ("", ", stroke reversed")
                   for shoulder in ("right", "left") for wrist in ("not flipped", "flipped"))

    def __init__(self, table: DHTable) -> None:
        if table.joint_types != "RRPRRR" or table.convention != STANDARD:
            raise ValueError("the Stanford solver takes the standard table of an RRP arm with a spherical wrist")
        self.table = table
        self.wrist = Wrist(table)
        self.centre_in_tool = _wrist_offset(table, self.wrist)
        self.d1 = table.rows[0].d
        self.d2 = table.rows[1].d
        self.stroke_offset = table.rows[2].d
        self._use_the_kernel()

    def _arm_numbers(self) -> tuple[int, list[float]]:
        return _STANFORD, [self.d1, self.d2, self.stroke_offset]

    def explain(self, failure: int, detail: float) -> str:
        if failure == INSIDE_OFFSET:
            at, bound, _ = mm_apart(detail, self.d2)
            return (f"the wrist centre is {at} mm from the base axis, inside the shoulder offset "
                    f"d2 = {bound} mm: no θ1 lines the arm up with it")
        return "no branch reaches this pose"

    def solve(self, T: np.ndarray, hint: np.ndarray | None) -> dict[str, np.ndarray]:
        if len(T) == 1:
            return self._solve_one(T[0], None if hint is None else hint[0].tolist())
        N = len(T)
        out = empty_branches((N,), 8, 6)
        q, valid, singular = out["q"], out["valid"], out["singular"]
        R, centre = _pose_parts(self.centre_in_tool, T)
        x, y, z = centre[:, 0], centre[:, 1], centre[:, 2] - self.d1
        rho = np.hypot(x, y)
        d2 = self.d2
        inside = rho < abs(d2) - LENGTH_TOLERANCE
        reach = np.sqrt(np.clip(rho * rho - d2 * d2, 0.0, None))
        hint = np.zeros((N, 6)) if hint is None else hint
        c1h, s1h = np.cos(hint[:, 0]), np.sin(hint[:, 0])
        hint_u = c1h * x + s1h * y
        # θ1 is fixed only to √rounding where WC is on the d2 cylinder: the hint's wherever it puts
        # WC within the tolerance of the offset (−s1 x + c1 y = d2)
        hint_fits = np.abs(-s1h * x + c1h * y - d2) <= CHOICE_TOLERANCE
        out["failure"][:] = np.where(inside, INSIDE_OFFSET, 0)[:, None]
        out["detail"][:] = rho[:, None]
        ok = ~inside
        arm_rounding = np.zeros((N, 8))
        for shoulder in (0, 1):
            sign = 1.0 if shoulder == 0 else -1.0
            # −s1 x + c1 y = d2 and c1 x + s1 y = ±reach
            theta1 = np.arctan2(y, x) - np.arctan2(d2, sign * reach)
            chosen1 = hint_fits & ((sign * hint_u >= 0) | (np.abs(hint_u) <= SIDE_TOLERANCE))
            theta1 = np.where(chosen1, hint[:, 0], theta1)
            u = np.cos(theta1) * x + np.sin(theta1) * y  # = s2 d3
            stroke = np.hypot(u, z)
            # WC on the shoulder, to the tolerance: there, with the stroke 0, θ2 is free
            stroke = np.where(stroke <= LENGTH_TOLERANCE, 0.0, stroke)
            # θ2 fixed only to the rounding of u over the stroke (SQUARE_ROUNDING), no better than LIMIT_TOLERANCE
            loose2 = np.abs(u) * stroke * LIMIT_TOLERANCE <= SQUARE_ROUNDING * rho * rho
            with np.errstate(divide="ignore", invalid="ignore"):  # (where u or the stroke is 0 the slot is singular)
                rounding = np.where((u != 0.0) & (stroke != 0.0), _arm_rounding(rho, u, stroke), np.inf)
            for reversed_ in (0, 1):  # (s2, c2) d3 = (u, z): θ2 and the stroke, or θ2 + π and minus the stroke
                slot = 4 * reversed_ + 2 * shoulder
                theta2 = np.arctan2(u, z) + math.pi * reversed_
                # near d3 = 0, θ2 barely moves WC: the hint's wherever it moves WC by at most the tolerance
                chosen2 = stroke * np.abs(wrap(theta2 - hint[:, 1])) <= CHOICE_TOLERANCE
                theta2 = np.where(chosen2, hint[:, 1], theta2)
                d3 = (-stroke if reversed_ else stroke) - self.stroke_offset
                q[ok, slot, :3] = np.stack([wrap(theta1), wrap(theta2), d3], axis=-1)[ok]
                valid[ok, slot] = True
                # singular where the pose fixes a value loosely or not at all: WC on the d2 cylinder, θ2 (loose2)
                singular[ok, slot] = ((np.abs(u) <= LENGTH_TOLERANCE) | loose2)[ok]
                arm_rounding[:, slot] = rounding
        _wrist_slots(self.table, self.wrist, out, R, hint, arm_rounding)
        return out

    def _solve_one(self, T: np.ndarray, hint: list[float] | None) -> dict[str, np.ndarray]:
        """:meth:`solve` for one pose in floats, step for step the same decisions."""
        out = empty_branches((1,), 8, 6)
        q, valid, singular, failure, detail = (out[key][0] for key in ("q", "valid", "singular", "failure", "detail"))
        R = T[:3, :3]
        x, y, z = (T[:3, 3] + R @ self.centre_in_tool).tolist()
        z -= self.d1
        rho = math.hypot(x, y)
        d2 = self.d2
        inside = rho < abs(d2) - LENGTH_TOLERANCE
        reach = math.sqrt(max(rho * rho - d2 * d2, 0.0))
        h = hint or [0.0] * 6
        c1h, s1h = math.cos(h[0]), math.sin(h[0])
        hint_u = c1h * x + s1h * y
        hint_fits = abs(-s1h * x + c1h * y - d2) <= CHOICE_TOLERANCE
        failure[:] = INSIDE_OFFSET if inside else 0
        detail[:] = rho
        arm_rounding = [0.0] * 8
        for shoulder in () if inside else (0, 1):
            sign = 1.0 if shoulder == 0 else -1.0
            theta1 = math.atan2(y, x) - math.atan2(d2, sign * reach)
            if hint_fits and (sign * hint_u >= 0 or abs(hint_u) <= SIDE_TOLERANCE):
                theta1 = h[0]
            u = math.cos(theta1) * x + math.sin(theta1) * y
            stroke = math.hypot(u, z)
            if stroke <= LENGTH_TOLERANCE:
                stroke = 0.0
            loose2 = abs(u) * stroke * LIMIT_TOLERANCE <= SQUARE_ROUNDING * rho * rho
            rounding = _arm_rounding(rho, u, stroke) if u and stroke else math.inf
            for reversed_ in (0, 1):
                slot = 4 * reversed_ + 2 * shoulder
                theta2 = math.atan2(u, z) + math.pi * reversed_
                if stroke * abs(_wrap1(theta2 - h[1])) <= CHOICE_TOLERANCE:
                    theta2 = h[1]
                q[slot, :3] = (_wrap1(theta1), _wrap1(theta2), (-stroke if reversed_ else stroke) - self.stroke_offset)
                valid[slot] = True
                singular[slot] = abs(u) <= LENGTH_TOLERANCE or loose2
                arm_rounding[slot] = rounding
        _wrist_slots_one(self.table, self.wrist, out, R, hint, arm_rounding)
        return out


class CylindricalArm:
    """RPP + spherical wrist (standard DH: the cylindrical arm's rows, then the wrist's): 4 slots,
    ``k = 2 reversed + wrist``; the last two with θ1 turned by π and the stroke negative, beyond a real
    arm's range (flagged by ``within_limits``).

    The wrist centre WC = (x, y, z) is the cylindrical arm's tool point, so joints 1–3 are
    its closed form (:class:`ur10core.solvers.planar.Cylindrical`): x = −s1 d3, y = c1 d3,
    z = d1 + d2; joints 4–6 then turn the tool to ``R3_6 = R0_3ᵀ R``.

    Example: the arm's home pose, and the three other branches that reach its tool pose.

    >>> from ur10core import Arm
    >>> arm = Arm.preset("cylindrical_wrist")
    >>> q = np.array([math.radians(30), 0.35, 0.35, *np.radians([20, 40, 10])])
    >>> sol = arm.ik(arm.fk(q))
    >>> np.degrees(sol.q[:, 0]).round(6).tolist()   # θ1: turned by π where the stroke is reversed
    [30.0, 30.0, -150.0, -150.0]
    >>> np.degrees(sol.q[:2, 3:]).round(6).tolist()   # θ4, θ5, θ6: the wrist not flipped, and flipped
    [[20.0, 40.0, 10.0], [-160.0, -40.0, -170.0]]
    >>> (1000 * sol.q[:, 2]).round(6).tolist(), sol.within_limits.tolist()   # d3: reversed, beyond its range
    ([350.0, 350.0, -350.0, -350.0], [True, True, False, False])
    """

    task = "pose"
    labels = tuple(f"stroke {stroke}, wrist {wrist}" for stroke in ("forward", "reversed")
                   for wrist in ("not flipped", "flipped"))

    def __init__(self, table: DHTable) -> None:
        if table.joint_types != "RPPRRR" or table.convention != STANDARD:
            raise ValueError("the cylindrical solver with a wrist takes the standard table of an RPP arm with a "
                             "spherical wrist")
        self.table = table
        self.column = Cylindrical(DHTable(table.rows[:3], STANDARD))  # checks the first three rows
        self.wrist = Wrist(table)
        self.centre_in_tool = _wrist_offset(table, self.wrist)

    def explain(self, failure: int, detail: float) -> str:
        return "no branch reaches this pose"

    def _wrist_centre_poses(self, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The tool's rotations and a pose (N, 4, 4) at each wrist centre, for the cylindrical arm's solver."""
        R, centre = _pose_parts(self.centre_in_tool, T)
        at_centre = np.broadcast_to(np.eye(4), T.shape).copy()
        at_centre[:, :3, 3] = centre
        return R, at_centre

    def solve(self, T: np.ndarray, hint: np.ndarray | None) -> dict[str, np.ndarray]:
        N = len(T)
        R, at_centre = self._wrist_centre_poses(T)
        column = self.column.solve(at_centre, None if hint is None else hint[:, :3])
        out = empty_branches((N,), 4, 6)
        for key in ("valid", "singular", "failure", "detail"):
            out[key][:, 0::2] = column[key]
        out["q"][:, 0::2, :3] = column["q"]
        if N == 1:
            _wrist_slots_one(self.table, self.wrist, out, R[0], None if hint is None else hint[0].tolist())
        else:
            _wrist_slots(self.table, self.wrist, out, R, hint)
        return out


class WristSplit(NamedTuple):
    """A pose split at the wrist centre (:func:`wrist_split`)."""

    centre: np.ndarray  #: (3,) WC in the base frame (m)
    centre_in_tool: np.ndarray  #: (3,) c, WC in the tool frame: WC = p + R c
    R0_3: np.ndarray  #: (3, 3) the frame before the wrist's first row, set by joints 1–3
    R3_6: np.ndarray  #: (3, 3) R0_3ᵀ R: what the wrist turns
    twist: float  #: α of the wrist's first row where the table puts it before the wrist (modified DH), else 0
    signs: tuple[float, float]  #: (s5, s6): ``Rx(−twist) R3_6 = Rz(θ4) Ry(s5 θ5) Rz(s6 θ6)`` (offsets 0)
    euler: np.ndarray  #: (3,) Z-Y-Z (φ, θ, ψ) of ``Rx(−twist) R3_6``
    euler_flipped: np.ndarray  #: (3,) the other Z-Y-Z solution (φ + π, −θ, ψ + π): the other wrist choice
    wrist: np.ndarray  #: (2, 3) θ4, θ5, θ6 read back from ``euler`` and from ``euler_flipped``: the arm's are one


def spherical_wrist(arm) -> tuple[Wrist, np.ndarray]:
    """The arm's spherical wrist and c, WC in the tool frame: its solver's, or read from its DH table (a typed
    table's); ``ValueError`` saying why where the last three axes are not a spherical wrist.

    >>> from ur10core import Arm
    >>> spherical_wrist(Arm.preset("ur10"))   # its d5 = 115.7 mm
    Traceback (most recent call last):
    ...
    ValueError: no spherical wrist: the last three axes do not meet in one point (at the zero pose, axes 4 and 6 pass 116 mm apart)
    >>> spherical_wrist(Arm.from_dh([(0.5, 0.0, 0.0, 0.0)], joint_types="R"))
    Traceback (most recent call last):
    ...
    ValueError: no spherical wrist: this arm has 1 joint, and a spherical wrist is three more after the three that place it
    """
    if hasattr(arm.solver, "wrist"):
        return arm.solver.wrist, arm.solver.centre_in_tool
    if arm.n_joints < 6 or arm.dh is None:
        joints = f"{arm.n_joints} joint{'s' * (arm.n_joints != 1)}"
        raise ValueError(f"no spherical wrist: this arm has {joints}, and a spherical wrist is three more after the "
                         "three that place it")
    try:
        wrist = Wrist(arm.dh)
        return wrist, _wrist_offset(arm.dh, wrist)
    except ValueError as why:
        reason = str(why).removesuffix(": not a spherical wrist")
    if reason.startswith("the last three axes do not meet"):  # how far apart, at the table's zero
        z, o = arm.dh.joint_axes(arm.dh.frames(np.zeros(arm.n_joints)))
        normal, between = np.cross(z[-3], z[-1]), o[-1] - o[-3]
        skew = np.linalg.norm(normal) > 1e-9
        gap = abs(between @ normal) / np.linalg.norm(normal) if skew else np.linalg.norm(np.cross(between, z[-3]))
        reason += f" (at the zero pose, axes {arm.n_joints - 2} and {arm.n_joints} pass {1000 * gap:.0f} mm apart)"
    raise ValueError(f"no spherical wrist: {reason}")


def wrist_split(arm, q, frames: np.ndarray | None = None) -> WristSplit:
    """Kinematic decoupling at joints ``q`` (n,) (docs/kinematics.md §7.3): where the last three axes meet, WC,
    the first three joints place; the wrist's three turn the rest, ``R3_6 = R0_3ᵀ R``, which is a Z-Y-Z
    Euler product of θ4, θ5, θ6 (between the fixed turns of the table's wrist rows, for the KR210 one before).
    ``frames``: ``arm.frames(q)``, where the caller has them already.

    ``ValueError`` for an arm without a spherical wrist (:func:`spherical_wrist`; the UR family's last three axes
    do not meet). A typed table with one is split as a preset is.

    Example: the elbow arm's wrist joints are the Z-Y-Z Euler angles of R3_6, as the lecture notes show.

    >>> from ur10core import Arm
    >>> split = wrist_split(Arm.preset("elbow"), np.radians([20, 40, 60, 30, 50, -10]))
    >>> np.degrees(split.euler).round(6).tolist(), np.degrees(split.euler_flipped).round(6).tolist()
    ([30.0, 50.0, -10.0], [-150.0, -50.0, 170.0])
    >>> (1000 * split.centre_in_tool).round(6).tolist()   # WC = p − 100 mm · z, d6 back along the tool's z
    [0.0, 0.0, -100.0]
    """
    wrist, centre_in_tool = spherical_wrist(arm)
    q = arm.joints(q)
    if q.shape != (arm.n_joints,):
        raise ValueError(f"q must be one pose of {arm.n_joints} joints, got shape {q.shape}")
    frames = arm.frames(q) if frames is None else frames
    R0_3, T = frames[wrist.first_row, :3, :3], frames[-1]
    R3_6 = R0_3.T @ T[:3, :3]
    W = wrist.P.T @ R3_6 @ wrist.post.T
    euler, flipped = zyz_euler(W, check=False), zyz_euler(W, check=False, flip=True)
    joints = wrap(np.stack([euler, flipped]) * [1.0, wrist.s5, wrist.s6] - wrist.offsets)
    return WristSplit(T[:3, 3] + T[:3, :3] @ centre_in_tool, centre_in_tool.copy(), R0_3, R3_6,
                      float(math.atan2(wrist.P[2, 1], wrist.P[1, 1])), (wrist.s5, wrist.s6), euler, flipped, joints)
