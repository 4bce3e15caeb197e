"""The course's 3-DOF desktop arm in a browser (docs/kinematics.md §8.6): its parallelogram drive,
its tool velocities along the course's joint path, and the pose that needs the most torque for a tool force.

The arm is not a DH chain (its forearm angle is absolute), so it has a session of its own:
joint sliders instead of an IK target, and the course's two exercises as lessons.
"""

from __future__ import annotations

import contextlib
import math
import threading
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import viser
import viser.uplot

from ur10core.orientation import quaternion
from ur10core.three_dof import ThreeDofArm, course_path, torque_grid

from ..animation import Player
from ..camera import CameraControls
from ..feedback import chosen, guard, notify
from ..style import DANGER_RED, JOINT_CAP_GREY, SHOULDER_COLOR, SLOT_COLORS, hex_color, number
from ..velocity import ANGULAR_COLOR, LINEAR_COLOR
from ..view import View
from ..workers import HEAVY, FoldedRuns, PanelRefresher
from ..workspace import colormap

ROOT = "/desktop_arm"
#: A classroom explorer's own desktop arm, apart from the class's (which it hides in that one browser).
EXPLORER_ROOT = "/explored_desktop_arm"
#: The course's y = 0 (the shoulder) stands this high above the floor, so that every reach stays above it.
SHOULDER_HEIGHT = 1.5
#: The course's base frame (y up) turned into the app's world (z up): Rx(90°), so x stays, y → z, z → −y.
COURSE_TO_WORLD = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
#: Length of the parallelogram's crank at the shoulder (m): the drive is drawn to scale with it.
CRANK = 0.3
LINK_GREY = (90, 94, 102)
DRIVE_COLOR = SHOULDER_COLOR
JOINT_LABELS = ("θ1 base", "θ2 upper arm", "θ3 forearm")
#: The course's path: one period of its sin t, played in real time.
PATH_SECONDS = 2 * math.pi
PATH_STEPS = 361
#: Arrows: metres drawn per m/s of the tool, and per rad/s of its turning.
METRES_PER_SPEED, METRES_PER_TURN_RATE = 1.0, 0.6
#: Directions of the tool force, in the course's frame (y up).
DIRECTIONS = {"down (−y)": (0.0, -1.0, 0.0), "up (+y)": (0.0, 1.0, 0.0), "+x": (1.0, 0.0, 0.0),
              "−x": (-1.0, 0.0, 0.0), "+z": (0.0, 0.0, 1.0), "−z": (0.0, 0.0, -1.0)}
MAX_FORCE_N = 50.0
ARROW_METRES_PER_N = 0.03
#: Joint values per range in the torque search: 31³ = 29,791 poses, a few tens of milliseconds.
GRID_STEPS = 31


def to_world(points: np.ndarray) -> np.ndarray:
    """(..., 3) points of the course's base frame → the app's world (the shoulder raised off the floor)."""
    return points @ COURSE_TO_WORLD.T + (0.0, 0.0, SHOULDER_HEIGHT)


@dataclass(frozen=True)
class DesktopSnapshot:
    """The arm at one instant: the views draw from it."""

    q: np.ndarray  #: (3,) joints (rad)
    rates: np.ndarray  #: (3,) joint rates (rad/s): zero unless a path is playing
    tool: np.ndarray  #: (4, 4) ``arm.fk(q)``, in the course's frame
    points: np.ndarray  #: (4, 3) world: the pedestal's foot, the shoulder, the elbow, the tool

    @property
    def frames(self) -> np.ndarray:
        """(4, 4, 4) the same points as frames, for the camera."""
        out = np.tile(np.eye(4), (len(self.points), 1, 1))
        out[:, :3, 3] = self.points
        return out

    @property
    def target(self) -> np.ndarray:
        return self.frames[-1]

    @property
    def lowest(self) -> tuple[np.ndarray]:
        return (self.points[0],)


