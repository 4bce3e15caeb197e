"""The UR family's eight-branch IK, step by step in plain Python (docs/kinematics.md §4).

This is the readable statement of the method and the numpy backend's one-pose path.
``_numpy_kernels.ik_batch`` runs the same steps vectorised over many poses and the
compiled kernel (``_kernels.c``) runs them in C; the tests hold the three to each other,
decisions and failure codes included.
"""

from __future__ import annotations

import math

from .branches import INSIDE_OFFSET, REACHED, TOO_CLOSE, TOO_FAR
from .tolerances import (
    BAND_LEVERAGE, CHOICE_TOLERANCE, LENGTH_TOLERANCE, REACH_ROUNDING, WRIST_TOLERANCE, WRIST_TURN_TOLERANCE,
)

#: Why a slot has no solution (``IKSolution.failure``): every arm's codes, by the UR family's names.
REACHABLE = REACHED
WRIST_INSIDE_CYLINDER = INSIDE_OFFSET  #: P5 closer than d4 to the base axis: no θ1 at all
ELBOW_TOO_FAR = TOO_FAR  #: the frame-4 origin is beyond a2 + a3 from the shoulder
ELBOW_TOO_CLOSE = TOO_CLOSE  #: the frame-4 origin is closer than |a2 − a3| to the shoulder

PI = math.pi
TAU = 2.0 * math.pi


def wrap(angle: float) -> float:
    """``angle`` into (−π, π], exactly (IEEE remainder), in O(1) for any finite angle.

    >>> wrap(3 * math.pi) == math.pi, wrap(-math.pi) == math.pi, wrap(1e9)
    (True, True, 0.5773954624831035)
    """
    if -PI < angle <= PI:
        return angle
    angle = math.remainder(angle, TAU)
    return angle + TAU if angle <= -PI else angle


def nearest_reachable_theta234(A: float, V: float, theta234: float, d5: float, distance: float) -> float:
    """The θ234 nearest ``theta234`` that puts the frame-4 origin ``distance`` from the shoulder.

    In the arm plane the frame-4 origin is ``(A + d5 s234, V − d5 c234)``, so its squared
    distance from the shoulder is a sinusoid in θ234 (docs/kinematics.md §4.3)::

        r² = A² + V² + d5² + 2 d5 (A s234 − V c234) = K + 2 d5 R sin(θ234 − ψ)

    with ``R = |(A, V)|`` and ``ψ = atan2(V, A)``. ``sin(θ234 − ψ) = u`` has the two
    solutions ``asin u`` and ``π − asin u``; the nearer one is returned. Where no θ234
    reaches ``distance``, ``u`` is clamped to ±1: the θ234 that comes closest.
    ``R`` must be positive.
    """
    R = math.hypot(A, V)
    u = (distance * distance - (R * R + d5 * d5)) / (2.0 * d5 * R)
    u = min(1.0, max(-1.0, u))
    psi = math.atan2(V, A)
    x = theta234 - psi
    first = wrap(math.asin(u) - x)
    second = wrap(PI - math.asin(u) - x)
    return theta234 + (first if abs(first) <= abs(second) else second)


def hint_values(hint, lengths) -> tuple[float, float, float]:
    """What the IK takes from the joints ``hint``: ``(θ6, A, θ3)``; ``(0, NaN, NaN)`` without one.

    A is the signed reach of the wrist-2 point along x1, the shoulder factor
    ``a2 c2 + a3 c23 − d5 s234`` (docs/kinematics.md §3).
    """
    if hint is None:
        return 0.0, math.nan, math.nan
    _, a2, a3, _, d5, _ = lengths
    t2, t3, t4 = hint[1], hint[2], hint[3]
    return hint[5], a2 * math.cos(t2) + a3 * math.cos(t2 + t3) - d5 * math.sin(t2 + t3 + t4), t3


