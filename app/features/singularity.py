"""The singularity-manifold overlay (docs/kinematics.md §5).

det J = a2 · a3 · (a2 c2 + a3 c23 − d5 s234) · s3 · s5: three factors, three kinds of
singularity. The overlay shows each factor as a gauge that turns from green to red as it
approaches zero, a short rolling plot, det J itself and its factored formula (rendered
MathML from ``ur10core.symbolic``), and in the 3D view the geometry each factor measures:

* shoulder — the cylinder of radius d4 about the base axis and the wrist-2 point P5
  (singular when P5 touches the cylinder);
* elbow — the reach circles (a2 + a3 stretched, |a2 − a3| folded) of the frame-4
  origin P4 about the shoulder, in the arm's plane;
* wrist — axes 4 and 6 as lines (singular when they are parallel).

Buttons put the arm exactly on each singularity for a demonstration.
"""

from __future__ import annotations

import collections
import functools
import time
from typing import TYPE_CHECKING

import numpy as np
import trimesh
import viser
import viser.uplot

from ur10core import symbolic
from ur10core.orientation import in_frame

from ..feedback import chosen
from .robot import node_name
from ..state import SINGULARITY_KINDS, Snapshot
from ..view import View
from ..style import DANGER_RED, ELBOW_COLOR, OVERLAY_IDLE, SAFE_GREEN, SHOULDER_COLOR, WRIST_COLOR, blend, hex_color, number

if TYPE_CHECKING:
    from ..session import ClientSession

#: Below this share of its largest value a factor is drawn fully red.
ALARM_AT = 0.05
#: From this share up a factor is drawn fully green.
CALM_AT = 0.35
#: The 3D overlay's colours move in this many steps from calm to alarm (each step is a message).
ALARM_STEPS = 20
PLOT_SECONDS = 10.0
PLOT_SAMPLES = 200
CIRCLE_SEGMENTS = 96
AXIS_HALF_LENGTH = 0.25


def factor_levels(snapshot: Snapshot, reach: float) -> tuple[float, float, float]:
    """|factor| as a share of its largest value: shoulder by a2 + a3, elbow |s3|, wrist |s5|."""
    shoulder, elbow, wrist = snapshot.factors.tolist()
    return min(abs(shoulder) / reach, 1.0), abs(elbow), abs(wrist)


def alarm(level: float) -> float:
    """0 (calm) … 1 (on the singularity) for a factor level in [0, 1]."""
    return min(1.0, max(0.0, (CALM_AT - level) / (CALM_AT - ALARM_AT)))


def circle_segments(center: np.ndarray, u: np.ndarray, v: np.ndarray, radius: float) -> np.ndarray:
    """A circle as (N, 2, 3) line segments in the plane spanned by unit vectors u, v."""
    angles = np.linspace(0.0, 2 * np.pi, CIRCLE_SEGMENTS + 1)
    points = center + radius * (np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v)
    return np.stack([points[:-1], points[1:]], axis=1)


def gauges_html(snapshot: Snapshot, levels: np.ndarray, colors: list[tuple[int, int, int]]) -> str:
    """Three labelled bars, green → red as each factor of det J approaches zero, and det J."""
    shoulder, elbow, wrist = snapshot.factors
    rows = (
        ("shoulder", f"a2c2 + a3c23 − d5s234 = {number(shoulder * 1000, '+.1f')} mm"),
        ("elbow", f"s3 = {number(elbow, '+.4f')}"),
        ("wrist", f"s5 = {number(wrist, '+.4f')}"),
    )
    bars = []
    for (name, value), level, color in zip(rows, levels, colors):
        bars.append(
            f"<div style='margin:3px 0'><b>{name}</b> {value}"
            "<div style='height:8px;background:#e9ecef;border-radius:4px'>"
            f"<div class='gauge-{name}' style='height:8px;width:{100 * level:.1f}%;border-radius:4px;"
            f"background:{hex_color(color)}'></div></div></div>"
        )
    bars.append(f"<div><b>det J</b> = {number(snapshot.det_j, '+.5f')} m³ (|det J| is the manipulability)</div>")
    return "<div style='font-size:0.85em'>" + "".join(bars) + "</div>"


