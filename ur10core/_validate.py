"""Validation at the boundary of the core.

Every public function of :mod:`ur10core` passes its array arguments through one of
these helpers, so a bad value is refused with a :class:`ValueError` that names the
argument, what is wrong, and (for batches) the first offending index.
"""

from __future__ import annotations

import math
from typing import NoReturn

import numpy as np

from .tolerances import BOTTOM_ROW_TOLERANCE, ROTATION_TOLERANCE

#: Looked up once: ``np.ma`` goes through numpy's module ``__getattr__`` on every use (0.1 µs a call).
_MASKED_ARRAY = np.ma.MaskedArray


def _first_index(mask: np.ndarray) -> tuple[int, ...]:
    return tuple(int(i) for i in np.argwhere(mask)[0])


def as_float_array(value, name: str) -> np.ndarray:
    """``value`` as a float64 array, or ``ValueError`` for anything that is not plainly real numbers.

    Refused: complex numbers (their imaginary part would be dropped), dates and times,
    strings, masked arrays (their mask would be ignored), and integers too large for a
    float.
    """
    if isinstance(value, _MASKED_ARRAY):
        raise ValueError(f"{name} must be a plain array of numbers, not a masked array (its mask would be ignored)")
    if type(value) is np.ndarray and value.dtype == np.float64:
        return value
    try:
        array = np.asarray(value)
        if array.dtype.kind in "iuf":
            return array.astype(float, copy=False)
        if array.dtype.kind == "O" and not any(isinstance(v, (complex, np.complexfloating, str, bytes)) for v in array.flat):
            return array.astype(float)
    except (TypeError, ValueError, OverflowError) as error:
        raise ValueError(f"{name} must be real numbers, got {value!r:.80}") from error
    kind = {"b": "true/false values", "c": "complex numbers", "M": "dates", "m": "time spans", "U": "text", "S": "bytes"}.get(array.dtype.kind, "not numbers")
    raise ValueError(f"{name} must be real numbers, got {kind}: {value!r:.80}")


def _few_values(array: np.ndarray) -> list[float] | None:
    """The values of a one-pose argument (16 at most) as plain floats, which beat a numpy reduction; else None."""
    if array.size > 16:
        return None
    return array.tolist() if array.ndim == 1 else array.ravel().tolist()


def check_finite(array: np.ndarray, name: str) -> None:
    values = _few_values(array)
    if values is not None and math.isfinite(sum(values)):
        return  # a sum that overflowed (finite values near 1e308) is checked again below
    if not np.isfinite(array).all():
        where = _first_index(~np.isfinite(array))
        raise ValueError(
            f"{name} contains a non-finite value ({float(array[where])} at index {where})"
        )


def vectors(value, name: str, size: int) -> np.ndarray:
    """Validate a float array of shape ``(..., size)`` with finite entries; returns it."""
    array = as_float_array(value, name)
    if array.ndim == 0 or array.shape[-1] != size:
        raise ValueError(f"{name} must have shape (..., {size}), got shape {array.shape}")
    check_finite(array, name)
    return array


#: Radians (or metres). A current joint value beyond this is refused where branches are turned
#: next to it: no joint turns that far, and its squared distance to a branch would overflow.
MAX_JOINT_VALUE = 1e9


def within_reason(array: np.ndarray, name: str) -> np.ndarray:
    """``array`` (finite), or ``ValueError`` where a value is beyond ±:data:`MAX_JOINT_VALUE`."""
    values = _few_values(array)
    if values is not None and max(map(abs, values), default=0.0) <= MAX_JOINT_VALUE:
        return array
    beyond = np.abs(array) > MAX_JOINT_VALUE
    if beyond.any():
        where = _first_index(beyond)
        raise ValueError(f"{name} has {float(array[where]):g} at index {where}: joint values beyond "
                         f"±{MAX_JOINT_VALUE:g} are refused (no joint turns that far)")
    return array


#: A workspace sample is at most this many joint vectors: ten million already take 0.5 GB (a
#: laptop's memory is the limit; the app asks at most a million).
MAX_SAMPLES = 10_000_000


