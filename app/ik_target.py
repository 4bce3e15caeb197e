"""The draggable IK target and the eight branches it has, drawn as translucent ghost arms.

Each slot k keeps its colour and label for every pose (``ur10core.SLOTS``); a branch
that does not exist for the target is hidden by scaling its instances to zero. The
solid arm follows the branch nearest its joints (``ArmState.move_target``); clicking a
ghost, or a number in the branch list, puts the arm on that branch.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

import numpy as np
import viser

from ur10core import SLOTS
from ur10core.orientation import rotation_from_quaternion, rotation_from_zyx_euler

from .meshes import LinkMesh
from .state import ArmState, Snapshot
from .style import GHOST_OPACITY, SLOT_COLORS, UNREACHABLE_RED, swatch
from .view import View

if TYPE_CHECKING:
    from .session import ClientSession

BRANCH_BUTTONS = tuple(str(slot.index + 1) for slot in SLOTS)


def branch_table(snapshot: Snapshot) -> str:
    """The eight slots with their colour, label and joint values (°)."""
    solution = snapshot.solution
    rows = ["| | # | branch | θ1…θ6 (°) |", "|---|---:|---|---|"]
    for slot in SLOTS:
        k = slot.index
        if solution.valid[k]:
            values = ", ".join(f"{v:.1f}" for v in np.degrees(solution.q[k]))
        else:
            values = "— no solution"
        mark = " **← arm**" if k == snapshot.slot else ""
        rows.append(f"| {swatch(SLOT_COLORS[k])} | {k + 1} | {slot.label}{mark} | {values} |")
    return "\n".join(rows)


def status_markdown(snapshot: Snapshot) -> str:
    if not snapshot.reachable:
        return f"<span style='color:#c81e1e'>**Target unreachable.**</span> {snapshot.reason[len('unreachable: '):]}"
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


class IKTargetView(View):
    def __init__(
        self, scene: viser.SceneApi, gui: viser.GuiApi, links: tuple[LinkMesh, ...], session: "ClientSession"
    ) -> None:
        self._session = session
        self._pending_target: np.ndarray | None = None
        self._drag_lock = threading.Lock()
        snapshot = session.state.last
        self.gizmo = scene.add_transform_controls(
            "/ik_target", scale=0.3, line_width=3.0, depth_test=False,
            wxyz=snapshot.flange_wxyz, position=snapshot.flange[:3, 3],
        )
        # transform controls have no colour of their own: a red halo on the target says "unreachable"
        self.unreachable_marker = scene.add_icosphere(
            "/ik_target/unreachable", radius=0.06, color=UNREACHABLE_RED, opacity=0.45, visible=False,
            cast_shadow=False, receive_shadow=False,
        )
        identity = np.tile([1.0, 0.0, 0.0, 0.0], (8, 1))
        self.ghosts = []
        self._scales: bytes = b""
        self._positions: dict[int, bytes] = {i: b"" for i in range(1, 7)}  # last sent, to skip unchanged
        for link in links[1:]:  # every branch shares the fixed base with the solid arm
            vertices, faces = link.merged
            ghost = scene.add_batched_meshes_simple(
                f"/ghosts/link{link.index}", vertices, faces,
                batched_wxyzs=identity, batched_positions=np.zeros((8, 3)), batched_scales=np.zeros(8),
                batched_colors=np.array(SLOT_COLORS, dtype=np.uint8), opacity=GHOST_OPACITY, lod="off",
                cast_shadow=False, receive_shadow=False,
            )
            ghost.on_click(session.guard(self._ghost_clicked))
            self.ghosts.append(ghost)

        with gui.add_folder("IK target: all 8 branches"):
            gui.add_markdown("Drag the gizmo at the flange. Each colour is one IK branch; click a ghost arm "
                             "or a number below to put the arm on it.")
            self.show_ghosts = gui.add_checkbox("Show ghost arms", True)
            self.branch_buttons = gui.add_button_group("Use branch", BRANCH_BUTTONS)
            self.branches = gui.add_markdown(branches_markdown(snapshot))
            self.typed_pose = gui.add_text(
                "Target x y z (mm), α β γ (°)", "",
                hint="Position in mm and Z-Y-X Euler angles in degrees, e.g. 520, 57.7, 1110.7, -159.6, 25.6, -34.6",
            )
            self.move_button = gui.add_button("Move target here", icon=viser.Icon.TARGET)
            self.snap_button = gui.add_button("Put target back on the flange", icon=viser.Icon.ARROW_BACK_UP)

        self.gizmo.on_update(session.guard(self._dragged))
        self.branch_buttons.on_click(session.guard(self._branch_button))
        self.show_ghosts.on_update(session.guard(lambda _: self.render(session.state.last)))
        self.move_button.on_click(session.guard(self._typed_target))
        self.snap_button.on_click(session.guard(lambda _: session.apply(lambda state: state.set_joints(state.q))))

    # ------------------------------------------------------------------ input

    def _dragged(self, event: viser.TransformControlsEvent) -> None:
        T = np.eye(4)
        T[:3, :3] = rotation_from_quaternion(np.asarray(self.gizmo.wxyz, dtype=float))
        T[:3, 3] = self.gizmo.position
        # Latest wins: events that queue up behind a slow one are folded into one update,
        # so a busy server never works through a backlog of stale targets.
        self._pending_target = T
        while self._pending_target is not None:
            if not self._drag_lock.acquire(blocking=False):
                return  # the thread holding it picks up our target
            try:
                target, self._pending_target = self._pending_target, None
                if target is not None:
                    self._session.apply(lambda state: state.move_target(target), timed="drag")
            finally:
                self._drag_lock.release()

    def _ghost_clicked(self, event) -> None:
        if event.instance_index is None:
            return
        self._session.apply(lambda state: state.select_branch(int(event.instance_index)))

    def _branch_button(self, _: viser.GuiEvent) -> None:
        slot = int(self.branch_buttons.value) - 1
        self._session.apply(lambda state: state.select_branch(slot))

    def _typed_target(self, _: viser.GuiEvent) -> None:
        values = ArmState.parse_degrees(self.typed_pose.value, count=6, what="target pose")
        T = np.eye(4)
        T[:3, :3] = rotation_from_zyx_euler(np.radians(values[3:]))
        T[:3, 3] = values[:3] / 1000.0
        self._session.apply(lambda state: state.move_target(T))

    # ------------------------------------------------------------------ output

    def render(self, snapshot: Snapshot) -> None:
        if snapshot.cause != "target":  # the user is not holding the gizmo: put it on the flange
            self.gizmo.wxyz = snapshot.flange_wxyz
            self.gizmo.position = snapshot.flange[:3, 3]
        self.unreachable_marker.visible = not snapshot.reachable
        shown = snapshot.solution.valid & self.show_ghosts.value
        if snapshot.slot >= 0:
            shown = shown.copy()
            shown[snapshot.slot] = False  # the solid arm is there already
        scales = shown.astype(np.float32)
        update_scales = scales.tobytes() != self._scales  # which branches exist rarely changes mid-drag
        self._scales = scales.tobytes()
        for i, ghost in enumerate(self.ghosts, start=1):  # links 1..6
            if update_scales:
                ghost.batched_scales = scales
            ghost.batched_wxyzs = snapshot.ghost_wxyz[:, i]
            positions = snapshot.ghost_frames[:, i, :3, 3].astype(np.float32)
            if positions.tobytes() != self._positions[i]:  # frames 1 and 2 sit on the shoulder whatever q is
                self._positions[i] = positions.tobytes()
                ghost.batched_positions = positions

    def render_panel(self, snapshot: Snapshot) -> None:
        self.branches.content = branches_markdown(snapshot)

