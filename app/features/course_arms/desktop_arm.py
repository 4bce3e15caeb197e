"""The course's 3-DOF desktop arm in a browser (docs/kinematics.md §8.6): drawn with its parallelogram drive,
and the session that drives it.

The arm is not a DH chain (its forearm angle is absolute), so it has a session of its own:
joint sliders instead of an IK target, and the course's two exercises as lessons
(``desktop_lessons``).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import viser

from ur10core.orientation import quaternion
from ur10core import Arm

from ..camera import CameraControls
from ...session_basics import SessionBasics
from ..motion_lessons import MotionLessons
from ..reach_map import ReachMapView
from ...style import JOINT_CAP_GREY, SHOULDER_COLOR
from ..velocity import ANGULAR_COLOR, LINEAR_COLOR
from ...view import View
from ...serving.workers import PanelRefresher
from .desktop_lessons import CoursePathLesson, DesktopAbout, DesktopForces
from .panel import CourseJointSliders
from .desktop_state import COURSE_TO_WORLD, DesktopArmState, DesktopSnapshot, to_world

ROOT = "/desktop_arm"
#: A classroom explorer's own desktop arm, apart from the class's (which it hides in that one browser).
EXPLORER_ROOT = "/explored_desktop_arm"
#: Length of the parallelogram's crank at the shoulder (m): the drive is drawn to scale with it.
CRANK = 0.3
LINK_GREY = (90, 94, 102)
DRIVE_COLOR = SHOULDER_COLOR
#: Arrows: metres drawn per m/s of the tool, and per rad/s of its turning.
METRES_PER_SPEED, METRES_PER_TURN_RATE = 1.0, 0.6


class DesktopArmScene(View):
    """The arm in 3D: pedestal, upper arm and forearm, the parallelogram drive, the course's base frame, the arrows."""

    def __init__(self, scene: viser.SceneApi, arm: Arm, first: DesktopSnapshot, root: str = ROOT) -> None:
        self._arm = arm
        self.root = root  #: every node's parent: a classroom explorer's own arm has one apart from the class's
        self.size = arm.upper_arm + arm.forearm  #: the arm's reach (m)
        self.links = scene.add_line_segments(f"{root}/links", self._links(first), LINK_GREY, thickness=0.06)
        self.drive = scene.add_line_segments(f"{root}/drive", self._drive(first), DRIVE_COLOR, thickness=0.025)
        self.joints = [scene.add_icosphere(f"{root}/joint_{k}", radius=0.07, color=JOINT_CAP_GREY, position=p)
                       for k, p in enumerate(first.points[1:3])]
        wxyz = quaternion(COURSE_TO_WORLD, check=False)
        scene.add_frame(f"{root}/base_frame", wxyz=wxyz, position=first.points[1], axes_length=0.45, axes_radius=0.012)
        for name, axis in (("x₀", (0.5, 0, 0)), ("y₀ (up)", (0, 0.5, 0)), ("z₀", (0, 0, 0.5))):
            scene.add_label(f"{root}/base_frame/{name}", name, font_screen_scale=1.3, position=axis)
        self.tool = scene.add_frame(f"{root}/tool", axes_length=0.3, axes_radius=0.01)
        self.labels = [scene.add_label(f"{root}/label_{k}", text, font_screen_scale=1.4, anchor="bottom-left")
                       for k, text in enumerate(("θ2", "θ3 (absolute)", "tool"))]
        self.velocity = [scene.add_arrows(f"{root}/{name}", np.zeros((1, 2, 3)), colour, shaft_radius=0.015,
                                          head_radius=0.04, head_length=0.08, visible=False)
                         for name, colour in (("linear", LINEAR_COLOR), ("angular", ANGULAR_COLOR))]
        self.velocity_labels = [scene.add_label(f"{root}/{name}_label", text, font_screen_scale=1.4, anchor="center-left",
                                                visible=False) for name, text in (("linear", "v"), ("angular", "ω"))]
        self.render(first)

    @staticmethod
    def _links(snapshot: DesktopSnapshot) -> np.ndarray:
        foot, shoulder, elbow, tool = snapshot.points
        return np.array([[foot, shoulder], [shoulder, elbow], [elbow, tool]])

    @staticmethod
    def _drive(snapshot: DesktopSnapshot) -> np.ndarray:
        """The crank at the shoulder, the coupler and the lever at the elbow: a parallelogram, so the forearm keeps the crank's angle."""
        _, shoulder, elbow, tool = snapshot.points
        back = CRANK * (elbow - tool) / np.linalg.norm(tool - elbow)
        return np.array([[shoulder, shoulder + back], [shoulder + back, elbow + back], [elbow + back, elbow]])

    def render(self, snapshot: DesktopSnapshot) -> None:
        self.links.points = self._links(snapshot)
        drive = self._drive(snapshot)
        self.drive.points = drive
        for joint, point in zip(self.joints, snapshot.points[1:3]):
            joint.position = point
        self.tool.wxyz = quaternion(COURSE_TO_WORLD @ snapshot.tool[:3, :3], check=False)
        self.tool.position = snapshot.points[3]
        for label, point in zip(self.labels, (snapshot.points[1], drive[0, 1], snapshot.points[3])):
            label.position = point
        moving = bool(np.any(snapshot.rates))
        if moving:
            twist = self._arm.tool_twist(snapshot.q, snapshot.rates)
            tip = snapshot.points[3]
            for arrow, label, vector, scale in zip(self.velocity, self.velocity_labels, (twist[:3], twist[3:]),
                                                   (METRES_PER_SPEED, METRES_PER_TURN_RATE)):
                end = tip + scale * COURSE_TO_WORLD @ vector
                arrow.points = np.array([[tip, end]])
                label.position = end
        for node in (*self.velocity, *self.velocity_labels):
            if node.visible != moving:
                node.visible = moving