class DesktopArmState:
    """The arm's joints; every change returns a new :class:`DesktopSnapshot`."""

    def __init__(self, arm: ThreeDofArm, q=None) -> None:
        self.arm = arm
        self.lock = threading.RLock()
        self.last = self._snapshot(course_path(0.0)[0] if q is None else np.array(q, dtype=float), np.zeros(3))

    def _snapshot(self, q: np.ndarray, rates: np.ndarray) -> DesktopSnapshot:
        frames = self.arm.frames(q)
        points = to_world(np.vstack([[0.0, -SHOULDER_HEIGHT, 0.0], frames[:, :3, 3]]))
        return DesktopSnapshot(q, rates, frames[-1], points)

    def set_joints(self, q, rates=(0.0, 0.0, 0.0)) -> DesktopSnapshot:
        """Move to ``q`` (3,) rad, within the joint ranges, turning at ``rates`` (3,) rad/s."""
        q = np.array(q, dtype=float)
        rates = np.array(rates, dtype=float)
        if q.shape != (3,) or rates.shape != (3,) or not (np.isfinite(q).all() and np.isfinite(rates).all()):
            raise ValueError("the desktop arm takes three finite joint angles")
        for label, value, (low, high) in zip(JOINT_LABELS, q, self.arm.limits):
            if not low - 1e-9 <= value <= high + 1e-9:
                raise ValueError(f"{label}: from {math.degrees(low):.0f}° to {math.degrees(high):.0f}°, "
                                 f"got {math.degrees(value):.1f}°")
        self.last = self._snapshot(q, rates)
        return self.last

    def set_joint(self, index: int, value: float) -> DesktopSnapshot:
        q = self.last.q.copy()
        q[index] = value
        return self.set_joints(q)


class DesktopArmScene(View):
    """The arm in 3D: pedestal, upper arm and forearm, the parallelogram drive, the course's base frame, the arrows."""

    def __init__(self, scene: viser.SceneApi, arm: ThreeDofArm, first: DesktopSnapshot, root: str = ROOT) -> None:
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


def factors_markdown(arm: ThreeDofArm, snapshot: DesktopSnapshot) -> str:
    """The tool's position (mm, the course's frame) and det J_v with its two factors, red near zero."""
    p = 1000 * snapshot.tool[:3, 3]
    reach, fold = arm.singularity_factors(snapshot.q)
    det = -arm.forearm * arm.upper_arm * reach * fold

    def flagged(text: str, near: bool) -> str:
        return f"<b style='color:{hex_color(DANGER_RED)}'>{text} (singular)</b>" if near else text

    return "\n".join([
        f"Tool p = ({', '.join(number(v, '.0f') for v in p)}) mm (course frame, y up)", "",
        f"det J_v = −l1 l5 · (l1 c3 − l5 c2) · sin(θ2 − θ3) = **{number(det, '+.3f')} m³**", "",
        "| factor | value | zero when |", "|---|---:|---|",
        f"| l1 c3 − l5 c2 | {flagged(number(1000 * reach, '+.0f') + ' mm', abs(reach) < 0.05)} | the tool is on the base's axis |",
        f"| sin(θ2 − θ3) | {flagged(number(fold, '+.3f'), abs(fold) < 0.05)} | upper arm and forearm in one line |",
    ])


class DesktopJoints(View):
    """The arm's folder: what it is, a slider per joint, its position and det J_v."""

    def __init__(self, gui: viser.GuiApi, session: "DesktopArmSession") -> None:
        self._session = session
        arm = session.arm
        folder = gui.add_folder("Desktop arm (3-DOF)", order=1.0)
        self.folders = (folder,)
        with folder:
            gui.add_markdown(
                f"The course's desktop arm: upper arm l5 = {1000 * arm.upper_arm:.0f} mm, forearm l1 = "
                f"{1000 * arm.forearm:.0f} mm. Joint 3 drives the forearm through a parallelogram (orange), so "
                "θ3 is the forearm's angle to the horizontal, not to the upper arm. The course's base frame has "
                "**y up**: p = (c1(l1c3 − l5c2), l1s3 − l5s2, −s1(l1c3 − l5c2)).")
            q = np.degrees(session.state.last.q)
            self.sliders = [gui.add_slider(f"{label} (°)", min=float(np.degrees(low)), max=float(np.degrees(high)), step=0.5,
                                           initial_value=round(float(value), 1))
                            for label, value, (low, high) in zip(JOINT_LABELS, q, arm.limits)]
            self.readout = gui.add_markdown("")
        self._shown = [slider.value for slider in self.sliders]
        for k, slider in enumerate(self.sliders):
            slider.on_update(session.guard(self._moved(k)))

    def _moved(self, index: int):
        def moved(event: viser.GuiEvent) -> None:
            if event.client is None:
                return
            self._shown[index] = float(self.sliders[index].value)
            self._session.path.player.stop()
            self._session.apply(lambda state: state.set_joint(index, math.radians(self._shown[index])))
        return moved

    def render_panel(self, snapshot: DesktopSnapshot) -> None:
        for k, (slider, value) in enumerate(zip(self.sliders, np.degrees(snapshot.q))):
            shown = round(float(value), 1)
            if not abs(self._shown[k] - shown) <= 1e-9:
                self._shown[k] = shown
                slider.value = shown
        self.readout.content = factors_markdown(self._session.arm, snapshot)


