"""Two motions to watch (docs/kinematics.md §8.7, §8.8): the arm let go under gravity, and the way from a
remembered pose to the current one along a straight tool line or with the joints interpolated, with its
joint rates plotted.

Each is computed as a slow job (``ur10teach.serving.workers.HEAVY``) in the worker process (``ur10teach.serving.workers.APART``:
a Python loop) and then played on the arm in real time (``ur10teach.features.animation``).
"""

from __future__ import annotations

import functools
import itertools
from typing import Callable

import numpy as np
import viser
import viser.uplot

from ur10core import dynamics, paths
from ur10core.branches import wrap
from ur10core.workspace import through_floor

from ..feedback import Beside, chosen
from ..serving.workers import APART, HEAVY
from ..style import SLOT_COLORS, hex_color, number
from ..view import Session, View
from .animation import Player
from .velocity import shown_rates

DROP_SECONDS = 3.0
PATH_SECONDS = 4.0
PATH_STEPS = 240
PATHS = ("straight tool line", "joints interpolated")


#: Shading of the rate charts: where the resolved rates were damped, and where a joint went over its speed limit.
SINGULAR_FILL, OVER_FILL = "rgba(90, 90, 100, 0.22)", "rgba(220, 38, 38, 0.22)"
LIMIT_DASHES = ((8.0, 4.0), (3.0, 3.0), (1.0, 2.0))


def limit_groups(limits: np.ndarray | None, labels: tuple[str, ...]) -> list[tuple[float, tuple[str, ...]]]:
    """Each distinct speed limit (as shown: °/s, mm/s) with the joints that have it, in joint order."""
    if limits is None:
        return []
    groups: dict[float, list[str]] = {}
    for label, limit in zip(labels, limits):
        groups.setdefault(float(limit), []).append(label)
    return [(limit, tuple(names)) for limit, names in groups.items()]


def spoken_list(names: tuple[str, ...]) -> str:
    """("elbow", "wrist 1", "wrist 2") → "elbow, wrist 1 and wrist 2"."""
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"


def rate_chart_data(path: paths.Path, limits: np.ndarray | None, kinds: str = "RRRRRR") -> tuple[np.ndarray, ...]:
    """The columns of a path's chart: t, each joint's speed |q̇| (°/s, or mm/s for a sliding joint),
    a line at each distinct speed limit of ``limits`` (n,) (none for an arm without published
    limits), and the two marks (the chart's top where they hold, 0 elsewhere, drawn as shading)."""
    speeds = np.abs(shown_rates(path.qdot, kinds))
    lines = [] if limits is None else list(dict.fromkeys(float(limit) for limit in limits))  # as limit_groups orders them
    top = 1.1 * max([float(speeds.max()), *lines])
    ones = np.ones_like(path.t)
    singular = np.where(path.damping > 0, top, 0.0)
    over = np.where((speeds > limits).any(axis=1), top, 0.0) if limits is not None else 0.0 * ones
    columns = (path.t, *speeds.T, *(limit * ones for limit in lines), singular, over)
    return tuple(np.asarray(c, dtype=np.float32) for c in columns)


def rate_chart(gui: viser.GuiApi, kind: str, labels: tuple[str, ...], kinds: str,
               limits: np.ndarray | None) -> viser.GuiUplotHandle:
    """An empty chart for the joint speeds along one kind of path, hidden until a path fills it."""
    groups = limit_groups(limits, labels)
    series = (viser.uplot.Series(label="time (s)"),
              *(viser.uplot.Series(label=label, stroke=hex_color(colour), width=2)
                for label, colour in zip(labels, SLOT_COLORS)),
              *(viser.uplot.Series(label=f"limit, {spoken_list(names)}", stroke="#333333", width=1.5, dash=dash)
                for (_, names), dash in zip(groups, itertools.cycle(LIMIT_DASHES))),
              viser.uplot.Series(label="near a singularity", stroke="rgba(0, 0, 0, 0)", width=0.0, fill=SINGULAR_FILL),
              viser.uplot.Series(label="over a speed limit", stroke="rgba(0, 0, 0, 0)", width=0.0, fill=OVER_FILL))
    units = "°/s" if set(kinds) == {"R"} else "°/s, mm/s"
    return gui.add_uplot(
        data=(np.zeros(2, np.float32),) * len(series), series=series,
        scales={"x": viser.uplot.Scale(time=False)},  # seconds, not dates
        axes=(viser.uplot.Axis(label="seconds"), viser.uplot.Axis(label=f"|q̇| ({units})")),
        title=f"{kind.capitalize()}: joint speeds", aspect=2.0, visible=False)


