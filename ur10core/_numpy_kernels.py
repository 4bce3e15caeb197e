"""The numpy backend: every function of the compiled kernel ``_kernels.c``, in numpy.

Same names, arguments and results, so the rest of the core does not care which one
runs (``ur10core.BACKEND``). One pose goes through plain Python (numpy's per-call
overhead would dominate); many poses through the vectorised steps of
:mod:`ur10core.ik_reference`, one array element per (pose, θ1, wrist sign).
"""

from __future__ import annotations

import math

import numpy as np

from . import ik_reference as ref
from .differential import cross
from .tolerances import (
    BAND_LEVERAGE,
    BOTTOM_ROW_TOLERANCE,
    CHOICE_TOLERANCE,
    LENGTH_TOLERANCE,
    REACH_ROUNDING,
    ROTATION_TOLERANCE,
    WRIST_TOLERANCE,
    WRIST_TURN_TOLERANCE,
)

PI, TAU = ref.PI, ref.TAU


def set_tolerances(*values: float) -> None:
    """The compiled kernel is handed the tolerances; this module reads :mod:`ur10core.tolerances` itself."""


def wrap(angle: np.ndarray) -> np.ndarray:
    """Into (−π, π], exactly: ``fmod`` is exact and so are both corrections (Sterbenz)."""
    angle = np.fmod(angle, TAU)
    angle = np.where(angle > PI, angle - TAU, angle)
    return np.where(angle <= -PI, angle + TAU, angle)


# --------------------------------------------------------------------------- FK, frames, quaternions