class CoursePathLesson(View):
    """The course's velocity exercise: play its joint path, with v and ω drawn at the tool and plotted."""

    def __init__(self, gui: viser.GuiApi, session: "DesktopArmSession") -> None:
        self._session = session
        self.player = Player(session)
        t = np.linspace(0.0, PATH_SECONDS, PATH_STEPS)
        q, qdot = course_path(t)
        twist = session.arm.tool_twist(q, qdot)
        self.path = (t, np.hstack([q, qdot]))
        folder = gui.add_folder("Velocities along the course's path", order=2.0)
        self.folders = (folder,)
        xyz = ("x", "y", "z")
        with folder:
            gui.add_markdown("The course drives the joints at θ̇ = (π/6 cos t, π/6 cos t, π/8 cos t) from (0°, 0°, 135°). "
                             "Play it: the arrows are the tool's velocity v = J_v θ̇ (blue) and its turning rate "
                             "ω = J_ω θ̇ (purple), the course's plots below.")
            self.play = gui.add_button("Play the course's path", icon=viser.Icon.PLAYER_PLAY)
            self.stop = gui.add_button("Stop", icon=viser.Icon.PLAYER_STOP)
            self.readout = gui.add_markdown("")
            gui.add_uplot(
                data=(t.astype(np.float32), *(1000 * twist[:, :3].T).astype(np.float32)),
                series=(viser.uplot.Series(label="t (s)"),
                        *(viser.uplot.Series(label=f"v{a} (mm/s)", stroke=hex_color(c), width=2)
                          for a, c in zip(xyz, SLOT_COLORS[:3]))),
                scales={"x": viser.uplot.Scale(time=False)},  # seconds, not dates
                axes=(viser.uplot.Axis(label="t (s)"), viser.uplot.Axis(label="mm/s")),
                title="Tool velocity v", aspect=2.0)
            gui.add_uplot(
                data=(t.astype(np.float32), *np.degrees(twist[:, 3:].T).astype(np.float32)),
                series=(viser.uplot.Series(label="t (s)"),
                        *(viser.uplot.Series(label=f"ω{a} (°/s)", stroke=hex_color(c), width=2)
                          for a, c in zip(xyz, SLOT_COLORS[3:6]))),
                scales={"x": viser.uplot.Scale(time=False)},  # seconds, not dates
                axes=(viser.uplot.Axis(label="t (s)"), viser.uplot.Axis(label="°/s")),
                title="Tool turning rate ω", aspect=2.0)
        self.play.on_click(session.guard(lambda _: self.start()))
        self.stop.on_click(session.guard(lambda _: self.halt()))

    def halt(self) -> None:
        """Stop the path where it is: the arm stays, its rates (and the arrows) go to zero."""
        self.player.stop()
        self._session.apply(lambda state: state.set_joints(state.last.q))

    def start(self) -> None:
        session = self._session
        self.player.play(lambda: self.path, "course path",
                         show=lambda state, row: state.set_joints(row[:3], row[3:]),
                         done=lambda: session.apply(lambda state: state.set_joints(state.last.q)))

    def render_panel(self, snapshot: DesktopSnapshot) -> None:
        if not np.any(snapshot.rates):
            self.readout.content = "Not playing: the arrows show while the path plays."
            return
        twist = self._session.arm.tool_twist(snapshot.q, snapshot.rates)
        self.readout.content = (f"v = ({', '.join(number(1000 * v, '+.0f') for v in twist[:3])}) mm/s  \n"
                                f"ω = ({', '.join(number(math.degrees(w), '+.1f') for w in twist[3:])}) °/s")

    def close(self) -> None:
        self.player.stop()


