"""The ways the course reads an orientation (docs/kinematics.md §3, Craig ch. 2, Paul ch. 2).

* Z-Y-X Euler angles (α, β, γ): rotate about Z by α, then about the *new* Y by β,
  then about the new X by γ: ``R = Rz(α) Ry(β) Rx(γ)``.
* X-Y-Z fixed angles (γ, β, α): rotate about the *fixed* X by γ, then fixed Y by β,
  then fixed Z by α: ``R = Rz(α) Ry(β) Rx(γ)`` as well — Craig's observation that the
  two conventions give the same matrix, with the angles read in opposite order.
* Z-Y-Z Euler angles (φ, θ, ψ), as the course's Stanford-arm report reads T6 (Paul's Euler
  angles): ``R = Rz(φ) Ry(θ) Rz(ψ)``, θ in [0, π].
* Equivalent angle–axis (θ, k̂), θ in [0, π].
* Euler parameters: the unit quaternion (w, x, y, z) with w ≥ 0.

Every function takes rotation matrices of shape (..., 3, 3) (a 4x4 pose's ``[:3, :3]``)
and is vectorised; angles in radians. Input is checked to be a proper rotation unless
``check=False`` is passed, for rotations that come out of the core itself (the app's
redraw path converts dozens per frame).

Example
-------
>>> R = rotation_from_zyx_euler([0.3, -0.2, 0.1])
>>> zyx_euler(R).round(6).tolist(), xyz_fixed(R).round(6).tolist()
([0.3, -0.2, 0.1], [0.1, -0.2, 0.3])
"""

from __future__ import annotations

import math

import numpy as np

from ._backend import kernels
from ._validate import as_float_array, check_finite, rotation_matrix, vectors
from .tolerances import GIMBAL_TOLERANCE


