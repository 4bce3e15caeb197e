"""A course arm's singularities in 3D: the geometry each factor of det J measures (docs/kinematics.md §7.6).

Each factor gets lines in its own colour (the UR10 overlay's: shoulder orange, elbow bluish
green, wrist reddish purple), turning red as the factor nears zero, and its name in 3D:

* shoulder — axis 1 and the wrist centre's distance from it (the Stanford arm: axis 1 and
  the boom, parallel when singular);
* elbow — the two links, seen along axis 1 for a SCARA or a planar arm, in line when singular;
* wrist — axes 4 and 6, parallel when singular;
* stroke (Stanford) — the wrist centre's distance from axis 2, d3; reach (cylindrical) — the
  tool's distance from the column's axis.
"""

from __future__ import annotations

import numpy as np
import viser

from ur10core import symbolic_arms
from ur10core import Arm
from ur10core.serial import PRESETS

from ...viser_internals.fast_updates import set_positions
from ..singularity import ALARM_STEPS, line_color, alarm
from ...style import DANGER_RED, ELBOW_COLOR, SHOULDER_COLOR, WRIST_COLOR, blend
from .state import CourseSnapshot

FACTOR_COLORS = {"shoulder": SHOULDER_COLOR, "stroke": SHOULDER_COLOR, "reach": SHOULDER_COLOR,
                 "elbow": ELBOW_COLOR, "wrist": WRIST_COLOR}


def _foot(point: np.ndarray, axis_point: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """The point of a line (through ``axis_point`` along unit ``axis``) nearest ``point``."""
    return axis_point + np.dot(point - axis_point, axis) * axis


def factor_geometry(arm: Arm, q: np.ndarray, frames: np.ndarray, size: float) -> dict[str, np.ndarray]:
    """Per factor of the preset's det J, the (m, 2, 3) segments that show what it measures at joints ``q``.

    ``frames`` are ``arm.frames(q)``; ``size`` (the arm's reach, m) sets how long axes are drawn.
    """
    z, o = arm.dh.joint_axes(frames)
    tool = frames[-1, :3, 3]
    centre = arm.wrist_centre(q) if arm.n_joints == 6 else tool
    axis_line = [o[0] - 0.1 * size * z[0], o[0] + 0.9 * size * z[0]]
    out: dict[str, np.ndarray] = {}
    for factor in symbolic_arms.load(arm.name).factors:
        if factor.name == "shoulder" and arm.joint_types[2] == "P":  # Stanford: the boom parallel to axis 1
            out["shoulder"] = np.array([axis_line, [centre - 0.5 * size * z[2], centre + 0.2 * size * z[2]]])
        elif factor.name == "shoulder":  # the wrist centre's distance from axis 1
            out["shoulder"] = np.array([axis_line, [_foot(centre, o[0], z[0]), centre]])
        elif factor.name == "reach":
            out["reach"] = np.array([axis_line, [_foot(tool, o[0], z[0]), tool]])
        elif factor.name == "stroke":  # the wrist centre's distance from axis 2: d3
            out["stroke"] = np.array([[_foot(centre, o[1], z[1]), centre]])
        elif factor.name == "wrist":
            half = 0.25 * size
            out["wrist"] = np.array([[centre - half * z[3], centre + half * z[3]], [centre - half * z[5], centre + half * z[5]]])
        elif factor.name == "elbow" and arm.n_joints == 6:  # upper arm and forearm, up to the wrist centre
            out["elbow"] = np.array([[o[1], o[2]], [o[2], centre]])
        elif factor.name == "elbow":  # SCARA, planar: the links seen along axis 1, at the elbow's height
            flat = [p - np.dot(p - o[1], z[0]) * z[0] for p in (_foot(o[1], o[0], z[0]), o[1], tool)]
            out["elbow"] = np.array([[flat[0], flat[1]], [flat[1], flat[2]]])
        else:
            raise ValueError(f"no drawing for {arm.name}'s factor {factor.name!r}")
    return out


class CourseOverlay:
    """The factors' geometry in a course arm's scene, shown or hidden with the panel's switch.

    Colours move towards red in :data:`ALARM_STEPS` steps, so that a drag sends a colour
    only when it crosses a step. Not for a typed table (its det J is not derived).
    """

    def __init__(self, scene: viser.SceneApi, arm: Arm, first: CourseSnapshot, size: float, root: str) -> None:
        self._arm = arm
        self._size = size
        self.enabled = False
        self._steps: dict[str, int] = {}
        self.lines: dict[str, viser.LineSegmentsHandle] = {}
        self.labels: dict[str, viser.LabelHandle] = {}
        for name, segments in factor_geometry(arm, first.q, first.frames, size).items():
            self.lines[name] = scene.add_line_segments(f"{root}/singular/{name}", segments, FACTOR_COLORS[name],
                                                       thickness=0.01 * size, visible=False)
            self.labels[name] = scene.add_label(f"{root}/singular/{name}/label", name, font_screen_scale=1.3,
                                                anchor="bottom-center", visible=False)

    def levels(self, q: np.ndarray) -> np.ndarray:
        """Each factor's size as a share of its 99th percentile over the workspace (the gauges' scale), in [0, 1]."""
        from .panel import factor_scales

        return np.clip(np.abs(self._arm.singularity_factors(q)) / factor_scales(self._arm.name), 0.0, 1.0)

    def render(self, snapshot: CourseSnapshot) -> None:
        for line in (*self.lines.values(), *self.labels.values()):
            if line.visible != self.enabled:
                line.visible = self.enabled
        if not self.enabled or not self.lines:
            return
        geometry = factor_geometry(self._arm, snapshot.q, snapshot.frames, self._size)
        set_positions(list(self.labels.values()), np.array([segments[-1].mean(axis=0) for segments in geometry.values()]))
        for (name, segments), level in zip(geometry.items(), self.levels(snapshot.q)):
            self.lines[name].points = segments
            step = round(ALARM_STEPS * alarm(float(level)))
            if self._steps.get(name) != step:
                self._steps[name] = step
                self.lines[name].colors = line_color(blend(FACTOR_COLORS[name], DANGER_RED, step / ALARM_STEPS))


def has_overlay(arm: Arm) -> bool:
    return arm.name in PRESETS