class DesktopForces(View):
    """The course's statics exercise: τ = J_vᵀ F for a tool force, and the pose in the joint ranges that needs the most."""

    def __init__(self, scene: viser.SceneApi, gui: viser.GuiApi, session: "DesktopArmSession", root: str) -> None:
        self._session = session
        self._scene = scene
        self._root = root
        folder = gui.add_folder("Forces", order=3.0, expand_by_default=False)
        self.folders = (folder,)
        with folder:
            gui.add_markdown("The torques the joints hold for a force F at the tool: τ = J_vᵀ F.")
            self.enabled = gui.add_checkbox("Show the force", False)
            self.newtons = gui.add_slider("Force at the tool (N)", min=0.0, max=MAX_FORCE_N, step=1.0, initial_value=10.0)
            self.direction = gui.add_dropdown("Force direction", tuple(DIRECTIONS), initial_value="down (−y)")
            self.torques = gui.add_markdown("")
            self.search = gui.add_button("Find the pose that needs the largest ‖τ‖", icon=viser.Icon.SEARCH,
                                         hint=f"Every joint over its range, {GRID_STEPS} values each: "
                                              f"{GRID_STEPS ** 3:,} poses, coloured by ‖τ‖")
            self.result = gui.add_markdown("")
        self.arrow = scene.add_arrows(f"{root}/force", np.zeros((1, 2, 3)), LINEAR_COLOR, shaft_radius=0.02,
                                      head_radius=0.05, head_length=0.1, visible=False)
        self.label = scene.add_label(f"{root}/force/label", "F", font_screen_scale=1.4, visible=False)
        self._map: tuple[viser.SceneNodeHandle, ...] = ()
        self._map_lock = threading.Lock()
        self._searches = FoldedRuns(self._search)
        for widget in (self.enabled, self.newtons, self.direction):
            widget.on_update(session.guard(lambda _: session.redraw()))
        self.search.on_click(session.guard(lambda _: self._searches.start("torque-search", session.guard)))

    def force(self) -> np.ndarray:
        """(3,) the force in the course's frame, N."""
        newtons = float(self.newtons.value)
        if not 0.0 <= newtons <= MAX_FORCE_N:
            raise ValueError(f"force: from 0 to {MAX_FORCE_N:g} N, got {newtons:g}")
        return newtons * np.array(DIRECTIONS[chosen(self.direction, "force direction")])

    def render(self, snapshot: DesktopSnapshot) -> None:
        shown = bool(self.enabled.value) and float(self.newtons.value) > 0.0
        if shown:
            tip = snapshot.points[3]
            end = tip + ARROW_METRES_PER_N * COURSE_TO_WORLD @ self.force()
            self.arrow.points = np.array([[tip, end]])
            self.label.position = end
            self.label.text = f"F = {float(self.newtons.value):.0f} N"
        for node in (self.arrow, self.label):
            if node.visible != shown:
                node.visible = shown

    def render_panel(self, snapshot: DesktopSnapshot) -> None:
        torques = self._session.arm.static_torques(snapshot.q, self.force())
        self.torques.content = ("| τ1 | τ2 | τ3 | ‖τ‖ |\n|---:|---:|---:|---:|\n| "
                                + " | ".join(number(v, "+.2f") for v in torques)
                                + f" | **{number(float(np.linalg.norm(torques)), '.2f')}** |\n\n(N·m)")

    def _search(self) -> None:
        session = self._session
        arm, force = session.arm, self.force()
        if not force.any():
            raise ValueError("set a force first: with none, no pose needs any torque")
        q, norms = HEAVY.run(session.client.client_id, lambda: torque_grid(arm, force, GRID_STEPS))
        worst = int(np.argmax(norms))
        points = to_world(arm.fk(q)[:, :3, 3])
        with self._map_lock:
            if session.closed:
                return
            self._clear()
            top = float(norms[worst]) or 1.0
            cloud = self._scene.add_point_cloud(f"{self._root}/torque_map", points.astype(np.float32), colormap(norms, top),
                                                point_size=0.025, point_shape="circle")
            marker = self._scene.add_icosphere(f"{self._root}/worst", radius=0.08, color=DANGER_RED, position=points[worst])
            self._scene.add_label(f"{self._root}/worst/label", f"largest ‖τ‖ = {top:.1f} N·m", font_screen_scale=1.4,
                                  anchor="bottom-center")
            self._map = (cloud, marker)
        self.result.content = (
            f"Largest ‖τ‖ = **{norms[worst]:.2f} N·m** for {np.linalg.norm(force):.0f} N, at θ = ("
            + ", ".join(number(v, ".0f") for v in np.degrees(q[worst])) + f")° (red ball), of {len(q):,} poses "
            "coloured from 0 (purple) to it (yellow). For a vertical force the parallelogram decouples the links: "
            "joint 2 holds F l5 cos θ2 and joint 3 F l1 cos θ3, so the worst pose has both links level, "
            f"‖τ‖ = F √(l5² + l1²) = {np.linalg.norm(force) * math.hypot(arm.upper_arm, arm.forearm):.2f} N·m.")
        session.path.player.stop()
        session.apply(lambda state: state.set_joints(q[worst]))

    def _clear(self) -> None:
        for node in self._map:
            node.remove()  # the marker's label goes with it
        self._map = ()

    def close(self) -> None:
        with self._map_lock:
            self._clear()


