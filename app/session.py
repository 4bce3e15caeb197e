"""One browser's arm, panel and target.

viser runs plain ``def`` callbacks on a thread pool, so callbacks of one browser can
overlap: every change goes through :meth:`ClientSession.apply`, which holds the arm's
lock while it changes the state and redraws the 3D view, then asks the
:class:`~ur10teach.serving.workers.PanelRefresher` to redraw the side panel. Every callback is wrapped
by :meth:`ClientSession.guard`: no exception escapes, a refused value is explained in a
notification in that browser, and every other browser carries on.

Each view has ``render(snapshot)`` (the 3D scene, on every change) and
``render_panel(snapshot)`` (the GUI, at most ten times a second).
"""

from __future__ import annotations

import dataclasses
import logging
import time
from typing import Any, Callable

import viser

from ur10core import Arm
from ur10core.orientation import transform_from_quaternion

from .features.course_arms.panel import DHWalkthrough
from .features.dh_frames import FRAMES_NONE, DHFrames
from .features.ik_target import BranchesScene, IKTargetControls
from .features.camera import CameraControls
from .features.lecture import LectureMode
from .features.ellipsoids import EllipsoidsView
from .features.floor import FloorScene
from .features.joint_panel import JointPanel
from .meshes import ArmModels
from .serving.metrics import LATENCY
from .features.motion_lessons import MotionLessons
from .features.reach_map import ReachMapView
from .features.readouts import Readouts
from .serving.workers import DragQueue, PanelRefresher
from .features.robot import ArmModelControls, RobotScene
from .session_basics import SessionBasics
from .features.singularity import OverlayPanel, OverlayScene
from .features.statics import StaticsView
from .features.velocity import VelocityView
from .state import ArmState, Snapshot
from .features.workspace import WorkspaceView

log = logging.getLogger(__name__)

#: The UR10's reach (m), which sizes its DH frames' axes and labels.
DH_FRAMES_SIZE = 1.3


@dataclasses.dataclass
class SceneViews:
    """The 3D part of an arm: solid arm, ghost branches, singularity geometry, floor warnings.

    A session builds its own on its browser's scene; the classroom builds one on the
    shared scene, which the presenter's session then drives.
    """

    robot: RobotScene
    branches: BranchesScene
    overlay: OverlayScene
    floor: FloorScene

    @classmethod
    def build(cls, scene: viser.SceneApi, models: ArmModels, first: Snapshot,
              target_marker: bool = False) -> "SceneViews":
        branches = BranchesScene(scene, models, first, target_marker)
        return cls(RobotScene(scene, models, first), branches, OverlayScene(scene, first), FloorScene(scene, branches))

    def show(self, model: str) -> None:
        """Draw the solid arm and its ghosts as ``model`` ("Real UR10", "Schematic")."""
        self.robot.show(model)
        self.branches.show(model)

    def __iter__(self):  # the floor after the branches: it marks the ghosts they drew
        return iter((self.robot, self.branches, self.overlay, self.floor))


