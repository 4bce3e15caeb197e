"""The draggable IK target and every branch it has, drawn as ghost arms, for any arm.

Each slot keeps its colour and number for every pose (``arm.slot_labels``); clicking a ghost,
or a number in the branch list, puts the arm on that branch.
"""

from __future__ import annotations

import logging
import threading
from typing import Callable

import numpy as np
import viser

from ur10core import SLOTS
from ur10core.ik import SLOT_LABELS
from ur10core.orientation import (
    quaternion,
    rotation_from_zyx_euler,
    transform_from_quaternion,
)

from ..feedback import Beside, Crossings, chosen
from ..meshes import SKELETON, ArmModels, skeleton_links
from ..state import ArmState, Snapshot, joint_value_text
from ..style import (
    DANGER_RED,
    GHOST_OPACITY,
    SLOT_COLORS,
    UNREACHABLE_RED,
    UR10_SIZE,
    hex_color,
    number,
    sentence,
    swatch,
)
from ..view import HELD_BACK, Session, View
from ..viser_internals.fast_updates import set_instances, stop_echo
from .branch_labels import BranchLabels
from .branch_search import SEARCH_BUTTON
from .robot import model_slug

log = logging.getLogger(__name__)

#: What the "Ghosts shown" dropdown offers: every branch, one branch, or (for the UR family's
#: eight) the arm's branch and the one that differs from it in a single choice.
ALL_BRANCHES = "All branches"
#: How a mesh arm's ghosts are drawn: skeletons (the default: the solid arm stands out) or its meshes.
GHOST_STYLES = ("Skeletons", "Meshes")
FLIPS = {"Flip the shoulder": "shoulder", "Flip the elbow": "elbow", "Flip the wrist": "wrist"}
#: The status line's name for a typed table's branch search, in a panel that has the button (features/branch_search.py)
OWN_SEARCH = f"**{SEARCH_BUTTON}**"
#: Branches whose frame origins all lie this close (m) are drawn as one, labelled "3 = 4".
SAME_POSE = 1e-3
#: The gizmo's size as a share of the arm's reach: small enough to leave the wrist's
#: axes and the overlay's P5 in view (it is drawn over everything, to stay grabbable).
GIZMO_SHARE = 0.12
#: The "unreachable" halo's radius, as a share of the arm's reach too (0.06 m on the UR10).
HALO_SHARE = 0.046
GIZMO_LINE_WIDTH = {False: 3.0, True: 6.0}  #: pixels, normal and in lecture mode
#: How far above a branch's elbow (frame {3}) its number floats. Not the wrist: every branch of a
#: target shares the wrist centre P5 (and the flange); the elbows are where branches differ.
LABEL_LIFT = 0.07
#: What a typed target gives, by what of a pose the arm controls (``arm.task``).
TYPED_TARGET = {"pose": ("Target x y z (mm), α β γ (°)", "Position in mm and Z-Y-X Euler angles in degrees, "
                         "e.g. 520, 57.7, 1110.7, -159.6, 25.6, -34.6"),
                "position and yaw": ("Target x y z (mm), yaw (°)", "Position in mm and the tool's turn about z, "
                                     "e.g. 600, 200, 100, 30"),
                "position": ("Target x y z (mm)", "Position in mm, e.g. 600, 200, 100"),
                "position in its plane": ("Target x y (mm)", "Position in the plane the arm moves in, in mm, e.g. 600, 200")}
#: How many numbers each kind of typed target takes.
TYPED_COUNT = {"pose": 6, "position and yaw": 4, "position": 3, "position in its plane": 2}
#: The farthest a target's x, y or z may be from the base (mm) on an arm that reaches less far: one typed beyond is
#: refused (the KR210's gripper pose too), one dragged beyond stops there. A sliding joint's branches reach any
#: target, and ghosts 1e300 m out made the camera's framing NaN and overflowed the browser's float32.
MAX_TARGET_MM = 10_000.0


def target_room_mm(arm) -> float:
    """How far a target's x, y or z may be from ``arm``'s base (mm): :data:`MAX_TARGET_MM`, or farther on a typed
    arm whose links reach farther (``arm.reach_bound``): a target it reaches is never refused."""
    return max(MAX_TARGET_MM, 1000.0 * arm.reach_bound)


