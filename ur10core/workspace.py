"""Cross-sections of a sampled workspace (the side and top views the course draws), and the floor check.

:meth:`Arm.sample_workspace` gives flange positions of random joint vectors. θ1 turns
the whole arm about the base axis, so a vertical section through the base axis can use
*every* sample, turned about z into the section plane by θ1 alone, instead of the few that
happen to lie in a thin slab. Where θ1 turns a full turn the workspace is a solid of
revolution about z; where it turns less (the SCARA's ±105°), a sample is kept only where θ1
can turn that far (:func:`base_turn`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ._validate import as_float_array, check_finite, sample_size
from .solvers.numerical import sampling_range
from .tolerances import FLOOR_TOLERANCE, LIMIT_TOLERANCE


def _points(points) -> np.ndarray:
    points = as_float_array(points, "points")
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must have shape (n, 3), got {points.shape}")
    check_finite(points, "points")
    return points


def base_turn(arm) -> tuple[float, float] | None:
    """The range (θ1 min, θ1 max) in rad through which ``arm``'s first joint turns the whole arm about its vertical
    axis through the base's origin (z, or the desktop arm's y: ``Arm.up``), or None where it turns a full turn or
    more (the workspace is then a solid of revolution about that axis, docs/kinematics.md §3).

    ``ValueError`` saying why where the first joint does not turn the arm about that axis: it slides, or its
    axis is tilted or off the base's origin (a typed modified table's a0 or α0).

    The points of :func:`vertical_section` and :func:`turnable_into` are in the frame ``Arm.upright`` turns the
    base frame to, whose z is that axis. The desktop arm's θ1 turns it about its y (its tool at
    (c1·r, h, −s1·r), docs/kinematics.md §8.6): there, by θ1 about z.

    >>> from ur10core import Arm
    >>> base_turn(Arm.preset("ur10")) is None, [round(math.degrees(v)) for v in base_turn(Arm.preset("scara"))]
    (True, [-105, 105])
    >>> [round(math.degrees(v)) for v in base_turn(Arm.preset("three_dof"))]
    [-90, 90]
    """
    if arm.joint_types[0] != "R":
        raise ValueError("its first joint slides: no joint turns the whole arm about the base axis")
    if arm.dh is not None:  # (a DH table's vertical is its z)
        axes, on_axes = arm.dh.joint_axes(arm.dh.frames(arm.limits.mean(axis=1)))  # (the first axis is the same at any q)
        if axes[0, 2] < 1.0 - 1e-9 or np.hypot(*on_axes[0, :2]) > 1e-9:
            raise ValueError("its first joint's axis is not the base's z axis")
    low, high = (float(v) for v in arm.limits[0])
    return None if high - low >= 2.0 * math.pi - LIMIT_TOLERANCE else (low, high)


def vertical_section(points, azimuth: float = 0.0) -> np.ndarray:
    """Every point turned about the base axis into the vertical plane at ``azimuth`` (rad).

    Alternate points go to the two halves of the plane (±ρ), so the section shows both
    sides of the base axis. Returns (n, 3): ``(ρ cos a, ρ sin a, z)`` with ρ signed. On an arm
    whose θ1 turns less than a full turn, keep only the points :func:`turnable_into` says.

    >>> vertical_section([[3.0, 4.0, 1.0], [0.0, -2.0, 0.5]]).tolist()
    [[5.0, 0.0, 1.0], [-2.0, -0.0, 0.5]]
    """
    points = _points(points)
    rho = np.hypot(points[:, 0], points[:, 1])
    rho[1::2] *= -1.0
    return np.stack([rho * np.cos(azimuth), rho * np.sin(azimuth), points[:, 2]], axis=-1)


def turnable_into(points, azimuth: float, turns, turn_range: tuple[float, float]) -> np.ndarray:
    """(n,) bool: the points of :func:`vertical_section` that θ1 alone turns into the plane at ``azimuth``, within its
    range ``turn_range`` (:func:`base_turn`); ``turns`` (n,) is each point's θ1.

    A point of the section is where the arm puts the tool with θ1 turned by the point's turn about the axis
    (into the half of the plane :func:`vertical_section` gives it); it is in the arm's workspace only if that θ1 is.

    >>> turnable_into([[3.0, 4.0, 1.0], [0.0, -2.0, 0.5]], 0.0, [0.9, -1.6], (-1.0, 1.0)).tolist()
    [True, False]
    """
    points = _points(points)
    turns = as_float_array(turns, "turns")
    if turns.shape != (len(points),):
        raise ValueError(f"turns must have shape ({len(points)},), one θ1 per point, got {turns.shape}")
    low, high = turn_range
    half = azimuth + np.where(np.arange(len(points)) % 2 == 1, math.pi, 0.0)
    turned = low + np.mod(turns + half - np.arctan2(points[:, 1], points[:, 0]) - low, 2.0 * math.pi)
    on_axis = np.hypot(points[:, 0], points[:, 1]) < 1e-12  # (any turn leaves it where it is)
    return on_axis | (turned <= high + LIMIT_TOLERANCE)


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


#: Draws each joint is tried on, to pick the joint that moves the tool onto a section's height: the first trial's,
#: and the most a trial grows to (four times over) while fewer than :data:`_TRIAL_HITS` reach it (near the top or
#: bottom of the workspace, where a first trial's joint, reaching nothing, could be one that never moves the height).
_TRIAL_DRAWS, _MOST_TRIAL_DRAWS, _TRIAL_HITS = 256, 65536, 8


def sample_horizontal_section(arm, height: float, n: int, seed: int = 0, return_joints: bool = False):
    """Up to ``n`` tool positions exactly ``height`` (m) above ``arm``'s floor (:func:`heights_above_floor`), their
    manipulability and, with ``return_joints``, their joints: :meth:`Arm.sample_horizontal_section`.

    A horizontal section of the workspace sampled in the plane itself rather than filtered from a cloud (a thin
    slab of a 200 k cloud holds a few hundred points). With the other joints held, one joint k moves the tool's
    height h along a sinusoid (a revolute joint turns all after it rigidly about its axis) or a line (a prismatic
    one slides them), docs/kinematics.md §3, "A horizontal section":

        h(θk) = K + A cos θk + B sin θk,  K = (h(0) + h(π)) / 2,  A = (h(0) − h(π)) / 2,  B = h(π/2) − K
        h(dk) = h(0) + dk (h(1) − h(0))

    so with the others drawn as :meth:`Arm.sample_joints` does, θk = atan2(B, A) ± acos((height − K) / √(A² + B²))
    (either sign at random, the other where that one is beyond the limits) or dk = (height − h(0)) / (h(1) − h(0))
    puts the tool in the plane. k is the joint that puts the tool at ``height`` from the most of 256 trial draws
    (θ2 on the UR10), or of up to 65,536 where fewer than 8 of 256 reach it; the others are drawn until ``n``
    reach the plane or 20 ``n`` have been drawn (fewer than ``n`` come back only near the top or bottom of the
    workspace). FK checks every point, and the points are put in the plane exactly. ``ValueError`` where no tool
    position is found at that height.

    Returns points (m, 3) in the base frame, m ≤ n, manipulability (m,) and the joints (m, n_joints).

    >>> from ur10core import Arm
    >>> points, _ = sample_horizontal_section(Arm.preset("course"), 0.5, 4)
    >>> points[:, 2].round(12).tolist()
    [0.5, 0.5, 0.5, 0.5]
    >>> points, _ = sample_horizontal_section(Arm.preset("three_dof"), 0.5, 2)   # y up, its shoulder 1.5 m up
    >>> points[:, 1].round(12).tolist()
    [-1.0, -1.0]
    """
    n, seed = sample_size(n, seed)
    height = as_float_array(height, "height")
    if height.ndim != 0 or not np.isfinite(height):
        raise ValueError(f"height must be one finite number (m above the floor), got {height.tolist()!r:.40}")
    height = float(height)
    up = np.asarray(arm.up, dtype=float)
    level = height - arm.base_height  # along ``up`` from the base frame's origin
    if abs(level) >= arm.reach_bound:
        raise ValueError(f"height {height:.3f} m is outside the workspace: the tool is never more than "
                         f"{arm.reach_bound:.3f} m above or below its base, which stands {arm.base_height:.3f} m "
                         f"above the floor")
    rng = np.random.default_rng(seed)
    low, high = sampling_range(arm.limits, arm.revolute)

    def draws(count: int) -> np.ndarray:
        return rng.uniform(low, high, (count, arm.n_joints))

    def onto(q: np.ndarray, k: int) -> np.ndarray:  # the draws whose joint k puts the tool at ``level``
        K, A, B = height_curve(arm, q, k)
        if arm.revolute[k]:
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = (level - K) / np.hypot(A, B)
            sign = np.where(rng.random(len(q)) < 0.5, -1.0, 1.0)
            first, second = (_into(np.arctan2(B, A) + s * np.arccos(np.clip(ratio, -1.0, 1.0)), low[k])
                             for s in (sign, -sign))
            value = np.where(first <= high[k], first, second)
            reached = (np.abs(ratio) <= 1.0) & (value <= high[k])
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                value = (level - K) / A
            reached = (value >= low[k]) & (value <= high[k])  # (NaN, where it does not move the height, is neither)
        q = q[reached]
        q[:, k] = value[reached]
        return q

    trial = draws(_TRIAL_DRAWS)
    hits = [len(onto(trial, j)) for j in range(arm.n_joints)]
    while max(hits) < _TRIAL_HITS and len(trial) < _MOST_TRIAL_DRAWS:
        trial = draws(4 * len(trial))
        hits = [len(onto(trial, j)) for j in range(arm.n_joints)]
    k = int(np.argmax(hits))
    share = max(hits[k], 1) / len(trial)  # of the draws that reach the plane: rounds are sized by it
    kept, count, drawn = [], 0, 0
    while count < n and drawn < 20 * n:  # (near the top or bottom few reach it: the draws stop there)
        size = min(int(1.2 * (n - count) / share) + 64, 20 * n - drawn, 65536)  # (FK's arrays kept small)
        q = onto(draws(size), k)
        kept.append(q)
        count, drawn = count + len(q), drawn + size
    q = np.concatenate(kept)[:n]
    points = arm.fk(q)[:, :3, 3] if len(q) else np.empty((0, 3))
    on_plane = np.abs(points @ up - level) <= 1e-9 * max(1.0, arm.reach_bound)  # (the sinusoid and the line hold)
    q, points = q[on_plane], points[on_plane]
    if not len(q):
        raise ValueError(f"height {height:.3f} m: no tool position found at that height (beyond the top or bottom of "
                         f"the workspace, or a tool that does not move up and down)")
    points += (level - points @ up)[:, None] * up  # exact, not FK's last bit
    manipulability = arm.manipulability(q)
    return (points, manipulability, q) if return_joints else (points, manipulability)


def height_curve(arm, q, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """How joint ``k`` moves the tool's height (along ``arm.up`` from the base frame's origin) from each of the joint
    vectors ``q`` (m, n), the others held: (K, A, B) (m,) of h(θk) = K + A cos θk + B sin θk for a revolute joint,
    (h(0), slope, None) of h(dk) = h(0) + slope · dk for a prismatic one (:func:`sample_horizontal_section`).

    >>> from ur10core import Arm
    >>> [v.round(4).tolist() for v in height_curve(Arm.preset("course"), np.zeros((1, 6)), 1)]   # §3: d1, Q, P
    [[0.128], [0.1157], [1.1845]]
    """
    up = np.asarray(arm.up, dtype=float)

    def along(value: float) -> np.ndarray:
        moved = q.copy()
        moved[:, k] = value
        return arm.fk(moved)[:, :3, 3] @ up

    if not arm.revolute[k]:
        h0 = along(0.0)
        return h0, along(1.0) - h0, None
    h0, h90, h180 = along(0.0), along(math.pi / 2), along(math.pi)
    return (h0 + h180) / 2, (h0 - h180) / 2, h90 - (h0 + h180) / 2


def _into(angles: np.ndarray, low: float) -> np.ndarray:
    """``angles`` turned by whole turns into [low, low + 2π)."""
    return low + np.mod(angles - low, 2.0 * math.pi)


@functools.lru_cache(maxsize=32)
def tool_heights(arm) -> tuple[float, float]:
    """(lowest, highest) height of ``arm``'s tool above its floor (m) among 20 000 joint vectors drawn within its
    limits (:meth:`Arm.sample_joints`): :attr:`Arm.tool_heights`.

    A sample misses the very top and bottom, where a section is a speck (the UR10's by 8 mm, docs/kinematics.md §3),
    so a horizontal section is found at every height between the two. One height, twice, for an arm whose tool
    moves in one horizontal plane.
    """
    heights = heights_above_floor(arm, arm.fk(arm.sample_joints(20_000))[:, :3, 3])
    return float(heights.min()), float(heights.max())


def through_floor(arm, q, body_points=None, tolerance: float = FLOOR_TOLERANCE) -> np.ndarray:
    """(...,) bool: at joints ``q`` (..., n) some body point of the arm is below its floor
    (:func:`heights_above_floor`: z = 0 for an arm standing on it).

    ``body_points`` (L, P, 3) as for :func:`lowest_points`; the frame origins alone by default.

    >>> from ur10core import Arm
    >>> arm = Arm.preset("ur10")
    >>> through_floor(arm, np.radians([[0, 60, 0, 0, 0, 0], [0, -90, 0, -90, 0, 0]])).tolist()   # up, then down
    [False, True]
    >>> desk = Arm.preset("three_dof")                       # y up, its shoulder 1.5 m above the floor
    >>> through_floor(desk, np.radians([[-60, 0, 135], [0, 90, -90]])).tolist()   # the tool at z < 0; 2.6 m down
    [False, True]
    """
    frames = arm.frames(q)
    points = np.zeros((frames.shape[-3], 1, 3)) if body_points is None else body_points
    return heights_above_floor(arm, lowest_points(frames, points, arm.up)) < -tolerance


def heights_above_floor(arm, points) -> np.ndarray:
    """(...,) how high the base-frame ``points`` (..., 3) stand above the arm's floor: along :attr:`Arm.up`,
    from :attr:`Arm.base_height` below its base frame's origin.

    >>> from ur10core import Arm
    >>> heights_above_floor(Arm.preset("three_dof"), [[0.0, -1.0, -2.0]]).tolist()   # y up, the shoulder 1.5 m up
    [0.5]
    """
    return np.asarray(points, dtype=float) @ np.asarray(arm.up, dtype=float) + arm.base_height


def lowest_points(frames, body_points, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """The lowest point of an arm's bodies along ``up``, in the base frame: is the arm through the floor?

    docs/kinematics.md §3, "The floor".

    Parameters
    ----------
    frames : array_like, shape (..., L, 4, 4)
        Each body's frame in the base frame (:meth:`Arm.frames`: L = 7, frames {0}..{6}).
    body_points : array_like, shape (L, P, 3)
        P points of each body in its own frame, e.g. the corners of its convex hull
        (repeat a point to give every body the same P).
    up : array_like, shape (3,)
        The vertical in the base frame (:attr:`Arm.up`: z, the desktop arm's y).

    Returns
    -------
    (..., 3) array
        Per arm, the body point lowest along ``up``: ``min over l, p of up · (T_l · p)``.

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
    # the height of every point first (up · R, one row a body): only the lowest point is turned in full
    lead, bodies, count = frames.shape[:-3], frames.shape[-3], body_points.shape[1]
    frames = frames.reshape(-1, bodies, 4, 4)
    along = (np.asarray(up, dtype=float) @ frames[:, :, :3, :])[:, :, None, :]  # (N, L, 1, 4): up · [R | t]
    heights = (along[..., :3] @ body_points.transpose(0, 2, 1))[:, :, 0] + along[..., 3]  # (N, L, P)
    body, point = np.divmod(heights.reshape(len(frames), -1).argmin(axis=1), count)
    T = frames[np.arange(len(frames)), body]
    lowest = (T[:, :3, :3] @ body_points[body, point][..., None])[..., 0] + T[:, :3, 3]
    return lowest.reshape(lead + (3,))


MAP_PLANES = ("vertical", "horizontal")


@dataclass(frozen=True)
class BranchCountMap:
    """How many IK branches reach each point of a square in a plane, the tool turned as given.

    Cell (r, c) is centred at ``centre + (c − (n − 1)/2)·cell·u − (r − (n − 1)/2)·cell·v``:
    row 0 is the square's top edge (+v), column 0 its left edge (−u), as an image is read.
    """

    centre: np.ndarray  #: (3,) the middle of the square, m
    u: np.ndarray  #: (3,) unit vector along the rows
    v: np.ndarray  #: (3,) unit vector up the columns
    size: float  #: side of the square, m
    counts: np.ndarray  #: (n, n) int8, valid IK slots at each cell's centre (0…8)

    @property
    def cell(self) -> float:
        return self.size / self.counts.shape[0]

    def points(self) -> np.ndarray:
        """(n, n, 3) the cell centres, in the base frame."""
        n = self.counts.shape[0]
        offsets = (np.arange(n) - (n - 1) / 2) * self.cell
        return self.centre + offsets[None, :, None] * self.u - offsets[:, None, None] * self.v


def map_extent(arm) -> tuple[float, float]:
    """(height on the base axis, half-width): the square a branch-count map covers, about any arm's workspace.

    For the UR family, the shoulder's height d1, and a2 + a3 + d5 + d6: no flange lies farther
    from the shoulder. For any other arm, from 4 000 samples of its workspace (seed 0): the
    middle of their heights, and the farthest of them from the base axis or from that middle
    height, with 5 % to spare (samples reach a little short of the boundary). Heights are
    along the arm's vertical (``arm.up``: z, or y for the course's desktop arm).
    """
    if all(hasattr(arm, name) for name in ("d1", "a2", "a3", "d5", "d6")):
        return arm.d1, abs(arm.a2) + abs(arm.a3) + abs(arm.d5) + abs(arm.d6)
    return _sampled_extent(arm)


@functools.lru_cache(maxsize=32)
def _sampled_extent(arm) -> tuple[float, float]:
    points, _ = arm.sample_workspace(4000, seed=0)
    up = np.asarray(getattr(arm, "up", (0.0, 0.0, 1.0)))
    heights = points @ up
    low, high = float(heights.min()), float(heights.max())
    middle = 0.5 * (low + high)
    across = np.linalg.norm(points - heights[:, None] * up, axis=1)
    return middle, 1.05 * max(float(across.max()), 0.5 * (high - low))


def branch_count_map(arm, target, plane: str = "vertical", resolution: int = 200) -> BranchCountMap:
    """For the orientation R of ``target``, the number of IK branches reaching each point of a plane through it.

    docs/kinematics.md §4.2, "Where each orientation can be reached". Every cell of an
    n × n grid asks the arm's IK for T = [R, p; 0, 1] with p the cell's centre, and
    counts its valid slots within the joint limits: 0 (out of reach with this orientation); for the UR family, 2 for
    each of the four (shoulder, wrist) pairs whose elbow reaches: 2, 4, 6 or 8.

    Parameters
    ----------
    arm : Arm or Arm
        Any arm with a closed-form IK (one call solves the whole grid); the square it
        covers is :func:`map_extent`.
    target : array_like, shape (4, 4)
        The target pose: its rotation is the orientation asked for everywhere (what of
        it the arm controls: ``arm.task``), its position a point of the plane.
    plane : {"vertical", "horizontal"}
        "vertical": the plane holding the base axis and the target (the arm's own plane
        when θ1 points at it), u horizontal towards the target, v up; "horizontal": the
        plane through the target square to the vertical, u = x, v = up × x (for z up, y). Either way a square centred on the base
        axis, as wide as the arm's longest reach each side (the vertical one centred at
        the shoulder's height d1).
    resolution : int
        n, cells per side (n² IK calls, vectorised).

    Returns
    -------
    BranchCountMap

    >>> from ur10core import Arm
    >>> arm = Arm.preset("course")
    >>> reach = branch_count_map(arm, arm.fk(np.radians([30, 45, 26, 50, 60, 80])), resolution=9)
    >>> np.bincount(reach.counts.ravel(), minlength=9).tolist()  # cells with 0, 1, …, 8 branches
    [38, 0, 4, 0, 6, 0, 2, 0, 31]
    """
    from ._validate import homogeneous_transform

    target = homogeneous_transform(target, "target")
    if target.shape != (4, 4):
        raise ValueError(f"target must be one pose of shape (4, 4), got {target.shape}")
    if plane not in MAP_PLANES:
        raise ValueError(f"plane must be one of {MAP_PLANES}, got {plane!r}")
    if isinstance(resolution, bool) or not isinstance(resolution, (int, np.integer)) or not 2 <= resolution <= 1000:
        raise ValueError(f"resolution must be an integer number of cells per side in [2, 1000], got {resolution!r}")
    height, reach = map_extent(arm)
    size = 2.0 * (reach + 0.05)
    position = target[:3, 3]
    up = np.asarray(getattr(arm, "up", (0.0, 0.0, 1.0)), dtype=float)  # the arm's vertical
    across = np.array([1.0, 0.0, 0.0])  # a horizontal axis of every arm's base frame
    if plane == "vertical":
        towards = position - (position @ up) * up
        length = np.linalg.norm(towards)
        u = towards / length if length > 1e-9 else across  # on the axis: any vertical plane holds it
        v = up
        centre = height * up
    else:
        u, v = across, np.cross(up, across)  # so that u × v = up: the map is seen from above
        centre = (position @ up) * up
    grid = BranchCountMap(centre, u, v, size, np.zeros((resolution, resolution), np.int8))
    poses = np.broadcast_to(target, (resolution * resolution, 4, 4)).copy()
    poses[:, :3, 3] = grid.points().reshape(-1, 3)
    solution = arm.ik(poses)
    reached = solution.valid & getattr(solution, "within_limits", True)  # a course arm's joint limits bind
    counts = reached.sum(axis=-1).astype(np.int8)
    return BranchCountMap(centre, u, v, size, counts.reshape(resolution, resolution))


def revolved_boundary(points, bins: int = 48) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The surfaces bounding a workspace that is a solid of revolution about z, from samples of it.

    For an arm whose θ1 turns the whole arm a full turn about the base axis (:func:`base_turn`
    is None): its workspace is then bounded by an outer surface and an inner one (the hole
    about the axis) that are both surfaces of revolution: at each height, the largest and
    smallest distance ρ = √(x² + y²) of a sample from the axis. Sampled, both are estimates
    from inside: the more samples, the closer (200 k samples put the UR10's hole at 72 mm =
    d4 − d6 to the millimetre).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Samples of the workspace (:meth:`Arm.sample_workspace`).
    bins : int
        Height slices, from the lowest sample to the highest.

    Returns
    -------
    heights, inner, outer : (m,) arrays, m ≤ bins
        For each slice holding samples: its middle height (the first and last slices at
        the lowest and highest sample instead, so the surfaces close the whole cloud),
        the smallest and the largest ρ in it.

    >>> heights, inner, outer = revolved_boundary([[1, 0, 0], [0, 2, 0], [0.5, 0, 1], [0, -3, 1]], bins=2)
    >>> heights.tolist(), inner.tolist(), outer.tolist()
    ([0.0, 1.0], [1.0, 0.5], [2.0, 3.0])
    """
    points = _points(points)
    if isinstance(bins, bool) or not isinstance(bins, (int, np.integer)) or bins < 2:
        raise ValueError(f"bins must be an integer ≥ 2, got {bins!r}")
    if len(points) == 0:
        raise ValueError("points is empty: there is no workspace to bound")
    rho, z = np.hypot(points[:, 0], points[:, 1]), points[:, 2]
    low, high = float(z.min()), float(z.max())
    if high - low < 1e-12:
        raise ValueError("the points all lie at one height: a revolved boundary needs some height")
    slice_of = np.minimum(((z - low) / (high - low) * bins).astype(int), bins - 1)
    count = np.bincount(slice_of, minlength=bins)
    inner = np.full(bins, np.inf)
    outer = np.full(bins, -np.inf)
    np.minimum.at(inner, slice_of, rho)
    np.maximum.at(outer, slice_of, rho)
    heights = low + (np.arange(bins) + 0.5) * (high - low) / bins
    heights[0], heights[-1] = low, high
    held = count > 0
    return heights[held], inner[held], outer[held]
