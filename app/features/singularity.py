"""Singularities, for any arm whose model factors det J: gauges, a rolling plot, the formula and a 3D overlay.

What each factor's overlay draws: docs/kinematics.md §5.1.
"""

from __future__ import annotations

import collections
import functools
import time
from typing import Callable

import numpy as np
import viser
import viser.uplot

from ur10core import Arm, symbolic, symbolic_arms
from ur10core.arm import factor_scales
from ur10core.orientation import from_frame, in_frame
from ur10core.serial import PRESETS

from ..feedback import Beside, chosen
from ..serving.workers import HEAVY, FoldedRuns
from ..state import Snapshot
from ..style import (
    COLOUR_IS_CONTENT,
    DANGER_RED,
    ELBOW_COLOR,
    SAFE_GREEN,
    SHOULDER_COLOR,
    WRIST_COLOR,
    blend,
    hex_color,
    number,
)
from ..view import HELD_BACK, Session, View, say_held_back
from .branch_labels import BranchLabels

#: Below this share of its largest value a factor is drawn fully red.
ALARM_AT = 0.05
#: From this share up a factor is drawn fully green.
CALM_AT = 0.35
#: The 3D overlay's colours move in this many steps from calm to alarm (each step is a message).
ALARM_STEPS = 20
PLOT_SECONDS = 10.0
PLOT_SAMPLES = 200
CIRCLE_SEGMENTS = 48
AXIS_HALF_LENGTH = 0.25
#: Each factor's colour (Okabe-Ito): shoulder orange (and the Stanford arm's stroke, the cylindrical
#: arm's reach), elbow bluish green, wrist reddish purple.
FACTOR_COLORS = {"shoulder": SHOULDER_COLOR, "stroke": SHOULDER_COLOR, "reach": SHOULDER_COLOR,
                 "elbow": ELBOW_COLOR, "fold": ELBOW_COLOR, "wrist": WRIST_COLOR}


def alarm(level: float) -> float:
    """0 (calm) … 1 (on the singularity) for a factor level in [0, 1]."""
    return min(1.0, max(0.0, (CALM_AT - level) / (CALM_AT - ALARM_AT)))


def circle_segments(center: np.ndarray, u: np.ndarray, v: np.ndarray, radius: float) -> np.ndarray:
    """A circle as (N, 2, 3) line segments in the plane spanned by unit vectors u, v."""
    angles = np.linspace(0.0, 2 * np.pi, CIRCLE_SEGMENTS + 1)
    points = center + radius * (np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v)
    return np.stack([points[:-1], points[1:]], axis=1)


def factor_levels(arm: Arm, factors: np.ndarray) -> np.ndarray:
    """Each factor's size as a share of its scale (:func:`factor_scales`), in [0, 1]."""
    return np.clip(np.abs(factors) / factor_scales(arm), 0.0, 1.0)


@functools.lru_cache(maxsize=64)  # typed tables come and go: a bounded few
def factor_words(arm: Arm) -> tuple[str, list[tuple[str, str, str]]] | None:
    """(what det J is, [(name, expression as HTML, what makes it zero)] per factor) as the model gives them,
    or None for a typed table (its det J is not derived). A derived expression is rendered math (MathML)."""
    if arm.name in PRESETS:
        derivation = symbolic_arms.load(arm.name)
        types = "".join(arm.joint_types)
        return (f"det J = {derivation.constant} × the factors (derived with sympy from the DH table)",
                [(f.name, symbolic_arms.mathml(f.expression, types), f.meaning) for f in derivation.factors])
    words = getattr(arm.solver, "factor_words", None)
    if words is None:
        return None
    what = "det J" if arm.task == "pose" else "det J_v"
    return (f"{what} = {arm.solver.det_constant} × the factors (the course's closed form)",
            [(name, f"<code>{expression}</code>", meaning) for name, expression, meaning in words])