def check_target_position(position_mm: np.ndarray, room_mm: float = MAX_TARGET_MM) -> None:
    """``ValueError`` unless each of a target's x y (z) (mm, (2,) or (3,)) is within ``room_mm`` of the base.

    >>> check_target_position(np.array([12_000.0, 0.0, 0.0]))
    Traceback (most recent call last):
    ...
    ValueError: target: a position within 10 m of the base, please (each of x y z from -10000 to 10000 mm); got 12000.0 mm
    """
    farthest = float(np.abs(position_mm).max())
    if not farthest <= room_mm:
        raise ValueError(f"target: a position within {number(room_mm / 1000, '.4g')} m of the base, please (each of "
                         f"{'x y z'[:2 * len(position_mm) - 1]} from {number(-room_mm, '.0f')} to "
                         f"{number(room_mm, '.0f')} mm); got {number(farthest, '.1f')} mm")


def typed_target_kind(arm) -> str:
    """What a typed target gives for ``arm`` (a :data:`TYPED_TARGET` key): what it controls of a pose, and
    for an arm that moves in a plane (the planar elbow) no height, which it could not reach."""
    return "position in its plane" if arm.planar and arm.task == "position" else arm.task


def has_flips(arm) -> bool:
    """The arm's slots are the UR family's eight: shoulder, elbow and wrist choices."""
    return tuple(arm.slot_labels) == SLOT_LABELS


def focus_options(arm) -> tuple[str, ...]:
    """The "Ghosts shown" choices for ``arm``."""
    flips = tuple(FLIPS) if has_flips(arm) else ()
    return (ALL_BRANCHES, *flips, *(f"Only branch {k + 1}" for k in range(len(arm.slot_labels))))


def flipped(slot: int, choice: str) -> int:
    """The UR slot that differs from ``slot`` in ``choice`` ("shoulder", "elbow" or "wrist") alone.

    >>> flipped(4, "shoulder"), flipped(4, "elbow"), flipped(4, "wrist")
    (1, 5, 6)
    """
    this = SLOTS[slot]
    others = ("shoulder", "elbow", "wrist")
    return next(other.index for other in SLOTS
                if all((getattr(other, name) == getattr(this, name)) != (name == choice) for name in others))


def focused(focus: str, arm_slot: int, arm) -> np.ndarray:
    """(k,) bool: the branches of ``arm`` the "Ghosts shown" choice ``focus`` asks for.

    >>> from ur10core import Arm
    >>> ur10 = Arm.preset("ur10")
    >>> focused("Flip the elbow", 4, ur10).nonzero()[0].tolist(), focused("Only branch 3", 4, ur10).nonzero()[0].tolist()
    ([4, 5], [2])
    """
    if focus == ALL_BRANCHES:  # the usual choice, on every drag: no list of choices built
        return np.ones(len(arm.slot_labels), bool)
    if focus not in focus_options(arm):
        raise ValueError(f"ghosts shown: {focus!r:.40} is not one of the choices")
    shown = np.zeros(len(arm.slot_labels), bool)
    if focus in FLIPS:
        slot = max(arm_slot, 0)  # with the target out of reach: the pair of branch 1
        shown[[slot, flipped(slot, FLIPS[focus])]] = True
    else:
        shown[int(focus.rsplit(" ", 1)[1]) - 1] = True  # "Only branch k"
    return shown


def same_pose_groups(ghost_frames: np.ndarray, valid: np.ndarray, tolerance: float = SAME_POSE) -> tuple[tuple[int, ...], ...]:
    """The valid slots grouped by pose: slots in one group have every frame origin within ``tolerance``.

    At a singularity two branches coincide (docs/kinematics.md §5); they are drawn as one.

    >>> frames = np.tile(np.eye(4), (8, 7, 1, 1)); frames[3, :, 0, 3] = 1.0
    >>> same_pose_groups(frames, np.array([True, True, False, True, False, False, False, False]))
    ((0, 1), (3,))
    """
    origins = ghost_frames[..., :3, 3]
    apart = np.abs(origins[:, None] - origins[None]).max(axis=(2, 3)) > tolerance
    valid = np.asarray(valid, bool)
    slots = len(valid)
    if apart.sum() == slots * (slots - 1):  # no two coincide (away from singularities): every valid slot alone
        return tuple((int(k),) for k in valid.nonzero()[0])
    groups, taken = [], ~valid
    for k in range(slots):
        if not taken[k]:
            members = (~apart[k] & ~taken).nonzero()[0]
            taken[members] = True
            groups.append(tuple(int(m) for m in members))
    return tuple(groups)


