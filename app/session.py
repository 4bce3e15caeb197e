"""One browser's arm, panel and target, for any arm of the course.

Why it is built so: docs/architecture.md §1.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from typing import Any, Callable

import numpy as np
import viser

from ur10core import Arm

from .features.branch_labels import BranchLabels, ScreenView, chain, place_in_order, screen_view
from .features.branch_search import BranchSearch
from .features.camera import CameraControls
from .features.course_arms.desktop_lessons import desktop_lessons
from .features.course_arms.editor import DHEditor
from .features.course_arms.kr210_lessons import kr210_lessons
from .features.decoupling import DecouplingView
from .features.dh_table import DHTableView, DHWalkthrough
from .features.drawings import MeshArm, arm_drawing
from .features.ellipsoids import EllipsoidsView
from .features.ik_target import IKTarget, pose_from_gizmo
from .features.joint_panel import JointPanel
from .features.lecture import LectureMode, size_chart, size_labels
from .features.light_view import LightView
from .features.motion_lessons import MotionLessons
from .features.reach_map import ReachMapView
from .features.readouts import Readouts
from .features.robot import ArmModelControls
from .features.singularity import Singularities
from .features.statics import StaticsView
from .features.velocity import VelocityView
from .features.workspace import WorkspaceView
from .feedback import Beside, guard, notify
from .meshes import SCHEMATIC, ArmModels, material
from .serving.metrics import LATENCY
from .serving.workers import DragQueue, PanelRefresher
from .state import ArmState, Snapshot
from .style import NAME_SCALE
from .view import View

log = logging.getLogger(__name__)

#: Changes after which the camera frames the arm again: it may have gone far (a drag or a slider moves it gradually).
REFRAMED = ("singularity", "typed")
#: An arm's own lessons (the course's exercises with it), beside the features every arm has.
LESSONS = {"three_dof": desktop_lessons, "kr210": kr210_lessons}


class ArmSession:
    """One browser's controls on an arm.

    Parameters
    ----------
    client : viser.ClientHandle
        The browser. Its panel and gizmo are always its own.
    arm : Arm
        Any arm of the course, or a typed table.
    refresher, drags : PanelRefresher, DragQueue
        The server's workers: panel redraws and drag events, off viser's thread pool.
    models : ArmModels, optional
        UR's meshes, to draw a UR-family arm with; its DH skeleton otherwise.
    state : ArmState, optional
        The arm to drive; a new one at the home pose by default.
    server, drawing : viser.ViserServer, drawing, optional
        Where the arm is drawn: the browser's own scene by default (under ``root``, for a
        classroom explorer's arm apart from the class's); the classroom's presenter drives a
        drawing in the server's shared scene instead. Its messages go out through the
        server's queue, which a redraw batches (``atomic``) and sends at once (``flush``) as it
        does the browser's own: viser otherwise holds a message up to 1/60 s to batch it with
        the next, and a viewer could see the arm moved and its ghosts not yet.
    own_camera, lecture, light, phone : bool
        Build the browser's "View" folder (camera framing, :mod:`ur10teach.features.camera`; lecture
        mode and the light view, starting as ``lecture`` and ``light`` say; framed above the panel on a
        ``phone``), handed the browser's camera moves by whoever holds the session
        (``camera.relay_camera_moves``); the classroom builds one per browser instead.
    rebuild, text, convention : optional
        For a typed table: ``rebuild(arm, text, convention)`` puts a newly typed arm in this
        one's place (the server does it); ``text`` and ``convention`` fill the DH editor.
    asks : str, optional
        What a class challenge running on this arm asks (``Challenge.asks``): the views hold back what would answer
        it from the first draw on (``hold_back``), so that a browser is never sent it.

    Its widgets reach the browser as they are made, so a quick click can run a callback before
    the constructor ends: until the constructor sets ``built``, nothing is drawn, and the first
    render then draws the state as that click left it.
    """

    built = False
    panel_views: tuple = ()
    #: built last: a click during the build finds none (no path playing to stop, no camera to reframe)
    motion: MotionLessons | None = None
    lessons: tuple = ()
    camera: CameraControls | None = None
    _lecture: LectureMode | None = None  #: the lecture switch it follows, once it follows one
    _light: LightView | None = None  #: the light-view switch it follows, once it follows one
    #: the arm picker's label of this arm, and the typed table (arm, text, convention) it was
    #: built from: the server sets them, and keeps the state under them when the browser leaves the arm
    choice: str = ""
    typed: tuple | None = None

    def __init__(
        self, client: viser.ClientHandle, arm: Arm, refresher: PanelRefresher, drags: DragQueue,
        models: ArmModels | None = None, state: ArmState | None = None, server: viser.ViserServer | None = None,
        drawing=None, own_camera: bool = True, lecture: bool = False, root: str | None = None,
        rebuild: Callable[[Arm, str, str], None] | None = None, text: str = "", convention: str = "standard",
        asks: str | None = None, light: bool = False, phone: bool = False,
    ) -> None:
        self.client = client
        self.arm = arm
        self.state = state or ArmState(arm, body_points=None if models is None else models.outline)
        self.refresher = refresher
        self.drags = drags
        self.closed = False
        self._panel_drawn = threading.RLock()  # a close waits for a panel redraw under way, not the reverse
        #: called after every change, e.g. to refresh the classroom's live panel
        self.observers: list[Callable[[Snapshot], None]] = []
        #: called after a redraw with the state unchanged (a toggle): the live panel shows the overlay's gauges with it
        self.redrawn: list[Callable[[], None]] = []
        scene = client.scene if server is None else server.scene
        self._senders: tuple[viser.ClientHandle | viser.ViserServer, ...] = (client,) if server is None else (client, server)
        gui = client.gui
        first = self.state.last
        self.drawing = drawn = drawing or arm_drawing(scene, arm, first, models, root)
        self.editor = DHEditor(gui, self, text, convention, rebuild) if rebuild is not None else None
        self.search = BranchSearch(gui, self) if self.state.numerical else None
        self.joints = JointPanel(gui, self, before=self.stop_lessons)
        #: "Arm drawn as" (real or schematic), where the drawing has more than one model
        self.arm_model = ArmModelControls(gui, self.joints.folders[0], drawn, self) if len(drawn.names) > 1 else None
        self.ik_target = IKTarget(client.scene, gui, drawn, self)
        self.readouts = Readouts(gui, first)
        self.singularities = Singularities(gui, drawn.overlay, self)
        self.decoupling = DecouplingView(gui, self)
        self.dh_table = DHTableView(gui, self, drawn.dh_frames)
        self.walkthrough = DHWalkthrough(gui, self, drawn.dh_frames)
        nodes = drawn.root
        self.workspace = WorkspaceView(scene, gui, self, root=nodes, size=drawn.size)
        self.reach_map = ReachMapView(scene, gui, self, root=f"{nodes}/reach_map", world=drawn.world)
        self.statics = StaticsView(scene, gui, self, root=f"{nodes}/statics", size=drawn.size,
                                  handle_size=drawn.handle_size)
        self.ellipsoids = EllipsoidsView(scene, gui, self, root=f"{nodes}/ellipsoids", reach=drawn.size)
        self.velocity = VelocityView(scene, gui, self, root=f"{nodes}/velocity", size=drawn.size)
        self.motion = MotionLessons(gui, self, before=self.stop_lessons, payload_kg=self.statics.payload_kg)
        self.lessons = LESSONS[arm.name](scene, gui, self) if arm.name in LESSONS else ()
        # its camera's moves are handed to it (``camera.relay_camera_moves``): viser would keep a callback of its own
        self.camera = (CameraControls(client, lambda: drawn.framed(self.state.last), self.guard, lecture,
                                      arm=arm, body_radius=drawn.body_radius, follow=False, light=light,
                                      phone=phone)
                       if own_camera else None)
        #: the scene whose 3D labels this browser's lecture mode sizes: its own (a shared one follows the server's)
        self._label_scene = scene if server is None else None
        #: (frame (4, 4)) -> the names drawn in this browser by something else (a challenge's target), as
        #: ``branch_labels.obstacle`` tuples in that frame
        self.names_elsewhere: Callable[[Any], list] = lambda frame: []
        #: the views this session built in the browser's own panel (the drawing may be the classroom's)
        self.panel_views = tuple(view for view in (
            self.editor, self.search, self.joints, self.arm_model, self.ik_target, self.readouts,
            self.singularities, self.decoupling, self.dh_table, self.walkthrough, self.workspace, self.reach_map,
            self.statics, self.ellipsoids, self.velocity, self.motion, *self.lessons, self.camera) if view is not None)
        self.views = (drawn, *self.panel_views)
        if self.camera is not None:
            self.follow_lecture_mode(self.camera.lecture)
            self.follow_light_view(self.camera.light)
        #: what the views name at moving points (``View.names``: the arrows' tips), placed apart before the
        #: drawing's own labels, which keep clear of them
        colours = [colour for _, _, colour in self._named()]
        self.names = BranchLabels(scene, f"{nodes}/view_names", len(colours), scale=NAME_SCALE, colours=colours,
                                  merge_px=0.0)  # names of different things at one spot: each its own, not "a · b"
        self.names.view, self.names.world, self.names.fixed = (lambda: drawn.label_sets[0].view()), drawn.world, self._fixed_labels
        chain(drawn.label_sets, outside=self._names_beside)
        self.names.placing = drawn.label_sets[0].placing  # placed first, in the same turn as the drawing's
        pools = (self.names, *drawn.label_sets)
        placed = self.guard(lambda _: place_in_order(pools))
        self._place_numbers = lambda: placed(None)  # on every camera move: the 3D labels placed for the new view
        if server is None:  # the 3D labels placed apart for this browser's camera, as it moves
            for labels in drawn.label_sets:
                labels.view = self._screen_view
        if self.camera is not None:
            self.watch_camera(self.camera)
        if asks is not None:  # before anything is drawn (not yet built): a browser is sent no readout a challenge asks
            self.hold_back(asks)
        self.built = True
        self.render(self.state.last)  # as a click during the build may have left it
        self.render_panel()
        if self.camera is not None:
            self.camera.frame()

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
        if snapshot.cause in REFRAMED and self.camera is not None:
            self.camera.frame()  # the arm may have gone far from where the student was looking
        return snapshot

    def drag_to(self, pose) -> None:
        """The drag queue's worker solving for the gizmo's newest ``(wxyz, position, released)``.

        While held, the gizmo stays where the student has it; once released it goes onto the
        target the arm took (a SCARA's tool turned down again).
        """
        self.stop_lessons()  # a path playing stops: the drag has the last word, under the arm's lock

        def move(state: ArmState) -> Snapshot:
            T, released = pose_from_gizmo(pose, state.arm)  # ValueError for a pose a bad client made up
            return state.move_target(T, cause="dropped" if released else "target")

        self.guard(lambda _: self.apply(move, timed="drag"))(None)

    def stop_lessons(self) -> None:
        """A slider, a motion or a search moves the arm: a path playing stops first."""
        for lesson in (self.motion, *self.lessons):
            player = getattr(lesson, "player", None)
            if player is not None:
                player.stop()

    def hold_back(self, asked: str | None) -> None:
        """A class challenge asking ``asked`` (``Challenge.asks``) runs on this arm, or none does (None): each view
        takes away what would answer it, or gives it back (``View.hold_back``), and the scene and panel follow."""
        with self.state.lock:  # not while the panel is being taken away (``_leave``: a hand-over, on another thread)
            if self.closed:
                return
            before = [view.held for view in self.panel_views]
            for view in self.panel_views:
                view.hold_back(asked)
            changed = [view.held for view in self.panel_views] != before
        if changed:  # a reach holds nothing: a hundred arms not redrawn
            self.redraw()

    def redraw(self) -> None:
        """The 3D view again, unchanged state (a toggle changed what is shown), and the panel after it."""
        with self.state.lock:
            self.render(self.state.last)
        self.refresher.request(self)
        for follower in self.redrawn:
            follower()

    def render(self, snapshot: Snapshot) -> None:
        """The 3D scene, atomically, to every sender."""
        if self.closed or not self.built:
            return
        with contextlib.ExitStack() as batch:
            for sender in self._senders:
                batch.enter_context(sender.atomic())
            for view in self.views:
                self._refusing(view.render, snapshot)
        for sender in self._senders:
            sender.flush()

    def render_panel(self) -> None:
        """The side panel, from the newest state (called by the refresher, one thread at a time)."""
        with self._panel_drawn:
            if self.closed or not self.built:
                return
            start = time.perf_counter()
            snapshot = self.state.last
            with self.client.atomic():
                if self._label_scene is not None and self._lecture is not None:
                    size_labels(self._label_scene, self._lecture.on)
                with self.names.placing:  # the names first, as the drawing's labels keep clear of them
                    self._refusing(lambda _: self._show_names(), snapshot)
                    self._refusing(self.drawing.render_panel, snapshot)  # its panel-paced parts: the branch numbers
                for view in self.panel_views:
                    self._refusing(view.render_panel, snapshot)
            LATENCY.record("panel", time.perf_counter() - start)

    def _refusing(self, draw: Callable[[Snapshot], None], snapshot: Snapshot) -> None:
        """Draw one view; a value it refuses (a slider a client set out of range, which it puts back) is
        explained, and the other views are drawn all the same: the change being drawn is not the refused one."""
        try:
            draw(snapshot)
        except ValueError as refused:
            self.notify("Not accepted", str(refused))
            # numpy's shape errors are ValueErrors too: the teacher's console keeps what tells a bug from a refusal
            log.info("browser %s: a redraw refused a value: %s", self.client.client_id, refused, exc_info=True)

    # ------------------------------------------------------------------ display choices

    def _kept_views(self):
        """The panel's views whose choices the server keeps with the arm: lecture mode follows the browser,
        and the state has the pose."""
        return (view for view in self.panel_views if view is not self.camera and view is not self.joints)

    def _switches(self):
        """((view, label), handle) of each checkbox, dropdown, slider and text box of the panel: what is shown,
        the settings of the lessons (joint rates, the force, a section's height) and what was typed, not where
        the arm is."""
        for view in self._kept_views():
            for value in vars(view).values():
                for handle in value if isinstance(value, list) else (value,):  # the Velocities' rate sliders
                    if isinstance(handle, (viser.GuiCheckboxHandle, viser.GuiDropdownHandle, viser.GuiSliderHandle,
                                           viser.GuiTextHandle)):
                        yield (type(view).__name__, handle.label), handle

    def display_choices(self) -> dict[tuple[str, Any], Any]:
        """What the student chose to show (ghosts, overlay, cloud, frames, …), set (joint rates, the force,
        the payload, a section's height), typed and asked (a tool velocity): the server keeps it with the arm."""
        kept = {(type(view).__name__, None): view.kept() for view in self._kept_views()}
        return {key: handle.value for key, handle in self._switches()} | {key: value for key, value in kept.items() if value}

    def show_choices(self, choices: dict[tuple[str, Any], Any]) -> None:
        """Show what was chosen when the browser last had this arm (each switch's own callback applies it)."""
        for key, handle in self._switches():
            if key in choices and handle.value != choices[key]:
                handle.value = choices[key]
        for view in self._kept_views():
            if (type(view).__name__, None) in choices:
                view.restore(choices[type(view).__name__, None])

    # ------------------------------------------------------------------ the browser

    def guard(self, handler: Callable[[Any], None], beside: Beside | None = None) -> Callable[[Any], None]:
        """Wrap a viser callback so that nothing it raises escapes; a refusal is explained ``beside`` its input
        (see ``ur10teach.feedback``)."""
        return guard(self.client, handler, is_closed=lambda: self.closed, on_refused=lambda: self.refresher.request(self),
                     beside=beside)

    def watch_camera(self, camera: CameraControls) -> None:
        """Use this browser's camera (a classroom's member has one for all its sessions): frame with it,
        and place the branch numbers of this session's own drawing for it as it moves."""
        self.camera = camera
        camera.show_arm(self.drawing.body_radius, self.arm)
        if self._label_scene is not None:
            camera.on_moved.append(self._place_numbers)

    def _fixed_labels(self) -> list:
        """The 3D labels drawn where they stay (``View.obstacles``: a map's largest ‖τ‖, say) and
        :attr:`names_elsewhere`, in the drawing's frame: every placed label keeps clear of them."""
        if self.closed:
            return []
        return [*(label for view in self.panel_views for label in view.obstacles()), *self.names_elsewhere(self.drawing.world)]

    def _names_beside(self) -> list:
        """What the drawing's placed labels keep clear of: the views' names (:attr:`names`) and the fixed labels."""
        return [] if self.closed else [*self.names.labels, *self._fixed_labels()]

    def colouring_shown(self, shown: View) -> None:
        for view in self.panel_views:
            if view is not shown:
                view.hide_colouring()

    def _named(self) -> list[tuple]:
        return [name for view in self.panel_views for name in view.names()]

    def _show_names(self) -> None:
        named = self._named()
        points = [np.zeros(3) if point is None else point for point, _, _ in named]
        self.names.show(np.array(points, dtype=float).reshape(-1, 3), ["" if point is None else text for point, text, _ in named])

    def _screen_view(self) -> ScreenView:
        """This browser's camera, to place the branch numbers for (the default one until it reports)."""
        return self.camera.view() if self.camera is not None else screen_view(self.client)

    def notify(self, title: str, body: str, color: str = "yellow") -> None:
        if not self.closed:
            notify(self.client, title, body, color)

    def follow_lecture_mode(self, lecture: LectureMode) -> None:
        """Thick gizmo lines and big 3D labels while the browser's lecture mode is on (until this session closes)."""
        lecture.on_change.append(self._lecture_changed)
        self._lecture = lecture
        self._lecture_changed(lecture.on)  # a panel built before it followed one has not sized its labels

    def _lecture_changed(self, on: bool) -> None:
        """Lecture mode switched: thick gizmo lines, big chart axes, and the 3D labels sized at the next panel redraw."""
        self.ik_target.thicken(on)
        for chart in (chart for view in self.panel_views for chart in view.charts):
            size_chart(chart, on)
        self.refresher.request(self)

    def follow_light_view(self, light: LightView) -> None:
        """The arm drawn as the schematic, toon-shaded, while the browser's light view is on, as first drawn after
        (until this session closes). Only a session with a drawing of its own follows: the class's arm is the
        presenter's."""
        light.on_change.append(self._light_changed)
        self._light = light
        if light.on:
            self._light_changed(True)

    def _light_changed(self, on: bool) -> None:
        drawing = self.drawing
        if not isinstance(drawing, MeshArm):  # a line drawing is drawn unlit
            return
        with self.state.lock:
            drawing.set_material(material(on))  # without the environment map's light, toon keeps the colours
            drawing.show(SCHEMATIC if on else drawing.names[0])  # ("Arm drawn as", if any, follows at its next render)
        self.redraw()

    def close(self) -> None:
        """The browser has gone (or handed over): stop drawing and let go of everything shared."""
        self._leave(lambda view: view.close())

    def remove(self) -> None:
        """Close, and take this session's panel and gizmo out of a browser that stays."""
        self._leave(lambda view: view.remove())

    def _leave(self, how: Callable[[Any], None]) -> None:
        # the classroom's lecture switch outlives this session: it must not keep the session alive
        if self._lecture is not None and self._lecture_changed in self._lecture.on_change:
            self._lecture.on_change.remove(self._lecture_changed)
        self._lecture = None
        if self._light is not None and self._light_changed in self._light.on_change:
            self._light.on_change.remove(self._light_changed)
        self._light = None
        if self.camera is not None and self._place_numbers in self.camera.on_moved:
            self.camera.on_moved.remove(self._place_numbers)
        self.closed = True
        pools = self.drawing.label_sets
        if pools and pools[0].outside == self._names_beside:  # a shared drawing outlives this session
            chain(pools)
        # not while a drag or the panel is being drawn: an update would reach a widget the browser has removed
        with self._panel_drawn, self.state.lock:
            for view in self.panel_views:
                how(view)
            self.names.remove()  # from a scene everyone shares too
        self.refresher.forget(self)
