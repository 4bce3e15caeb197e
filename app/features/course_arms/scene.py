"""The course arm in 3D: its DH skeleton, joint axes, DH frames with their labels, and one ghost per branch.

The arm is drawn as the DH method builds it: from each frame origin to the next along d
and a (:func:`skeleton`), a short rod along each joint axis (a box for a prismatic joint),
and, optionally, the x and z axes of every frame with their names (:mod:`..dh_frames`). Each IK slot is a ghost skeleton in
its slot colour with balls at its joints (a click on one puts the arm on that branch) and its number by the joint
where the branches part, as the UR10's ghosts are by their elbows.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import trimesh
import viser

from ur10core import Arm
from ur10core.dh import DHTable
from ur10core.orientation import from_frame, quaternion

from ...state import Snapshot
from ...style import JOINT_CAP_GREY, SLOT_COLORS
from ...viser_internals.fast_updates import set_orientations, set_positions
from ..branch_labels import BranchLabels, chain
from ..dh_frames import DHFrames, show
from ..ik_target import ALL_BRANCHES, SAME_POSE, add_unreachable_halo, focused, numbered, one_ghost_per_pose, same_pose_groups
from ..singularity import SingularityOverlay, has_overlay

ROOT = "/course_arm"
#: An explorer's own arm in a classroom, apart from the class's (which it hides in that one browser).
EXPLORER_ROOT = "/explored_arm"
SKELETON_GREY = (60, 62, 68)


class Framed(NamedTuple):
    """What the camera frames of an arm placed in the world (``LineDrawing.framed``), in the world."""

    frames: np.ndarray  #: (m, 4, 4) the joints to keep in view: the arm's, its branches', its pedestal's foot
    target: np.ndarray  #: (4, 4)
    lowest: tuple[np.ndarray]  #: its lowest point (3,)


def world_placement(arm: Arm) -> np.ndarray:
    """(4, 4) the arm's base frame in the app's world (z up, the floor z = 0): turned so that its vertical
    (``arm.up``) is z, and raised ``arm.base_height`` (a table that starts at the shoulder: a pedestal under it)."""
    world = np.eye(4)
    world[:3, :3] = arm.upright
    world[2, 3] = arm.base_height
    return world


def skeleton(table: DHTable, frames: np.ndarray) -> np.ndarray:
    """(m, 2, 3) segments of the DH construction, zero-length ones dropped (at least one kept).

    Each row goes from one frame origin to the next in two straight moves, as the row's
    transform does: standard DH along z_{i−1} by d_i, then along x_i by a_i; modified DH
    along x_{i−1} by a_{i−1}, then along z_i by d_i.
    """
    origins = frames[..., :3, 3]
    points = [origins[0]]
    for i, row in enumerate(table.rows, start=1):
        if table.convention == "standard":
            corner = origins[i] - row.a * frames[i, :3, 0]
        else:
            corner = origins[i - 1] + row.a * frames[i - 1, :3, 0]
        points += [corner, origins[i]]
    points = np.array(points)
    segments = np.stack([points[:-1], points[1:]], axis=-2)
    long = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=-1) > 1e-9
    return segments[long] if long.any() else segments[:1]


def middle_frame(arm: Arm) -> int:
    """The frame at the arm's middle joint (its third, or its last of fewer)."""
    return arm.dh.joint_rows[min(2, arm.n_joints - 1)] + (0 if arm.convention == "standard" else 1)


def label_frame(arm: Arm, snapshot: Snapshot) -> int | None:
    """The frame by whose origin each branch's number goes: the one at which most of ``snapshot``'s branches
    are apart (the SCARA's elbow, not its wrist, which both its branches share), the middle joint where that
    is one of them; None where they are apart nowhere (one branch, or all together on a singularity)."""
    origins = snapshot.ghost_frames[snapshot.solution.valid, :, :3, 3]
    pairs_apart = (np.linalg.norm(origins[:, None] - origins[None], axis=-1) > SAME_POSE).sum(axis=(0, 1))
    if not pairs_apart.any():
        return None
    middle = middle_frame(arm)
    return middle if pairs_apart[middle] == pairs_apart.max() else int(pairs_apart.argmax())