def lead(group: tuple[int, ...], within_limits: np.ndarray, focus: np.ndarray | None = None) -> int:
    """The slot that stands for a group of coinciding branches: the ghost drawn, clicked and labelled. The first
    within the joint limits, so a click on the ghost puts the arm there whenever one of them can; of those, the
    first of ``focus`` ((k,) bool, the branches *Ghosts shown* asks for), so "Only branch 5" draws and takes 5.

    >>> within = np.array([False, True, True, True, True, True, True, True])
    >>> lead((0, 4), within), lead((1, 5), within), lead((1, 5), within, focus=np.arange(8) == 5)
    (4, 1, 5)
    """
    return min(group, key=lambda k: (not within_limits[k], focus is not None and not focus[k]))


def one_ghost_per_pose(snapshot: Snapshot, groups: tuple[tuple[int, ...], ...], focus: np.ndarray) -> np.ndarray:
    """(k,) bool: the ghosts drawn for ``groups`` (:func:`same_pose_groups`): one per pose, the :func:`lead` one, which
    its number names and a click takes; none where the solid arm is (a ghost would tint it), none of the branches
    ``focus`` ((k,) bool) leaves out."""
    shown = np.zeros(len(snapshot.solution.valid), bool)
    for group in groups:
        shown[lead(group, snapshot.solution.within_limits, focus)] = snapshot.slot not in group and focus[list(group)].any()
    return shown


def branch_labels(snapshot: Snapshot, groups: tuple[tuple[int, ...], ...], focus: np.ndarray | None = None) -> list[str]:
    """The 3D label of each slot ("" for none): its number, "3 = 4" for coinciding branches ("all 8" where every
    slot does: "1 = 2 = … = 8" was too wide to find a free spot in lecture mode), the arm's marked, and a ghost
    the arm cannot be put on (every branch of it beyond a joint limit) marked so before a student clicks it.

    Only the :func:`lead` slot of a group (for the branches ``focus`` asks for) carries the group's label.
    """
    solution = snapshot.solution
    slots = len(solution.labels)
    texts = [""] * slots
    floor = snapshot.through_floor[1:]
    for group in groups:
        text = f"all {slots}" if len(group) == slots > 2 else " = ".join(str(k + 1) for k in group)
        if snapshot.slot in group:
            text = f"arm: {text}"
        if not solution.within_limits[list(group)].any():
            text += " ⚠ limit"
        if floor[list(group)].any():
            text += " ⚠ floor"
        texts[lead(group, solution.within_limits, focus)] = text
    return texts


def joints_text(arm, q: np.ndarray) -> str:
    """Joint values as the sliders show them: ``30.0°, 45.0°, 120.0 mm``."""
    return ", ".join(joint_value_text(kind, float(v)) for kind, v in zip(arm.joint_types, q))


def branch_table(snapshot: Snapshot) -> str:
    """Every slot with its colour, label and joint values.

    Each revolute joint is the turn of it nearest the arm's own joints, as the sliders would
    show it: the arm's branch reads exactly as its sliders do.
    """
    arm, solution = snapshot.arm, snapshot.solution
    floor = snapshot.body_points is not None  # the floor is checked where the arm's bodies are known
    rows = ["| | # | branch | joints, as the sliders would show them | |", "|---|---:|---|---|---|"]
    for k, label in enumerate(solution.labels):
        colour = swatch(SLOT_COLORS[k % len(SLOT_COLORS)])
        if not solution.valid[k]:
            if solution.method != "found numerically":  # a search's empty slots are room, not branches
                rows.append(f"| {colour} | {k + 1} | {label} | — no solution | |")
            continue
        flags = []
        if k == snapshot.slot:
            flags.append("**← arm**")
        if floor and snapshot.through_floor[k + 1]:
            flags.append("⚠ through the floor")
        if not solution.within_limits[k]:
            flags.append(f"<span style='color:{hex_color(DANGER_RED)}'>beyond a joint limit</span>")
        if solution.singular[k]:
            flags.append("singular: a joint chosen, not fixed")
        rows.append(f"| {colour} | {k + 1} | {label} | {joints_text(arm, solution.take(k, snapshot.q))} | {', '.join(flags)} |")
    return "\n".join(rows)


