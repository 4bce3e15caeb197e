"""The draggable IK target and the eight branches it has, drawn as translucent ghost arms.

Each slot k keeps its colour and label for every pose (``ur10core.SLOTS``); a branch
that does not exist for the target is hidden by scaling its instances to zero. The
solid arm follows the branch nearest its joints (``ArmState.move_target``); clicking a
ghost, or a number in the branch list, puts the arm on that branch.

:class:`BranchesScene` is the 3D part (ghosts, target marker, the red "unreachable"
halo); :class:`IKTargetControls` is the user's gizmo and panel. In the classroom's
shared mode the scene part is shared by everyone while only the presenter has the
controls.
"""

from __future__ import annotations

import logging
import threading
from typing import TYPE_CHECKING, Callable

import numpy as np
import viser

from ur10core import JOINT_LIMIT, SLOTS
from ur10core.ik import equivalent_near
from ur10core.orientation import quaternion, rotation_from_zyx_euler

from .fast_updates import set_instances, stop_echo
from .feedback import chosen
from .meshes import LinkMesh
from .state import ArmState, Snapshot
from .style import GHOST_OPACITY, SLOT_COLORS, UNREACHABLE_RED, number, sentence, swatch
from .view import View

if TYPE_CHECKING:
    from .session import ClientSession

log = logging.getLogger(__name__)

BRANCH_BUTTONS = tuple(str(slot.index + 1) for slot in SLOTS)


def branch_table(snapshot: Snapshot) -> str:
    """The eight slots with their colour, label and joint values (°).

    Each angle is the turn of it nearest the arm's own joints, as the sliders show them:
    the arm's branch reads exactly as its sliders do.
    """
    solution = snapshot.solution
    rows = ["| | # | branch | θ1…θ6 (°), as the sliders would show them |", "|---|---:|---|---|"]
    shown = equivalent_near(np.where(solution.valid[:, None], solution.q, 0.0), snapshot.q, JOINT_LIMIT)
    for slot in SLOTS:
        k = slot.index
        if solution.valid[k]:
            values = ", ".join(number(v, ".1f") for v in np.degrees(shown[k]))
        else:
            values = "— no solution"
        mark = " **← arm**" if k == snapshot.slot else ""
        rows.append(f"| {swatch(SLOT_COLORS[k])} | {k + 1} | {slot.label}{mark} | {values} |")
    return "\n".join(rows)


def status_markdown(snapshot: Snapshot) -> str:
    if not snapshot.reachable:
        return f"<span style='color:#c81e1e'>**Target unreachable.**</span> {sentence(snapshot.reason[len('unreachable: '):])}."
    solution = snapshot.solution
    notes = [f"**{int(solution.valid.sum())} of 8 branches** reach this target; the arm is on "
             f"**{snapshot.slot + 1}: {SLOTS[snapshot.slot].label}**."]
    if solution.shoulder_singular:
        notes.append("Shoulder singular: the shoulder-left and shoulder-right branches coincide.")
    if solution.elbow_singular[snapshot.slot]:
        notes.append("Elbow singular (stretched or folded): the elbow-up and elbow-down branches coincide.")
    if solution.wrist_singular[snapshot.slot]:
        notes.append("Wrist singular: axes 4 and 6 are parallel; θ6 was kept and θ2…θ4 follow it.")
    return " ".join(notes)


def branches_markdown(snapshot: Snapshot) -> str:
    """The status line above the eight-branch table."""
    return status_markdown(snapshot) + "\n\n" + branch_table(snapshot)


def add_unreachable_halo(scene: viser.SceneApi, parent: str) -> viser.IcosphereHandle:
    """Transform controls have no colour of their own: a red halo on the target says "unreachable"."""
    return scene.add_icosphere(f"{parent}/unreachable", radius=0.06, color=UNREACHABLE_RED, opacity=0.45,
                               visible=False, cast_shadow=False, receive_shadow=False)