def energy_chart(gui: viser.GuiApi) -> viser.GuiUplotHandle:
    """An empty chart for a gravity drop's kinetic, potential and total energy, hidden until a drop fills it."""
    series = (viser.uplot.Series(label="time (s)"),
              viser.uplot.Series(label="kinetic T", stroke=hex_color(SLOT_COLORS[1]), width=2),
              viser.uplot.Series(label="potential V", stroke=hex_color(SLOT_COLORS[0]), width=2),
              viser.uplot.Series(label="T + V", stroke="#333333", width=2, dash=LIMIT_DASHES[0]))
    return gui.add_uplot(data=(np.zeros(2, np.float32),) * len(series), series=series,
                         scales={"x": viser.uplot.Scale(time=False)},
                         axes=(viser.uplot.Axis(label="seconds"), viser.uplot.Axis(label="energy (J)")),
                         title="Gravity drop: energy", aspect=2.0, visible=False)


def path_summary(path: paths.Path, kind: str, limits: np.ndarray | None, labels: tuple[str, ...],
                 kinds: str, out_of_reach: tuple[float, float, str] | None = None) -> str:
    """What a student should notice: each joint's fastest rate against its limit, where damping acted,
    how far the tool gets from the straight line, and where that line is out of the arm's reach."""
    fastest = np.abs(shown_rates(path.qdot, kinds)).max(axis=0)
    over_limit = fastest > limits if limits is not None else np.zeros(len(fastest), bool)
    cells = " · ".join((f"<b style='color:#dc2626'>{label} {number(rate, '.0f')}{unit}</b>" if over
                        else f"{label} {number(rate, '.0f')}{unit}")
                       for label, rate, over, unit in zip(labels, fastest, over_limit,
                                                          ("°/s" if k == "R" else " mm/s" for k in kinds)))
    lines = [f"**{kind.capitalize()}**, {path.t[-1]:.0f} s. Fastest rate of each joint: {cells}."]
    over = int(over_limit.sum())
    if limits is None:
        lines.append("The maker publishes no speed limits for this arm.")
    else:
        lines.append(f"{over} joint{'s' if over != 1 else ''} over the arm's speed limit." if over
                     else "Every joint within the arm's speed limits.")
    damped = np.flatnonzero(path.damping > 0)
    if len(damped):
        lines.append(f"Near a singularity from {path.t[damped[0]]:.2f} s to {path.t[damped[-1]]:.2f} s: the rates were damped.")
    if kind == PATHS[0] and out_of_reach is not None:
        first, last, why = out_of_reach
        lines.append(f"The straight line leaves the arm's reach from {first:.0%} to {last:.0%} of the way "
                     f"({why.removeprefix('unreachable: ')}): no arm can follow it there.")
    deviation = 1000 * paths.line_deviation(path)
    lines.append(f"The tool keeps to the straight line (within {number(deviation, '.2g')} mm)." if deviation < 1
                 else f"The tool leaves the straight line by up to **{number(deviation, '.0f')} mm**.")
    return "  \n".join(lines)


def no_gravity_reason(arm) -> str:
    """Why this arm cannot be let go under gravity ("" if it can): the course knows link masses for some arms only."""
    try:
        dynamics.link_masses(arm)
    except ValueError:
        return "No link masses are published for this arm, so it cannot be let go under gravity."
    return ""


