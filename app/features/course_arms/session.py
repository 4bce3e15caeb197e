"""One browser driving any of the course's arms but the UR10: the other presets, a typed table, the desktop arm."""

from __future__ import annotations

import time
from typing import Callable

import numpy as np
import viser

from ur10core.orientation import quaternion, transform_from_quaternion
from ur10core import Arm

from ..camera import CameraControls
from ..ellipsoids import EllipsoidsView
from ...serving.metrics import LATENCY
from ..motion_lessons import MotionLessons
from ..reach_map import ReachMapView
from ...session_basics import SessionBasics
from ..statics import StaticsView
from ..velocity import VelocityView
from ..workspace import WorkspaceView
from ...view import View
from ...serving.workers import APART, HEAVY, DragQueue, FoldedRuns, PanelRefresher
from .editor import DHEditor
from .gripper import GripperPose
from .panel import CourseBranches, CourseDHTable, CourseJointSliders, CourseSingularities, DHWalkthrough
from .desktop_arm import DesktopArmScene
from .desktop_lessons import desktop_lessons
from .scene import CourseArmScene
from .state import CourseArmState, CourseSnapshot

#: An arm's own lessons (the course's exercises with it), beside the features every arm has.
LESSONS = {"three_dof": desktop_lessons}


def body_radius(size: float) -> float:
    """Room the camera keeps around each joint of an arm that reaches ``size`` m (its rods and gizmo scale so)."""
    return 0.15 * size


def reach(arm: Arm) -> float:
    """How far the arm's tool gets from the base (m), from a workspace sample: sizes follow it."""
    points, _ = arm.sample_workspace(4000, seed=0)
    return float(max(np.linalg.norm(points, axis=-1).max(), 0.3))


def arm_scene(scene: viser.SceneApi, arm: Arm, first: CourseSnapshot, root: str | None = None) -> CourseArmScene | DesktopArmScene:
    """The arm in 3D: its DH skeleton and frames, or, for an arm without a DH table, its own drawing."""
    kind = DesktopArmScene if arm.dh is None else CourseArmScene
    return kind(scene, arm, first, reach(arm), *(() if root is None else (root,)))


class BranchSearch(View):
    """"Find every branch": a typed table's numerical IK from many starts, in the worker process."""

    def __init__(self, gui: viser.GuiApi, session: "CourseArmSession") -> None:
        self._session = session
        self._runs = FoldedRuns(self._search)
        folder = gui.add_folder("Numerical IK", order=0.3)
        self.folders = (folder,)
        with folder:
            self.button = gui.add_button("Find every branch", icon=viser.Icon.SEARCH,
                                         hint="Damped least squares from 48 starts: every distinct solution it finds")
        self.button.on_click(session.guard(lambda _: self._request()))

    def _request(self) -> None:
        self._runs.start("branch-search", self._session.guard)

    def _search(self) -> None:
        session = self._session
        snapshot = session.state.last
        solution = HEAVY.run(session.client, lambda: APART.run(session.state.arm.ik, snapshot.target, hint=snapshot.q),
                             cancelled=lambda: session.closed)
        if not session.closed:
            session.apply(lambda state: state.with_branches(snapshot, solution), move_gizmo=False)