def fk_one(q: np.ndarray, params) -> np.ndarray | None:
    """Closed-form T06 of one joint vector (docs/kinematics.md §3); None if q is not finite."""
    t1, t2, t3, t4, t5, t6 = q.tolist()
    if not all(map(math.isfinite, (t1, t2, t3, t4, t5, t6))):
        return None
    d1, a2, a3, d4, d5, d6 = params
    cos, sin = math.cos, math.sin
    c1, s1, c5, s5, c6, s6 = cos(t1), sin(t1), cos(t5), sin(t5), cos(t6), sin(t6)
    c2, s2, c23, s23 = cos(t2), sin(t2), cos(t2 + t3), sin(t2 + t3)
    c234, s234 = cos(t2 + t3 + t4), sin(t2 + t3 + t4)
    u, w = -s1 * s5 + c1 * c5 * c234, s5 * c1 + s1 * c5 * c234
    r13, r23, r33 = s1 * c5 + s5 * c1 * c234, -c1 * c5 + s5 * s1 * c234, s5 * s234
    reach = a2 * c2 + a3 * c23 - d5 * s234
    return np.array(
        [
            [c6 * u - s6 * s234 * c1, -s6 * u - s234 * c1 * c6, r13, c1 * reach + d4 * s1 + d6 * r13],
            [c6 * w - s6 * s234 * s1, -s6 * w - s234 * s1 * c6, r23, s1 * reach - d4 * c1 + d6 * r23],
            [s6 * c234 + s234 * c5 * c6, c6 * c234 - s234 * c5 * s6, r33, a2 * s2 + a3 * s23 + d1 + d5 * c234 + d6 * r33],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


#: cos and sin of alpha_{i-1}, rows i = 1..6 of the course's DH table.
_COS_ALPHA = np.array([1.0, 0.0, 1.0, 1.0, 0.0, 0.0])
_SIN_ALPHA = np.array([0.0, 1.0, 0.0, 0.0, -1.0, 1.0])


def frames(q: np.ndarray, params, out: np.ndarray) -> None:
    """Frames {0}..{6} of n joint vectors (n, 6) into ``out`` (n, 7, 4, 4): T0i = T01 ... T(i-1,i)."""
    if len(q) == 1 and all(map(math.isfinite, q[0].tolist())):
        _frames_one(q[0].tolist(), params, out[0])
        return
    d1, a2, a3, d4, d5, d6 = params
    a = np.array([0.0, 0.0, a2, a3, 0.0, 0.0])
    d = np.array([d1, 0.0, 0.0, d4, d5, d6])
    ct, st = np.cos(q), np.sin(q)
    link = np.zeros(q.shape + (4, 4))
    link[..., 0, 0], link[..., 0, 1], link[..., 0, 3] = ct, -st, a
    link[..., 1, 0], link[..., 1, 1], link[..., 1, 2], link[..., 1, 3] = st * _COS_ALPHA, ct * _COS_ALPHA, -_SIN_ALPHA, -_SIN_ALPHA * d
    link[..., 2, 0], link[..., 2, 1], link[..., 2, 2], link[..., 2, 3] = st * _SIN_ALPHA, ct * _SIN_ALPHA, _COS_ALPHA, _COS_ALPHA * d
    link[..., 3, 3] = 1.0
    out[:, 0] = np.eye(4)
    for i in range(6):
        np.matmul(out[:, i], link[:, i], out=out[:, i + 1])


def jacobians(q: np.ndarray, params, out: np.ndarray) -> None:
    """Flange Jacobians (n, 6, 6) of n joint vectors (n, 6) into ``out``: column i is [z_i × (o_6 − o_i); z_i]."""
    F = np.empty((len(q), 7, 4, 4))
    frames(q, params, F)
    z, o = F[:, 1:, :3, 2], F[:, 1:, :3, 3]  # (n, 6, 3)
    out[:, :3] = np.swapaxes(cross(z, o[:, 5:6] - o), -1, -2)
    out[:, 3:] = np.swapaxes(z, -1, -2)


def jacobian_one(q: np.ndarray, params) -> np.ndarray | None:
    """The flange Jacobian (6, 6) of one joint vector; None if q is not finite."""
    if not all(map(math.isfinite, q.tolist())):
        return None
    J = np.empty((1, 6, 6))
    jacobians(q.reshape(1, 6), params, J)
    return J[0]


def _frames_one(q: list[float], params, out: np.ndarray) -> None:
    """:func:`frames` of one joint vector: each link's matrix from floats, six 4 × 4 products (the drag's call)."""
    d1, a2, a3, d4, d5, d6 = params
    T = _EYE4
    out[0] = T
    for i, (t, a, d, ca, sa) in enumerate(zip(q, (0.0, 0.0, a2, a3, 0.0, 0.0), (d1, 0.0, 0.0, d4, d5, d6),
                                             _COS_ALPHA.tolist(), _SIN_ALPHA.tolist())):
        ct, st = math.cos(t), math.sin(t)
        T = T @ np.array([[ct, -st, 0.0, a], [st * ca, ct * ca, -sa, -sa * d], [st * sa, ct * sa, ca, ca * d],
                          [0.0, 0.0, 0.0, 1.0]])
        out[i + 1] = T


_EYE4 = np.eye(4)


#: Shepperd's method: row k of the symmetric matrix below is 4 q_k q; entry (a, b) is
#: Σ sign · R[i, j] over these terms, the first row plus or minus the trace's terms.
_SHEPPERD = np.zeros((4, 4, 9))
for (a, b), terms in {
    (0, 0): [(1, 0), (1, 4), (1, 8)], (1, 1): [(1, 0), (-1, 4), (-1, 8)], (2, 2): [(-1, 0), (1, 4), (-1, 8)],
    (3, 3): [(-1, 0), (-1, 4), (1, 8)], (0, 1): [(1, 7), (-1, 5)], (0, 2): [(1, 2), (-1, 6)], (0, 3): [(1, 3), (-1, 1)],
    (1, 2): [(1, 1), (1, 3)], (1, 3): [(1, 2), (1, 6)], (2, 3): [(1, 5), (1, 7)],
}.items():
    for sign, index in terms:
        _SHEPPERD[a, b, index] = _SHEPPERD[b, a, index] = sign


def quaternions(R: np.ndarray, out: np.ndarray) -> None:
    """Unit quaternions (w, x, y, z), w ≥ 0, of n rotations (n, 3, 3), by Shepperd's method."""
    if len(R) == 1:
        out[0] = _quaternion_one(R[0].tolist())
        return
    rows = _SHEPPERD @ R.reshape(-1, 1, 9, 1)  # (n, 4, 4, 1)
    rows = rows[..., 0] + np.eye(4)  # the diagonal's 1 + ...
    largest = np.argmax(np.diagonal(rows, axis1=-2, axis2=-1), axis=-1)  # divide by the largest q_k
    v = np.take_along_axis(rows, largest[:, None, None], axis=1)[:, 0]
    norm = np.sqrt((v * v).sum(axis=-1, keepdims=True))
    out[:] = v / np.where(v[:, :1] < 0.0, -norm, norm)


def _quaternion_one(R: list[list[float]]) -> list[float]:
    """:func:`quaternions` of one rotation, in floats: the same four rows, the same choice."""
    (r11, r12, r13), (r21, r22, r23), (r31, r32, r33) = R
    rows = ((r11 + r22 + r33 + 1.0, r32 - r23, r13 - r31, r21 - r12),
            (r32 - r23, r11 - r22 - r33 + 1.0, r12 + r21, r13 + r31),
            (r13 - r31, r12 + r21, -r11 + r22 - r33 + 1.0, r23 + r32),
            (r21 - r12, r13 + r31, r23 + r32, -r11 - r22 + r33 + 1.0))
    v = rows[max(range(4), key=lambda k: rows[k][k])]  # the first of equal largest, as np.argmax
    norm = math.sqrt(sum(x * x for x in v))
    norm = -norm if v[0] < 0.0 else norm
    return [x / norm for x in v]


# --------------------------------------------------------------------------- nearest branch


def shift_near(q, current, limit: float) -> np.ndarray:
    """Each angle of ``q`` as its 2π-equivalent nearest ``current``, moved by whole turns into ±limit (≥ π)."""
    with np.errstate(invalid="ignore"):
        shifted = q + TAU * np.round((current - q) / TAU)  # half to even, as C's nearbyint
        shifted = np.where(shifted > limit, shifted - TAU * np.ceil((shifted - limit) / TAU), shifted)
        return np.where(shifted < -limit, shifted + TAU * np.ceil((-limit - shifted) / TAU), shifted)


def nearest_one(q: np.ndarray, valid: np.ndarray, current: np.ndarray, limit: float, prefer: int, tie: float):
    """The valid slot nearest ``current`` and its angles shifted next to it; see ``_kernels.c``."""
    shifted = shift_near(q, current, limit)
    with np.errstate(invalid="ignore"):
        distance = ((shifted - current) ** 2).sum(axis=-1)
    distance = np.where(valid & np.isfinite(distance), distance, np.inf)
    best = int(np.argmin(distance))  # the first of equals, as the C loop
    if distance[best] == np.inf:
        return -1, np.full(6, math.nan)
    if 0 <= prefer < 8 and distance[prefer] <= distance[best] + tie:
        best = prefer
    return best, shifted[best]


# --------------------------------------------------------------------------- IK


def pose_is_valid(T: np.ndarray) -> np.ndarray:
    """(n,) bool for (n, 16) row-major poses: finite, bottom row [0 0 0 1], proper rotation."""
    with np.errstate(invalid="ignore", over="ignore"):
        ok = np.isfinite(T).all(axis=-1)
        ok &= (np.abs(T[:, 12:15]) <= BOTTOM_ROW_TOLERANCE).all(axis=-1) & (np.abs(T[:, 15] - 1.0) <= BOTTOM_ROW_TOLERANCE)
        R = T.reshape(-1, 4, 4)[:, :3, :3]
        gram = np.einsum("nia,nib->nab", R, R)
        ok &= (np.abs(gram - np.eye(3)) <= ROTATION_TOLERANCE).all(axis=(-2, -1))
        ok &= np.einsum("ni,ni->n", np.cross(R[:, :, 0], R[:, :, 1]), R[:, :, 2]) > 0.0
    return ok


def _one_pose_is_valid(rows: list[list[float]]) -> bool:
    """:func:`pose_is_valid` for one pose's rows, in plain Python (the same checks as the C kernel)."""
    if not all(math.isfinite(value) for row in rows for value in row):
        return False
    if any(abs(value) > BOTTOM_ROW_TOLERANCE for value in rows[3][:3]) or abs(rows[3][3] - 1.0) > BOTTOM_ROW_TOLERANCE:
        return False
    columns = list(zip(*rows[:3]))[:3]
    for a in range(3):
        for b in range(a, 3):
            dot = sum(x * y for x, y in zip(columns[a], columns[b]))
            if abs(dot - (1.0 if a == b else 0.0)) > ROTATION_TOLERANCE:
                return False
    (x1, x2, x3), (y1, y2, y3), (z1, z2, z3) = columns
    return (x2 * y3 - x3 * y2) * z1 + (x3 * y1 - x1 * y3) * z2 + (x1 * y2 - x2 * y1) * z3 > 0.0


def ik_one(T: np.ndarray, theta6_hint: float, reach_hint: float, theta3_hint: float, params):
    """All eight slots of one C-contiguous (4, 4) pose, or None when it is not a valid pose."""
    rows = T.tolist()
    if not _one_pose_is_valid(rows):
        return None
    q, valid, wrist, elbow, shoulder, failure, rho, distance = ref.solve_pose(
        rows, theta6_hint, reach_hint, theta3_hint, params
    )
    return (
        np.array(q).reshape(8, 6), np.array(valid), np.array(wrist), np.array(elbow), np.array(shoulder),
        np.array(failure, dtype=np.int8), np.array(rho), np.array(distance),
    )


def ik_batch(T, theta6_hint, reach_hint, theta3_hint, params, q, valid, wrist, elbow, shoulder, failure, rho_out, distance) -> int:
    """All eight slots of n poses (n, 16) into the preallocated outputs; see ``_kernels.c``.

    Returns the index of the first pose that is not a valid transform (its outputs are
    not written), or −1.
    """
    ok = pose_is_valid(T)
    bad = np.flatnonzero(~ok)
    if len(bad):
        good = np.flatnonzero(ok)
        outputs = (q, valid, wrist, elbow, shoulder, failure, rho_out, distance)
        parts = [np.empty((len(good),) + out.shape[1:], out.dtype) for out in outputs]
        ik_batch(T[good], theta6_hint[good], reach_hint[good], theta3_hint[good], params, *parts)
        for out, part in zip(outputs, parts):
            out[good] = part
        return int(bad[0])
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        _solve(T, theta6_hint, reach_hint, theta3_hint, params, q, valid, wrist, elbow, shoulder, failure, rho_out, distance)
    return -1


def _nearest_reachable_theta234(A, V, theta234, d5, distance):
    """Vectorised :func:`ur10core.ik_reference.nearest_reachable_theta234`."""
    R = np.hypot(A, V)
    u = np.clip((distance * distance - (R * R + d5 * d5)) / (2.0 * d5 * R), -1.0, 1.0)
    x = theta234 - np.arctan2(V, A)
    first = wrap(np.arcsin(u) - x)
    second = wrap(PI - np.arcsin(u) - x)
    return theta234 + np.where(np.abs(first) <= np.abs(second), first, second)


def _in_reach(r, outer, inner):
    return (inner - LENGTH_TOLERANCE <= r) & (r <= outer + LENGTH_TOLERANCE)


def _within(r, outer, inner):
    """Within the exact reach (no tolerance); False for NaN."""
    return (inner <= r) & (r <= outer)


def _reaches(r, outer, inner):
    """Vectorised :func:`ur10core.ik_reference._reaches`."""
    return (inner - REACH_ROUNDING <= r) & (r <= outer + REACH_ROUNDING)


def _wrist_and_elbow(R, p5, c1, s1, A, sign, hint, params):
    """Vectorised :func:`ur10core.ik_reference._wrist_and_elbow`: every argument (m,) or (m, 3, 3)/(m, 3)."""
    d1, a2, a3, d4, d5, d6 = params
    r11, r12, r13, r21, r22, r23, r31, r32, r33 = (R[:, a, b] for a in range(3) for b in range(3))
    theta1 = wrap(np.arctan2(s1, c1))
    c5 = r13 * s1 - r23 * c1
    c6s5 = r21 * c1 - r11 * s1
    s6s5 = r12 * s1 - r22 * c1
    s5_abs = np.sqrt(c6s5 * c6s5 + s6s5 * s6s5)
    s5 = sign * s5_abs
    theta5 = wrap(np.arctan2(s5, c5))
    nonzero = s5_abs > 0.0
    c6 = np.where(nonzero, sign * c6s5 / s5_abs, 1.0)
    s6 = np.where(nonzero, sign * s6s5 / s5_abs, 0.0)
    theta6_pose = np.arctan2(s6, c6)
    keep_hint = s5_abs * np.abs(wrap(hint - theta6_pose)) <= WRIST_TURN_TOLERANCE
    theta6 = np.where(keep_hint, hint, wrap(theta6_pose))
    c6 = np.where(keep_hint, np.cos(hint), c6)
    s6 = np.where(keep_hint, np.sin(hint), s6)
    c234 = s5 * (r13 * c1 + r23 * s1) + c5 * c5 * (s6 * r31 + c6 * r32)
    s234 = s5 * r33 + c5 * (c6 * r31 - s6 * r32)
    norm = np.sqrt(c234 * c234 + s234 * s234)
    c234, s234 = c234 / norm, s234 / norm
    theta234 = np.arctan2(s234, c234)
    V = p5[:, 2] - d1
    h4, v4 = A + d5 * s234, V - d5 * c234
    r = np.sqrt(h4 * h4 + v4 * v4)
    outer, inner = a2 + a3, abs(a2 - a3)
    beyond, reach = np.where(r > outer, r - outer, inner - r), np.hypot(A, V)
    slide = np.flatnonzero((beyond > 0.0) & (reach > 0.0) & (s5_abs * beyond * r <= 2.0 * WRIST_TURN_TOLERANCE * d5 * reach))
    if len(slide):
        Ai, Vi, t234 = A[slide], V[slide], theta234[slide]
        moved = _nearest_reachable_theta234(Ai, Vi, t234, d5, np.where(r[slide] > outer, outer, inner))
        turn = np.where(c5[slide] >= 0.0, 1.0, -1.0)
        theta6_moved = wrap(theta6[slide] - turn * (moved - t234))
        allowed = s5_abs[slide] * np.abs(wrap(theta6_moved - theta6_pose[slide])) <= WRIST_TURN_TOLERANCE
        take = slide[allowed]
        theta234[take], theta6[take] = moved[allowed], theta6_moved[allowed]
        h4[take] = A[take] + d5 * np.sin(theta234[take])
        v4[take] = V[take] - d5 * np.cos(theta234[take])
        r[take] = np.sqrt(h4[take] * h4[take] + v4[take] * v4[take])
    return theta1, theta5, theta6, theta234, s5_abs, h4, v4, r


def _reach_within_band(R, p5, slot, A, band_a, band_b, sign, hint, params):
    """Vectorised :func:`ur10core.ik_reference._reach_within_band`: (best slot values, where found)."""
    d1, a2, a3, d4, d5, d6 = params
    outer, inner = a2 + a3, abs(a2 - a3)
    low, high = np.minimum(band_a, band_b), np.maximum(band_a, band_b)
    rho = np.sqrt(p5[:, 0] * p5[:, 0] + p5[:, 1] * p5[:, 1])
    h4, v4, r = slot[5], slot[6], slot[7].copy()
    limit = np.where(r > outer, outer, inner)
    done = ~((np.abs(r - limit) <= BAND_LEVERAGE * (high - low)) & (np.abs(v4) <= limit))
    step = np.copysign(np.sqrt(np.maximum(limit * limit - v4 * v4, 0.0)), h4) - h4
    best = [value.copy() for value in slot]
    A = A.copy()
    for _ in range(4):
        active = np.flatnonzero(~done)
        moved = np.clip(A[active] + step[active], low[active], high[active])
        stuck = moved == A[active]
        done[active[stuck]] = True
        active, moved = active[~stuck], moved[~stuck]
        if not len(active):
            break
        scale = rho[active] * np.sqrt(moved * moved + d4 * d4)
        c1 = (p5[active, 0] * moved - p5[active, 1] * d4) / scale
        s1 = (p5[active, 1] * moved + p5[active, 0] * d4) / scale
        better = _wrist_and_elbow(R[active], p5[active], c1, s1, moved, sign[active], hint[active], params)
        reached = better[-1]
        changed = reached != r[active]
        secant = (limit[active] - reached) * (moved - A[active]) / np.where(changed, reached - r[active], 1.0)
        step[active] = np.where(changed, secant, step[active])
        keep = _in_reach(reached, outer, inner) | (np.abs(reached - limit[active]) < np.abs(best[-1][active] - limit[active]))
        for value, new in zip(best, better):
            value[active[keep]] = new[keep]
        A[active], r[active] = moved, reached
        done[active[_within(reached, outer, inner)]] = True
    return best, _in_reach(best[-1], outer, inner) & np.isfinite(slot[7])


def _solve(T, theta6_hint, reach_hint, theta3_hint, params, q, valid, wrist, elbow, shoulder, failure, rho_out, distance) -> None:
    d1, a2, a3, d4, d5, d6 = params
    n = len(T)
    M = T.reshape(n, 4, 4)
    p5 = M[:, :3, 3] - d6 * M[:, :3, 2]
    rho2 = p5[:, 0] ** 2 + p5[:, 1] ** 2
    rho = np.sqrt(rho2)
    rho_out[:] = rho
    shoulder[:] = np.abs(rho - d4) <= LENGTH_TOLERANCE
    q[:] = np.nan
    valid[:] = False
    wrist[:] = False
    elbow[:] = False
    failure[:] = ref.WRIST_INSIDE_CYLINDER
    distance[:] = np.nan
    has_theta1 = np.flatnonzero(rho >= d4 - LENGTH_TOLERANCE)
    if not len(has_theta1):
        return
    # one element per (pose, θ1 side i, wrist sign j): index 4 m + 2 i + j
    pose = np.repeat(has_theta1, 4)
    side = np.tile([-1.0, -1.0, 1.0, 1.0], len(has_theta1))
    sign = np.tile([1.0, -1.0, 1.0, -1.0], len(has_theta1))
    rho, rho2, P5, R = rho[pose], rho2[pose], p5[pose], M[pose, :3, :3]
    reach = np.sqrt(np.maximum(rho2 - d4 * d4, 0.0))
    reach_low = np.sqrt(np.maximum((rho - CHOICE_TOLERANCE) ** 2 - d4 * d4, 0.0))
    reach_high = np.sqrt(np.maximum((rho + CHOICE_TOLERANCE) ** 2 - d4 * d4, 0.0))
    theta1_band = (reach_high - reach_low) * d4 / (reach * reach + d4 * d4)
    A_hint = reach_hint[pose]
    A = side * np.where((reach_low <= np.abs(A_hint)) & (np.abs(A_hint) <= reach_high), np.abs(A_hint), reach)
    scale = rho * np.sqrt(A * A + d4 * d4)
    c1 = (P5[:, 0] * A - P5[:, 1] * d4) / scale
    s1 = (P5[:, 1] * A + P5[:, 0] * d4) / scale
    hint = wrap(theta6_hint)[pose]
    slot = list(_wrist_and_elbow(R, P5, c1, s1, A, sign, hint, params))
    first_s5 = slot[4].copy()
    outer, inner = a2 + a3, abs(a2 - a3)
    beyond = np.flatnonzero(~_reaches(slot[-1], outer, inner))
    if len(beyond):
        band_a = np.where(reach_low > 0.0, side * reach_low, -side * reach_high)
        better, found = _reach_within_band(
            R[beyond], P5[beyond], [value[beyond] for value in slot], A[beyond], band_a[beyond],
            (side * reach_high)[beyond], sign[beyond], hint[beyond], params,
        )
        for value, new in zip(slot, better):
            value[beyond[found]] = new[found]
    beyond = np.flatnonzero(~_reaches(slot[-1], outer, inner))
    if len(beyond):
        own = _wrist_and_elbow(R[beyond], P5[beyond], c1[beyond], s1[beyond], A[beyond], sign[beyond],
                               np.full(len(beyond), np.nan), params)
        found = _reaches(own[-1], outer, inner)
        for value, new in zip(slot, own):
            value[beyond[found]] = new[found]
    # Shoulder and wrist both singular, where the reference turns θ1 within its band (its
    # _theta1_for_reach): that step is ill-conditioned (an ulp of atan2 moves θ1 by 1e-10, and
    # the wrist's split with it), and numpy's vectorised atan2, sin and cos differ from the C
    # library's by an ulp on some CPUs (AVX-512). Those poses are solved by the reference, whose
    # arithmetic is the compiled kernel's: both backends then give the same branches.
    at_triple = np.unique(pose[(first_s5 <= theta1_band) | (slot[4] <= theta1_band)])
    theta1, theta5, theta6, theta234, s5_abs, h4, v4, r = slot
    # per slot pair: the two elbow slots 4 i + 2 j + l share everything above
    pair = 8 * pose + 4 * (side > 0) + 2 * (sign < 0)
    too_far = ~(r <= outer + LENGTH_TOLERANCE)
    too_close = ~too_far & (r < inner - LENGTH_TOLERANCE)
    ok = ~too_far & ~too_close
    flat_distance, flat_wrist, flat_failure = distance.reshape(-1), wrist.reshape(-1), failure.reshape(-1)
    code = np.where(too_far, ref.ELBOW_TOO_FAR, np.where(too_close, ref.ELBOW_TOO_CLOSE, ref.REACHABLE))
    for l in (0, 1):
        flat_distance[pair + l] = r
        flat_wrist[pair + l] = s5_abs <= WRIST_TOLERANCE
        flat_failure[pair + l] = code
    at_limit = (r >= outer - LENGTH_TOLERANCE) | (r <= inner + LENGTH_TOLERANCE)
    c3 = np.clip((r * r - a2 * a2 - a3 * a3) / (2.0 * a2 * a3), -1.0, 1.0)
    s3 = np.sqrt(1.0 - c3 * c3)
    theta3 = np.arctan2(s3, c3)
    elbow_hint = np.abs(wrap(theta3_hint))[pose]
    r_hint = np.sqrt(a2 * a2 + a3 * a3 + 2.0 * a2 * a3 * np.cos(elbow_hint))
    keep = np.abs(r - r_hint) <= CHOICE_TOLERANCE  # θ3 is fixed only to √rounding at the limits
    theta3 = np.where(keep, elbow_hint, theta3)
    c3 = np.where(keep, np.cos(elbow_hint), c3)
    s3 = np.where(keep, np.sin(elbow_hint), s3)
    beta = np.arctan2(v4, h4)
    gamma = np.arctan2(a3 * s3, a2 + a3 * c3)
    flat_q, flat_valid, flat_elbow = q.reshape(-1, 6), valid.reshape(-1), elbow.reshape(-1)
    for l, (t3, t2) in enumerate(((theta3, beta - gamma), (-theta3, beta + gamma))):
        t3, t2 = wrap(t3), wrap(t2)
        k = (pair + l)[ok]
        flat_q[k] = np.stack([theta1, t2, t3, wrap(theta234 - t2 - t3), theta5, theta6], -1)[ok]
        flat_valid[k] = True
        flat_elbow[k] = at_limit[ok]
    for m in at_triple:
        result = ref.solve_pose(M[m].tolist(), float(theta6_hint[m]), float(reach_hint[m]), float(theta3_hint[m]), params)
        for out, value in zip((q, valid, wrist, elbow, shoulder, failure, rho_out, distance), result):
            out[m] = np.reshape(value, out[m].shape)