def solve_pose(rows, theta6_hint: float, reach_hint: float, theta3_hint: float, lengths) -> tuple:
    """The eight IK slots of one pose; what :func:`ur10core.ik.solve_reference` wraps.

    ``rows`` are the pose's top three rows (already validated), ``lengths`` the arm's
    ``(d1, a2, a3, d4, d5, d6)``. The hint's θ6, shoulder reach and θ3
    (:func:`hint_values`; NaN for none) are kept wherever they reproduce the pose within
    the tolerances.
    Returns plain lists, in the order of the compiled kernel's ``ik_one``: ``q`` (48
    angles, slot-major), ``valid``, ``wrist_singular``, ``elbow_singular`` (8 each),
    ``shoulder_singular``, ``failure`` (8), ``rho``, ``elbow_distance`` (8).
    """
    R = [row[:3] for row in rows[:3]]
    (_, _, r13, px), (_, _, r23, py), (_, _, r33, pz) = rows[:3]
    d1, a2, a3, d4, d5, d6 = lengths
    sqrt, atan2, cos, sin = math.sqrt, math.atan2, math.cos, math.sin

    # Step 1: the wrist-2 point P5 = p − d6 z6 and its distance ρ from the base axis.
    p5 = (px - d6 * r13, py - d6 * r23, pz - d6 * r33)
    rho2 = p5[0] * p5[0] + p5[1] * p5[1]
    rho = sqrt(rho2)
    q = [math.nan] * 48
    valid = [False] * 8
    wrist_singular = [False] * 8
    elbow_singular = [False] * 8
    failure = [WRIST_INSIDE_CYLINDER] * 8
    elbow_distance = [math.nan] * 8
    shoulder_singular = abs(rho - d4) <= LENGTH_TOLERANCE
    if not rho >= d4 - LENGTH_TOLERANCE:
        return q, valid, wrist_singular, elbow_singular, shoulder_singular, failure, rho, elbow_distance

    reach = sqrt(max(rho2 - d4 * d4, 0.0))
    # Every reach A with |sqrt(A² + d4²) − ρ| ≤ CHOICE_TOLERANCE reproduces P5. Near the
    # shoulder singularity that band is wide (A ≈ 0 is known only to about 1e-8 m): the
    # hint's |A| is kept for both shoulder slots when it lies inside, and θ1 is as
    # uncertain as theta1_band says.
    reach_low = sqrt(max((rho - CHOICE_TOLERANCE) ** 2 - d4 * d4, 0.0))
    reach_high = sqrt(max((rho + CHOICE_TOLERANCE) ** 2 - d4 * d4, 0.0))
    theta1_band = (reach_high - reach_low) * d4 / (reach * reach + d4 * d4)
    outer, inner = a2 + a3, abs(a2 - a3)
    hint = wrap(theta6_hint)
    theta3_hint = abs(wrap(theta3_hint)) if math.isfinite(theta3_hint) else math.nan
    r_hint = sqrt(a2 * a2 + a3 * a3 + 2.0 * a2 * a3 * cos(theta3_hint))  # where the hint's elbow puts P4
    for i, side in ((0, -1.0), (1, 1.0)):
        A = side * (abs(reach_hint) if reach_low <= abs(reach_hint) <= reach_high else reach)
        # θ1 from A: x1 = (c1, s1) with P5 = A x1 + d4 (s1, −c1)
        scale = rho * sqrt(A * A + d4 * d4)
        c1 = (p5[0] * A - p5[1] * d4) / scale
        s1 = (p5[1] * A + p5[0] * d4) / scale
        for j, sign in ((0, 1.0), (1, -1.0)):
            slot = _wrist_and_elbow(R, p5, c1, s1, A, sign, hint, lengths)
            if not _reaches(slot[-1], outer, inner):
                # Beyond the reach, if only just: move A within its band instead of putting
                # the frame-4 origin on the boundary (docs/kinematics.md §4.3).
                # Where the band holds A = 0 the two shoulder slots are one branch, and either may cross.
                band_a = side * reach_low if reach_low > 0.0 else -side * reach_high
                slot = _reach_within_band(R, p5, slot, A, band_a, side * reach_high, sign, hint, lengths) or slot
            if not _reaches(slot[-1], outer, inner):
                # The hint's θ6 (or the default 0) may be kept where |s5| is tiny and still
                # leave the elbow out of reach: the pose's own θ6 then may reach.
                own = _wrist_and_elbow(R, p5, c1, s1, A, sign, math.nan, lengths)
                slot = own if _reaches(own[-1], outer, inner) else slot
            if not _reaches(slot[-1], outer, inner) and slot[4] <= theta1_band:
                # Shoulder and wrist both nearly singular: θ1 is uncertain and the wrist's
                # split of θ234 ± θ6 swings with it. Turn θ1 within its band to where the
                # wrist gives a θ6 that reaches.
                slot = _theta1_for_reach(R, p5, slot, sign, hint, lengths) or slot
            theta1, theta5, theta6, theta234, s5_abs, h4, v4, r = slot
            base = 4 * i + 2 * j
            elbow_distance[base] = elbow_distance[base + 1] = r
            wrist_singular[base] = wrist_singular[base + 1] = s5_abs <= WRIST_TOLERANCE
            if not r <= outer + LENGTH_TOLERANCE:  # NaN too: a target so far that r overflowed
                failure[base] = failure[base + 1] = ELBOW_TOO_FAR
                continue
            if r < inner - LENGTH_TOLERANCE:
                failure[base] = failure[base + 1] = ELBOW_TOO_CLOSE
                continue
            at_limit = r >= outer - LENGTH_TOLERANCE or r <= inner + LENGTH_TOLERANCE
            c3 = min(1.0, max(-1.0, (r * r - a2 * a2 - a3 * a3) / (2.0 * a2 * a3)))
            s3 = sqrt(1.0 - c3 * c3)
            theta3 = atan2(s3, c3)
            if abs(r - r_hint) <= CHOICE_TOLERANCE:  # θ3 is fixed only to √rounding at the limits
                theta3, c3, s3 = theta3_hint, cos(theta3_hint), sin(theta3_hint)
            beta = atan2(v4, h4)
            gamma = atan2(a3 * s3, a2 + a3 * c3)
            for l, (t3, t2) in enumerate(((theta3, beta - gamma), (-theta3, beta + gamma))):
                t3, t2 = wrap(t3), wrap(t2)
                k = base + l
                q[6 * k : 6 * k + 6] = theta1, t2, t3, wrap(theta234 - t2 - t3), theta5, theta6
                valid[k] = True
                elbow_singular[k] = at_limit
                failure[k] = REACHABLE
    return q, valid, wrist_singular, elbow_singular, shoulder_singular, failure, rho, elbow_distance


