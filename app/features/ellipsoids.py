"""The manipulability ellipsoids at the tool (the UR10's flange; docs/kinematics.md §8.4).

The velocity ellipsoid (sky blue) holds the flange velocities of all joint rates of unit
norm that keep the tool's orientation; the force ellipsoid (vermilion) the forces the joints
hold with torques of unit norm. Same axes, reciprocal lengths: near a singularity that costs
the flange a direction of travel, the first flattens and the second stretches along it.
Both follow the drag, each named in 3D; their axis lengths and the scales they are drawn at are in
the panel, the force ellipsoid's scaled with the arm's reach, and smaller where it would leave the screen.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np
import viser

from ur10core.orientation import quaternion

from ..feedback import chosen
from ..state import Snapshot
from ..style import UR10_SIZE, joint_units, number, swatch, turning_and_sliding
from ..view import HELD_BACK, Session, View
from ..viser_internals.fast_updates import set_orientations, set_positions, set_scales

VELOCITY_COLOR, FORCE_COLOR = (86, 180, 233), (213, 94, 0)
#: Drawn size: metres per unit of σ (m/s per rad/s) and, at most, of 1/σ (N per N·m) on the UR10. σ grows with an
#: arm's lengths and 1/σ shrinks with them, so another arm's force ellipsoid is drawn at FORCE_METRES times the square
#: of its reach over the UR10's: at 0.05 the KR210's (1.8 N per N·m at its home) was a 9 cm speck beside a 3.9 m arm.
VELOCITY_METRES, FORCE_METRES = 0.3, 0.05
#: The force ellipsoid's longest drawn semi-axis, as a share of the arm's reach: it grows without bound
#: near a singularity, so it is drawn smaller there (at a scale the panel prints) and stays on screen.
LONGEST_SHARE = 0.35
SHOWN = {"velocity": (True, False), "force": (False, True), "both": (True, True)}


def force_scale(force: np.ndarray, reach: float) -> float:
    """Metres drawn per N per N·m for an arm of ``reach`` (m): :data:`FORCE_METRES` · (reach / UR10_SIZE)², or less,
    so that the longest semi-axis fits.

    >>> force_scale(np.array([1.0, 2.0, 4.0]), UR10_SIZE), force_scale(np.array([1.0, 2.0, 4.0]), 2 * UR10_SIZE)
    (0.05, 0.2)
    >>> round(force_scale(np.array([1.0, 2.0, 70.0]), UR10_SIZE), 4)  # 70 × 0.05 m would not fit: 0.35 × 1.3 m does
    0.0065
    """
    largest = FORCE_METRES * (reach / UR10_SIZE) ** 2
    longest = float(np.max(np.where(np.isfinite(force), force, 0.0), initial=0.0))
    return largest if longest * largest <= LONGEST_SHARE * reach else LONGEST_SHARE * reach / longest


def drawn_force_axes(force: np.ndarray, reach: float) -> np.ndarray:
    """The force ellipsoid's semi-axes as drawn (m), at :func:`force_scale`; an infinite one (a force the joints hold
    with no torque: the planar elbow's vertical) as long as the longest may be drawn. It was drawn as zero, flat
    where it is endless, and at an exact singularity the axis that grew as the arm neared it vanished.

    >>> drawn_force_axes(np.array([1.0, 2.0, np.inf]), UR10_SIZE).round(3).tolist()
    [0.05, 0.1, 0.455]
    """
    finite = np.isfinite(force)
    return np.where(finite, force_scale(force, reach) * np.where(finite, force, 0.0), LONGEST_SHARE * reach)


def key_html(joint_types: str = "RRRRRR") -> str:
    """Which colour is which ellipsoid, for the panel; on an arm with turning and sliding joints, that a norm adds
    rad/s to m/s (N·m to N), so the ellipsoids' shapes depend on those units."""
    mixed = "in rad/s and m/s alike, so its shape depends on those units" if turning_and_sliding(joint_types) else ""
    return (f"{swatch(VELOCITY_COLOR)} **velocity ellipsoid**: where joint rates of norm 1 can move the tool"
            f"{' (' + mixed + ')' if mixed else ''}  \n"
            f"{swatch(FORCE_COLOR)} **force ellipsoid**: the forces joint torques of norm 1 can hold"
            f"{' (N·m and N alike)' if mixed else ''}")


def ellipsoid_pose(axes: np.ndarray) -> np.ndarray:
    """(4,) wxyz of a rotation whose columns are the ellipsoid's axes (one flipped if they are left-handed)."""
    rotation = axes.copy()
    if np.linalg.det(rotation) < 0:
        rotation[:, 2] *= -1.0
    return quaternion(rotation, check=False)