class BranchesScene(View):
    """The eight ghost arms, one batched mesh per moving link with an instance per slot.

    With ``target_marker`` it also draws the target itself (axes and the red halo): the
    shared scene of the classroom needs that, since only the presenter has a gizmo.
    """

    def __init__(self, scene: viser.SceneApi, links: tuple[LinkMesh, ...], first: Snapshot,
                 target_marker: bool = False) -> None:
        self.show_ghosts = True
        #: called with (client, slot) when a ghost is clicked; set by whoever drives this scene
        self.on_select: Callable[[viser.ClientHandle | None, int], None] | None = None
        self.target = self.unreachable = None
        if target_marker:
            self.target = scene.add_frame("/target", axes_length=0.1, axes_radius=0.004, origin_radius=0.008,
                                          wxyz=first.flange_wxyz, position=first.flange[:3, 3])
            self.unreachable = add_unreachable_halo(scene, "/target")
        identity = np.tile([1.0, 0.0, 0.0, 0.0], (8, 1))
        self.ghosts = []
        self._scales = b""
        self._positions = {i: b"" for i in range(1, 7)}  # last sent, to skip unchanged ones
        for link in links[1:]:  # every branch shares the fixed base with the solid arm
            vertices, faces = link.merged
            ghost = scene.add_batched_meshes_simple(
                f"/ghosts/link{link.index}", vertices, faces,
                batched_wxyzs=identity, batched_positions=np.zeros((8, 3)), batched_scales=np.zeros(8),
                batched_colors=np.array(SLOT_COLORS, dtype=np.uint8), opacity=GHOST_OPACITY, lod="off",
                cast_shadow=False, receive_shadow=False,
            )
            ghost.on_click(self._clicked)
            self.ghosts.append(ghost)

    def _clicked(self, event) -> None:
        if self.on_select is not None and event.instance_index is not None:
            self.on_select(event.client, int(event.instance_index))

    def render(self, snapshot: Snapshot) -> None:
        if self.target is not None:
            self.target.wxyz = quaternion(snapshot.target[:3, :3], check=False)
            self.target.position = snapshot.target[:3, 3]
            self.unreachable.visible = not snapshot.reachable
        shown = snapshot.solution.valid & self.show_ghosts
        if snapshot.slot >= 0:
            shown = shown.copy()
            shown[snapshot.slot] = False  # the solid arm is there already
        scales = shown.astype(np.float32)
        update_scales = scales.tobytes() != self._scales  # which branches exist rarely changes mid-drag
        self._scales = scales.tobytes()
        # link-major float32 copies, made once: each link's (8, 3) and (8, 4) rows are then contiguous
        all_positions = np.ascontiguousarray(np.swapaxes(snapshot.ghost_frames[:, 1:, :3, 3], 0, 1), dtype=np.float32)
        all_wxyzs = np.ascontiguousarray(np.swapaxes(snapshot.ghost_wxyz[:, 1:], 0, 1), dtype=np.float32)
        for i, ghost in enumerate(self.ghosts, start=1):  # links 1..6
            if update_scales:
                ghost.batched_scales = scales
            positions = all_positions[i - 1]
            if positions.tobytes() == self._positions[i]:  # frames 1 and 2 sit on the shoulder whatever q is
                positions = None
            else:
                self._positions[i] = positions.tobytes()
            set_instances(ghost, all_wxyzs[i - 1], positions)