def in_reach(r: float, outer: float, inner: float) -> bool:
    """The frame-4 origin at distance ``r`` from the shoulder is within the elbow's reach."""
    return inner - LENGTH_TOLERANCE <= r <= outer + LENGTH_TOLERANCE


def _reaches(r: float, outer: float, inner: float) -> bool:
    """The frame-4 origin at ``r`` is within the elbow's reach but for rounding (``REACH_ROUNDING``)."""
    return inner - REACH_ROUNDING <= r <= outer + REACH_ROUNDING


def _wrist_and_elbow(R, p5, c1, s1, A, sign, hint, lengths) -> tuple:
    """Steps 2–5 for one θ1 (``c1, s1``, reach ``A``) and one wrist sign (+1 or −1).

    Returns ``(θ1, θ5, θ6, θ234, |s5|, h4, v4, r)``: the wrist angles and the frame-4
    origin ``(h4, v4)`` in the arm plane, ``r`` from the shoulder.
    """
    (r11, r12, r13), (r21, r22, r23), (r31, r32, r33) = R
    d1, a2, a3, d4, d5, d6 = lengths
    sqrt, atan2, hypot, cos, sin = math.sqrt, math.atan2, math.hypot, math.cos, math.sin
    theta1 = wrap(atan2(s1, c1))
    # Step 2: c5 = z4·z6; |s5| from the row pair of step 3.
    c5 = r13 * s1 - r23 * c1
    c6s5 = r21 * c1 - r11 * s1
    s6s5 = r12 * s1 - r22 * c1
    s5_abs = sqrt(c6s5 * c6s5 + s6s5 * s6s5)
    s5 = sign * s5_abs
    theta5 = wrap(atan2(s5, c5))
    # Step 3: θ6 from the pose, or the hint's θ6 wherever that reproduces the pose
    # within WRIST_TURN_TOLERANCE (always so at the singularity).
    c6, s6 = (sign * c6s5 / s5_abs, sign * s6s5 / s5_abs) if s5_abs > 0.0 else (1.0, 0.0)
    theta6_pose = atan2(s6, c6)
    if s5_abs * abs(wrap(hint - theta6_pose)) <= WRIST_TURN_TOLERANCE:
        theta6, c6, s6 = hint, cos(hint), sin(hint)
    else:
        theta6 = wrap(theta6_pose)
    # Step 4, blended with the third row so that it holds at every θ5.
    c234 = s5 * (r13 * c1 + r23 * s1) + c5 * c5 * (s6 * r31 + c6 * r32)
    s234 = s5 * r33 + c5 * (c6 * r31 - s6 * r32)
    norm = sqrt(c234 * c234 + s234 * s234)
    c234, s234 = c234 / norm, s234 / norm
    theta234 = atan2(s234, c234)
    # Step 5: the frame-4 origin in the arm plane.
    V = p5[2] - d1
    h4, v4 = A + d5 * s234, V - d5 * c234
    r = sqrt(h4 * h4 + v4 * v4)
    outer, inner = a2 + a3, abs(a2 - a3)
    # r changes by at most d5·|(A, V)|/r per radian of θ234: a turn that could not fit the
    # tolerance (twice over: θ6 may be the hint's already) is not tried.
    beyond, R = (r - outer if r > outer else inner - r), hypot(A, V)
    if beyond > 0.0 and R > 0.0 and s5_abs * beyond * r <= 2.0 * WRIST_TURN_TOLERANCE * d5 * R:
        # Beyond the reach with this θ6 (if only just): slide along the wrist's singular
        # direction (θ6 + Δ, θ234 ∓ Δ) to the nearest θ234 in reach, if the pose allows
        # that turn. That beats putting the frame-4 origin on the boundary.
        turn = 1.0 if c5 >= 0.0 else -1.0
        moved = nearest_reachable_theta234(A, V, theta234, d5, outer if r > outer else inner)
        theta6_moved = wrap(theta6 - turn * (moved - theta234))
        if s5_abs * abs(wrap(theta6_moved - theta6_pose)) <= WRIST_TURN_TOLERANCE:
            theta234, theta6 = moved, theta6_moved
            h4, v4 = A + d5 * sin(theta234), V - d5 * cos(theta234)
            r = sqrt(h4 * h4 + v4 * v4)
    return theta1, theta5, theta6, theta234, s5_abs, h4, v4, r