def lengths_markdown(velocity: np.ndarray, force: np.ndarray, place: str = "tool", held: str = "the tool's orientation held",
                     scales: tuple[float, float] = (VELOCITY_METRES, FORCE_METRES), joint_types: str = "RRRRRR") -> str:
    def listed(values: np.ndarray) -> str:
        return ", ".join("∞" if not np.isfinite(v) else number(v, ".3g") for v in values)

    rate, effort = joint_units(joint_types)
    return (f"The {place}'s ellipsoids{' with ' + held if held else ''} (docs §8.4).  \n"
            f"**Velocity ellipsoid** semi-axes (m/s per {rate} of joint rate): {listed(velocity)}; "
            f"drawn at {number(1000 * scales[0], '.3g')} mm per m/s per {rate}  \n"
            f"**Force ellipsoid** semi-axes (N per {effort} of joint {'torque' if effort == 'N·m' else 'effort'}): "
            f"{listed(force)}; drawn at {number(1000 * scales[1], '.3g')} mm per N per {effort}  \n"
            "Same axes; each force axis is 1 / the velocity axis. Drag towards a singularity and watch "
            "one velocity axis shrink while its force axis grows (drawn smaller, to stay on screen)."
            + ("  \n∞: the joints hold a force along that axis with no torque at all (the structure takes it); "
               "drawn as long as the longest axis may be." if not np.isfinite(force).all() else ""))


#: What an arm keeps still for its translational ellipsoid, by what it controls (``arm.task``).
HELD = {"pose": "the tool's orientation held", "position and yaw": "the tool's yaw held", "position": ""}


class EllipsoidsView(View):
    """The "Manipulability ellipsoids" folder and the two ellipsoids at the tool.

    ``root``, ``tool`` and ``place`` as for ``ur10teach.features.velocity.VelocityView``: the arm's tool by default.
    """

    answers = ("det_j",)  # on an arm that places its tool only, the velocity semi-axes multiply to |det J|

    def __init__(self, scene: viser.SceneApi, gui: viser.GuiApi, session: Session, root: str = "/ellipsoids",
                 tool: Callable[[Any], np.ndarray] = lambda snapshot: snapshot.flange, place: str = "tool",
                 reach: float = UR10_SIZE) -> None:
        self._arm = session.arm
        self._reach = reach
        self._tool = tool
        self._place = place
        folder = gui.add_folder("Manipulability ellipsoids", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            self.enabled = gui.add_checkbox(f"Show at the {place}", False)
            self.which = gui.add_dropdown("Ellipsoid", tuple(SHOWN), initial_value="both")
            self.key = gui.add_markdown(key_html(self._arm.joint_types))
            self.lengths = gui.add_markdown("", visible=False)
        # one frame at the tool, turned to the ellipsoids' axes (they share them), so a drag moves one node;
        # in it, a unit sphere per ellipsoid scaled per axis, tiny until first sized, so it never shows a metre wide
        self.frame = scene.add_frame(root, show_axes=False)
        self.velocity = scene.add_icosphere(f"{root}/velocity", radius=1.0, color=VELOCITY_COLOR, opacity=0.35,
                                            subdivisions=3, cast_shadow=False, receive_shadow=False, visible=False,
                                            scale=(1e-4, 1e-4, 1e-4))
        self.force = scene.add_icosphere(f"{root}/force", radius=1.0, color=FORCE_COLOR, opacity=0.3,
                                         subdivisions=3, cast_shadow=False, receive_shadow=False, visible=False,
                                         scale=(1e-4, 1e-4, 1e-4))
        # each named in 3D at the end of its longest axis (colour alone does not say which is which), by the session
        self._name_points: list[np.ndarray | None] = [None, None]  #: (3,) in the drawing's frame, while it shows

        def changed(_) -> None:
            chosen(self.which, "ellipsoid")  # refuses a value that is not offered, with a message
            session.redraw()

        for widget in (self.enabled, self.which):
            widget.on_update(session.guard(changed))

    def render(self, snapshot: Snapshot) -> None:
        show_velocity, show_force = SHOWN.get(self.which.value, (False, False)) if self.enabled.value else (False, False)
        if show_velocity or show_force:
            translation = self._arm.translation_ellipsoid(snapshot.q)
            at = self._tool(snapshot)[:3, 3]
            set_orientations([self.frame], ellipsoid_pose(translation.axes)[None])
            set_positions([self.frame], at[None])
            sizes = np.maximum([VELOCITY_METRES * translation.velocity, drawn_force_axes(translation.force, self._reach)],
                               1e-4)
            shown = [show_velocity, show_force]  # sized before they show; a zero axis makes a flat disc
            set_scales([node for node, on in zip((self.velocity, self.force), shown) if on], sizes[shown])
            longest = np.argmax(sizes, axis=1)
            self._name_points = [at + translation.axes[:, k] * size[k] if on else None for k, size, on in zip(longest, sizes, shown)]
        else:
            self._name_points = [None, None]
        for node, shown in ((self.velocity, show_velocity), (self.force, show_force)):
            if node.visible != shown:
                node.visible = shown

    def names(self) -> list[tuple]:
        return list(zip(self._name_points, ("velocity", "force"), (VELOCITY_COLOR, FORCE_COLOR)))

    def render_panel(self, snapshot: Snapshot) -> None:
        self.lengths.visible = bool(self.enabled.value)
        if self.lengths.visible and self.held:
            self.lengths.content = HELD_BACK
        elif self.lengths.visible:
            translation = self._arm.translation_ellipsoid(snapshot.q)
            self.lengths.content = lengths_markdown(translation.velocity, translation.force, self._place,
                                                    HELD.get(getattr(self._arm, "task", "pose"), ""),
                                                    (VELOCITY_METRES, force_scale(translation.force, self._reach)),
                                                    self._arm.joint_types)

    def close(self) -> None:
        """The session has gone: so do its ellipsoids, even from a scene everyone shares."""
        self.frame.remove()  # and the ellipsoids in it