def reach_count(solution) -> str:
    """How many branches reach, in words that fit the arm: "**6 of 8 branches** reach this target". Counted within
    the joint limits, as the reach map and the class challenges count them, with those only beyond one after.

    >>> from ur10core import Arm
    >>> cylindrical = Arm.preset("cylindrical")
    >>> reach_count(cylindrical.ik(cylindrical.fk(cylindrical.specs.home)))  # the second with its stroke reversed
    '**1 of 2 branches** reach this target within the joint limits, and 1 more only beyond a limit'
    """
    slots, found = len(solution.labels), int(solution.valid.sum())
    within = int((solution.valid & solution.within_limits).sum())
    beyond = f", and {found - within} more only beyond a limit" if within < found else ""
    if solution.method == "found numerically":
        return f"**{found} solution{'s' * (found != 1)}** found (this chain has at most {slots})" + (
            f", {found - within} of them beyond a joint limit" if within < found else "")
    if within == found:
        return "**Its one branch** reaches this target" if slots == 1 else f"**{found} of {slots} branches** reach this target"
    if slots == 1:
        return "**Its one branch** reaches this target only beyond a joint limit"
    return f"**{within} of {slots} branches** reach this target within the joint limits{beyond}"


def status_markdown(snapshot: Snapshot, search: str = OWN_SEARCH) -> str:
    """How many branches reach the target and which the arm is on, or why none does; ``search`` names the button
    that searches a typed table's branches for whoever reads it."""
    solution = snapshot.solution
    if not snapshot.reachable:
        reason = snapshot.reason.removeprefix("unreachable: ")
        # a typed table's search, from the arm's joints or from many starts, proves nothing out of reach: its reason
        # says how close it came, or (beyond every length laid end to end) that no joints could reach it
        verdict = "Target not reached" if snapshot.arm.numerical else "Target unreachable"
        return f"<span style='color:{hex_color(DANGER_RED)}'>**{verdict}.**</span> {sentence(reason)}."
    if solution is None:  # a typed table, not searched yet
        return ("The arm follows the target from its own joints (damped least squares). "
                f"{search} searches from many starts for the others.")
    notes = [f"{reach_count(solution)} ({solution.method}; the arm places its {solution.task}); the arm is on "
             f"**{snapshot.slot + 1}: {solution.labels[snapshot.slot]}**."]
    if has_flips(snapshot.arm):  # the UR family names which of its choices a singularity merges
        if solution.shoulder_singular:
            notes.append("Shoulder singular: the shoulder-left and shoulder-right branches coincide.")
        if solution.elbow_singular[snapshot.slot]:
            notes.append("Elbow singular (stretched or folded): the elbow-up and elbow-down branches coincide.")
        if solution.wrist_singular[snapshot.slot]:
            notes.append("Wrist singular: axes 4 and 6 are parallel; θ6 was kept and θ2…θ4 follow it.")
    else:
        if solution.singular[snapshot.slot]:
            notes.append("Singular: the pose does not fix every joint; the arm's own value was kept, or the nearest one "
                         "within the joint limits.")
        together = " and ".join(" = ".join(str(k + 1) for k in group) for group in drawn_as_one(snapshot))
        if together:
            notes.append(f"Ghosts {together} lie on each other: their joints sit in the same places, turned or slid "
                         "differently (the table gives each one's values).")
    return " ".join(notes)


def drawn_as_one(snapshot: Snapshot) -> list[tuple[int, ...]]:
    """The groups of :func:`same_pose_groups` whose branches differ in their joints, not only in name: drawn as one
    ghost all the same, since every joint of theirs sits in the same place (a spherical wrist flipped, θ4 + 180°,
    −θ5, θ6 + 180°, moves none)."""
    solution = snapshot.solution
    groups = [group for group in same_pose_groups(snapshot.ghost_frames, solution.valid) if len(group) > 1]
    return [group for group in groups
            if np.ptp([solution.take(k, snapshot.q) for k in group], axis=0).max() > SAME_POSE]


def branches_markdown(snapshot: Snapshot, search: str = OWN_SEARCH) -> str:
    """The status line (:func:`status_markdown`) above the branch table."""
    if snapshot.solution is None:
        return status_markdown(snapshot, search)
    return status_markdown(snapshot, search) + "\n\n" + branch_table(snapshot)


def add_unreachable_halo(scene: viser.SceneApi, parent: str, size: float) -> viser.IcosphereHandle:
    """Transform controls have no colour of their own: a red halo on the target says "unreachable"; ``size``, the
    arm's reach (m), sizes it with the gizmo."""
    return scene.add_icosphere(f"{parent}/unreachable", radius=HALO_SHARE * size, color=UNREACHABLE_RED, opacity=0.45,
                               visible=False, cast_shadow=False, receive_shadow=False)


