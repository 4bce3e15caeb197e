"""The desktop arm's lessons: its joints and det J_v, the course's velocity exercise, and its statics exercise
(docs/kinematics.md §8.6)."""

from __future__ import annotations

import math
import threading

import numpy as np
import viser
import viser.uplot

from ur10core.specs import largest_torque, torque_grid
from ur10core.three_dof import course_path

from ...feedback import Beside
from ...serving.workers import HEAVY, FoldedRuns
from ...state import Snapshot
from ...style import DANGER_RED, SLOT_COLORS, hex_color, number
from ...view import HELD_BACK, Session, View
from ..animation import Player
from ..branch_labels import obstacle
from ..workspace import colormap

#: The course's path: one period of its sin t, played in real time.
PATH_SECONDS = 2 * math.pi
PATH_STEPS = 361
#: Joint values per range in the torque search: 31³ = 29,791 poses, a few tens of milliseconds.
GRID_STEPS = 31
#: How far above the worst pose's ball its label sits (m, the course's y: up): clear of the base frame's labels.
WORST_LABEL_RISE = 0.8
#: What the camera keeps in view with the arm while the course's path plays, and while the torque search's map shows.
PATH_VIEW, SEARCH_VIEW = "the course's path", "the torque search"
#: Said under the search's numbers where its map has made way for the workspace's other colouring.
MAP_HIDDEN = "  \n*Its map is hidden, for the workspace's other colouring: find it again to show it.*"


class DesktopAbout(View):
    """The arm's own folder: what it is (its tool pose and det J_v are in the folders every arm has)."""

    def __init__(self, gui: viser.GuiApi, session: Session) -> None:
        arm = session.arm
        folder = gui.add_folder("Desktop arm (3-DOF)", order=0.9)
        self.folders = (folder,)
        with folder:
            gui.add_markdown(
                f"The course's desktop arm: upper arm l5 = {1000 * arm.upper_arm:.0f} mm, forearm l1 = "
                f"{1000 * arm.forearm:.0f} mm. Joint 3 drives the forearm through a parallelogram (orange), so "
                "θ3 is the forearm's angle to the horizontal, not to the upper arm. The course's base frame has "
                "**y up**: p = (c1(l1c3 − l5c2), l1s3 − l5s2, −s1(l1c3 − l5c2)).")