class CourseArmSession(SessionBasics):
    """A browser's course arm: its state, scene, gizmo and panel (the UR10's ``ClientSession`` for other arms).

    ``rebuild(arm, text, convention)``, given for a typed table, puts a newly typed arm in
    this one's place (the server does it); ``text`` and ``convention`` fill the editor.

    ``state``, ``scene`` and ``server``: the classroom's presenter drives an arm drawn in the
    server's shared scene (``ur10teach.serving.classroom``); its panel and gizmo stay its own. A browser
    draws its own arm by default, under ``root``. ``own_camera`` as for ``ClientSession``.
    """

    def __init__(self, client: viser.ClientHandle, arm: Arm, refresher: PanelRefresher, drags: DragQueue,
                 lecture: bool = False, rebuild: Callable[[Arm, str, str], None] | None = None,
                 text: str = "", convention: str = "standard", state: CourseArmState | None = None,
                 scene: CourseArmScene | DesktopArmScene | None = None, server: viser.ViserServer | None = None,
                 own_camera: bool = True, root: str | None = None) -> None:
        self.client = client
        self.arm = arm
        self.state = state or CourseArmState(arm)
        self.refresher = refresher
        self.drags = drags
        self.closed = False
        #: called after every change (the classroom refreshes its live panel)
        self.observers: list[Callable[[CourseSnapshot], None]] = []
        self._senders: tuple[viser.ClientHandle | viser.ViserServer, ...] = (client,) if server is None else (client, server)
        first = self.state.last
        self.scene = scene or arm_scene(client.scene, arm, first, root)
        size = self.scene.size
        self.gizmo = client.scene.add_transform_controls(
            f"{self.scene.root}/target", scale=0.12 * size, line_width=3.0, depth_test=False,
            disable_rotations=arm.task == "position",
            active_axes=(True, True, arm.name != "planar_elbow"),
            wxyz=quaternion(first.target[:3, :3], check=False), position=first.target[:3, 3])
        self.gizmo.on_update(self._dragged)
        gui = client.gui
        self.editor = DHEditor(gui, self, text, convention, rebuild) if rebuild is not None else None
        self.search = BranchSearch(gui, self) if self.state.numerical else None
        self.joints = CourseJointSliders(gui, self, before=self.stop_lessons)
        self.branches = CourseBranches(gui, arm)
        self.singularities = CourseSingularities(gui, self)
        self.dh_table = CourseDHTable(gui, self)
        self.walkthrough = DHWalkthrough(gui, self, getattr(self.scene, "dh_frames", None))
        drawn_in = client.scene if server is None else server.scene
        # the UR10's folders, for this arm's joints and tool: what J does there (docs/kinematics.md §8), its workspace
        nodes = self.scene.root
        self.workspace = WorkspaceView(drawn_in, gui, self, root=nodes)

        self.velocity = VelocityView(drawn_in, gui, self, root=f"{nodes}/velocity", place="tool")
        self.ellipsoids = EllipsoidsView(drawn_in, gui, self, root=f"{nodes}/ellipsoids", place="tool")
        self.statics = StaticsView(drawn_in, gui, self, root=f"{nodes}/statics", size=size)
        self.at_tool_views = (self.velocity, self.ellipsoids, self.statics)
        self.reach_map = ReachMapView(drawn_in, gui, self, root=f"{nodes}/reach_map", world=self.scene.world)
        self.motion = MotionLessons(gui, self, before=self.stop_lessons)
        self.gripper = GripperPose(gui, self) if arm.name == "kr210" else None
        self.lessons = LESSONS[arm.name](drawn_in, gui, self) if arm.name in LESSONS else ()
        self.camera = (CameraControls(client, lambda: self.scene.framed(self.state.last), self.guard, lecture,
                                      body_radius=body_radius(size)) if own_camera else None)
        self.panel_views = (*(v for v in (self.editor, self.search, self.gripper, self.camera) if v is not None),
                            self.joints, self.branches, self.singularities, self.dh_table, self.walkthrough, self.workspace,
                            *self.at_tool_views, self.reach_map, self.motion, *self.lessons)
        self.built = True
        self.render(self.state.last)
        self.render_panel()
        if self.camera is not None:
            self.camera.frame()

    # ------------------------------------------------------------------ changes

    def apply(self, change: Callable[[CourseArmState], CourseSnapshot], timed: str | None = None,
              move_gizmo: bool = True) -> CourseSnapshot:
        """Change the state and redraw the 3D view (the gizmo to the tool, unless the student holds it); the panel follows."""
        start = time.perf_counter()
        with self.state.lock:
            snapshot = change(self.state)
            self.render(snapshot, move_gizmo)
        if timed:
            LATENCY.record(timed, time.perf_counter() - start)
        self.refresher.request(self)
        for observer in self.observers:
            observer(snapshot)
        return snapshot

    def stop_lessons(self) -> None:
        """A slider, a motion or a search moves the arm: a lesson playing a path stops first."""
        for lesson in self.lessons:
            player = getattr(lesson, "player", None)
            if player is not None:
                player.stop()

    def _dragged(self, event: viser.TransformControlsEvent) -> None:
        if self.closed:
            return
        # the drag queue keeps only the newest pose and solves it off viser's thread pool
        self.drags.submit(self, (np.array(self.gizmo.wxyz), np.array(self.gizmo.position), event.phase == "end"))

    def drag_to(self, pose) -> None:
        """The drag queue's worker solving for the gizmo's newest ``(wxyz, position, released)``.

        While held, the gizmo stays where the student has it; once released it snaps to the
        tool if the arm reached (a SCARA's tool turned down again), and stays put, with the
        reason in the panel, if it did not.
        """
        wxyz, position, released = pose
        self.stop_lessons()  # a path playing stops: the drag has the last word, under the arm's lock
        self.guard(lambda _: self.apply(lambda state: state.move_target(transform_from_quaternion(wxyz, position)),
                                        timed="course_drag", move_gizmo=released))(None)

    def render(self, snapshot: CourseSnapshot, move_gizmo: bool = False) -> None:
        if self.closed or not self.built:
            return
        with self._batch():  # the arm and the gizmo arrive together, as in ClientSession.render
            self.scene.render(snapshot)
            for view in (*self.at_tool_views, *self.lessons):
                view.render(snapshot)
            if move_gizmo and not snapshot.reason:
                self.gizmo.wxyz = quaternion(snapshot.frames[-1, :3, :3], check=False)
                self.gizmo.position = snapshot.frames[-1, :3, 3]

    def remove(self) -> None:
        """Close, and take this session's panel and gizmo out of a browser that stays."""
        super().remove()
        self.gizmo.remove()
