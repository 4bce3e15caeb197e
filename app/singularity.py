"""The singularity-manifold overlay (COURSE_NOTES §5).

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
import time
from typing import TYPE_CHECKING

import numpy as np
import trimesh
import viser
import viser.uplot

from ur10core import symbolic

from .state import SINGULARITY_KINDS, Snapshot
from .style import DANGER_RED, ELBOW_COLOR, OVERLAY_IDLE, SAFE_GREEN, SHOULDER_COLOR, WRIST_COLOR, blend, hex_color

if TYPE_CHECKING:
    from .session import ClientSession

#: Below this share of its largest value a factor is drawn fully red.
ALARM_AT = 0.05
#: From this share up a factor is drawn fully green.
CALM_AT = 0.35
PLOT_SECONDS = 10.0
PLOT_SAMPLES = 200
CIRCLE_SEGMENTS = 96
AXIS_HALF_LENGTH = 0.25


def factor_levels(snapshot: Snapshot, reach: float) -> np.ndarray:
    """|factor| as a share of its largest value: shoulder by a2 + a3, elbow |s3|, wrist |s5|."""
    shoulder, elbow, wrist = np.abs(snapshot.factors)
    return np.array([min(shoulder / reach, 1.0), elbow, wrist])


def alarm(level: float) -> float:
    """0 (calm) … 1 (on the singularity) for a factor level in [0, 1]."""
    return float(np.clip((CALM_AT - level) / (CALM_AT - ALARM_AT), 0.0, 1.0))


def circle_segments(center: np.ndarray, u: np.ndarray, v: np.ndarray, radius: float) -> np.ndarray:
    """A circle as (N, 2, 3) line segments in the plane spanned by unit vectors u, v."""
    angles = np.linspace(0.0, 2 * np.pi, CIRCLE_SEGMENTS + 1)
    points = center + radius * (np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v)
    return np.stack([points[:-1], points[1:]], axis=1)


def _segment_colors(rgb: tuple[int, int, int], count: int) -> np.ndarray:
    return np.broadcast_to(np.array(rgb, dtype=np.uint8), (count, 2, 3)).copy()


class SingularityOverlay:
    def __init__(self, scene: viser.SceneApi, gui: viser.GuiApi, session: "ClientSession") -> None:
        self._session = session
        arm = session.arm
        self._reach = arm.a2 + arm.a3
        self._history: collections.deque = collections.deque(maxlen=PLOT_SAMPLES)
        self._started = time.monotonic()

        with gui.add_folder("Singularities"):
            self.enabled = gui.add_checkbox("Show singularity overlay", False)
            self.formula = gui.add_html(
                "<div style='font-size:1.05em'>" + symbolic.det_j_mathml() + "</div>", visible=False
            )
            self.values = gui.add_markdown("", visible=False)
            self.gauges = [gui.add_progress_bar(100.0, color=SAFE_GREEN, visible=False) for _ in range(3)]
            self.plot = gui.add_uplot(
                data=(np.zeros(2), np.ones(2), np.ones(2), np.ones(2)),
                series=(
                    viser.uplot.Series(label="time (s)"),
                    viser.uplot.Series(label="shoulder", stroke=hex_color(SHOULDER_COLOR), width=2),
                    viser.uplot.Series(label="elbow |s3|", stroke=hex_color(ELBOW_COLOR), width=2),
                    viser.uplot.Series(label="wrist |s5|", stroke=hex_color(WRIST_COLOR), width=2),
                ),
                scales={"x": viser.uplot.Scale(time=False), "y": viser.uplot.Scale(range=(0.0, 1.0))},
                title="factors over the last 10 s (share of their maximum)",
                aspect=2.0,
                visible=False,
            )
            self.demo = gui.add_button_group("Put the arm on the", ("shoulder", "elbow", "wrist"), visible=False)

        # 3D geometry, hidden until the overlay is switched on
        cylinder = trimesh.creation.cylinder(radius=arm.d4, segment=[[0, 0, 0], [0, 0, 1.6]], sections=64)
        self.cylinder = scene.add_mesh_simple(
            "/overlay/shoulder_cylinder", cylinder.vertices, cylinder.faces, color=SHOULDER_COLOR,
            opacity=0.18, side="double", cast_shadow=False, receive_shadow=False, visible=False,
        )
        self.p5 = scene.add_icosphere("/overlay/p5", radius=0.022, color=SHOULDER_COLOR, visible=False, cast_shadow=False)
        self.p4 = scene.add_icosphere("/overlay/p4", radius=0.022, color=ELBOW_COLOR, visible=False, cast_shadow=False)
        empty = np.zeros((CIRCLE_SEGMENTS, 2, 3))
        self.circles = scene.add_line_segments("/overlay/elbow_circles", np.concatenate([empty, empty]),
                                               OVERLAY_IDLE, thickness=0.006, visible=False)
        self.axes = scene.add_line_segments("/overlay/wrist_axes", np.zeros((2, 2, 3)), OVERLAY_IDLE,
                                            thickness=0.01, visible=False)

        self.enabled.on_update(session.guard(self._toggled))
        self.demo.on_click(session.guard(self._demo))

    @property
    def _widgets(self) -> list:
        return [self.formula, self.values, *self.gauges, self.plot, self.demo,
                self.cylinder, self.p5, self.p4, self.circles, self.axes]

    def _toggled(self, _: viser.GuiEvent) -> None:
        for widget in self._widgets:
            widget.visible = self.enabled.value
        self.render(self._session.state.last)

    def _demo(self, _: viser.GuiEvent) -> None:
        kind = self.demo.value
        if kind not in SINGULARITY_KINDS:
            raise ValueError(f"unknown singularity {kind!r}")
        self._session.apply(lambda state: state.place_in_singularity(kind))

    def render(self, snapshot: Snapshot) -> None:
        levels = factor_levels(snapshot, self._reach)
        now = time.monotonic() - self._started
        self._history.append((now, *levels))
        if not self.enabled.value:
            return
        shoulder, elbow, wrist = snapshot.factors
        alarms = [alarm(level) for level in levels]
        for gauge, level, a in zip(self.gauges, levels, alarms):
            gauge.value = float(np.clip(100.0 * level, 0.0, 100.0))
            gauge.color = blend(SAFE_GREEN, DANGER_RED, a)
        rows = [
            f"**shoulder** a2c2 + a3c23 − d5s234 = {shoulder * 1000:+.1f} mm",
            f"**elbow** s3 = {elbow:+.4f}",
            f"**wrist** s5 = {wrist:+.4f}",
            f"**det J** = {snapshot.det_j:+.5f} m³  (|det J| is the manipulability)",
        ]
        self.values.content = "  \n".join(rows)
        history = np.array([h for h in self._history if h[0] >= now - PLOT_SECONDS])
        if len(history) < 2:
            history = np.vstack([history, history])
        self.plot.data = tuple(np.ascontiguousarray(column) for column in (history[:, 0] - now, *history[:, 1:].T))

        g = snapshot.geometry
        self.cylinder.color = blend(SHOULDER_COLOR, DANGER_RED, alarms[0])
        self.p5.position = g.p5
        self.p5.color = blend(SHOULDER_COLOR, DANGER_RED, alarms[0])
        up = np.array([0.0, 0.0, 1.0])
        outer, inner = g.elbow_radii
        self.circles.points = np.concatenate(
            [circle_segments(g.elbow_center, g.arm_forward, up, r) for r in (outer, inner)]
        ).astype(np.float32)
        self.circles.colors = _segment_colors(blend(OVERLAY_IDLE, DANGER_RED, alarms[1]), 2 * CIRCLE_SEGMENTS)
        self.p4.position = g.p4
        self.p4.color = blend(ELBOW_COLOR, DANGER_RED, alarms[1])
        self.axes.points = np.array(
            [
                [g.p4 - AXIS_HALF_LENGTH * g.axis4, g.p4 + AXIS_HALF_LENGTH * g.axis4],
                [g.flange - AXIS_HALF_LENGTH * g.axis6, g.flange + AXIS_HALF_LENGTH * g.axis6],
            ],
            dtype=np.float32,
        )
        self.axes.colors = _segment_colors(blend(WRIST_COLOR, DANGER_RED, alarms[2]), 2)