class BranchesScene(View):
    """The eight ghost arms, one batched mesh per moving link with an instance per slot.

    Drawn as thick coloured skeletons (:func:`ur10teach.meshes.skeleton_links`) by default, so
    that the solid arm is unmistakable among them, or as the arm's own meshes, translucent.
    With ``target_marker`` it also draws the target itself (axes and the red halo): the
    shared scene of the classroom needs that, since only the presenter has a gizmo.
    """

    def __init__(self, scene: viser.SceneApi, models: ArmModels, first: Snapshot,
                 target_marker: bool = False) -> None:
        self.show_ghosts = True
        self.focus = ALL_BRANCHES  #: one of focus_options(arm)
        self.style = GHOST_STYLES[0]  #: one of GHOST_STYLES
        self.shown = np.zeros(8, bool)  #: the ghosts drawn by the last render
        #: called with (client, slot) when a ghost is clicked; set by whoever drives this scene
        self.on_select: Callable[[viser.ClientHandle | None, int], None] | None = None
        self.target = self.unreachable = None
        if target_marker:
            self.target = scene.add_frame("/target", axes_length=0.1, axes_radius=0.004, origin_radius=0.008,
                                          wxyz=first.flange_wxyz, position=first.flange[:3, 3])
            self.unreachable = add_unreachable_halo(scene, "/target", UR10_SIZE)
        self._scene, self._models, self._material = scene, models, models.material
        self._geometries = {SKELETON: skeleton_links(first.arm.dh), **models.by_name}
        #: each geometry's batched ghost meshes, links 1..6, sent when first shown
        #: (every branch shares the base with the solid arm)
        self.models: dict[str, list[viser.BatchedMeshHandle]] = {}
        self.model = models.names[0]  #: the solid arm's model, which "Meshes" draws the ghosts as
        self.ghosts = self._send(self.geometry)  #: the shown geometry's; only these follow the arm
        self._forget_sent()
        # each branch's number by its elbow, as in the table: colours alone cannot tell eight apart for everyone
        self.numbers = BranchLabels(scene, "/ghosts", 8, colours=list(SLOT_COLORS))

    @property
    def geometry(self) -> str:
        """What the ghosts are drawn as now: the skeleton, or the solid arm's model."""
        return SKELETON if self.style == GHOST_STYLES[0] else self.model

    @property
    def labels(self) -> list[viser.LabelHandle]:
        return self.numbers.labels

    def _forget_sent(self) -> None:
        self._scales = {i: b"" for i in range(1, 7)}
        self._positions = {i: b"" for i in range(1, 7)}  # last sent, to skip unchanged ones

    def _send(self, name: str) -> list[viser.BatchedMeshHandle]:
        identity = np.tile([1.0, 0.0, 0.0, 0.0], (8, 1))
        ghosts = []
        for link in self._geometries[name][1:]:
            vertices, faces = link.ghost
            ghost = self._scene.add_batched_meshes_simple(
                f"/ghosts/{model_slug(name)}/link{link.index}", vertices, faces,
                batched_wxyzs=identity, batched_positions=np.zeros((8, 3)), batched_scales=np.zeros(8),
                batched_colors=np.array(SLOT_COLORS, dtype=np.uint8), opacity=1.0 if name == SKELETON else GHOST_OPACITY,
                lod="off", material=self._material, cast_shadow=False, receive_shadow=False,
            )
            ghost.on_click(self._clicked)
            ghosts.append(ghost)
        self.models[name] = ghosts
        return ghosts

    def set_material(self, material: str) -> None:
        """Shade the ghosts with viser's ``material``, those sent so far and those to come."""
        self._material = material
        for ghost in (ghost for ghosts in self.models.values() for ghost in ghosts):
            ghost.material = material

    def show(self, model: str) -> None:
        """The solid arm is drawn as ``model``: so are the ghosts, when drawn as meshes."""
        if model not in self._models.names:
            raise ValueError(f"no arm model {model!r}; the models are {', '.join(self._models.names)}")
        self.model = model
        self._draw_as(self.geometry)

    def set_style(self, style: str) -> None:
        """Draw the ghosts as skeletons or as meshes (one of :data:`GHOST_STYLES`); the next render poses them."""
        if style not in GHOST_STYLES:
            raise ValueError(f"ghosts drawn as: {style!r:.40} is not one of the choices")
        self.style = style
        self._draw_as(self.geometry)

    def _draw_as(self, geometry: str) -> None:
        for ghost in self.ghosts:
            ghost.visible = False
        self.ghosts = self.models[geometry] if geometry in self.models else self._send(geometry)
        for ghost in self.ghosts:
            ghost.visible = True
        self._forget_sent()

    def _clicked(self, event) -> None:
        if self.on_select is not None and event.instance_index is not None:
            self.on_select(event.client, int(event.instance_index))

    def render(self, snapshot: Snapshot) -> None:
        if self.target is not None:
            self.target.wxyz = quaternion(snapshot.target[:3, :3], check=False)
            self.target.position = snapshot.target[:3, 3]
            self.unreachable.visible = not snapshot.reachable
        valid = snapshot.solution.valid
        groups = same_pose_groups(snapshot.ghost_frames, valid)
        focus = focused(self.focus, snapshot.slot, snapshot.arm)
        if len(groups) == valid.sum():  # none coincide (away from singularities)
            shown = valid & focus & self.show_ghosts
            if snapshot.slot >= 0:
                shown[snapshot.slot] = False  # the solid arm is there already
        else:
            shown = one_ghost_per_pose(snapshot, groups, focus) & self.show_ghosts
        self.shown = shown
        # a ghost's link where the solid arm's is (the shoulder, for the branches on the arm's side) is
        # not drawn: the two surfaces would flicker through each other
        apart = np.abs(snapshot.ghost_frames[:, 1:] - snapshot.frames[None, 1:]).max(axis=(2, 3)) > SAME_POSE
        # link-major float32 copies, made once: each link's (8, 3) and (8, 4) rows are then contiguous
        all_positions = np.ascontiguousarray(np.swapaxes(snapshot.ghost_frames[:, 1:, :3, 3], 0, 1), dtype=np.float32)
        all_wxyzs = np.ascontiguousarray(np.swapaxes(snapshot.ghost_wxyz[:, 1:], 0, 1), dtype=np.float32)
        for i, ghost in enumerate(self.ghosts, start=1):  # links 1..6
            scales = (shown & apart[:, i - 1]).astype(np.float32)
            if scales.tobytes() != self._scales[i]:  # which branches exist rarely changes mid-drag
                self._scales[i] = scales.tobytes()
                ghost.batched_scales = scales
            positions = all_positions[i - 1]
            if positions.tobytes() == self._positions[i]:  # frames 1 and 2 sit on the shoulder whatever q is
                positions = None
            else:
                self._positions[i] = positions.tobytes()
            set_instances(ghost, all_wxyzs[i - 1], positions)

    def render_panel(self, snapshot: Snapshot) -> None:
        """The branch numbers, at the panel's pace (≤ 10 Hz): off the drag path, which they would double."""
        elbows = snapshot.ghost_frames[:, 3, :3, 3] + (0.0, 0.0, LABEL_LIFT)
        self.numbers.show(elbows, numbered(snapshot, self.show_ghosts, self.focus))