class DesktopArmSession(SessionBasics):
    """A browser driving the course's 3-DOF desktop arm (``Arm.preset("three_dof")``), as ``CourseArmSession`` does a DH arm.

    ``state``, ``scene``, ``server``, ``own_camera`` and ``root`` as for ``CourseArmSession``: the
    classroom's presenter drives an arm drawn in the server's shared scene, an explorer its own.
    """

    def __init__(self, client: viser.ClientHandle, arm: Arm, refresher: PanelRefresher, lecture: bool = False,
                 state: DesktopArmState | None = None, scene: DesktopArmScene | None = None,
                 server: viser.ViserServer | None = None, own_camera: bool = True, root: str = ROOT) -> None:
        self.client = client
        self.arm = arm
        self.refresher = refresher
        self.closed = False
        self.state = state or DesktopArmState(arm)
        #: called after every change (the classroom refreshes its live panel)
        self.observers: list[Callable[[DesktopSnapshot], None]] = []
        self._senders: tuple[viser.ClientHandle | viser.ViserServer, ...] = (client,) if server is None else (client, server)
        first = self.state.last
        self.scene = scene or DesktopArmScene(client.scene, arm, first, root)
        gui = client.gui
        self.about = DesktopAbout(gui, self)
        # a slider stops the course's path first: the arm goes where the student puts it
        self.joints = CourseJointSliders(gui, self, before=lambda: self.path.player.stop(), order=1.0)
        self.path = CoursePathLesson(gui, self)
        self.motion = MotionLessons(gui, self, before=lambda: self.path.player.stop())
        world = np.eye(4)  # the course's base frame (y up) in the scene, the shoulder raised off the floor
        world[:3, :3], world[:3, 3] = COURSE_TO_WORLD, to_world(np.zeros(3))
        self.reach_map = ReachMapView(client.scene if server is None else server.scene, gui, self,
                                      root=f"{self.scene.root}/reach_map", target_of=lambda snapshot: snapshot.tool,
                                      world=world)
        self.forces = DesktopForces(client.scene if server is None else server.scene, gui, self, self.scene.root)
        self.camera = (CameraControls(client, self._framed, self.guard, lecture, body_radius=0.15 * self.scene.size)
                       if own_camera else None)
        self.panel_views = (*((self.camera,) if self.camera is not None else ()), self.about, self.joints, self.path,
                            self.forces, self.reach_map, self.motion)
        self.built = True
        self.render(self.state.last)
        self.render_panel()
        if self.camera is not None:
            self.camera.frame()

    def _framed(self) -> DesktopSnapshot:
        """What the camera frames: the arm as it is, and its reach about the shoulder level and above."""
        snapshot = self.state.last
        shoulder = snapshot.points[1]
        ends = shoulder + self.scene.size * np.array([[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0], [0, 0, 1.0]])
        return DesktopSnapshot(snapshot.q, snapshot.rates, snapshot.tool, np.vstack([snapshot.points, ends]))

    def apply(self, change: Callable[[DesktopArmState], DesktopSnapshot]) -> DesktopSnapshot:
        with self.state.lock:
            snapshot = change(self.state)
            self.render(snapshot)
        self.refresher.request(self)
        for observer in self.observers:
            observer(snapshot)
        return snapshot

    def render(self, snapshot: DesktopSnapshot) -> None:
        if self.closed or not self.built:
            return
        with self._batch():  # the arm and its arrows arrive together
            self.scene.render(snapshot)
            self.forces.render(snapshot)