def none_of(items: np.ndarray, others: np.ndarray) -> np.ndarray:
    """(m,) bool: which of ``items`` (m, ...) is none of ``others`` (n, ...), to a micrometre.

    >>> none_of(np.array([[0.0, 0.0], [1.0, 2.0]]), np.array([[1.0, 2.0 + 1e-9]])).tolist()
    [True, False]
    """
    gaps = np.abs(items[:, None] - others[None]).reshape(len(items), len(others), -1).max(axis=-1)
    return gaps.min(axis=1) > 1e-6


def rod_rotations(axes: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations whose z columns are the unit ``axes`` (n, 3): how each joint's rod is turned."""
    helper = np.where(np.abs(axes[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    x = np.cross(helper, axes)
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    return np.stack([x, np.cross(axes, x), axes], axis=-1)


class LineDrawing:
    """What the course's line drawings share (the interface of ``..drawings``): ghosts shown as chosen, a target marker."""

    names: tuple[str, ...] = ()  #: one way to draw it: no "Arm drawn as"
    show_ghosts = True
    focus = ALL_BRANCHES
    on_select = None  #: called with (browser, slot) when a ball at a ghost's joint is clicked (the IK target sets it)
    clicked = "a ball at a ghost's joint"  #: what a student clicks to put the arm on a ghost's branch
    overlay = None  #: det J's factors in 3D, where the arm has them
    target = unreachable = None
    top: str
    root: str
    size: float
    world: np.ndarray
    foot: np.ndarray

    @property
    def roots(self) -> tuple[str, ...]:
        return (self.top,)

    def _place(self, scene: viser.SceneApi, arm: Arm, top: str) -> None:
        """Hang the drawing from ``top`` (a classroom explorer's own arm has one apart from the class's): every
        node under :attr:`root`, the IK target and the features' drawings included, is in the arm's base frame,
        which a node of its own places in the world where it is not the world's (:func:`world_placement`)."""
        self.top = self.root = top
        self.world = world_placement(arm)
        #: (3,) the floor under its base frame's origin, in that frame: where a pedestal stands (the origin itself
        #: for an arm standing on the floor)
        self.foot = -arm.base_height * np.asarray(arm.up, dtype=float)
        if not np.array_equal(self.world, np.eye(4)):
            self.root = f"{top}/base_frame"
            scene.add_frame(self.root, wxyz=quaternion(self.world[:3, :3], check=False), position=self.world[:3, 3],
                            show_axes=False)

    def framed(self, snapshot: Snapshot) -> Snapshot | Framed:
        """What the camera frames: the arm's frames and its branches' (from its pedestal's foot), and its target,
        in the world."""
        if np.array_equal(self.world, np.eye(4)):
            return snapshot
        valid = snapshot.solution.valid if snapshot.solution is not None else np.zeros(len(snapshot.ghost_frames), bool)
        frames = self.world @ np.concatenate([snapshot.frames[None], snapshot.ghost_frames[valid]]).reshape(-1, 4, 4)
        foot = np.eye(4)
        foot[:3, 3] = from_frame(self.world, self.foot)
        return Framed(np.concatenate([foot[None], frames]), self.world @ snapshot.target, (foot[:3, 3],))

    def _label_sets(self, pools: tuple[BranchLabels, ...]) -> tuple[BranchLabels, ...]:
        """``pools`` placed in order, each clear of those before it (``chain``), in the arm's base frame placed in the world."""
        for labels in pools:
            labels.world = self.world
        return chain(pools)

    @property
    def handle_size(self) -> float:
        """The reach (m) what a student grabs or spots is sized by (the IK target's gizmo, marker and halo, the force's
        handle): the arm's own, as the camera frames it."""
        return self.size

    @property
    def body_radius(self) -> float:
        """Room the camera keeps around each joint (the rods and the gizmo scale with the reach)."""
        return 0.15 * self.size

    def _add_target_marker(self, scene: viser.SceneApi) -> None:
        """The target, drawn for the shared scene (only the presenter has a gizmo)."""
        name = f"{self.root}/target_marker"
        self.target = scene.add_frame(name, axes_length=0.08 * self.handle_size, axes_radius=0.004 * self.handle_size)
        self.unreachable = add_unreachable_halo(scene, name, self.handle_size)

    def _render_target(self, snapshot: Snapshot) -> None:
        if self.target is not None:
            self.target.wxyz = quaternion(snapshot.target[:3, :3], check=False)
            self.target.position = snapshot.target[:3, 3]
            show(self.unreachable, not snapshot.reachable)

    def shown_ghosts(self, snapshot: Snapshot, count: int) -> np.ndarray:
        """(count,) bool: the ghosts to draw, as the snapshot and the "Ghosts shown" choice say, one per pose: of
        branches that coincide, the lead one, which its number names and a click takes (``ik_target.one_ghost_per_pose``)."""
        if not (self.show_ghosts and snapshot.ghosts.any()):
            return np.zeros(count, bool)
        groups = same_pose_groups(snapshot.ghost_frames, snapshot.solution.valid)
        return one_ghost_per_pose(snapshot, groups, focused(self.focus, snapshot.slot, snapshot.arm))

    def render_panel(self, snapshot: Snapshot) -> None:
        """The DH axes' names and the branch numbers, placed apart on the screen, at the panel's pace."""
        for labelled in (self.overlay, self.dh_frames):  # before the numbers, which keep clear of them
            if labelled is not None:
                labelled.render_panel(snapshot)
        if snapshot.solution is None:  # a typed table not searched yet: no branches to number
            self.numbers.show(np.zeros((0, 3)), [])
            return
        self.numbers.show(self._ghost_labels(snapshot), numbered(snapshot, self.show_ghosts, self.focus))

    def _add_ghosts(self, scene: viser.SceneApi, arm: Arm, frames: np.ndarray, thickness: float, ball: float) -> None:
        """One skeleton per slot in its colour, a ball of diameter ``ball`` at each of its joints, and the numbers
        (hidden until a branch is there). The balls are one batched mesh, slot by slot: viser reports a click on a
        mesh, not on a line, so they are what a student clicks to take a ghost's branch."""
        slots = len(arm.slot_labels)
        colours = [SLOT_COLORS[k % len(SLOT_COLORS)] for k in range(slots)]
        self.ghosts = [scene.add_line_segments(f"{self.root}/ghosts/slot{k + 1}", self._ghost_lines(frames), colours[k],
                                               thickness=thickness, visible=False) for k in range(slots)]
        self.joints_per_ghost = len(self._ghost_joints(frames))
        balls = slots * self.joints_per_ghost
        sphere = trimesh.creation.icosphere(subdivisions=2, radius=ball / 2)
        self.ghost_joints = scene.add_batched_meshes_simple(
            f"{self.root}/ghosts/joints", sphere.vertices, sphere.faces, batched_wxyzs=np.tile([1.0, 0.0, 0.0, 0.0], (balls, 1)),
            batched_positions=np.zeros((balls, 3)), batched_scales=np.zeros(balls),
            batched_colors=np.repeat(np.array(colours, dtype=np.uint8), self.joints_per_ghost, axis=0),
            lod="off", cast_shadow=False, receive_shadow=False)
        self.ghost_joints.on_click(self._ball_clicked)
        self.numbers = BranchLabels(scene, f"{self.root}/ghosts", slots, colours=colours)
        self.label_sets = (self.numbers,)

    def _ball_clicked(self, event) -> None:
        if self.on_select is not None and event.instance_index is not None:
            self.on_select(event.client, int(event.instance_index) // self.joints_per_ghost)

    def _render_ghosts(self, snapshot: Snapshot) -> None:
        """The target marker, and each branch shown as the drawing draws an arm (``_ghost_lines``), with
        its joints (``_ghost_joints``); what lies on the solid arm is left to it (the two would flicker, and
        a ghost's ball on the arm's joint would colour the arm as that branch's)."""
        self._render_target(snapshot)
        shown = self.shown_ghosts(snapshot, len(self.ghosts))
        positions = np.zeros((len(self.ghosts), self.joints_per_ghost, 3), np.float32)
        scales = np.zeros((len(self.ghosts), self.joints_per_ghost), np.float32)
        solid, solid_joints = self._ghost_lines(snapshot.frames), self._ghost_joints(snapshot.frames)
        for k in np.flatnonzero(shown):
            lines = self._ghost_lines(snapshot.ghost_frames[k])
            own = none_of(lines, solid)
            shown[k] = own.any()
            if shown[k]:
                self.ghosts[k].points = lines[own]
                positions[k] = self._ghost_joints(snapshot.ghost_frames[k])
                scales[k] = none_of(positions[k], solid_joints)
        for ghost, show_it in zip(self.ghosts, shown):
            show(ghost, show_it)
        if scales.tobytes() != self.ghost_joints.batched_scales.tobytes():
            self.ghost_joints.batched_scales = scales.reshape(-1)
        if scales.any():
            self.ghost_joints.batched_positions = positions.reshape(-1, 3)


class CourseArmScene(LineDrawing):
    """Everything one course arm draws in a browser's scene."""

    def __init__(self, scene: viser.SceneApi, arm: Arm, first: Snapshot, size: float,
                 root: str = ROOT, target_marker: bool = False) -> None:
        self._scene = scene
        self._place(scene, arm, root)
        root = self.root
        self._arm = arm
        self.size = size  #: the arm's reach (m): sizes of rods, axes and the gizmo follow it
        segments = skeleton(arm.dh, first.frames)
        self.body = scene.add_line_segments(f"{root}/body", segments, SKELETON_GREY, thickness=0.012 * size)
        #: where its table starts at the shoulder (the Stanford arm's), the pedestal it stands on, up to its base frame
        self.pedestal = scene.add_line_segments(f"{root}/pedestal", np.array([[self.foot, np.zeros(3)]]), SKELETON_GREY,
                                                thickness=0.03 * size) if arm.base_height else None
        self.joints = []
        for k, kind in enumerate(arm.joint_types):
            if kind == "R":
                rod = scene.add_cylinder(f"{root}/joint{k + 1}", radius=0.018 * size, height=0.06 * size,
                                         color=JOINT_CAP_GREY)
            else:
                rod = scene.add_box(f"{root}/joint{k + 1}", color=JOINT_CAP_GREY,
                                    dimensions=(0.03 * size, 0.03 * size, 0.06 * size))
            self.joints.append(rod)
        #: the DH frames, x and z named, and a row's parameters (the DH folders switch them)
        self.dh_frames = DHFrames(scene, arm, first.frames, size, root)
        self._label_frame: int | None = None  #: chosen from the first branches apart (a typed table's come with its search)
        self._add_ghosts(scene, arm, first.frames, 0.009 * size, 0.04 * size)
        #: det J's factors in 3D (a preset's; a typed table's det J is not derived)
        self.overlay = SingularityOverlay(scene, arm, first, size, root) if has_overlay(arm) else None
        #: the 3D labels placed apart for a camera, in order, each pool clear of those before it
        self.label_sets = self._label_sets(((self.overlay.names,) if self.overlay is not None else ())
                                           + (self.dh_frames.values, self.dh_frames.names, self.numbers))
        if target_marker:
            self._add_target_marker(scene)

    def render(self, snapshot: Snapshot) -> None:
        frames = snapshot.frames
        self.body.points = skeleton(self._arm.dh, frames)
        z, o = self._arm.dh.joint_axes(frames)
        set_orientations(self.joints, quaternion(rod_rotations(z), check=False))
        set_positions(self.joints, o)
        self.dh_frames.render(snapshot)
        if self.overlay is not None:
            self.overlay.render(snapshot)
        self._render_ghosts(snapshot)

    def _ghost_lines(self, frames: np.ndarray) -> np.ndarray:
        return skeleton(self._arm.dh, frames)

    def _ghost_labels(self, snapshot: Snapshot) -> np.ndarray:
        if self._label_frame is None:  # chosen once the branches are apart somewhere, kept from then on
            self._label_frame = label_frame(self._arm, snapshot)
        frame = self._label_frame if self._label_frame is not None else middle_frame(self._arm)
        return snapshot.ghost_frames[:, frame, :3, 3]

    def _ghost_joints(self, frames: np.ndarray) -> np.ndarray:
        return self._arm.dh.joint_axes(frames)[1]