class ClientSession(SessionBasics):
    """One browser's controls on an arm.

    Parameters
    ----------
    client : viser.ClientHandle
        The browser. Its panel and gizmo are always its own.
    arm, models : Arm, ArmModels
        The arm's dimensions, and the meshes it can be drawn with.
    refresher, drags : PanelRefresher, DragQueue
        The server's workers: panel redraws and drag events, off viser's thread pool.
    state : ArmState, optional
        The arm to drive; a new one at the home pose by default.
    own_camera, lecture : bool
        Build the browser's "View" folder (camera framing, :mod:`ur10teach.features.camera`; lecture mode,
        starting as ``lecture`` says); the classroom builds one per browser instead,
        whatever its role.
    server, scene_views : viser.ViserServer, SceneViews, optional
        Where the arm is drawn: the browser's own scene by default; the classroom's
        presenter drives the views in the server's shared scene instead. Their messages
        go out through the server's queue, which a redraw batches (``atomic``) and sends
        at once (``flush``) as it does the browser's own: viser otherwise holds a message
        up to 1/60 s to batch it with the next, and a viewer could see the arm moved and
        its ghosts not yet.
    """

    _lecture: LectureMode | None = None  #: the lecture switch it follows, once it follows one

    def __init__(
        self, client: viser.ClientHandle, arm: Arm, models: ArmModels, refresher: PanelRefresher,
        drags: DragQueue, state: ArmState | None = None, server: viser.ViserServer | None = None,
        scene_views: SceneViews | None = None, own_camera: bool = True, lecture: bool = False,
    ) -> None:
        self.client = client
        self.arm = arm
        self.state = state or ArmState(arm, body_points=models.outline)
        self.refresher = refresher
        self.drags = drags
        self.closed = False
        #: called after every change, e.g. to refresh the classroom's live panel
        self.observers: list[Callable[[Snapshot], None]] = []
        scene = client.scene if server is None else server.scene
        self._senders: tuple[viser.ClientHandle | viser.ViserServer, ...] = (client,) if server is None else (client, server)
        gui = client.gui
        first = self.state.last
        self.scene_views = scene_views or SceneViews.build(scene, models, first)
        self.joints = JointPanel(gui, self)
        #: "Arm drawn as" (real or schematic), where the arm has more than one model
        self.arm_model = (ArmModelControls(gui, self.joints.folders[0], self.scene_views, self)
                          if len(self.scene_views.robot.names) > 1 else None)
        self.ik_target = IKTargetControls(client.scene, gui, self.scene_views.branches, self)
        self.readouts = Readouts(gui, arm, first)
        self.singularity = OverlayPanel(gui, self.scene_views.overlay, self)
        self.workspace = WorkspaceView(scene, gui, self)
        self.reach_map = ReachMapView(scene, gui, self)
        self.statics = StaticsView(scene, gui, self)
        self.ellipsoids = EllipsoidsView(scene, gui, self)
        self.velocity = VelocityView(scene, gui, self)
        self.motion = MotionLessons(gui, self)
        #: the course's table as frames on the arm, hidden until the walkthrough draws them
        self.dh_frames = DHFrames(scene, arm, first.frames, DH_FRAMES_SIZE, "/dh_frames", at_rest=FRAMES_NONE)
        self.walkthrough = DHWalkthrough(gui, self, self.dh_frames)
        self.camera = CameraControls(client, lambda: self.state.last, self.guard, lecture) if own_camera else None
        if self.camera is not None:
            self.follow_lecture_mode(self.camera.lecture)
        #: the views this session built in the browser's own panel (the scene views may be the classroom's)
        self.panel_views = (self.joints, *([self.arm_model] if self.arm_model else []), self.ik_target, self.readouts,
                            self.singularity, self.workspace, self.reach_map, self.statics, self.ellipsoids, self.velocity,
                            self.motion, self.dh_frames, self.walkthrough, *([self.camera] if self.camera else []))
        self.views = (*self.scene_views, *self.panel_views)
        self.built = True
        self.render(self.state.last)  # as a click during the build may have left it
        self.render_panel()

    # ------------------------------------------------------------------ changes

    def apply(self, change: Callable[[ArmState], Snapshot], timed: str | None = None) -> Snapshot:
        """Change the state and redraw this browser's 3D view; the panel follows shortly."""
        start, cpu_start = time.perf_counter(), time.thread_time()
        with self.state.lock:
            snapshot = change(self.state)
            self.render(snapshot)
        if timed:
            LATENCY.record(timed, time.perf_counter() - start)
            # the server's own work, without the time the OS gave other processes meanwhile
            LATENCY.record(f"{timed}_cpu", time.thread_time() - cpu_start)
        self.refresher.request(self)
        for observer in self.observers:
            observer(snapshot)
        return snapshot

    def drag_to(self, pose) -> None:
        """The drag queue's worker solving for the gizmo's newest ``(wxyz, position)``."""
        self.guard(lambda _: self.apply(lambda state: state.move_target(transform_from_quaternion(*pose)), timed="drag"))(None)

    def render(self, snapshot: Snapshot) -> None:
        """The 3D scene, atomically."""
        if self.closed or not self.built:
            return
        with self._batch():
            for view in self.views:
                view.render(snapshot)

    def render_panel(self) -> None:
        """The side panel, from the newest state (called by the refresher, one thread at a time)."""
        if self.closed or not self.built:
            return
        start = time.perf_counter()
        snapshot = self.state.last
        with self.client.atomic():
            for view in self.views:  # the scene views' panel parts too (the branch numbers, say)
                view.render_panel(snapshot)
        LATENCY.record("panel", time.perf_counter() - start)

    def follow_lecture_mode(self, lecture: "LectureMode") -> None:
        """Thick gizmo lines while the browser's lecture mode is on (until this session closes)."""
        lecture.on_change.append(self.ik_target.thicken)
        self._lecture = lecture
        self.ik_target.thicken(lecture.on)

    def _unfollow_lecture_mode(self) -> None:
        # the classroom's lecture switch outlives this session: it must not keep the session alive
        if self._lecture is not None and self.ik_target.thicken in self._lecture.on_change:
            self._lecture.on_change.remove(self.ik_target.thicken)
        self._lecture = None

    def _leave(self, how: Callable[[Any], None]) -> None:
        self._unfollow_lecture_mode()
        super()._leave(how)