class DesktopArmSession:
    """A browser driving the course's 3-DOF desktop arm (``Arm.preset("three_dof")``), as ``CourseArmSession`` does a DH arm.

    ``state``, ``scene``, ``server``, ``own_camera`` and ``root`` as for ``CourseArmSession``: the
    classroom's presenter drives an arm drawn in the server's shared scene, an explorer its own.
    """

    def __init__(self, client: viser.ClientHandle, arm: ThreeDofArm, refresher: PanelRefresher, lecture: bool = False,
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
        self.joints = DesktopJoints(gui, self)
        self.path = CoursePathLesson(gui, self)
        self.forces = DesktopForces(client.scene if server is None else server.scene, gui, self, self.scene.root)
        self.camera = (CameraControls(client, self._framed, self.guard, lecture, body_radius=0.15 * self.scene.size)
                       if own_camera else None)
        self.panel_views = (*((self.camera,) if self.camera is not None else ()), self.joints, self.path, self.forces)
        self.render(first)
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

    def redraw(self) -> None:
        with self.state.lock:
            self.render(self.state.last)
        self.refresher.request(self)

    def render(self, snapshot: DesktopSnapshot) -> None:
        if self.closed:
            return
        with contextlib.ExitStack() as batch:  # the arm and its arrows arrive together
            for sender in self._senders:
                batch.enter_context(sender.atomic())
            self.scene.render(snapshot)
            self.forces.render(snapshot)
        for sender in self._senders:
            sender.flush()

    def render_panel(self) -> None:
        if self.closed:
            return
        snapshot = self.state.last
        with self.client.atomic():
            for view in self.panel_views:
                view.render_panel(snapshot)

    def guard(self, handler: Callable[[Any], None]) -> Callable[[Any], None]:
        return guard(self.client, handler, is_closed=lambda: self.closed, on_refused=lambda: self.refresher.request(self))

    def notify(self, title: str, body: str, color: str = "yellow") -> None:
        if not self.closed:
            notify(self.client, title, body, color)

    def close(self) -> None:
        """The browser has gone (or handed over): stop drawing and let go of everything shared."""
        self.closed = True
        with self.state.lock:
            for view in self.panel_views:
                view.close()
        self.refresher.forget(self)

    def remove(self) -> None:
        """Close, and take this session's panel out of a browser that stays."""
        self.closed = True
        with self.state.lock:
            for view in self.panel_views:
                view.remove()
        self.refresher.forget(self)