class MotionLessons(View):
    """The "Motion" folder: release the arm (where its link masses are known), or move it from a
    remembered pose two ways; a plot of the joint rates. For any arm, its joints named as the arm names them."""

    def __init__(self, gui: viser.GuiApi, session: Session, before: Callable[[], None] = lambda: None,
                 payload_kg: Callable[[], float] = lambda: 0.0) -> None:
        self._session = session
        self._before = before  #: called before a motion starts (another lesson's own motion stops)
        self._payload_kg = payload_kg  #: what the flange holds as the arm is let go (set in Forces and gravity)
        self.player = Player(session)
        arm = session.arm
        self._labels, self._kinds = arm.joint_names, "".join(arm.joint_types)
        limits = arm.specs.speed_limits
        self._limits = None if limits is None else shown_rates(limits, self._kinds)
        folder = gui.add_folder("Motion", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            unable = no_gravity_reason(arm)
            self.gravity_text = gui.add_markdown(f"**Gravity.** {unable}" if unable else
                                                 "**Gravity.** Let the arm go from where it is: every joint free, no friction, "
                                                 "UR's link masses and the payload set in *Forces and gravity* "
                                                 "(M q̈ + C q̇ + g = 0).")
            self.release = gui.add_button("Release the arm", icon=viser.Icon.ARROW_DOWN, disabled=bool(unable))
            gui.add_markdown("**Paths.** Remember a start pose, move the arm somewhere else (drag or sliders), then "
                             "watch it go from the start to here: the tool along a straight line (resolved rates), "
                             "or every joint at once (interpolated).")
            self.remember = gui.add_button("Remember this pose as the start", icon=viser.Icon.PIN)
            self.start_text = gui.add_markdown("No start pose yet.")
            self.path = gui.add_button_group("Go from the start to here along", PATHS)
            self.refusal = Beside(gui)  # a path asked for before a start pose was remembered
            self.stop = gui.add_button("Stop the motion", icon=viser.Icon.PLAYER_STOP)
            self.summary = gui.add_markdown("")
            self.caption = gui.add_markdown("Both ways between the same two poses, the one played first. Shaded: grey "
                                            "where the straight line passed near a singularity (the rates were damped)"
                                            + (", red where a joint went over its speed limit (the dashed lines)."
                                               if self._limits is not None else "."), visible=False)
            #: one chart per kind of path, side by side in time: the same endpoints both ways
            self.path_charts = {kind: rate_chart(gui, kind, self._labels, self._kinds, self._limits) for kind in PATHS}
            self.energy = energy_chart(gui)
        self.charts = (*self.path_charts.values(), self.energy)
        self.start: np.ndarray | None = None  #: the remembered start pose (rad, m)
        self.remember.on_click(session.guard(lambda _: self._remember(), beside=self.refusal))
        self.release.on_click(session.guard(lambda _: self._release()))
        self.path.on_click(session.guard(lambda _: self._move(chosen(self.path, "path")), beside=self.refusal))
        self.stop.on_click(session.guard(lambda _: self.player.stop()))

    def _release(self) -> None:
        session = self._session
        arm, start, points = session.arm, session.state.last.q.copy(), session.state.body_points
        dynamics.link_masses(arm)  # an arm without published masses: refused here, with the reason
        payload = self._payload_kg()
        self._before()

        # the equations of motion know no floor: the drop ends where the arm first touches it, as a real one would
        floor = None if through_floor(arm, start, points) else functools.partial(through_floor, arm, body_points=points)

        def compute() -> tuple[np.ndarray, np.ndarray]:
            motion = HEAVY.run(session.client, lambda: APART.run(dynamics.release, arm, start, duration=DROP_SECONDS,
                                                                  payload_kg=payload, stop=floor),
                               cancelled=self.player.cancelled)
            hit = floor is not None and bool(floor(motion.q[-1]))
            end = len(motion.t) - hit  # shown up to the touch, not through the floor
            t, q = motion.t[:end], motion.q[:end]
            kinetic, potential = dynamics.energies(arm, q, motion.qd[:end], payload)
            total = kinetic + potential
            holding = f" holding {number(payload, 'g')} kg" if payload else ""
            self.summary.content = (
                (f"**Gravity.** The arm{holding} hits the floor at {motion.t[-1]:.2f} s: the drop stops there "
                 "(the equations of motion know no floor)." if hit else
                 f"**Gravity.** {motion.t[-1]:.0f} s of free fall{holding and ','}{holding}, clear of the floor.")
                + f" Potential energy V turns into kinetic energy T (the chart); with no friction, T + V stays at "
                f"{number(total[0], '.1f')} J (within {number(1000 * np.ptp(total), '.2g')} mJ).")
            with session.client.atomic():
                self.energy.data = tuple(np.asarray(c, dtype=np.float32) for c in (t, kinetic, potential, total))
                self.energy.visible = True
                for chart in (*self.path_charts.values(), self.caption):
                    chart.visible = False
            return t, wrap(q)  # a joint that swung round is shown within one turn

        self.player.play(compute, "motion")

    def _remember(self) -> None:
        self.start = self._session.state.last.q.copy()
        self.start_text.content = "Start: " + ", ".join(
            f"{label} {number(np.degrees(v), '.1f')}°" if kind == "R" else f"{label} {number(1000 * v, '.0f')} mm"
            for label, v, kind in zip(self._labels, self.start, self._kinds))

    def _move(self, kind: str) -> None:
        if self.start is None:
            raise ValueError("remember a start pose first, then move the arm to where it should go")
        session = self._session
        arm, start, goal = session.arm, self.start.copy(), session.state.last.q.copy()
        self._before()

        def compute() -> tuple[np.ndarray, np.ndarray]:
            both = {PATHS[0]: HEAVY.run(session.client,
                                        lambda: APART.run(paths.straight_line, arm, start, arm.fk(goal),
                                                          PATH_SECONDS, PATH_STEPS),
                                        cancelled=self.player.cancelled),
                    PATHS[1]: paths.joint_interpolation(arm, start, goal, PATH_SECONDS, PATH_STEPS)}
            out_of_reach = paths.line_out_of_reach(arm, start, arm.fk(goal))
            self.summary.content = "\n\n".join(path_summary(both[k], k, self._limits, self._labels, self._kinds, out_of_reach)
                                                for k in (kind, *(k for k in PATHS if k != kind)))
            with session.client.atomic():
                for name, path in both.items():
                    self.path_charts[name].data = rate_chart_data(path, self._limits, self._kinds)
                    self.path_charts[name].visible = True
                self.caption.visible, self.energy.visible = True, False
            camera = session.camera
            if camera is not None:  # the whole way in view, both ways
                camera.show_also("path", np.vstack([path.tool for path in both.values()]), session.drawing.world)
            outside = paths.out_of_range(arm, both[kind])
            if outside:  # said before the arm moves, not when it stops halfway
                raise ValueError(f"the {kind} cannot be played: {outside}. Its summary and chart are in Motion.")
            return both[kind].t, np.hstack([both[kind].q, both[kind].qdot])

        n = arm.n_joints  # each frame carries its rates: the velocity arrows show them while it plays
        self.player.play(compute, "motion", show=lambda state, row: state.set_joints(row[:n], "motion", rates=row[n:]),
                         done=lambda: session.apply(lambda state: state.set_joints(state.q, "motion")),
                         ended=self._forget_path)

    def _forget_path(self) -> None:
        """Played, stopped or refused: the path, not drawn, is no longer kept in view."""
        if self._session.camera is not None:
            self._session.camera.show_also("path", None, now=False)

    def close(self) -> None:
        self.player.stop()