def numbered(snapshot: Snapshot, show_ghosts: bool, focus: str) -> list[str]:
    """The number each slot's ghost carries ("" for none): one per pose, the arm's always, the others as shown."""
    groups = same_pose_groups(snapshot.ghost_frames, snapshot.solution.valid)
    shown_focus = focused(focus, snapshot.slot, snapshot.arm)
    texts = branch_labels(snapshot, groups, shown_focus)
    for group in groups:  # a group's label is its lead slot's; the arm's is shown whatever the focus
        if not (snapshot.slot in group or (show_ghosts and bool(shown_focus[list(group)].any()))):
            texts[lead(group, snapshot.solution.within_limits, shown_focus)] = ""
    return texts


class IKTarget(View):
    """One browser's gizmo at the tool and its "IK target" folder, for any arm.

    ``drawing`` draws the ghosts (and, in the shared scene, the target marker); ``session``
    applies the changes. A drag is filed on viser's event loop and solved by the drag queue.
    """

    answers = ("theta1",)  # the branch table lists every branch's joints; a branch chosen shows its own

    def __init__(self, controls: viser.SceneApi, gui: viser.GuiApi, drawing, session: Session) -> None:
        self._session = session
        self._drawing = drawing
        self._seen: tuple | None = None
        self._crossings = Crossings(later=session.redraw)  # the gizmo's pose: put on the target here, or dropped by the student
        self._seen_lock = threading.Lock()
        arm, snapshot = session.arm, session.state.last
        self.gizmo = controls.add_transform_controls(
            f"{drawing.root}/ik_target", scale=GIZMO_SHARE * drawing.handle_size, line_width=GIZMO_LINE_WIDTH[False],
            depth_test=False, opacity=0.85, disable_rotations=arm.task == "position",
            active_axes=(True, True, not arm.planar),
            wxyz=quaternion(snapshot.target[:3, :3], check=False), position=snapshot.target[:3, 3])
        stop_echo(self.gizmo)
        # the halo rides on the gizmo unless the (shared) scene draws the target itself
        self.unreachable = None if drawing.target is not None else add_unreachable_halo(controls, f"{drawing.root}/ik_target", drawing.handle_size)
        slots = len(arm.slot_labels)
        folder = gui.add_folder(f"IK target: all {slots} branches" if slots > 1 and not arm.numerical else "IK target")
        self.folders = (folder,)
        label, hint = TYPED_TARGET[typed_target_kind(arm)]
        with folder:
            gui.add_markdown("Drag the gizmo at the tool. Each ghost arm is one IK branch, numbered as in the "
                             f"table; click {drawing.clicked} or a number below to put the arm on it.")
            self.show_ghosts = gui.add_checkbox("Show ghost arms", drawing.show_ghosts)
            self.focus = gui.add_dropdown("Ghosts shown", focus_options(arm), initial_value=drawing.focus,
                                          hint="One branch, or the arm's branch beside the one a single choice away")
            styles = getattr(drawing, "ghost_styles", ())
            self.ghost_style = (gui.add_dropdown("Ghosts drawn as", styles, initial_value=drawing.ghost_style,
                                                 hint="Coloured skeletons, so the solid arm stands out; or the arm's own "
                                                      "meshes, translucent") if len(styles) > 1 else None)
            self.branch_buttons = gui.add_button_group("Use branch", tuple(str(k + 1) for k in range(slots)))
            self.branch_refusal = Beside(gui)  # a branch this target does not have, or beyond a joint limit
            self.branches = gui.add_markdown("")  # (filled by the first render_panel, held back if a challenge asks θ1)
            self.typed_pose = gui.add_text(label, "", hint=hint)
            self.move_button = gui.add_button("Move target here", icon=viser.Icon.TARGET)
            self.refusal = Beside(gui)
            self.snap_button = gui.add_button("Put target back on the tool", icon=viser.Icon.ARROW_BACK_UP)

        drawing.on_select = self._ghost_clicked
        self.gizmo.on_update(self._dragged)
        self.branch_buttons.on_click(session.guard(self._branch_button, beside=self.branch_refusal))
        self.show_ghosts.on_update(session.guard(self._toggle_ghosts))
        self.focus.on_update(session.guard(self._choose_focus))
        if self.ghost_style is not None:
            self.ghost_style.on_update(session.guard(self._choose_style))
        self.move_button.on_click(session.guard(self._typed_target, beside=self.refusal))
        self.snap_button.on_click(session.guard(lambda _: session.apply(lambda state: state.set_joints(state.q))))

    def obstacles(self) -> list:
        """The gizmo's centre, where its handles cross: a 3D label placed there (the desktop arm's "tool") was drawn
        under them. As a blank label about 45 × 35 px, centred on it; on the target while a drag holds the gizmo
        beyond :func:`target_room_mm` (1e300 m out, it overflowed the labels' placing)."""
        centre = np.asarray(self.gizmo.position, dtype=float)
        if not np.abs(centre).max() <= target_room_mm(self._session.arm) / 1000.0:
            centre = self._session.state.last.target[:3, 3]
        return [(centre, "  ", 2.0, "center-center")]

    def thicken(self, lecture: bool) -> None:
        """The gizmo's lines for lecture mode (thick) or not."""
        self.gizmo.line_width = GIZMO_LINE_WIDTH[lecture]

    def close(self) -> None:
        """Stop driving the drawing's ghosts (the browser has gone, or a presenter handed over)."""
        if self._drawing.on_select == self._ghost_clicked:
            self._drawing.on_select = None

    def remove(self) -> None:
        super().remove()
        self.gizmo.remove()  # the red halo hangs under it

    # ------------------------------------------------------------------ input

    async def _dragged(self, event: viser.TransformControlsEvent) -> None:
        """Runs on viser's event loop (no thread-pool hop): it only files the newest pose."""
        try:
            pose = (tuple(self.gizmo.wxyz), tuple(self.gizmo.position), event.phase == "end")
            with self._seen_lock:
                self._crossings.received()
                if pose == self._seen:
                    return  # a repeated update
                self._seen = pose
            self._session.drags.submit(self._session, pose)  # solved by the drag queue's worker
        except Exception:  # nothing may escape onto the event loop
            log.exception("could not queue a drag")

    def hold_back(self, asked: str | None) -> None:
        super().hold_back(asked)
        self.branch_buttons.visible = self.held is None
        if self.held is not None:
            self.branch_refusal.clear()

    def _ghost_clicked(self, client: viser.ClientHandle | None, slot: int) -> None:
        if client is None or client.client_id != self._session.client.client_id:
            return  # in the shared scene only the presenter's clicks count
        self._session.guard(lambda _: self._select(slot))(None)

    def _branch_button(self, _: viser.GuiEvent) -> None:
        self._select(int(chosen(self.branch_buttons, "branch")) - 1)

    def _select(self, slot: int) -> None:
        # (held: the joint panel would show the other branch's joints)
        self._session.apply(self.unless_held(lambda state: state.select_branch(slot)))
        self.branch_refusal.clear()  # (a ghost clicked, too: the branch refused before no longer stands below)

    def _toggle_ghosts(self, _: viser.GuiEvent) -> None:
        self._drawing.show_ghosts = bool(self.show_ghosts.value)
        self._session.redraw()

    def _choose_focus(self, _: viser.GuiEvent) -> None:
        self._drawing.focus = chosen(self.focus, "ghosts shown")
        self._session.redraw()

    def _choose_style(self, _: viser.GuiEvent) -> None:
        style = chosen(self.ghost_style, "ghosts drawn as")
        with self._session.state.lock:
            self._drawing.set_ghost_style(style)
        self._session.redraw()

    def _typed_target(self, _: viser.GuiEvent) -> None:
        arm = self._session.arm
        count = TYPED_COUNT[typed_target_kind(arm)]
        values = ArmState.parse_numbers(self.typed_pose.value, count=count, what="target")
        position = min(count, 3)  # x y, or x y z
        check_target_position(values[:position], target_room_mm(arm))
        T = np.array(self._session.state.last.target)
        T[:position, 3] = values[:position] / 1000.0
        if count == 6:
            T[:3, :3] = rotation_from_zyx_euler(np.radians(values[3:]))
        elif count == 4:
            T[:3, :3] = rotation_from_zyx_euler(np.radians([values[3], 0.0, 0.0]))
        self._session.apply(lambda state: state.move_target(T, cause="typed"))

    # ------------------------------------------------------------------ output

    def render(self, snapshot: Snapshot) -> None:
        if snapshot.cause != "target":  # the user is not holding the gizmo: put it on the target
            held = (tuple(self.gizmo.wxyz), tuple(self.gizmo.position))
            self.gizmo.wxyz = quaternion(snapshot.target[:3, :3], check=False)
            self.gizmo.position = snapshot.target[:3, 3]
            with self._seen_lock:
                self._seen = None  # the next drag starts afresh, even from this very pose
                if (tuple(self.gizmo.wxyz), tuple(self.gizmo.position)) != held:
                    self._crossings.sent()
                else:
                    self._crossings.settle(self.gizmo)
        if self.unreachable is not None:
            self.unreachable.visible = not snapshot.reachable

    def render_panel(self, snapshot: Snapshot) -> None:
        self.branches.content = status_markdown(snapshot) + "\n\n" + HELD_BACK if self.held else branches_markdown(snapshot)


def pose_from_gizmo(pose, arm) -> tuple[np.ndarray, bool]:
    """A filed drag ``(wxyz, position, released)`` of ``arm``'s target → (T (4, 4), released); ``ValueError`` for a
    pose that is not one. A target dragged beyond :func:`target_room_mm` stops there, as at the edge of the room: a
    notice for each of a drag's twenty updates a second would bury the panel's own word, and the gizmo, let go, goes
    back onto it."""
    wxyz, position, released = pose
    T = transform_from_quaternion(wxyz, position)
    farthest = target_room_mm(arm) / 1000.0
    if not all(-farthest <= v <= farthest for v in T[:3, 3].tolist()):  # (no numpy call on every drag's way)
        T[:3, 3] = np.clip(T[:3, 3], -farthest, farthest)
    return T, released
