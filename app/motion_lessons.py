"""Two motions to watch (docs/kinematics.md §8.7, §8.8): the arm let go under gravity, and the way from a
remembered pose to the current one along a straight tool line or with the joints interpolated, with its
joint rates plotted.

Each is computed on a thread of its own as a slow job (``app.workers.HEAVY``) and then
played on the arm in real time (``app.animation``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import viser
import viser.uplot

from ur10core import dynamics, paths
from ur10core.branches import wrap

from .animation import Player
from .feedback import chosen
from .style import JOINT_LABELS, SLOT_COLORS, hex_color, number
from .velocity import SPEED_LIMITS
from .view import View
from .workers import HEAVY

if TYPE_CHECKING:
    from .session import ClientSession

DROP_SECONDS = 3.0
PATH_SECONDS = 4.0
PATH_STEPS = 240
PATHS = ("straight tool line", "joints interpolated")


def path_summary(path: paths.Path, kind: str) -> str:
    """What a student should notice: each joint's fastest rate against its limit, and where damping acted."""
    fastest = np.degrees(np.abs(path.qdot).max(axis=0))
    cells = " · ".join((f"<b style='color:#dc2626'>{label} {number(rate, '.0f')}°/s</b>" if rate > limit
                        else f"{label} {number(rate, '.0f')}°/s") for label, rate, limit in zip(JOINT_LABELS, fastest, SPEED_LIMITS))
    lines = [f"**{kind.capitalize()}**, {path.t[-1]:.0f} s. Fastest rate of each joint: {cells}."]
    over = int((fastest > SPEED_LIMITS).sum())
    lines.append(f"{over} joint{'s' if over != 1 else ''} over the UR10's speed limit." if over
                 else "Every joint within the UR10's speed limits.")
    damped = np.flatnonzero(path.damping > 0)
    if len(damped):
        lines.append(f"Near a singularity from {path.t[damped[0]]:.2f} s to {path.t[damped[-1]]:.2f} s: the rates were damped "
                     "(the tool leaves the line a little there).")
    return "  \n".join(lines)


class MotionLessons(View):
    """The "Motion" folder: release the arm, or move it from a remembered pose two ways; a plot of the joint rates."""

    def __init__(self, gui: viser.GuiApi, session: "ClientSession") -> None:
        self._session = session
        self.player = Player(session)
        folder = gui.add_folder("Motion", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            gui.add_markdown("**Gravity.** Let the arm go from where it is: every joint free, no friction, "
                             "UR's link masses (M q̈ + C q̇ + g = 0).")
            self.release = gui.add_button("Release the arm", icon=viser.Icon.ARROW_DOWN)
            gui.add_markdown("**Paths.** Remember a start pose, move the arm somewhere else (drag or sliders), then "
                             "watch it go from the start to here: the tool along a straight line (resolved rates), "
                             "or every joint at once (interpolated).")
            self.remember = gui.add_button("Remember this pose as the start", icon=viser.Icon.PIN)
            self.start_text = gui.add_markdown("No start pose yet.")
            self.path = gui.add_button_group("Go from the start to here along", PATHS)
            self.stop = gui.add_button("Stop", icon=viser.Icon.PLAYER_STOP)
            self.summary = gui.add_markdown("")
            self.plot = gui.add_uplot(
                data=(np.zeros(2, np.float32), *(np.zeros(2, np.float32) for _ in range(6))),
                series=(viser.uplot.Series(label="time (s)"),
                        *(viser.uplot.Series(label=label, stroke=hex_color(colour), width=2)
                          for label, colour in zip(JOINT_LABELS, SLOT_COLORS))),
                axes=(viser.uplot.Axis(label="seconds"), viser.uplot.Axis(label="joint rate (°/s)")),
                title="Joint rates along the last path (UR10 limits: 120 and 180 °/s)", aspect=2.0, visible=False)
        self.start: np.ndarray | None = None  #: the remembered start pose (rad)
        self.remember.on_click(session.guard(lambda _: self._remember()))
        self.release.on_click(session.guard(lambda _: self._release()))
        self.path.on_click(session.guard(lambda _: self._move(chosen(self.path, "path"))))
        self.stop.on_click(session.guard(lambda _: self.player.stop()))

    def _release(self) -> None:
        session = self._session
        arm, start = session.arm, session.state.last.q.copy()
        dynamics.link_masses(arm)  # an arm without published masses: refused here, with the reason

        def compute() -> tuple[np.ndarray, np.ndarray]:
            motion = HEAVY.run(session.client.client_id, lambda: dynamics.release(arm, start, duration=DROP_SECONDS))
            return motion.t, wrap(motion.q)  # a joint that swung round is shown within one turn

        self.player.play(compute, "motion")

    def _remember(self) -> None:
        self.start = self._session.state.last.q.copy()
        self.start_text.content = "Start: (" + ", ".join(number(v, ".1f") for v in np.degrees(self.start)) + ")°"

    def _move(self, kind: str) -> None:
        if self.start is None:
            raise ValueError("remember a start pose first, then move the arm to where it should go")
        session = self._session
        arm, start, goal = session.arm, self.start.copy(), session.state.last.q.copy()

        def compute() -> tuple[np.ndarray, np.ndarray]:
            if kind == PATHS[0]:
                path = HEAVY.run(session.client.client_id,
                                 lambda: paths.straight_line(arm, start, arm.fk(goal), PATH_SECONDS, PATH_STEPS))
            else:
                path = paths.joint_interpolation(arm, start, goal, PATH_SECONDS, PATH_STEPS)
            self.summary.content = path_summary(path, kind)
            self.plot.data = (path.t.astype(np.float32), *np.degrees(path.qdot.T).astype(np.float32))
            self.plot.visible = True
            return path.t, path.q

        self.player.play(compute, "motion")

    def close(self) -> None:
        self.player.stop()
