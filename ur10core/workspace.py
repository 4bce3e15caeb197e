"""Cross-sections of a sampled workspace (the side and top views the course draws), and the floor check.

:meth:`Arm.sample_workspace` gives flange positions of random joint vectors. θ1 turns
the whole arm about the base axis, so the workspace is a solid of revolution about z:
a vertical section through the base axis can use *every* sample, turned about z into
the section plane, instead of the few that happen to lie in a thin slab.
"""

from __future__ import annotations

import numpy as np

from ._validate import as_float_array, check_finite


def _points(points) -> np.ndarray:
    points = as_float_array(points, "points")
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must have shape (n, 3), got {points.shape}")
    check_finite(points, "points")
    return points


def vertical_section(points, azimuth: float = 0.0) -> np.ndarray:
    """Every point turned about the base axis into the vertical plane at ``azimuth`` (rad).

    Alternate points go to the two halves of the plane (±ρ), so the section shows both
    sides of the base axis. Returns (n, 3): ``(ρ cos a, ρ sin a, z)`` with ρ signed.

    >>> vertical_section([[3.0, 4.0, 1.0], [0.0, -2.0, 0.5]]).tolist()
    [[5.0, 0.0, 1.0], [-2.0, -0.0, 0.5]]
    """
    points = _points(points)
    rho = np.hypot(points[:, 0], points[:, 1])
    rho[1::2] *= -1.0
    return np.stack([rho * np.cos(azimuth), rho * np.sin(azimuth), points[:, 2]], axis=-1)


def horizontal_section(points, height: float, thickness: float = 0.02) -> tuple[np.ndarray, np.ndarray]:
    """The points within ``thickness / 2`` of the plane z = ``height`` (metres), flattened onto it.

    Returns the flattened points (m, 3) and the boolean mask (n,) of the points kept
    (to select their colours, say).

    >>> section, kept = horizontal_section([[1.0, 0.0, 0.505], [1.0, 0.0, 0.6]], height=0.5)
    >>> section.tolist(), kept.tolist()
    ([[1.0, 0.0, 0.5]], [True, False])
    """
    points = _points(points)
    height, thickness = float(as_float_array(height, "height")), float(as_float_array(thickness, "thickness"))
    if not np.isfinite(height) or not np.isfinite(thickness) or thickness <= 0:
        raise ValueError(f"height must be finite and thickness positive, got {height!r}, {thickness!r}")
    keep = np.abs(points[:, 2] - height) <= thickness / 2
    out = points[keep].copy()
    out[:, 2] = height
    return out, keep


def lowest_points(frames, body_points) -> np.ndarray:
    """The lowest point of an arm's bodies, in the base frame: is the arm through the floor (z < 0)?

    docs/kinematics.md §3, "The floor".

    Parameters
    ----------
    frames : array_like, shape (..., L, 4, 4)
        Each body's frame in the base frame (:meth:`Arm.frames`: L = 7, frames {0}..{6}).
    body_points : array_like, shape (L, P, 3)
        P points of each body in its own frame, e.g. the corners of its convex hull
        (repeat a point to give every body the same P).

    Returns
    -------
    (..., 3) array
        Per arm, the body point with the smallest base-frame z: ``min over l, p of T_l · p``.

    >>> frames = np.tile(np.eye(4), (2, 1, 1))
    >>> frames[1, :3, 3] = [1.0, 0.0, -0.25]
    >>> lowest_points(frames, [[[0.0, 0.0, 0.1]], [[0.0, 0.0, 0.05]]]).tolist()
    [1.0, 0.0, -0.2]
    """
    frames = as_float_array(frames, "frames")
    body_points = as_float_array(body_points, "body_points")
    if frames.shape[-2:] != (4, 4) or frames.ndim < 3:
        raise ValueError(f"frames must have shape (..., L, 4, 4), got {frames.shape}")
    if body_points.ndim != 3 or body_points.shape[0] != frames.shape[-3] or body_points.shape[2] != 3:
        raise ValueError(f"body_points must have shape ({frames.shape[-3]}, P, 3), got {body_points.shape}")
    check_finite(frames, "frames")
    check_finite(body_points, "body_points")
    # z of every point first (one row of each rotation): only the lowest point is turned in full
    lead, bodies, count = frames.shape[:-3], frames.shape[-3], body_points.shape[1]
    frames = frames.reshape(-1, bodies, 4, 4)
    heights = (frames[:, :, 2, None, :3] @ body_points.transpose(0, 2, 1))[:, :, 0] + frames[:, :, 2, 3, None]  # (N, L, P)
    body, point = np.divmod(heights.reshape(len(frames), -1).argmin(axis=1), count)
    T = frames[np.arange(len(frames)), body]
    lowest = (T[:, :3, :3] @ body_points[body, point][..., None])[..., 0] + T[:, :3, 3]
    return lowest.reshape(lead + (3,))