def _rot(axis: int, angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros(np.shape(angle) + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R[..., axis, axis] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    return R


def rotation_from_zyx_euler(angles) -> np.ndarray:
    """``R = Rz(α) Ry(β) Rx(γ)`` from Z-Y-X Euler angles ``(α, β, γ)`` (..., 3)."""
    alpha, beta, gamma = np.moveaxis(vectors(angles, "angles", 3), -1, 0)
    # intrinsic: each rotation about the axes of the frame the previous ones produced
    return _rot(2, alpha) @ _rot(1, beta) @ _rot(0, gamma)


def rotation_from_xyz_fixed(angles) -> np.ndarray:
    """R from X-Y-Z fixed angles ``(γ, β, α)`` (..., 3): about fixed X by γ, Y by β, Z by α."""
    gamma, beta, alpha = np.moveaxis(vectors(angles, "angles", 3), -1, 0)
    R = _rot(0, gamma)
    R = _rot(1, beta) @ R  # extrinsic: each later rotation pre-multiplies
    return _rot(2, alpha) @ R


def _rotations(R, check: bool) -> np.ndarray:
    return rotation_matrix(R) if check else np.asarray(R, dtype=float)


def zyx_euler(R, check: bool = True) -> np.ndarray:
    """Z-Y-X Euler angles ``(α, β, γ)`` of R, (..., 3); β in [−π/2, π/2].

    Craig (2.66): ``β = atan2(−r31, sqrt(r11² + r21²))``, ``α = atan2(r21, r11)``,
    ``γ = atan2(r32, r33)``. At gimbal lock (cos β ≈ 0) only α ∓ γ is defined:
    α = 0 and ``γ = ±atan2(r12, r22)``.
    """
    R = _rotations(R, check)
    r11, r21, r31 = R[..., 0, 0], R[..., 1, 0], R[..., 2, 0]
    cos_beta = np.hypot(r11, r21)
    beta = np.arctan2(-r31, cos_beta)
    locked = cos_beta < GIMBAL_TOLERANCE
    alpha = np.where(locked, 0.0, np.arctan2(r21, r11))
    gamma = np.where(
        locked,
        np.sign(-r31) * np.arctan2(R[..., 0, 1], R[..., 1, 1]),
        np.arctan2(R[..., 2, 1], R[..., 2, 2]),
    )
    return np.stack([alpha, beta, gamma], axis=-1)


def xyz_fixed(R, check: bool = True) -> np.ndarray:
    """X-Y-Z fixed angles ``(γ, β, α)`` of R, (..., 3), in the order they are applied.

    The same three numbers as :func:`zyx_euler`, read in the opposite order (Craig 2.71).
    """
    return zyx_euler(R, check)[..., ::-1]


def rotation_from_zyz_euler(angles) -> np.ndarray:
    """``R = Rz(φ) Ry(θ) Rz(ψ)`` from Z-Y-Z Euler angles ``(φ, θ, ψ)`` (..., 3)."""
    phi, theta, psi = np.moveaxis(vectors(angles, "angles", 3), -1, 0)
    return _rot(2, phi) @ _rot(1, theta) @ _rot(2, psi)


def zyz_euler(R, check: bool = True, flip: bool = False) -> np.ndarray:
    """Z-Y-Z Euler angles ``(φ, θ, ψ)`` of R, (..., 3), θ in [0, π]: docs/kinematics.md §3, as the
    course's Stanford-arm report reads T6 = [n o a p] (Paul's Euler angles).

    ``φ = atan2(a_y, a_x)``, ``θ = atan2(cφ a_x + sφ a_y, a_z)``,
    ``ψ = atan2(−sφ n_x + cφ n_y, −sφ o_x + cφ o_y)``. ``flip``: the report's other solution,
    φ + 180° (``atan2(−a_y, −a_x)``) through the same formulas, which give θ in [−π, 0] and
    ψ + 180°. When a is along ±z (sin θ ≈ 0) only φ ± ψ is defined: φ = 0 and ψ carries the
    whole turn about z, flipped or not.

    >>> R = rotation_from_zyz_euler([0.3, 1.2, -0.4])
    >>> zyz_euler(R).round(6).tolist(), np.degrees(zyz_euler(R, flip=True)).round(3).tolist()
    ([0.3, 1.2, -0.4], [-162.811, -68.755, 157.082])
    >>> np.degrees(zyz_euler(rotation_from_zyz_euler([0.3, 0.0, -0.4]))).round(3).tolist()  # only φ + ψ
    [0.0, 0.0, -5.73]
    """
    R = _rotations(R, check)
    n, o, a = R[..., :, 0], R[..., :, 1], R[..., :, 2]
    locked = np.hypot(a[..., 0], a[..., 1]) < GIMBAL_TOLERANCE
    sign = -1.0 if flip else 1.0
    phi = np.where(locked, 0.0, np.arctan2(sign * a[..., 1], sign * a[..., 0]))
    c, s = np.cos(phi), np.sin(phi)
    theta = np.arctan2(c * a[..., 0] + s * a[..., 1], a[..., 2])
    psi = np.arctan2(-s * n[..., 0] + c * n[..., 1], -s * o[..., 0] + c * o[..., 1])
    return np.stack([phi, theta, psi], axis=-1)


def quaternion(R, check: bool = True) -> np.ndarray:
    """Euler parameters (unit quaternion) ``(w, x, y, z)`` of R, (..., 4), with w ≥ 0.

    Shepperd's method: with ``t = trace R``, the rows
    ``(1 + t, r32 − r23, r13 − r31, r21 − r12)``, ``(r32 − r23, 1 + 2 r11 − t, r12 + r21, r13 + r31)``, …
    are 4 q_k q for k = w, x, y, z; the one with the largest diagonal term (the largest
    |q_k|) is normalised, so it stays accurate at every angle, including θ = π.
    Computed by the backend's kernel (compiled, or numpy).
    """
    R = _rotations(R, check)
    flat = np.ascontiguousarray(R.reshape(-1, 3, 3), dtype=float)
    out = np.empty((len(flat), 4))
    kernels.quaternions(flat, out)
    return out.reshape(R.shape[:-2] + (4,))


def rotation_from_quaternion(q) -> np.ndarray:
    """R from a quaternion ``(w, x, y, z)`` (..., 4); it is normalised first."""
    q = vectors(q, "q", 4)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    if (norm == 0).any() or not np.isfinite(norm).all():
        raise ValueError("q must not be the zero quaternion (nor overflow)")
    w, x, y, z = np.moveaxis(q / norm, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def transform_from_quaternion(wxyz, position) -> np.ndarray:
    """The pose with rotation ``rotation_from_quaternion(wxyz)`` and translation ``position``, (..., 4, 4).

    What a gizmo reports (a quaternion and a point) as the 4x4 target the IK takes.
    One pose is built in plain Python (it is on the drag path); ``ValueError`` for a
    quaternion that is zero or not finite, or a position that is not finite.

    >>> transform_from_quaternion((0.0, 0.0, 0.0, 2.0), (0.1, 0.2, 0.3))[:3].round(6).tolist()  # half a turn about z
    [[-1.0, 0.0, 0.0, 0.1], [0.0, -1.0, 0.0, 0.2], [0.0, 0.0, 1.0, 0.3]]
    """
    if type(wxyz) is tuple and type(position) is tuple and len(wxyz) == 4 and len(position) == 3 \
            and all(isinstance(v, float) for v in wxyz + position):  # a gizmo's pose, as viser hands it over
        (w, x, y, z), (px, py, pz) = wxyz, position
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        if not (0.0 < norm < math.inf and all(map(math.isfinite, position))):
            vectors(wxyz, "wxyz", 4)  # words what is wrong
            vectors(position, "position", 3)
            raise ValueError(f"wxyz {wxyz} is not a rotation (its norm is {norm})")
        w, x, y, z = w / norm, x / norm, y / norm, z / norm
        return np.array([
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y), px],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x), py],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y), pz],
            [0.0, 0.0, 0.0, 1.0],
        ])
    R = rotation_from_quaternion(wxyz)
    position = vectors(position, "position", 3)
    T = np.zeros(np.broadcast_shapes(R.shape[:-2], position.shape[:-1]) + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = position
    T[..., 3, 3] = 1.0
    return T


def in_frame(T, points) -> np.ndarray:
    """Base-frame ``points`` (..., 3) expressed in the frame whose pose is ``T`` (4, 4): ``Rᵀ (p − o)``.

    >>> in_frame(transform_from_quaternion((1.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0)), [2.0, 0.0, 0.0]).tolist()
    [1.0, 0.0, 0.0]
    """
    T = as_float_array(T, "T")
    points = vectors(points, "points", 3)
    return (points - T[:3, 3]) @ T[:3, :3]


def from_frame(T, points) -> np.ndarray:
    """``points`` (..., 3) given in the frame whose pose is ``T`` (4, 4), expressed in the base frame:
    ``R p + o`` (the inverse of :func:`in_frame`).

    >>> from_frame(transform_from_quaternion((1.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0)), [1.0, 0.0, 0.0]).tolist()
    [2.0, 0.0, 0.0]
    """
    T = as_float_array(T, "T")
    points = vectors(points, "points", 3)
    return points @ T[:3, :3].T + T[:3, 3]


def angle_axis(R, check: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Equivalent angle–axis ``(θ, k̂)`` of R: θ (...) in [0, π], k̂ (..., 3) unit.

    From the quaternion, ``θ = 2 atan2(|(x, y, z)|, w)``, ``k̂ = (x, y, z)/|(x, y, z)|``,
    which stays accurate near θ = 0 and θ = π where Craig's
    ``k̂ = (r32 − r23, r13 − r31, r21 − r12) / (2 sin θ)`` loses precision. At θ = 0 the
    axis is undefined; k̂ = (0, 0, 1) is returned.
    """
    return angle_axis_from_quaternion(quaternion(R, check))


def angle_axis_from_quaternion(q) -> tuple[np.ndarray, np.ndarray]:
    """``(θ, k̂)`` of a unit quaternion ``(w, x, y, z)`` with w ≥ 0 (as :func:`quaternion` returns)."""
    q = vectors(q, "q", 4)
    vector = q[..., 1:]
    length = np.linalg.norm(vector, axis=-1)
    theta = 2.0 * np.arctan2(length, q[..., 0])
    safe = np.where(length > 0, length, 1.0)[..., None]
    axis = np.where(length[..., None] > 0, vector / safe, (0.0, 0.0, 1.0))
    return theta, axis


def rotation_from_angle_axis(theta, axis) -> np.ndarray:
    """Rodrigues: ``R = I + sin θ [k]x + (1 − cos θ) [k]x²`` (Craig 2.80); k̂ is normalised."""
    theta = as_float_array(theta, "theta")
    check_finite(theta, "theta")
    axis = vectors(axis, "axis", 3)
    norm = np.linalg.norm(axis, axis=-1, keepdims=True)
    if (norm == 0).any():
        raise ValueError("axis must not be the zero vector")
    kx, ky, kz = np.moveaxis(axis / norm, -1, 0)
    zero = np.zeros_like(kx)
    K = np.stack([np.stack([zero, -kz, ky], -1), np.stack([kz, zero, -kx], -1), np.stack([-ky, kx, zero], -1)], -2)
    theta = np.asarray(theta)[..., None, None]
    return np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * (K @ K)