class CoursePathLesson(View):
    """The course's velocity exercise: play its joint path, with v and ω drawn at the tool and plotted."""

    answers = ("tool_velocity",)  # its readout and plot give v

    def __init__(self, gui: viser.GuiApi, session: Session) -> None:
        self._session = session
        self.player = Player(session)
        t = np.linspace(0.0, PATH_SECONDS, PATH_STEPS)
        q, qdot = course_path(t)
        twist = session.arm.tool_twist(q, qdot)
        self.path = (t, np.hstack([q, qdot]))
        self._tool_path = session.arm.fk(q[::10])[:, :3, 3]  #: kept in view while it plays
        folder = gui.add_folder("Velocities along the course's path", order=2.0, expand_by_default=False)
        self.folders = (folder,)
        xyz = ("x", "y", "z")
        with folder:
            gui.add_markdown("The course drives the joints at θ̇ = (π/6 cos t, π/6 cos t, π/8 cos t) from (0°, 0°, 135°). "
                             "Play it: the arrows are the tool's velocity v = J_v θ̇ (blue) and its turning rate "
                             "ω = J_ω θ̇ (purple), the course's plots below.")
            self.play = gui.add_button("Play the course's path", icon=viser.Icon.PLAYER_PLAY)
            self.stop = gui.add_button("Stop", icon=viser.Icon.PLAYER_STOP)
            self.readout = gui.add_markdown("")
            self.velocity = velocity = gui.add_uplot(
                data=(t.astype(np.float32), *(1000 * twist[:, :3].T).astype(np.float32)),
                series=(viser.uplot.Series(label="t (s)"),
                        *(viser.uplot.Series(label=f"v{a} (mm/s)", stroke=hex_color(c), width=2)
                          for a, c in zip(xyz, SLOT_COLORS[:3]))),
                scales={"x": viser.uplot.Scale(time=False)},  # seconds, not dates
                axes=(viser.uplot.Axis(label="t (s)"), viser.uplot.Axis(label="mm/s")),
                title="Tool velocity v", aspect=2.0)
            turning = gui.add_uplot(
                data=(t.astype(np.float32), *np.degrees(twist[:, 3:].T).astype(np.float32)),
                series=(viser.uplot.Series(label="t (s)"),
                        *(viser.uplot.Series(label=f"ω{a} (°/s)", stroke=hex_color(c), width=2)
                          for a, c in zip(xyz, SLOT_COLORS[3:6]))),
                scales={"x": viser.uplot.Scale(time=False)},  # seconds, not dates
                axes=(viser.uplot.Axis(label="t (s)"), viser.uplot.Axis(label="°/s")),
                title="Tool turning rate ω", aspect=2.0)
        self.charts = (velocity, turning)
        self.play.on_click(session.guard(lambda _: self.start()))
        self.stop.on_click(session.guard(lambda _: self.halt()))

    def halt(self) -> None:
        """Stop the path where it is: the arm stays, its rates (and the arrows) go to zero."""
        self.player.stop()
        self._session.apply(lambda state: state.set_joints(state.last.q))

    def start(self) -> None:
        session = self._session
        self.player.play(self._shown_path, "motion", show=lambda state, row: state.set_joints(row[:3], "motion", rates=row[3:]),
                         done=lambda: session.apply(lambda state: state.set_joints(state.last.q)),
                         ended=lambda: self._keep_in_view(None))

    def _shown_path(self) -> tuple[np.ndarray, np.ndarray]:
        self._keep_in_view(self._tool_path)  # the whole way in view while it plays (the camera frames the arm)
        return self.path

    def _keep_in_view(self, points: np.ndarray | None) -> None:
        if self._session.camera is not None:
            self._session.camera.show_also(PATH_VIEW, points, self._session.drawing.world, now=points is not None)

    def render_panel(self, snapshot: Snapshot) -> None:
        self.velocity.visible = self.held is None
        if self.held or snapshot.rates is None or not np.any(snapshot.rates):
            self.readout.content = HELD_BACK if self.held else "Not playing: the arrows show while the path plays."
            return
        twist = self._session.arm.tool_twist(snapshot.q, snapshot.rates)
        self.readout.content = (f"v = ({', '.join(number(1000 * v, '+.0f') for v in twist[:3])}) mm/s  \n"
                                f"ω = ({', '.join(number(math.degrees(w), '+.1f') for w in twist[3:])}) °/s")

    def close(self) -> None:
        self.player.stop()
        self._keep_in_view(None)  # a classroom's browser keeps its camera for its next arm


