"""The reference for batch IK speed: a plain numpy vectorisation of the course's steps.

docs/kinematics.md §4 as written, all eight branches at once by broadcasting over a leading
(2, 2, 2) axis for (θ1 sign, θ5 sign, θ3 sign): arccos where the notes say acos, sin
and cos of each intermediate angle, no special cases. It is what one would write first;
``benchmarks/bench_core.py`` checks that it is right before timing it.
"""

from __future__ import annotations

import numpy as np


def ik_numpy(arm, T: np.ndarray) -> np.ndarray:
    """(n, 4, 4) poses → (n, 8, 6) joint angles (NaN where a branch does not exist)."""
    d1, a2, a3, d4, d5, d6 = arm.dh_lengths
    r11, r12, r13 = T[:, 0, 0], T[:, 0, 1], T[:, 0, 2]
    r21, r22, r23 = T[:, 1, 0], T[:, 1, 1], T[:, 1, 2]
    r31, r32, r33 = T[:, 2, 0], T[:, 2, 1], T[:, 2, 2]
    px, py, pz = T[:, 0, 3], T[:, 1, 3], T[:, 2, 3]
    sign1 = np.array([1.0, -1.0])[:, None, None, None]  # +acos / -acos
    sign5 = np.array([1.0, -1.0])[None, :, None, None]
    sign3 = np.array([1.0, -1.0])[None, None, :, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        # step 1: θ1 from (py − d6 r23) c1 + (d6 r13 − px) s1 = −d4
        p5x, p5y = px - d6 * r13, py - d6 * r23
        theta1 = np.arctan2(p5y, p5x) + np.pi / 2 + sign1 * np.arccos(d4 / np.hypot(p5x, p5y))
        c1, s1 = np.cos(theta1), np.sin(theta1)
        # step 2: θ5 = ±acos(r13 s1 − r23 c1)
        theta5 = sign5 * np.arccos(r13 * s1 - r23 * c1)
        s5 = np.sin(theta5)
        # step 3: θ6 from s5 c6 = r21 c1 − r11 s1, −s5 s6 = r22 c1 − r12 s1
        theta6 = np.arctan2(-(r22 * c1 - r12 * s1) / s5, (r21 * c1 - r11 * s1) / s5)
        # step 4: θ234 from c234 s5 = r13 c1 + r23 s1, s234 s5 = r33
        theta234 = np.arctan2(r33 / s5, (r13 * c1 + r23 * s1) / s5)
        c234, s234 = np.cos(theta234), np.sin(theta234)
        # step 5: planar 2R for the frame-4 origin
        h4 = c1 * p5x + s1 * p5y + d5 * s234
        v4 = pz - d6 * r33 - d1 - d5 * c234
        c3 = (h4**2 + v4**2 - a2**2 - a3**2) / (2 * a2 * a3)
        theta3 = sign3 * np.arccos(c3)
        theta2 = np.arctan2(v4, h4) - np.arctan2(a3 * np.sin(theta3), a2 + a3 * np.cos(theta3))
        theta4 = theta234 - theta2 - theta3
        q = np.stack(np.broadcast_arrays(theta1, theta2, theta3, theta4, theta5, theta6), axis=-1)
    q = np.mod(q + np.pi, 2 * np.pi) - np.pi
    return q.reshape(8, -1, 6).transpose(1, 0, 2)