def _reach_within_band(R, p5, slot, A, band_a, band_b, sign, hint, lengths) -> tuple | None:
    """The slot redone with a reach A in ``[band_a, band_b]`` (either order) that puts the elbow at its limit.

    Every A of the band reproduces P5 within CHOICE_TOLERANCE. Near the shoulder
    singularity the band is wide and A itself uncertain by ~1e-8 m, so a pose from
    forward kinematics can come out a few nanometres beyond the elbow's reach. r(A) is
    smooth: the first step assumes the frame-4 origin's height stays (h4 follows A), then
    secant steps on r(A) take over (four evaluations at most). None when no A of the band
    reaches.
    """
    d1, a2, a3, d4, d5, d6 = lengths
    outer, inner = a2 + a3, abs(a2 - a3)
    low, high = min(band_a, band_b), max(band_a, band_b)
    rho = math.sqrt(p5[0] * p5[0] + p5[1] * p5[1])
    h4, v4, r = slot[5], slot[6], slot[7]
    limit = outer if r > outer else inner
    if not abs(r - limit) <= BAND_LEVERAGE * (high - low) or abs(v4) > limit:
        return None
    step = math.copysign(math.sqrt(limit * limit - v4 * v4), h4) - h4
    for _ in range(4):
        moved = min(high, max(low, A + step))
        if moved == A:
            break
        scale = rho * math.sqrt(moved * moved + d4 * d4)
        c1, s1 = (p5[0] * moved - p5[1] * d4) / scale, (p5[1] * moved + p5[0] * d4) / scale
        better = _wrist_and_elbow(R, p5, c1, s1, moved, sign, hint, lengths)
        if inner <= better[-1] <= outer:
            return better
        if better[-1] != r:  # secant on r(A)
            step = (limit - better[-1]) * (moved - A) / (better[-1] - r)
        if in_reach(better[-1], outer, inner) or abs(better[-1] - limit) < abs(slot[-1] - limit):
            slot = better
        A, r = moved, better[-1]
    return slot if in_reach(slot[-1], outer, inner) else None


def _theta1_for_reach(R, p5, slot, sign, hint, lengths) -> tuple | None:
    """The slot redone with the θ1 whose wrist split reaches, if one lies in θ1's band; else None.

    The wanted θ6 is the one the nearest θ234 in reach asks for; the θ1 giving it makes
    ``(r21 c1 − r11 s1, r12 s1 − r22 c1) = s5 (c6, s6)`` parallel to ``(c6, s6)``, in
    closed form (of its two solutions, the one next to θ1). That θ1 must still put P5 at
    distance d4 from the arm plane, within CHOICE_TOLERANCE; the slot redone with it
    must reach (it does not where that θ1 gives the other wrist sign, θ6 + π).
    """
    (r11, r12, _), (r21, r22, _), _ = R
    d1, a2, a3, d4, d5, d6 = lengths
    theta1, _, theta6, theta234, _, h4, _, r = slot
    A = h4 - d5 * math.sin(theta234)
    V = p5[2] - d1
    if not math.isfinite(r) or (A == 0.0 and V == 0.0):
        return None
    moved = nearest_reachable_theta234(A, V, theta234, d5, a2 + a3 if r > a2 + a3 else abs(a2 - a3))
    c5 = R[0][2] * math.sin(theta1) - R[1][2] * math.cos(theta1)
    wanted = theta6 - (1.0 if c5 >= 0.0 else -1.0) * (moved - theta234)
    ex, ey = math.cos(wanted), math.sin(wanted)
    candidate = math.atan2(r21 * ey + r22 * ex, r11 * ey + r12 * ex)
    candidate += PI * round((theta1 - candidate) / PI)  # of the two solutions, the one by θ1
    c1, s1 = math.cos(candidate), math.sin(candidate)
    if abs(p5[0] * s1 - p5[1] * c1 - d4) > CHOICE_TOLERANCE:
        return None  # outside θ1's band: P5 would move
    better = _wrist_and_elbow(R, p5, c1, s1, p5[0] * c1 + p5[1] * s1, sign, hint, lengths)
    return better if in_reach(better[-1], a2 + a3, abs(a2 - a3)) else None