class StaticsExercise(View):
    """The course's statics exercise: for the force of the "Forces and gravity" folder, the pose in the joint
    ranges that needs the largest ‖τ‖ = ‖J_vᵀ F‖, over a grid of them, the arm put there."""

    answers = ("largest_torque",)

    def __init__(self, scene: viser.SceneApi, gui: viser.GuiApi, session: Session) -> None:
        self._session = session
        self._scene = scene
        self._root = session.drawing.root
        folder = gui.add_folder("The course's statics exercise", order=3.0, expand_by_default=False)
        self.folders = (folder,)
        with folder:
            gui.add_markdown("Which pose needs the most torque to hold the force set in **Forces and gravity**?")
            self.search = gui.add_button("Find the pose that needs the largest ‖τ‖", icon=viser.Icon.SEARCH,
                                         hint=f"Every joint over its range, {GRID_STEPS} values each: "
                                              f"{GRID_STEPS ** 3:,} poses, coloured by ‖τ‖")
            self.refusal = Beside(gui)  # a search asked for with no force set
            self.result = gui.add_markdown("")
        self._map: tuple[viser.SceneNodeHandle, ...] = ()
        self._map_wanted = False  # no other colouring asked for since the last search began
        self._map_lock = threading.Lock()
        self._searches = FoldedRuns(self._search)
        self.search.on_click(session.guard(
            lambda _: self._searches.start("torque-search", lambda run: session.guard(run, beside=self.refusal)),
            beside=self.refusal))

    def hold_back(self, asked: str | None) -> None:
        super().hold_back(asked)
        self.search.visible = self.held is None
        with self._map_lock:  # after a search's result, or before it (which then sees ``held``), not between
            self.result.content = HELD_BACK if self.held else ""
            if self.held:
                self._clear()

    def _search(self) -> None:
        session = self._session
        if self.held:  # a click a browser cannot send while it is off
            raise ValueError(HELD_BACK)
        arm, force = session.arm, session.statics.fixed_force()
        if not force.any():
            raise ValueError("set a force first: with none, no pose needs any torque")
        self._map_wanted = True
        session.colouring_shown(self)

        def search():
            grid = torque_grid(arm, force, GRID_STEPS)
            return grid, largest_torque(arm, force, GRID_STEPS, grid=grid)

        (q, norms), worst = HEAVY.run(session.client, search, cancelled=lambda: session.closed)
        points, worst_at = arm.fk(q)[:, :3, 3], arm.fk(worst.q)[:3, 3]
        found = (f"Largest ‖τ‖ = **{worst.norm:.2f} N·m** for {np.linalg.norm(force):.0f} N, at θ = ("
                 + ", ".join(number(v, ".1f") for v in np.degrees(worst.q)) + f")° (red ball), from {len(q):,} poses "
                 "coloured from 0 (purple) to it (yellow), and a finer search around the largest.")
        if not force[[0, 2]].any():  # vertical: the course's closed form to check the search against
            found += (" For a vertical force the parallelogram decouples the links: joint 2 holds F l5 cos θ2 and "
                      "joint 3 F l1 cos θ3, so the worst pose has both links level, "
                      f"‖τ‖ = F √(l5² + l1²) = {np.linalg.norm(force) * math.hypot(arm.upper_arm, arm.forearm):.2f} N·m.")
        with self._map_lock:
            if session.closed or self.held:  # gone, or a class challenge began meanwhile
                return
            self._clear()
            self.result.content = found
            if self._map_wanted:
                self._map = self._draw_map(points, norms, worst.norm or 1.0, worst_at)
            else:  # the workspace's other colouring was asked for while this searched: the numbers, and the arm there
                self.result.content += MAP_HIDDEN
        if self._map and session.camera is not None:  # framed outside the lock: the camera places every label
            session.camera.frame()
        session.refresher.request(session)  # its label sized for lecture mode, and kept clear of
        session.stop_lessons()
        session.apply(self.unless_held(lambda state: state.set_joints(worst.q)))

    def _draw_map(self, points: np.ndarray, norms: np.ndarray, top: float, worst_at: np.ndarray) -> tuple:
        """The grid's tool positions (n, 3) coloured by their ‖τ‖ (n,) up to ``top``, and a red ball at the largest."""
        cloud = self._scene.add_point_cloud(f"{self._root}/torque_map", points.astype(np.float32), colormap(norms, top),
                                            point_size=0.025, point_shape="circle")
        marker = self._scene.add_icosphere(f"{self._root}/worst", radius=0.08, color=DANGER_RED, position=worst_at)
        # raised on a red stalk: at the ball it sat on the base frame's and the joints' labels
        rise = np.array([[[0.0, 0.0, 0.0], [0.0, WORST_LABEL_RISE, 0.0]]], np.float32)
        self._scene.add_line_segments(f"{self._root}/worst/stalk", rise, DANGER_RED, thickness=0.015)
        label = self._scene.add_label(f"{self._root}/worst/label", f"largest ‖τ‖ = {top:.1f} N·m", font_screen_scale=1.4,
                                      anchor="bottom-center", position=(0.0, WORST_LABEL_RISE, 0.0))
        if self._session.camera is not None:  # the map and its red ball in view with the arm, from its next framing
            self._session.camera.show_also(SEARCH_VIEW, np.vstack([points[:: max(1, len(points) // 2000)],
                                                                   worst_at + (0.0, WORST_LABEL_RISE, 0.0)]),
                                           self._session.drawing.world, now=False)
        return cloud, marker, label

    def obstacles(self) -> list[tuple]:
        """The largest ‖τ‖'s label, on its stalk over the red ball."""
        shown = self._map
        if not shown:
            return []
        return [obstacle(shown[2], under=shown[1].position)]  # the label, under the marker

    def hide_colouring(self) -> None:
        with self._map_lock:
            self._map_wanted = False
            if self._map:  # its numbers stay; the red ball they point to goes
                self._clear()
                self.result.content += MAP_HIDDEN

    def _clear(self) -> None:
        for node in self._map[:2]:
            node.remove()  # the marker's label and stalk go with it
        self._map = ()
        if self._session.camera is not None:  # (a classroom's browser keeps its camera for its next arm)
            self._session.camera.show_also(SEARCH_VIEW, None, now=False)

    def close(self) -> None:
        """The session has gone: so does its map, even from a scene everyone shares."""
        with self._map_lock:
            self._clear()


def desktop_lessons(scene: viser.SceneApi, gui: viser.GuiApi, session: Session) -> tuple[View, ...]:
    """The desktop arm's own folders: what it is, and the course's two exercises with it."""
    return DesktopAbout(gui, session), CoursePathLesson(gui, session), StaticsExercise(scene, gui, session)