def line_color(rgb: tuple[int, int, int]) -> np.ndarray:
    """One colour for a whole line-segments node: viser's browser reads per-vertex uint8 colours as 0…1 floats (white)."""
    return np.array(rgb, dtype=np.uint8)


@functools.lru_cache(maxsize=8)
def shoulder_cylinder_mesh(radius: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of the shoulder singularity's cylinder, made once per radius for every browser."""
    cylinder = trimesh.creation.cylinder(radius=radius, segment=[[0, 0, 0], [0, 0, 1.6]], sections=64)
    return cylinder.vertices, cylinder.faces


class OverlayScene(View):
    """The overlay's geometry in the 3D view, hidden until switched on.

    The markers and lines hang under the solid arm's link nodes (``robot.node_name``) in
    coordinates taken once from the core's geometry, so a redraw only recolours them.
    """

    def __init__(self, scene: viser.SceneApi, first: Snapshot) -> None:
        self.enabled = False
        self._reach = first.arm.a2 + first.arm.a3
        self._drawn_alarms: tuple[float, ...] | None = None
        F, g = first.frames, first.geometry

        def local(frame: int, point: np.ndarray) -> np.ndarray:
            return in_frame(F[frame], point)

        vertices, faces = shoulder_cylinder_mesh(g.cylinder_radius)
        self.cylinder = scene.add_mesh_simple(
            "/overlay/shoulder_cylinder", vertices, faces, color=SHOULDER_COLOR,
            opacity=0.18, side="double", cast_shadow=False, receive_shadow=False, visible=False,
        )
        self.p5 = scene.add_icosphere(f"{node_name(5)}/p5", radius=0.022, color=SHOULDER_COLOR,
                                      position=local(5, g.p5), visible=False, cast_shadow=False)
        self.p4 = scene.add_icosphere(f"{node_name(4)}/p4", radius=0.022, color=ELBOW_COLOR,
                                      position=local(4, g.p4), visible=False, cast_shadow=False)
        # the reach circles turn with θ1: they live in frame {1}, spanned by x1 and z1
        centre = local(1, g.elbow_center)
        x1, z1 = np.eye(3)[0], np.eye(3)[2]
        circles = np.concatenate([circle_segments(centre, x1, z1, r) for r in g.elbow_radii]).astype(np.float32)
        self.circles = scene.add_line_segments(f"{node_name(1)}/elbow_circles", circles,
                                               line_color(OVERLAY_IDLE), thickness=0.006,
                                               visible=False)
        self.axes = []
        for frame, point, axis in ((4, g.p4, g.axis4), (6, g.flange, g.axis6)):
            start = local(frame, point - AXIS_HALF_LENGTH * axis)
            end = local(frame, point + AXIS_HALF_LENGTH * axis)
            self.axes.append(scene.add_line_segments(f"{node_name(frame)}/axis{frame}", np.array([[start, end]], np.float32),
                                                     line_color(WRIST_COLOR), thickness=0.01, visible=False))

    def set_enabled(self, enabled: bool) -> None:
        """Show or hide the overlay; the next render colours it (the session redraws at once)."""
        self.enabled = enabled
        self._drawn_alarms = None
        for node in (self.cylinder, self.p5, self.p4, self.circles, *self.axes):
            node.visible = enabled

    def render(self, snapshot: Snapshot) -> None:
        if not self.enabled:
            return
        alarms = tuple(round(alarm(level) * ALARM_STEPS) / ALARM_STEPS for level in factor_levels(snapshot, self._reach))
        drawn = self._drawn_alarms or (None, None, None)
        self._drawn_alarms = alarms
        shoulder, elbow, wrist = alarms
        # a drag usually moves one factor's colour a step, or none: recolour only what changed
        if shoulder != drawn[0]:
            self.cylinder.color = blend(SHOULDER_COLOR, DANGER_RED, shoulder)
            self.p5.color = blend(SHOULDER_COLOR, DANGER_RED, shoulder)
        if elbow != drawn[1]:
            self.circles.colors = line_color(blend(OVERLAY_IDLE, DANGER_RED, elbow))
            self.p4.color = blend(ELBOW_COLOR, DANGER_RED, elbow)
        if wrist != drawn[2]:
            for axis in self.axes:
                axis.colors = line_color(blend(WRIST_COLOR, DANGER_RED, wrist))


class OverlayPanel(View):
    """The "Singularities" folder: the switch, det J's formula, gauges, rolling plot, demo buttons."""

    def __init__(self, gui: viser.GuiApi, scene: OverlayScene, session: "ClientSession") -> None:
        self._session = session
        self._scene = scene
        self._reach = session.arm.a2 + session.arm.a3
        self._history: collections.deque = collections.deque(maxlen=PLOT_SAMPLES)
        self._started = time.monotonic()
        folder = gui.add_folder("Singularities")
        self.folders = (folder,)
        with folder:
            self.enabled = gui.add_checkbox("Show singularity overlay", scene.enabled)
            self.formula = gui.add_html(
                "<div style='font-size:1.05em'>" + symbolic.det_j_mathml() + "</div>", visible=scene.enabled
            )
            # the three gauges and the numbers in one HTML element: one message per redraw
            self.gauges = gui.add_html("", visible=scene.enabled)
            self.levels = (1.0, 1.0, 1.0)  #: last drawn gauge levels (share of the factor's maximum)
            self.colors: list[tuple[int, int, int]] = [SAFE_GREEN] * 3  #: last drawn gauge colours
            self.plot = gui.add_uplot(
                data=(np.zeros(2, np.float32), np.ones(2, np.float32), np.ones(2, np.float32), np.ones(2, np.float32)),
                series=(
                    viser.uplot.Series(label="time (s)"),
                    viser.uplot.Series(label="shoulder", stroke=hex_color(SHOULDER_COLOR), width=2),
                    viser.uplot.Series(label="elbow |s3|", stroke=hex_color(ELBOW_COLOR), width=2),
                    viser.uplot.Series(label="wrist |s5|", stroke=hex_color(WRIST_COLOR), width=2),
                ),
                scales={"x": viser.uplot.Scale(time=False, range=(-PLOT_SECONDS, 0.0)),
                        "y": viser.uplot.Scale(range=(0.0, 1.0))},
                axes=(viser.uplot.Axis(label="seconds (0 = now)"), viser.uplot.Axis(label="share of maximum")),
                title="Factors over the last 10 s (share of their maximum)",
                aspect=2.0,
                visible=scene.enabled,
            )
            self.demo = gui.add_button_group("Put the arm on the", SINGULARITY_KINDS, visible=scene.enabled)
        self.enabled.on_update(session.guard(self._toggled))
        self.demo.on_click(session.guard(self._demo))

    def _toggled(self, _: viser.GuiEvent) -> None:
        for widget in (self.formula, self.gauges, self.plot, self.demo):
            widget.visible = self.enabled.value
        with self._session.state.lock:
            self._scene.set_enabled(self.enabled.value)
        self._session.redraw()
        self._session.refresher.request(self._session)

    def _demo(self, _: viser.GuiEvent) -> None:
        kind = chosen(self.demo, "singularity")
        self._session.apply(lambda state: state.place_in_singularity(kind))

    def render_panel(self, snapshot: Snapshot) -> None:
        levels = factor_levels(snapshot, self._reach)
        now = time.monotonic() - self._started
        self._history.append((now, *levels))
        if not self.enabled.value:
            return
        self.levels = levels
        self.colors = [blend(SAFE_GREEN, DANGER_RED, alarm(level)) for level in levels]
        self.gauges.content = gauges_html(snapshot, levels, self.colors)
        history = np.array([h for h in self._history if h[0] >= now - PLOT_SECONDS], dtype=np.float32)
        if len(history) < 2:
            history = np.vstack([history, history])
        history[:, 0] -= np.float32(now)
        self.plot.data = tuple(np.ascontiguousarray(column) for column in history.T)