def factors_html(arm: Arm, q: np.ndarray) -> str:
    """det J's factors as gauges, green far from their singularity and red at it, with what each means."""
    smallest = float(arm.smallest_singular_value(q))
    manipulability = float(arm.manipulability(q)) if smallest else 0.0  # (on a singularity, rounding's 3e-18 is 0)
    measures = f"manipulability {number(manipulability, '.4g')}, smallest singular value {number(smallest, '.4g')}"
    described = factor_words(arm)
    if described is None:  # a typed table has no derivation: the numbers that vanish at a singularity
        return f"<div>A typed table's det J is not derived; these go to zero at a singularity: {measures}</div>"
    heading, factors = described
    values = arm.singularity_factors(q)
    parts = [f"<div>{heading}</div>"]
    for (name, expression, meaning), value, level in zip(factors, values, factor_levels(arm, values)):
        colour = hex_color(blend(SAFE_GREEN, DANGER_RED, alarm(level)))
        parts.append(
            f"<div style='margin:4px 0'><b>{name}</b> {expression} = {number(value, '+.4f')}"
            f"<div style='height:8px;background:#e9ecef;border-radius:4px;{COLOUR_IS_CONTENT}'>"
            f"<div class='gauge-{name}' style='height:8px;width:{100 * level:.1f}%;border-radius:4px;"
            f"background:{colour}'></div></div><div style='font-size:0.85em'>zero when {meaning}</div></div>")
    parts.append(f"<div>{measures}</div>")
    return "<div style='font-size:0.9em'>" + "".join(parts) + "</div>"


def line_color(rgb: tuple[int, int, int]) -> np.ndarray:
    """One colour for a whole line-segments node: viser's browser reads per-vertex uint8 colours as 0…1 floats (white)."""
    return np.array(rgb, dtype=np.uint8)


#: Half the length of the cross that marks a point (m).
MARK = 0.03


def _cross(point: np.ndarray) -> np.ndarray:
    """(3, 2, 3) a small cross of three segments through ``point``, along x, y and z."""
    return np.stack([point - MARK * np.eye(3), point + MARK * np.eye(3)], axis=1)


def anchored_geometry(arm: Arm, frames: np.ndarray) -> dict[str, list[tuple[int | None, np.ndarray]]] | None:
    """The UR family's factors (docs/kinematics.md §5) as segments fixed in a frame of the arm: per factor,
    [(frame index, or None for the base; (m, 2, 3) segments in that frame)]. Hung under the links, they move
    with the arm and a redraw only recolours them. None for an arm whose model gives no such geometry.

    shoulder: the cylinder of radius d4 about axis 1 and the wrist-2 point P5 (singular on it); elbow: the
    reach circles of P4 about the shoulder, in the arm's plane (frame {1}'s x–z), and P4 on them; wrist:
    axes 4 and 6 (singular when parallel).
    """
    if not hasattr(arm.solver, "singularity_geometry_from_frames"):
        return None
    g = arm.singularity_geometry_from_frames(frames)
    x, y, z = np.eye(3)
    rings = [circle_segments(h * z, x, y, g.cylinder_radius) for h in (0.0, 0.8, 1.6)]
    sides = [[g.cylinder_radius * d, g.cylinder_radius * d + 1.6 * z] for d in (x, y, -x, -y)]
    centre = in_frame(frames[1], g.elbow_center)
    return {
        "shoulder": [(None, np.concatenate([*rings, sides])), (5, _cross(in_frame(frames[5], g.p5)))],
        "elbow": [(1, np.concatenate([circle_segments(centre, x, z, r) for r in g.elbow_radii])),
                  (4, _cross(in_frame(frames[4], g.p4)))],
        "wrist": [(4, in_frame(frames[4], np.array([[g.p4 - AXIS_HALF_LENGTH * g.axis4, g.p4 + AXIS_HALF_LENGTH * g.axis4]]))),
                  (6, in_frame(frames[6], np.array([[g.flange - AXIS_HALF_LENGTH * g.axis6,
                                                     g.flange + AXIS_HALF_LENGTH * g.axis6]])))],
    }


def _placed(frames: np.ndarray, parts: list[tuple[int | None, np.ndarray]]) -> np.ndarray:
    """Anchored parts in the base frame, one (m, 2, 3) array."""
    return np.concatenate([segments if anchor is None else from_frame(frames[anchor], segments) for anchor, segments in parts])


def factor_names(arm: Arm) -> list[str]:
    """The names of det J's factors, none for a typed table (its det J is not derived)."""
    try:
        return list(arm.factor_names)
    except ValueError:
        return []


