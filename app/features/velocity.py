"""Velocities: joint rates to the tool's velocity arrows, and a tool velocity to the joint rates it needs
(docs/kinematics.md §8.1, §8.2).

A joint-rate slider per joint draws v (blue) and ω (reddish purple) at the tool (the UR10's
flange), live with the drag. A typed tool velocity gets its joint rates from the damped
inverse, each in red where it exceeds the joint's speed limit (the UR10's, docs/kinematics.md
§1; the course's other arms have none), with the damping it took; live too, so that moving the
arm towards a singularity shows the rates it needs grow.
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np
import viser

from ur10core.challenges import RATE_LIMITS  # the rates a student can set: a velocity challenge is refused beyond them
from ur10core.differential import TASK_ROWS

from ..feedback import Beside, within
from ..state import Snapshot
from ..style import UR10_SIZE, number, swatch, typed_fields
from ..view import HELD_BACK, Session, View, say_held_back
from .joint_panel import rate_label

LINEAR_COLOR, ANGULAR_COLOR = (0, 114, 178), (204, 121, 167)
NAMES = ("v velocity", "ω turning rate")  #: the arrows' names in 3D
#: Drawn length: metres per m/s of the flange, and per rad/s of its turning on the UR10. A tool's speed grows with
#: its arm's lengths and its turning rate does not, so another arm's ω is drawn at METRES_PER_TURN_RATE times its
#: reach over the UR10's: at 0.15 the KR210's turning at 30°/s was 8 cm long beside a 3.9 m arm.
METRES_PER_SPEED, METRES_PER_TURN_RATE = 0.5, 0.15
MAX_TYPED = (2000.0, 360.0)  #: the largest typed speed (mm/s) and turning rate (°/s)


def parse_twist(text: str) -> np.ndarray:
    """``vx vy vz [ωx ωy ωz]`` in mm/s and °/s (ω = 0 if left out) → (6,) in m/s and rad/s; ``ValueError`` saying
    what is wrong."""
    fields = typed_fields(text, "the tool velocity")
    if len(fields) == 3:  # a velocity alone: all a position-only arm is asked
        fields += ["0", "0", "0"]
    if len(fields) != 6:
        raise ValueError(f"type three numbers, vx vy vz (mm/s), or six, with ωx ωy ωz (°/s) after them; got {len(fields)}")
    try:
        values = np.array([float(f) for f in fields])
    except ValueError:
        raise ValueError(f"the tool velocity must be numbers, got {text!r:.60}") from None
    if not np.isfinite(values).all():
        raise ValueError("the tool velocity must be finite numbers")
    if np.abs(values[:3]).max() > MAX_TYPED[0] or np.abs(values[3:]).max() > MAX_TYPED[1]:
        raise ValueError(f"speeds up to {MAX_TYPED[0]:.0f} mm/s and turning rates up to {MAX_TYPED[1]:.0f} °/s, please")
    return np.concatenate([values[:3] / 1000.0, np.radians(values[3:])])


def shown_rates(qdot: np.ndarray, kinds: str) -> np.ndarray:
    """Joint rates as the panel shows them: °/s for a revolute joint, mm/s for a prismatic one."""
    return np.where(np.array(list(kinds)) == "R", np.degrees(qdot), 1000.0 * np.asarray(qdot))


#: What an arm that controls less than a pose is asked of a typed velocity (``Arm.joint_rates`` solves those rows only).
UNASKED = {"position": "its tool's position only: the ω typed is not asked of it",
           "position and yaw": "its tool's position and yaw only: the ωx and ωy typed are not asked of it"}


def rates_markdown(qdot: np.ndarray, damping: float, asked: np.ndarray, achieved: np.ndarray,
                   labels: tuple[str, ...], kinds: str, limits: np.ndarray | None = None, task: str = "pose") -> str:
    """The joint rates (°/s, mm/s), red where over the joint's speed limit (if it has ``limits``), what the damping cost,
    and, on an arm that controls less than a pose (``task``), what of the velocity was not asked of it."""
    shown = shown_rates(qdot, kinds)
    over_limit = np.abs(shown) > limits if limits is not None else np.zeros(len(shown), bool)
    for_velocity = (f"For v = ({', '.join(number(1000 * v, '+.4g') for v in asked[:3])}) mm/s, ω = "
                    f"({', '.join(number(math.degrees(w), '+.4g') for w in asked[3:])}) °/s, at the arm's pose now:")
    cells = []
    for k, (label, rate, kind) in enumerate(zip(labels, shown, kinds)):
        text = f"{number(rate, '+.1f')}{'°/s' if kind == 'R' else ' mm/s'}"
        cells.append(f"| {label} | " + (f"<b style='color:#dc2626'>{text} (limit {limits[k]:.0f})</b>" if over_limit[k]
                                        else f"{text}") + " |")
    lines = [for_velocity, "", "| joint | rate |", "|---|---:|", *cells]
    over = int(over_limit.sum())
    lines.append("")
    if limits is not None:
        lines.append(f"**{over} joint{'s' if over != 1 else ''} over the limit.**" if over else "Every joint within its speed limit.")
    if damping > 0:
        miss_v = 1000 * np.linalg.norm(achieved[:3] - asked[:3])
        miss_w = math.degrees(np.linalg.norm(achieved[3:] - asked[3:]))
        lines.append(f"Near a singularity: damped (λ = {damping:.3f}), so the arm gives this velocity to within "
                     f"{miss_v:.1f} mm/s and {miss_w:.1f} °/s rather than turn its joints without bound.")
    if task in UNASKED:
        lines.append(f"This arm controls {UNASKED[task]}; these rates turn the tool at ω = "
                     f"({', '.join(number(math.degrees(w), '+.1f') for w in achieved[3:])}) °/s.")
    return "\n".join(lines)


def rates_formula(arm) -> str:
    """How the folder's joint rates come from a tool velocity: J⁻¹ where the rows the arm controls are as many as
    its joints, else the pseudo-inverse (the planar elbow's 3 × 2, a typed seven-joint arm's 6 × 7)."""
    rows, joints = len(TASK_ROWS[arm.task]), arm.n_joints
    if rows == joints:
        return "q̇ = J⁻¹ v"
    return f"q̇ = J⁺ v (J⁺ the pseudo-inverse: the J of what this arm controls is {rows} × {joints}, not square)"


class VelocityView(View):
    """The "Velocities" folder and the two arrows at the tool: for the sliders' joint rates, or a playing path's.

    ``root``: where its nodes hang; ``tool(snapshot)``: the (4, 4) pose the arrows start at
    (the arm's tool by default). The arrows' names are the session's to place (:meth:`names`). The
    kinds of joints and their speed limits (``arm.specs``, where the maker publishes them) come
    from ``session.arm``; ``size`` (the arm's reach, m) scales the arrows' thickness and the turning rate's
    length (:data:`METRES_PER_TURN_RATE`).
    """

    answers = ("velocity", "tool_velocity")  # "Find the joint rates" gives q̇ for a v; the readout gives v

    def __init__(self, scene: viser.SceneApi, gui: viser.GuiApi, session: Session, root: str = "/velocity",
                 tool: Callable[[Any], np.ndarray] = lambda snapshot: snapshot.flange, place: str = "tool",
                 size: float = UR10_SIZE) -> None:
        self._session = session
        self._arm = session.arm
        self._tool = tool
        self._kinds = "".join(self._arm.joint_types)
        self._turn_scale = METRES_PER_TURN_RATE * size / UR10_SIZE  #: metres drawn per rad/s of ω
        limits = self._arm.specs.speed_limits
        self._labels, self._limits = self._arm.joint_names, None if limits is None else shown_rates(limits, self._kinds)
        folder = gui.add_folder("Velocities", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            gui.add_markdown(f"Turn the joints at these rates: the arrows are the {place}'s velocity and turning "
                             f"rate, [v; ω] = J q̇.  \n{swatch(LINEAR_COLOR)} **v**: velocity, "
                             f"{number(1000 * METRES_PER_SPEED, '.0f')} mm drawn per m/s  \n{swatch(ANGULAR_COLOR)} **ω**: "
                             f"turning rate (about the arrow, right hand), {number(1000 * self._turn_scale, '.0f')} "
                             "mm drawn per rad/s (57.3°/s)")
            self.sliders = [gui.add_slider(rate_label(self._arm, i), min=-RATE_LIMITS[kind], max=RATE_LIMITS[kind], step=0.1,
                                           initial_value=0.0)
                            for i, kind in enumerate(self._kinds)]
            self.rates_refusal = Beside(gui)  # a rate typed in a slider's box beyond its range
            self.readout = gui.add_markdown("")
            gui.add_markdown(f"Or ask for a {place} velocity and see the joint rates it needs, {rates_formula(self._arm)}:")
            self.typed = gui.add_text("vx vy vz (mm/s) ωx ωy ωz (°/s)", "100 0 0 0 0 0",
                                      hint="Three numbers, v alone (ω = 0), or six")
            self.solve = gui.add_button("Find the joint rates")
            self.refusal = Beside(gui)
            self.rates = gui.add_markdown("")
            self.held_back = gui.add_markdown("", visible=False)
        self.linear, self.angular = (  # as thick, for its size, beside a 3.9 m KR210 as beside the UR10
            scene.add_arrows(f"{root}/{name}", np.zeros((1, 2, 3)), colour, shaft_radius=0.006 * size, head_radius=0.015 * size,
                             head_length=0.03 * size, visible=False)
            for name, colour in (("linear", LINEAR_COLOR), ("angular", ANGULAR_COLOR)))
        self._ends: tuple[np.ndarray, np.ndarray] | None = None  #: where the arrows end while they show
        self._asked: np.ndarray | None = None  #: (6,) the tool velocity asked last, whose rates follow the arm
        for slider in self.sliders:
            slider.on_update(session.guard(lambda _, slider=slider: self._rate_set(slider), beside=self.rates_refusal))
        self.solve.on_click(session.guard(lambda _: self._solve(), beside=self.refusal))

    def _rate_set(self, slider: viser.GuiSliderHandle) -> None:
        within(slider, slider.label)  # refused beside the sliders as it comes, not in the redraw that reads it
        self._session.redraw()

    def joint_rates(self) -> np.ndarray:
        """(n,) the sliders' joint rates, rad/s (m/s for a prismatic joint)."""
        shown = np.array([within(slider, slider.label) for slider in self.sliders])
        return np.where(np.array(list(self._kinds)) == "R", np.radians(shown), shown / 1000.0)

    def hold_back(self, asked: str | None) -> None:
        super().hold_back(asked)
        for widget in (self.typed, self.solve, self.rates):
            widget.visible = self.held != "velocity"
        if self.held == "velocity":  # the rates asked before it began would follow the arm to the answer
            self._asked = None
        say_held_back(self.held_back, self.held == "velocity")

    def _solve(self) -> None:
        if self.held == "velocity":  # a click a browser cannot send while it is off
            raise ValueError(HELD_BACK)
        self._asked = parse_twist(str(self.typed.value))
        self._session.redraw()  # and the panel: the rates, there and on every change of the arm after it

    def kept(self) -> dict:
        return {} if self._asked is None else {"asked": self._asked}

    def restore(self, kept: dict) -> None:
        if self.held != "velocity":
            self._asked = kept["asked"]
            self._session.refresher.request(self._session)

    def render(self, snapshot: Snapshot) -> None:
        playing = snapshot.rates is not None and bool(np.any(snapshot.rates))  # a path playing: its own rates
        moving = playing or any(slider.value != 0.0 for slider in self.sliders)  # on every drag: no arrays while all are still
        ends = None
        if moving:
            qdot = snapshot.rates if playing else self.joint_rates()
            twist = self._arm.tool_twist(snapshot.q, qdot)
            tip = self._tool(snapshot)[:3, 3]
            ends = (tip + METRES_PER_SPEED * twist[:3], tip + self._turn_scale * twist[3:])
            for arrow, end in zip((self.linear, self.angular), ends):
                arrow.points = np.array([[tip, end]])
        self._ends = ends
        for node in (self.linear, self.angular):
            if node.visible != moving:
                node.visible = moving

    def names(self) -> list[tuple]:
        ends = self._ends or (None, None)
        return list(zip(ends, NAMES, (LINEAR_COLOR, ANGULAR_COLOR)))

    def render_panel(self, snapshot: Snapshot) -> None:
        asked = self._asked
        if self.held == "velocity":
            if self.rates.content:  # (written by a redraw under way as the challenge began)
                self.rates.content = ""
        elif asked is not None:
            rates = self._arm.joint_rates(snapshot.q, asked)
            self.rates.content = rates_markdown(rates.qdot, float(rates.damping), asked, rates.achieved,
                                                self._labels, self._kinds, self._limits, self._arm.task)
        if self.held == "tool_velocity":
            self.readout.content = HELD_BACK
            return
        qdot = self.joint_rates()
        twist = self._arm.tool_twist(snapshot.q, qdot)
        self.readout.content = (f"v = ({', '.join(number(1000 * v, '+.1f') for v in twist[:3])}) mm/s, "
                                f"|v| = {number(1000 * np.linalg.norm(twist[:3]), '.1f')} mm/s  \n"
                                f"ω = ({', '.join(number(math.degrees(w), '+.1f') for w in twist[3:])}) °/s")

    def close(self) -> None:
        """The session has gone: so do its arrows, even from a scene everyone shares."""
        for node in (self.linear, self.angular):
            node.remove()