class IKTargetControls(View):
    """One user's gizmo at the flange and the "IK target" folder of their panel."""

    def __init__(self, controls: viser.SceneApi, gui: viser.GuiApi, branches: BranchesScene,
                 session: "ClientSession") -> None:
        self._session = session
        self._branches = branches
        self._seen_pose: tuple | None = None
        self._seen_lock = threading.Lock()
        snapshot = session.state.last
        self.gizmo = controls.add_transform_controls(
            "/ik_target", scale=0.3, line_width=3.0, depth_test=False,
            wxyz=snapshot.flange_wxyz, position=snapshot.flange[:3, 3],
        )
        stop_echo(self.gizmo)
        # the halo rides on the gizmo unless the (shared) scene draws the target itself
        self.unreachable = None if branches.target is not None else add_unreachable_halo(controls, "/ik_target")
        folder = gui.add_folder("IK target: all 8 branches")
        self.folders = (folder,)
        with folder:
            gui.add_markdown("Drag the gizmo at the flange. Each colour is one IK branch; click a ghost arm "
                             "or a number below to put the arm on it.")
            self.show_ghosts = gui.add_checkbox("Show ghost arms", branches.show_ghosts)
            self.branch_buttons = gui.add_button_group("Use branch", BRANCH_BUTTONS)
            self.branches = gui.add_markdown(branches_markdown(snapshot))
            self.typed_pose = gui.add_text(
                "Target x y z (mm), α β γ (°)", "",
                hint="Position in mm and Z-Y-X Euler angles in degrees, e.g. 520, 57.7, 1110.7, -159.6, 25.6, -34.6",
            )
            self.move_button = gui.add_button("Move target here", icon=viser.Icon.TARGET)
            self.snap_button = gui.add_button("Put target back on the flange", icon=viser.Icon.ARROW_BACK_UP)

        branches.on_select = self._ghost_clicked
        self.gizmo.on_update(self._dragged)
        self.branch_buttons.on_click(session.guard(self._branch_button))
        self.show_ghosts.on_update(session.guard(self._toggle_ghosts))
        self.move_button.on_click(session.guard(self._typed_target))
        self.snap_button.on_click(session.guard(lambda _: session.apply(lambda state: state.set_joints(state.q))))

    def close(self) -> None:
        """Stop driving the branches scene (the browser has gone, or a presenter handed over)."""
        if self._branches.on_select == self._ghost_clicked:
            self._branches.on_select = None

    def remove(self) -> None:
        super().remove()
        self.gizmo.remove()  # the red halo hangs under it

    # ------------------------------------------------------------------ input

    async def _dragged(self, event: viser.TransformControlsEvent) -> None:
        """Runs on viser's event loop (no thread-pool hop): it only files the newest pose."""
        try:
            pose = (tuple(self.gizmo.wxyz), tuple(self.gizmo.position))
            with self._seen_lock:
                if pose == self._seen_pose:
                    return  # the end of a drag repeats its last update
                self._seen_pose = pose
            self._session.drags.submit(self._session, pose)  # solved by the drag queue's worker
        except Exception:  # nothing may escape onto the event loop
            log.exception("could not queue a drag")

    def _ghost_clicked(self, client: viser.ClientHandle | None, slot: int) -> None:
        if client is None or client.client_id != self._session.client.client_id:
            return  # in the shared scene only the presenter's clicks count
        self._session.guard(lambda _: self._session.apply(lambda state: state.select_branch(slot)))(None)

    def _branch_button(self, _: viser.GuiEvent) -> None:
        slot = int(chosen(self.branch_buttons, "branch")) - 1
        self._session.apply(lambda state: state.select_branch(slot))

    def _toggle_ghosts(self, _: viser.GuiEvent) -> None:
        self._branches.show_ghosts = self.show_ghosts.value
        self._session.redraw()

    def _typed_target(self, _: viser.GuiEvent) -> None:
        values = ArmState.parse_degrees(self.typed_pose.value, count=6, what="target pose")
        T = np.eye(4)
        T[:3, :3] = rotation_from_zyx_euler(np.radians(values[3:]))
        T[:3, 3] = values[:3] / 1000.0
        self._session.apply(lambda state: state.move_target(T, cause="typed"))

    # ------------------------------------------------------------------ output

    def render(self, snapshot: Snapshot) -> None:
        if snapshot.cause != "target":  # the user is not holding the gizmo: put it on the target
            self.gizmo.wxyz = quaternion(snapshot.target[:3, :3], check=False)
            self.gizmo.position = snapshot.target[:3, 3]
            with self._seen_lock:
                self._seen_pose = None  # the next drag starts afresh, even from this very pose
        if self.unreachable is not None:
            self.unreachable.visible = not snapshot.reachable

    def render_panel(self, snapshot: Snapshot) -> None:
        self.branches.content = branches_markdown(snapshot)
