"""A serial chain from its Denavit–Hartenberg table: FK, frames and Jacobian for any arm (docs/kinematics.md §7).

Both conventions of docs/kinematics.md §7.1 are supported, row by row:

* **standard** (Spong, Paul): ``A_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i)``; frame {i} sits on
  the axis of joint i + 1.
* **modified** (Craig): ``T(i-1, i) = Rx(α_{i-1}) Tx(a_{i-1}) Rz(θ_i) Tz(d_i)``; frame {i}
  sits on the axis of joint i. A row's ``a`` and ``alpha`` are then a_{i-1}, α_{i-1}.

A row's joint is revolute (``"R"``: θ = q + theta), prismatic (``"P"``: d = q + d) or
fixed (``None``: a constant transform such as the KR210's gripper row G). Units are
metres and radians; every function takes any leading batch shape ``...``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._validate import as_float_array, check_finite
from .differential import cross

STANDARD = "standard"
MODIFIED = "modified"
REVOLUTE = "R"
PRISMATIC = "P"
#: Metres. A DH length beyond this is refused: no arm is a thousand kilometres long, and the
#: squares of such lengths in the IK and the workspace would overflow.
MAX_LENGTH = 1e6
CONVENTIONS = (STANDARD, MODIFIED)


@dataclass(frozen=True)
class Turn:
    """A DH angle drawn as a turn: ``start`` turned about ``axis`` by ``angle`` (right hand) at ``centre``."""

    centre: np.ndarray  #: (3,)
    axis: np.ndarray  #: (3,) unit
    start: np.ndarray  #: (3,) unit, perpendicular to axis
    angle: float  #: radians

    def points(self, radius: float, count: int = 24) -> np.ndarray:
        """(count, 3) points of the arc of ``radius`` from ``start`` to the end of the turn (Rodrigues)."""
        t = np.linspace(0.0, self.angle, count)[:, None]
        side = np.cross(self.axis, self.start)
        return self.centre + radius * (np.cos(t) * self.start + np.sin(t) * side)


@dataclass(frozen=True)
class RowGeometry:
    """Where one row's four parameters are on the arm (docs/kinematics.md §7.1), base frame, metres.

    ``d`` and ``a`` are segments (2, 3) from one frame origin to the next through the
    corner between them; ``theta`` and ``alpha`` are :class:`Turn` s. Standard DH: θ about
    z_{i−1} from x_{i−1} to x_i, d along z_{i−1}, a along x_i, α about x_i from z_{i−1} to z_i;
    modified: a along x_{i−1}, α about x_{i−1}, d along z_i, θ about z_i.
    """

    values: dict[str, float]  #: a, alpha, d, theta of the row at these joints
    d: np.ndarray
    a: np.ndarray
    theta: Turn
    alpha: Turn


@dataclass(frozen=True)
class DHRow:
    """One row of a DH table. ``joint``: ``"R"``, ``"P"`` or ``None`` (a fixed row).

    For a revolute row ``theta`` is the joint's offset (θ = q + theta); for a prismatic
    row ``d`` is (d = q + d). In the modified convention ``a``, ``alpha`` are a_{i-1}, α_{i-1}.
    """

    a: float
    alpha: float
    d: float
    theta: float
    joint: str | None

    def __post_init__(self) -> None:
        for name in ("a", "alpha", "d", "theta"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) or not math.isfinite(value):
                raise ValueError(f"DH row: {name} must be a finite number, got {value!r}")
            if name in ("a", "d") and abs(value) > MAX_LENGTH:
                raise ValueError(f"DH row: {name} must be a length within ±{MAX_LENGTH:g} m, got {value!r}")
            object.__setattr__(self, name, float(value))
        if self.joint not in (REVOLUTE, PRISMATIC, None):
            raise ValueError(f"DH row: joint must be 'R' (revolute), 'P' (prismatic) or None (fixed), got {self.joint!r}")


class DHTable:
    """An arm's DH rows in one convention, and the chain they make.

    Parameters
    ----------
    rows : sequence of DHRow or of (a, alpha, d, theta, joint) tuples
        In the order base → tool.
    convention : ``"standard"`` or ``"modified"``

    Example
    -------
    A planar 2R arm with 0.5 m and 0.4 m links, standard DH:

    >>> table = DHTable([(0.5, 0, 0, 0, "R"), (0.4, 0, 0, 0, "R")], "standard")
    >>> table.fk(np.radians([90, -90]))[:3, 3].round(12).tolist()
    [0.4, 0.5, 0.0]
    """

    def __init__(self, rows, convention: str) -> None:
        if convention not in CONVENTIONS:
            raise ValueError(f"convention must be 'standard' or 'modified', got {convention!r}")
        parsed = []
        for k, row in enumerate(rows):
            if isinstance(row, DHRow):
                parsed.append(row)
                continue
            try:
                a, alpha, d, theta, joint = row
            except (TypeError, ValueError):
                raise ValueError(f"DH row {k + 1} must be (a, alpha, d, theta, joint), got {row!r:.80}") from None
            try:
                parsed.append(DHRow(a, alpha, d, theta, joint))
            except ValueError as error:
                raise ValueError(f"DH row {k + 1}: {error}".replace("DH row: ", "")) from None
        if not parsed:
            raise ValueError("a DH table needs at least one row")
        if not any(row.joint for row in parsed):
            raise ValueError("a DH table needs at least one joint (every row is fixed)")
        self.rows: tuple[DHRow, ...] = tuple(parsed)
        self.convention = convention
        self.joint_rows = tuple(k for k, row in enumerate(self.rows) if row.joint)
        #: "R" or "P" per joint, e.g. "RRPRRR" for the Stanford arm
        self.joint_types = "".join(self.rows[k].joint for k in self.joint_rows)
        self.n_joints = len(self.joint_rows)
        self._a = np.array([row.a for row in self.rows])
        self._ca = np.cos([row.alpha for row in self.rows])
        self._sa = np.sin([row.alpha for row in self.rows])
        for k, row in enumerate(self.rows):  # exact zeros at the quarter turns the tables use
            for array, value in ((self._ca, math.cos(row.alpha)), (self._sa, math.sin(row.alpha))):
                if abs(value) < 1e-15:
                    array[k] = 0.0
        self._d = np.array([row.d for row in self.rows])
        self._theta = np.array([row.theta for row in self.rows])
        self._revolute = np.array([row.joint == REVOLUTE for row in self.rows])
        self._prismatic = np.array([row.joint == PRISMATIC for row in self.rows])

    def __repr__(self) -> str:
        return f"DHTable({len(self.rows)} rows, {self.convention}, joints {self.joint_types})"

    def __eq__(self, other) -> bool:
        return isinstance(other, DHTable) and (self.rows, self.convention) == (other.rows, other.convention)

    def __hash__(self) -> int:
        return hash((self.rows, self.convention))

    # ------------------------------------------------------------------ validation

    def joints(self, q, name: str = "q") -> np.ndarray:
        """``q`` validated as joint values of shape (..., n): radians for R joints, metres for P."""
        q = as_float_array(q, name)
        if q.ndim == 0 or q.shape[-1] != self.n_joints:
            raise ValueError(f"{name} must have shape (..., {self.n_joints}) ({self.n_joints} joint "
                             f"value{'s' * (self.n_joints != 1)}, {self.joint_types}), got shape {q.shape}")
        check_finite(q, name)
        return q

    # ------------------------------------------------------------------ chain

    def row_parameters(self, q) -> tuple[np.ndarray, np.ndarray]:
        """θ and d of every row for joints ``q``: two arrays (..., rows)."""
        q = self.joints(q)
        theta = np.broadcast_to(self._theta, q.shape[:-1] + self._theta.shape).copy()
        d = np.broadcast_to(self._d, theta.shape).copy()
        joint_rows = list(self.joint_rows)
        revolute = self._revolute[joint_rows]
        theta[..., [k for k, r in zip(joint_rows, revolute) if r]] += q[..., revolute]
        d[..., [k for k, r in zip(joint_rows, revolute) if not r]] += q[..., ~revolute]
        return theta, d

    def link_transforms(self, q) -> np.ndarray:
        """Each row's transform for joints ``q``, (..., rows, 4, 4) (docs/kinematics.md §7.1).

        standard: ``Rz(θ) Tz(d) Tx(a) Rx(α)`` =
        ``[[cθ, −sθ cα, sθ sα, a cθ], [sθ, cθ cα, −cθ sα, a sθ], [0, sα, cα, d], [0, 0, 0, 1]]``;
        modified: ``Rx(α) Tx(a) Rz(θ) Tz(d)`` =
        ``[[cθ, −sθ, 0, a], [sθ cα, cθ cα, −sα, −sα d], [sθ sα, cθ sα, cα, cα d], [0, 0, 0, 1]]``.
        """
        theta, d = self.row_parameters(q)
        ct, st = np.cos(theta), np.sin(theta)
        ca, sa, a = self._ca, self._sa, self._a
        T = np.zeros(theta.shape + (4, 4))
        if self.convention == STANDARD:
            T[..., 0, 0], T[..., 0, 1], T[..., 0, 2], T[..., 0, 3] = ct, -st * ca, st * sa, a * ct
            T[..., 1, 0], T[..., 1, 1], T[..., 1, 2], T[..., 1, 3] = st, ct * ca, -ct * sa, a * st
            T[..., 2, 1], T[..., 2, 2], T[..., 2, 3] = sa, ca, d
        else:
            T[..., 0, 0], T[..., 0, 1], T[..., 0, 3] = ct, -st, a
            T[..., 1, 0], T[..., 1, 1], T[..., 1, 2], T[..., 1, 3] = st * ca, ct * ca, -sa, -sa * d
            T[..., 2, 0], T[..., 2, 1], T[..., 2, 2], T[..., 2, 3] = st * sa, ct * sa, ca, ca * d
        T[..., 3, 3] = 1.0
        return T

    def frames(self, q) -> np.ndarray:
        """Frames {0}..{rows} in the base frame, (..., rows + 1, 4, 4): ``T0i = T01 T12 ... T(i-1, i)``."""
        links = self.link_transforms(q)
        out = np.empty(links.shape[:-3] + (len(self.rows) + 1, 4, 4))
        out[..., 0, :, :] = np.eye(4)
        for k in range(len(self.rows)):
            out[..., k + 1, :, :] = out[..., k, :, :] @ links[..., k, :, :]
        return out

    def fk(self, q) -> np.ndarray:
        """Base → last-row pose, (..., 4, 4)."""
        return self.frames(q)[..., -1, :, :]

    def joint_axes(self, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each joint's axis direction and a point on it, from :meth:`frames`: two arrays (..., n, 3).

        Standard DH: joint i moves along z_{i-1} through o_{i-1}; modified DH: along z_i through o_i.
        """
        index = [k if self.convention == STANDARD else k + 1 for k in self.joint_rows]
        chosen = frames[..., index, :, :]
        return chosen[..., :3, 2], chosen[..., :3, 3]

    def jacobian(self, q) -> np.ndarray:
        """Geometric Jacobian at the last frame's origin, in the base frame, (..., 6, n), rows [v; ω].

        docs/kinematics.md §7.2: a revolute column is ``[z × (o_n − o); z]``, a prismatic one
        ``[z; 0]``, with z the joint's axis and o a point on it.
        """
        return self.jacobian_from_frames(self.frames(q))

    def jacobian_from_frames(self, frames: np.ndarray) -> np.ndarray:
        """:meth:`jacobian` from frames already computed by :meth:`frames`."""
        z, o = self.joint_axes(frames)
        tip = frames[..., -1:, :3, 3]
        revolute = np.array([self.rows[k].joint == REVOLUTE for k in self.joint_rows])
        J = np.zeros(frames.shape[:-3] + (6, self.n_joints))
        J[..., :3, :] = np.swapaxes(np.where(revolute[:, None], cross(z, tip - o), z), -1, -2)
        J[..., 3:, :] = np.swapaxes(np.where(revolute[:, None], z, 0.0), -1, -2)
        return J

    def row_geometry(self, q, row: int) -> RowGeometry:
        """Row ``row`` (1-based) of the table drawn on the arm at joints ``q`` (n,): see :class:`RowGeometry`.

        >>> table = DHTable([(0.5, 0, 0.2, 0, "R")], "standard")
        >>> g = table.row_geometry([np.pi / 2], 1)
        >>> g.d.round(12).tolist(), g.a.round(12).tolist(), round(g.theta.angle, 12)
        ([[0.0, 0.0, 0.0], [0.0, 0.0, 0.2]], [[0.0, 0.0, 0.2], [0.0, 0.5, 0.2]], 1.570796326795)
        """
        if not 1 <= row <= len(self.rows):
            raise ValueError(f"row must be 1…{len(self.rows)}, got {row!r}")
        q = self.joints(q)
        if q.ndim != 1:
            raise ValueError("row_geometry draws one pose: q must have shape (n,)")
        frames = self.frames(q)
        theta, d = (values[row - 1] for values in self.row_parameters(q))
        spec = self.rows[row - 1]
        before, after = frames[row - 1], frames[row]
        o0, o1 = before[:3, 3], after[:3, 3]
        values = {"a": spec.a, "alpha": spec.alpha, "d": float(d), "theta": float(theta)}
        if self.convention == STANDARD:
            corner = o0 + d * before[:3, 2]
            return RowGeometry(values, np.array([o0, corner]), np.array([corner, o1]),
                               Turn(o0, before[:3, 2], before[:3, 0], float(theta)),
                               Turn(o1, after[:3, 0], before[:3, 2], spec.alpha))
        corner = o0 + spec.a * before[:3, 0]
        return RowGeometry(values, np.array([corner, o1]), np.array([o0, corner]),
                           Turn(o1, after[:3, 2], before[:3, 0], float(theta)),
                           Turn(corner, before[:3, 0], before[:3, 2], spec.alpha))

    # ------------------------------------------------------------------ conventions

    def converted(self, convention: str) -> "DHTable":
        """The same chain written in the other convention (docs/kinematics.md §7.1).

        Standard rows read ``Rz(θ1) Tz(d1) | Tx(a1) Rx(α1) | Rz(θ2) Tz(d2) | Tx(a2) Rx(α2) ...``;
        regrouped as ``[Tx(a_{i-1}) Rx(α_{i-1})] [Rz(θ_i) Tz(d_i)]`` they are modified rows, and
        the last ``Tx(a_n) Rx(α_n)`` becomes a fixed row (Tx and Rx about the same axis
        commute). The other way, a first modified row with a_0 or α_0 becomes a fixed row.
        Fixed rows of length zero are dropped. The base → tool pose is the same; the
        intermediate frames move.

        >>> table = DHTable([(0.5, 0, 0, 0, "R"), (0.4, 0, 0, 0, "R")], "standard")
        >>> [(r.a, r.joint) for r in table.converted("modified").rows]
        [(0.0, 'R'), (0.5, 'R'), (0.4, None)]
        """
        if convention not in CONVENTIONS:
            raise ValueError(f"convention must be 'standard' or 'modified', got {convention!r}")
        if convention == self.convention:
            return self
        rows = self.rows
        out: list[DHRow] = []
        if self.convention == STANDARD:
            previous = (0.0, 0.0)
            for row in rows:
                out.append(DHRow(previous[0], previous[1], row.d, row.theta, row.joint))
                previous = (row.a, row.alpha)
            out.append(DHRow(previous[0], previous[1], 0.0, 0.0, None))
        else:
            first = rows[0]
            if first.a or first.alpha:
                out.append(DHRow(first.a, first.alpha, 0.0, 0.0, None))
            for k, row in enumerate(rows):
                after = rows[k + 1] if k + 1 < len(rows) else DHRow(0.0, 0.0, 0.0, 0.0, None)
                out.append(DHRow(after.a, after.alpha, row.d, row.theta, row.joint))
        out = [row for row in out if row.joint or any((row.a, row.alpha, row.d, row.theta))]
        return DHTable(out, convention)