def sample_size(n, seed) -> tuple[int, int]:
    """``(n, seed)`` of a workspace sample as ints, or ``ValueError`` naming the one that is wrong."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n must be a positive integer number of samples, got {n!r}")
    if n > MAX_SAMPLES:
        raise ValueError(f"n must be at most {MAX_SAMPLES:,} samples, got {int(n):,}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return int(n), int(seed)


def joint_vector(q, name: str = "q") -> np.ndarray:
    """Validate joint angles of shape ``(..., 6)`` in radians; returns a float array."""
    q = as_float_array(q, name)
    if q.ndim == 0 or q.shape[-1] != 6:
        raise ValueError(f"{name} must have shape (..., 6) (six joint angles), got shape {q.shape}")
    check_finite(q, name)
    return q


def one_joint_vector(q, name: str = "q") -> list[float] | None:
    """:func:`joint_vector`'s check; the six values as plain floats if ``q`` is one vector, else None.

    The drag handler's hint is one float64 vector 20 times a second: a sum of its values is
    its finiteness check, before anything more general is tried.
    """
    if type(q) is np.ndarray and q.dtype == np.float64 and q.shape == (6,):
        values = q.tolist()
        if math.isfinite(sum(values)):
            return values
    q = joint_vector(q, name)
    return q.tolist() if q.shape == (6,) else None


def homogeneous_transform(T, name: str = "T") -> np.ndarray:
    """Validate a base-to-flange pose of shape ``(..., 4, 4)``.

    Checks, in order: shape, finiteness, bottom row ``[0, 0, 0, 1]``, and that the
    rotation part is a proper rotation (orthonormal to :data:`ROTATION_TOLERANCE`,
    determinant +1).
    """
    T = as_float_array(T, name)
    if T.ndim < 2 or T.shape[-2:] != (4, 4):
        raise ValueError(f"{name} must have shape (..., 4, 4) (homogeneous transforms), got shape {T.shape}")
    check_finite(T, name)
    bottom = T[..., 3, :]
    bad_bottom = np.abs(bottom - (0.0, 0.0, 0.0, 1.0)).max(axis=-1) > BOTTOM_ROW_TOLERANCE
    if bad_bottom.any():
        where = _first_index(bad_bottom) if bad_bottom.ndim else ()
        raise ValueError(
            f"{name}{list(where) if where else ''} has bottom row {bottom[where].tolist()}, "
            "expected [0, 0, 0, 1]"
        )
    R = T[..., :3, :3]
    error = np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3)).max(axis=(-2, -1))
    not_orthonormal = error > ROTATION_TOLERANCE
    if not_orthonormal.any():
        where = _first_index(not_orthonormal) if not_orthonormal.ndim else ()
        raise ValueError(
            f"{name}{list(where) if where else ''}: rotation part is not orthonormal "
            f"(max |R^T R - I| = {error[where]:.3g} > {ROTATION_TOLERANCE:g})"
        )
    det = np.linalg.det(R)
    improper = det < 0
    if improper.any():
        where = _first_index(improper) if improper.ndim else ()
        raise ValueError(
            f"{name}{list(where) if where else ''}: rotation part has determinant "
            f"{det[where]:.6g}; a proper rotation has +1 (this one is a reflection)"
        )
    return T


def poses_and_hints(T: np.ndarray, hint: np.ndarray) -> tuple[int, ...]:
    """The leading shape poses ``T`` (..., 4, 4) and a hint (..., n) broadcast to; ``ValueError`` naming both."""
    try:
        return np.broadcast_shapes(T.shape[:-2], hint.shape[:-1])
    except ValueError:
        raise ValueError(f"hint of shape {hint.shape} does not broadcast against poses of shape {T.shape}") from None


def refuse_pose(T, index: int, batch: tuple[int, ...]) -> NoReturn:
    """Raise for the pose at flat ``index`` of poses ``T`` (leading shape ``batch``) that a kernel found invalid.

    The kernels check a pose as :func:`homogeneous_transform` does, which words what is wrong; a
    pose only they refuse (at the very limit of a tolerance) gets a plain message.
    """
    homogeneous_transform(T)
    where = list(np.unravel_index(index, batch)) if batch else ""
    raise ValueError(f"T{where} is not a proper homogeneous transform (at the tolerance limit)")


def rotation_matrix(R, name: str = "R") -> np.ndarray:
    """Validate rotation matrices of shape ``(..., 3, 3)`` (proper, orthonormal)."""
    R = as_float_array(R, name)
    if R.ndim < 2 or R.shape[-2:] != (3, 3):
        raise ValueError(f"{name} must have shape (..., 3, 3) (rotation matrices), got shape {R.shape}")
    T = np.zeros(R.shape[:-2] + (4, 4))
    T[..., :3, :3] = R
    T[..., 3, 3] = 1.0
    homogeneous_transform(T, name)
    return R