def _foot(point: np.ndarray, axis_point: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """The point of a line (through ``axis_point`` along unit ``axis``) nearest ``point``."""
    return axis_point + np.dot(point - axis_point, axis) * axis


def factor_geometry(arm: Arm, q: np.ndarray, frames: np.ndarray, size: float) -> dict[str, np.ndarray]:
    """Per factor of the arm's det J, the (m, 2, 3) segments that show what it measures at joints ``q``.

    ``frames`` are ``arm.frames(q)``; ``size`` (the arm's reach, m) sets how long axes are drawn.
    """
    anchored = anchored_geometry(arm, frames)
    if anchored is not None:
        return {name: _placed(frames, parts) for name, parts in anchored.items()}
    if arm.dh is not None:
        z, o = arm.dh.joint_axes(frames)
    else:  # the desktop arm's frames: the shoulder, the elbow, the tool; its base turns about its vertical
        z, o = np.asarray([arm.up], dtype=float), frames[:1, :3, 3]
    tool = frames[-1, :3, 3]
    centre = arm.wrist_centre(q) if arm.n_joints == 6 else tool
    # axis 1 from below the shoulder to above the wrist centre's height: drawn 0.9 of the reach up, the KR210's
    # went 3.5 m up, off the top of the screen
    along = float(np.dot(centre - o[0], z[0]))
    axis_line = [o[0] + (min(along, 0.0) - 0.1 * size) * z[0], o[0] + (max(along, 0.2 * size) + 0.2 * size) * z[0]]
    out: dict[str, np.ndarray] = {}
    for name in factor_names(arm):
        if name == "shoulder" and arm.joint_types[2] == "P":  # Stanford: the boom parallel to axis 1
            out["shoulder"] = np.array([axis_line, [centre - 0.5 * size * z[2], centre + 0.2 * size * z[2]]])
        elif name == "shoulder":  # the wrist centre's distance from axis 1
            out["shoulder"] = np.array([axis_line, [_foot(centre, o[0], z[0]), centre]])
        elif name == "reach":  # the cylindrical arm's: the wrist centre's (the tool's) distance from the column
            out["reach"] = np.array([axis_line, [_foot(centre, o[0], z[0]), centre]])
        elif name == "stroke":  # the wrist centre's distance from axis 2: d3
            out["stroke"] = np.array([[_foot(centre, o[1], z[1]), centre]])
        elif name == "wrist":
            half = 0.25 * size
            out["wrist"] = np.array([[centre - half * z[3], centre + half * z[3]], [centre - half * z[5], centre + half * z[5]]])
        elif name == "elbow" and arm.n_joints == 6:  # upper arm and forearm, up to the wrist centre
            out["elbow"] = np.array([[o[1], o[2]], [o[2], centre]])
        elif name == "fold":  # the desktop arm's upper arm and forearm, in one line at the singularity
            out["fold"] = np.array([[o[0], frames[1, :3, 3]], [frames[1, :3, 3], tool]])
        elif name == "elbow":  # SCARA, planar: the links seen along axis 1, at the elbow's height
            flat = [p - np.dot(p - o[1], z[0]) * z[0] for p in (_foot(o[1], o[0], z[0]), o[1], tool)]
            out["elbow"] = np.array([[flat[0], flat[1]], [flat[1], flat[2]]])
        else:
            raise ValueError(f"no drawing for {arm.name}'s factor {name!r}")
    return out


class SingularityOverlay(View):
    """det J's factors in 3D for any arm whose model factors it: each factor's geometry (:func:`factor_geometry`)
    in its own colour, turning red as the factor nears zero, and its name; hidden until switched on.

    Where the arm's drawing has a node per link (``link_node(i)``, UR's meshes) and the model anchors its
    geometry in the links (:func:`anchored_geometry`), it is sent once and hangs under them: a drag only
    recolours it. Otherwise it is computed and sent again on every change. Colours move towards red in
    :data:`ALARM_STEPS` steps, so that a drag sends a colour only when it crosses a step.
    """

    def __init__(self, scene: viser.SceneApi, arm: Arm, first: Snapshot, size: float, root: str,
                 link_node: Callable[[int], str] | None = None) -> None:
        self._arm = arm
        self._size = size
        self.enabled = False
        self._steps: dict[str, int] = {}
        self._scales = factor_scales(arm).tolist()
        anchored = anchored_geometry(arm, first.frames) if link_node is not None else None
        self._moving = anchored is None  #: computed again on every change
        if anchored is None:
            anchored = {name: [(None, segments)] for name, segments in factor_geometry(arm, first.q, first.frames, size).items()}
        self.parts: dict[str, list[viser.LineSegmentsHandle]] = {}
        #: each name by its factor's last part (the point or the axis that matters): (link or None, point in it)
        self._name_points: list[tuple[int | None, np.ndarray]] = []
        for name, parts in anchored.items():
            self.parts[name] = []
            for k, (anchor, segments) in enumerate(parts):
                parent = f"{root}/singular" if anchor is None else link_node(anchor)
                self.parts[name].append(scene.add_line_segments(
                    f"{parent}/{name}{k}", segments.astype(np.float32), line_color(FACTOR_COLORS[name]),
                    thickness=0.01 * size, visible=False))
            anchor, segments = parts[-1]
            self._name_points.append((anchor, segments.mean(axis=(0, 1))))
        #: the factors' names, placed apart on the screen with the drawing's other labels
        self.names = BranchLabels(scene, f"{root}/singular/names", len(self.parts), scale=1.3,
                                  colours=[FACTOR_COLORS[name] for name in self.parts])
        #: each factor's first line drawing
        self.lines = {name: parts[0] for name, parts in self.parts.items()}

    @property
    def labels(self) -> dict[str, viser.LabelHandle]:
        """The label that shows each factor's name (one label may show several)."""
        return self.names.carriers(list(self.parts))

    def set_enabled(self, enabled: bool) -> None:
        """Show or hide it; the next render draws it, the names at the panel's pace (the session redraws at once)."""
        self.enabled = enabled
        for node in (part for parts in self.parts.values() for part in parts):
            node.visible = enabled
        if not enabled:
            self.names.show(np.zeros((0, 3)), [])

    def render_panel(self, snapshot: Snapshot) -> None:
        if not self.enabled:
            return
        if self._moving:
            points = [segments.mean(axis=(0, 1)) for segments in factor_geometry(self._arm, snapshot.q, snapshot.frames,
                                                                                  self._size).values()]
        else:
            points = [point if anchor is None else from_frame(snapshot.frames[anchor], point) for anchor, point in self._name_points]
        self.names.show(np.array(points), list(self.parts))

    def render(self, snapshot: Snapshot) -> None:
        if not self.enabled:
            return
        if self._moving:
            geometry = factor_geometry(self._arm, snapshot.q, snapshot.frames, self._size)
            for name, segments in geometry.items():
                self.lines[name].points = segments.astype(np.float32)
        for name, value, scale in zip(self.parts, snapshot.factors.tolist(), self._scales):  # a few floats: plain Python
            step = round(ALARM_STEPS * alarm(min(abs(value) / scale, 1.0)))
            if self._steps.get(name) != step:  # a drag usually moves a colour a step, or none: send only that
                self._steps[name] = step
                for part in self.parts[name]:
                    part.colors = line_color(blend(FACTOR_COLORS[name], DANGER_RED, step / ALARM_STEPS))


def has_overlay(arm: Arm) -> bool:
    """The model factors det J, and :func:`factor_geometry` draws each factor (not a typed table's: not derived)."""
    return factor_words(arm) is not None


def held_levels(history, now: float, seconds: float = PLOT_SECONDS) -> np.ndarray:
    """(m, 1 + k) float32 rows (time − now, levels…) of the last ``seconds``: each sample's levels held
    until the next change and the last until now, the first from the window's start, so an arm at
    rest draws level lines, not a dot.

    >>> held_levels([(0.0, 0.5), (4.0, 0.25)], now=6.0).tolist()
    [[-10.0, 0.5], [-2.0, 0.5], [-2.0, 0.25], [0.0, 0.25]]
    """
    samples = np.array(history, dtype=float)
    start = np.searchsorted(samples[:, 0], now - seconds, side="right") - 1  # the levels in force at the window's start
    samples = samples[max(start, 0):]
    samples[0, 0] = now - seconds  # at rest since the window's start (or since the arm was shown)
    steps = np.repeat(samples, 2, axis=0)
    steps[1::2, 0] = np.append(samples[1:, 0], now)  # each row held until the next one's time
    steps[:, 0] -= now
    return steps.astype(np.float32)


class Singularities(View):
    """The "Singularities" folder, for any arm: the 3D switch, the formula, gauges, rolling plot, demo buttons.

    ``overlay`` is the drawing's 3D part (``enabled``, ``set_enabled``), None where it draws none.
    """

    answers = ("singularity", "det_j")  # its buttons put the arm on one; its gauges and plot give det J

    def __init__(self, gui: viser.GuiApi, overlay, session: Session) -> None:
        self._session = session
        self._overlay = overlay
        arm = self._arm = session.arm
        self._words = factor_words(arm)
        self._history: collections.deque = collections.deque(maxlen=PLOT_SAMPLES)
        self._started = time.monotonic()
        folder = gui.add_folder("Singularities", expand_by_default=False)
        self.folders = (folder,)
        names = [name for name, _, _ in self._words[1]] if self._words else []
        with folder:
            self.enabled = (gui.add_checkbox("Show singularity overlay", overlay.enabled,
                                             hint="The geometry each factor measures, red as it nears zero")
                            if overlay is not None else None)
            if overlay is None:
                gui.add_markdown("No overlay on this arm: it draws what each factor of det J measures, and a typed "
                                 "table's det J is not derived into factors; the gauges below are what there is.")
            if arm.name in arm.UR_PRESETS:
                gui.add_html("<div style='font-size:1.05em'>" + symbolic.det_j_mathml() + "</div>")
            self.gauges = gui.add_html("")  # (filled by the first render_panel, held back if a challenge asks det J)
            self.plot = gui.add_uplot(
                data=(np.zeros(2, np.float32), *(np.ones(2, np.float32) for _ in names)),
                series=(viser.uplot.Series(label="time (s)"),
                        *(viser.uplot.Series(label=name, stroke=hex_color(FACTOR_COLORS.get(name, SHOULDER_COLOR)), width=2)
                          for name in names)),
                scales={"x": viser.uplot.Scale(time=False, range=(-PLOT_SECONDS, 0.0)),
                        "y": viser.uplot.Scale(range=(0.0, 1.0))},
                axes=(viser.uplot.Axis(label="seconds (0 = now)"), viser.uplot.Axis(label="|factor| / scale")),
                title="Factors over the last 10 s", aspect=1.5) if names else None
            self.demo = (gui.add_button_group("Put the arm on the", names, hint="Moves as few joints as it can, as "
                                              "little as it can, onto where that factor is zero") if names else None)
            self.refusal = Beside(gui)  # no pose within the limits puts the arm on that factor
            self.held_back = gui.add_markdown("", visible=False)  #: why the buttons are off (a class challenge)
        self.charts = () if self.plot is None else (self.plot,)
        self._pressed = ""  #: the newest button pressed
        self._presses = FoldedRuns(self._place)
        if self.enabled is not None:
            self.enabled.on_update(session.guard(self._toggled))
        if self.demo is not None:
            self.demo.on_click(session.guard(self._demo, beside=self.refusal))

    def _toggled(self, _: viser.GuiEvent) -> None:
        with self._session.state.lock:
            self._overlay.set_enabled(bool(self.enabled.value))
        self._session.redraw()

    def hold_back(self, asked: str | None) -> None:
        super().hold_back(asked)
        say_held_back(self.held_back, self.held == "singularity")
        if self.demo is not None:
            self.demo.visible = self.held != "singularity"
        if self.plot is not None:  # each factor's size against its scale: the UR10's s3 and s5 as they are
            self.plot.visible = self.held != "det_j"

    def _demo(self, _: viser.GuiEvent) -> None:
        if self.held == "singularity":  # a click a browser cannot send while they are off
            raise ValueError(HELD_BACK)
        self._pressed = chosen(self.demo, "singularity")
        self._presses.start("singularity", lambda run: self._session.guard(run, beside=self.refusal))

    def _place(self) -> None:
        """Presses fold into one under way and one waiting. An arm without closed forms is searched (up to about
        80 ms): a slow job, at most a share of the server's time (``HEAVY``); a closed form does not wait its turn
        behind other browsers' clouds."""
        session, kind = self._session, self._pressed

        def place() -> None:
            session.apply(self.unless_held(lambda state: state.place_in_singularity(kind), "singularity"))

        if self._arm.singularities_in_closed_form:
            place()
        else:
            HEAVY.run(session.client, place, cancelled=lambda: session.closed)

    def render_panel(self, snapshot: Snapshot) -> None:
        self.gauges.content = HELD_BACK if self.held == "det_j" else factors_html(self._arm, snapshot.q)
        if self.plot is None:
            return
        now = time.monotonic() - self._started
        self._history.append((now, *factor_levels(self._arm, snapshot.factors)))
        self.plot.data = tuple(np.ascontiguousarray(column) for column in held_levels(self._history, now).T)
