"""Forces and gravity, for any arm: the torques each joint must hold, as bars (docs/kinematics.md §8.3, §8.5).

A force the tool pushes with (its size in N; its direction from a list, or set by dragging
a handle that rides beside the tool) is drawn as an arrow. The panel shows, per joint,
τ = Jᵀ F for that force (N for a prismatic joint), the gravity torque of the arm and its
payload where its link masses are known, and their sum against what the joint is rated
for where that is published. The bars are drawn with the panel (≤ 10 Hz), the arrow with
the arm.
"""

from __future__ import annotations

import asyncio
import math
import threading

import numpy as np
import viser

from ur10core.dynamics import MASSES
from ur10core.specs import torque_map

from ..feedback import Beside, chosen, put_back, within
from ..serving.workers import HEAVY, FoldedRuns
from ..state import Snapshot
from ..style import (COLOUR_IS_CONTENT, DANGER_RED, SAFE_GREEN, UR10_SIZE, blend, hex_color, joint_units, number, swatch,
                     turning_and_sliding)
from ..view import HELD_BACK, Session, View, say_held_back
from ..viser_internals.fast_updates import set_positions, stop_echo
from .branch_labels import obstacle
from .workspace import POINT_SIZE, colormap

DRAGGED = "drag the handle"


def directions_for(arm) -> dict[str, tuple[float, float, float] | str | None]:
    """Where the force at the tool can point (base frame): down and up along the arm's vertical (z, or the
    desktop arm's y), the other axes both ways; None: along the tool's own z axis; DRAGGED: where the
    student dragged the handle, from the tool."""
    up = int(np.argmax(np.abs(arm.up)))
    out: dict[str, tuple[float, float, float] | str | None] = {}
    for axis in (up, *(k for k in range(3) if k != up)):
        name, unit = "xyz"[axis], np.eye(3)[axis]
        out[f"down (−{name})" if axis == up else f"−{name}"] = tuple(-unit)
        out[f"up (+{name})" if axis == up else f"+{name}"] = tuple(unit)
    return {**out, "along the tool's z": None, DRAGGED: DRAGGED}


#: How far from the tool the direction handle sits (m, for an arm 1 m across), and the gizmo's size there.
HANDLE_DISTANCE, HANDLE_SCALE = 0.35, 0.12
MAX_FORCE_N = 200.0
#: The force arrow's length per newton (m, for an arm 1 m across): the first 50 N reach a quarter of the arm's size,
#: clear of the IK target's gizmo at the same tool (at 0.002, the whole arrow lay inside it).
ARROW_METRES_PER_N = 0.005
FORCE_COLOR = (0, 114, 178)
#: The torque map's name among what the camera frames with the arm (``CameraControls.extra``).
MAP_VIEW = "torque map"
#: Joint vectors sampled for the torque map (``ur10core.specs.torque_map``): the worst of them is marked, by a red
#: ball this big (m, for an arm 1 m across).
TORQUE_MAP_POINTS = 20_000
WORST_RADIUS = 0.04


def force_vector(direction: str, newtons: float, flange: np.ndarray, dragged, directions: dict) -> np.ndarray:
    """(3,) the force in the base frame, N, pointing as ``directions[direction]`` says (:func:`directions_for`);
    ``dragged`` (3,) is the unit direction the handle was dragged to."""
    unit = directions[direction]
    if unit == DRAGGED:
        unit = dragged
    return newtons * (flange[:3, 2] if unit is None else np.array(unit))


def bars_html(force_torques: np.ndarray, gravity: np.ndarray, capacity: np.ndarray | None,
              labels: tuple[str, ...], kinds: str) -> str:
    """Per joint: a bar of |τ_force + τ_gravity| against its rated torque ``capacity`` (N·m), green to red,
    with the three numbers; without published ratings (``None``), against the largest of them in its unit. Then ‖Jᵀ F‖,
    the force's alone: what the statics exercise and the ‖τ‖ map weigh a pose by.
    ``kinds``: ``"R"``/``"P"`` per joint (a prismatic joint holds a force, in N)."""
    totals = np.asarray(force_torques) + np.asarray(gravity)
    mixed = turning_and_sliding(kinds)  # N·m and N: a bar is measured against its own kind's largest, not across units
    if capacity is not None:
        scale, rows = capacity, []
    else:
        kind_of = np.array(list(kinds))
        scale = np.array([max(float(np.abs(totals[kind_of == kind]).max()), 1e-9) for kind in kinds])
        rows = ["<div>No published ratings for this arm: each bar against the largest"
                + (" of its kind (N·m for a turning joint, N for a sliding one)" if mixed else "") + ".</div>"]
    for label, kind, f, g, total, cap in zip(labels, kinds, force_torques, gravity, totals, scale):
        unit = joint_units(kind)[1]
        share = min(abs(total) / cap, 1.0)
        colour = hex_color(blend(SAFE_GREEN, DANGER_RED, share))
        over = " <b style='color:#dc2626'>over its rating</b>" if capacity is not None and abs(total) > cap else ""
        rated = f"; rated {cap:.0f}" if capacity is not None else ""
        rows.append(
            f"<div style='margin:4px 0'><b>{label}</b> {number(total, '+.1f')} {unit} "
            f"<span style='font-size:0.85em'>(force {number(f, '+.1f')}, gravity {number(g, '+.1f')}{rated}){over}</span>"
            f"<div style='height:10px;background:#e9ecef;border-radius:4px;{COLOUR_IS_CONTENT}'>"
            f"<div class='torque-bar' style='height:10px;width:{100 * share:.1f}%;border-radius:4px;background:{colour}'>"
            "</div></div></div>")
    units = "N·m" if "P" not in kinds else "N·m and N"
    rows.append(f"<div style='margin-top:6px'><b>‖Jᵀ F‖ = {number(float(np.linalg.norm(force_torques)), '.2f')} {units}</b> "
                "for the force alone, as the ‖τ‖ map weighs each pose</div>")
    return "<div style='font-size:0.9em'>" + "".join(rows) + "</div>"


def gravity_words(arm) -> str:
    """What the folder says of the arm's weight: counted, or why not."""
    if arm.name in MASSES:
        return "plus the arm's own weight and its payload."
    return "the arm's own weight is not counted: no link masses are published for this arm, so no gravity."


class StaticsView(View):
    """The "Forces and gravity" folder and the force arrow at the tool, for any arm.

    ``root`` is where its nodes go in the scene; ``size`` (the arm's reach, m) scales the
    arrow, the handle's distance and the map's marker; ``handle_size`` (the drawing's: the reach by default) the handle.
    """

    answers = ("largest_torque", "torque", "gravity_torque")  # the map marks the pose that needs the most; the bars give τ

    def __init__(self, scene: viser.SceneApi, gui: viser.GuiApi, session: Session, root: str = "/statics",
                 size: float = 1.0, handle_size: float | None = None) -> None:
        self._session = session
        self._root, self._size = root, size
        self._handle_size = size if handle_size is None else handle_size
        arm = session.arm
        payload_kg = arm.specs.payload_kg if arm.name in MASSES else None
        folder = gui.add_folder("Forces and gravity", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            self._metres_per_n = ARROW_METRES_PER_N * size
            gui.add_markdown("The torques the joints must hold: τ = Jᵀ F for a force the tool pushes with; "
                             + gravity_words(arm) + f"  \n{swatch(FORCE_COLOR)} **F**: the arrow at the tool, "
                             f"{number(10000 * self._metres_per_n, '.0f')} mm drawn per 10 N")
            self.enabled = gui.add_checkbox("Show the torques", False)
            self.newtons = gui.add_slider("Force at the tool (N)", min=0.0, max=MAX_FORCE_N, step=5.0, initial_value=50.0)
            within(self.newtons, "force (N)")  # accepted: a first value refused puts it back here, not at 0
            self._directions = directions_for(arm)
            self.direction = gui.add_dropdown("Force direction", tuple(self._directions),
                                              initial_value=next(iter(self._directions)))
            self.payload = gui.add_slider("Payload (kg)", min=0.0, max=payload_kg or 1.0, step=0.5, initial_value=0.0,
                                          visible=payload_kg is not None)
            self.refusal = Beside(gui)  # a force or payload typed in its slider's box beyond its range
            self.bars = gui.add_html("", visible=False)
            self.mapped = gui.add_checkbox("Colour the workspace by ‖τ‖ for this force", False,
                                           hint=f"{TORQUE_MAP_POINTS:,} random joint vectors; the worst one is marked")
            self.map_refusal = Beside(gui)  # a map asked for with the force along the tool's z, which turns with the arm
            self.map_legend = gui.add_markdown("", visible=False)
            self.held_back = gui.add_markdown("", visible=False)  #: why the map is off (a class challenge)
        self.arrow = scene.add_arrows(f"{root}/force", np.zeros((1, 2, 3)), FORCE_COLOR, shaft_radius=0.012 * size,
                                      head_radius=0.03 * size, head_length=0.05 * size, visible=False)
        # the arrow's node rides at the tool: a drag moves one node, and the arrow's shape is sent again
        # only when the force itself turns or grows; its name is the session's to place (:meth:`names`)
        self._drawn_force: np.ndarray | None = None
        self._name: tuple[np.ndarray, str] | None = None  #: (the arrow's tip, its text) while it shows
        #: the direction handle: this browser's own, like the IK target
        self.handle = session.client.scene.add_transform_controls(
            f"{root}/force_handle", scale=HANDLE_SCALE * self._handle_size, disable_rotations=True, depth_test=False, visible=False)
        stop_echo(self.handle)
        self.dragged = -np.asarray(arm.up, dtype=float)  #: the unit direction the handle was last dragged to (base frame)
        self._holding = False
        #: the handle's events as they arrived, and the newest one taken: viser's pool runs them side by side
        self._handle_events = self._handle_taken = 0
        self._handle_lock = threading.Lock()
        self.handle.on_update(self._handle_dragged)
        self._scene = scene
        self._map: viser.PointCloudHandle | None = None
        self._worst: tuple[viser.IcosphereHandle, viser.LabelHandle] | None = None
        self._map_lock = threading.Lock()
        self._maps = FoldedRuns(self._draw_map)
        for widget in (self.enabled, self.newtons, self.direction, self.payload, self.mapped):
            widget.on_update(session.guard(lambda _, widget=widget: self._changed(widget), beside=self.refusal))

    def _changed(self, widget) -> None:
        # a size refused here is explained (and put back) at once, not in a redraw; the payload even where hidden
        within(self.newtons, "force (N)")
        within(self.payload, "payload (kg)")
        if widget is not self.mapped:
            self.loads(self._session.state.last)
            self._session.redraw()
        if widget is self.mapped and self.mapped.value:
            self._session.colouring_shown(self)
        if widget in (self.mapped, self.newtons, self.direction):
            self._map_again()

    def hide_colouring(self) -> None:
        self.mapped.value = False  # its callback takes the map away

    def _map_again(self) -> None:
        """The map drawn again for the newest choices, on a thread of its own; its refusal stands below its box."""
        self._maps.start("torque-map", lambda run: self._session.guard(run, beside=self.map_refusal))

    async def _handle_dragged(self, event: viser.TransformControlsEvent) -> None:
        """On viser's event loop, as the IK target's drags are: the handle's position as this event left
        it, before a redraw on another thread puts the handle back beside the tool (read later, on the
        thread pool, it was sometimes that one, and the drag was lost)."""
        position, released = np.array(self.handle.position, dtype=float), event.phase == "end"
        self._handle_events += 1
        number = self._handle_events
        asyncio.get_running_loop().run_in_executor(
            None, self._session.guard(lambda _: self._handle_moved(position, released, number)), None)

    def _handle_moved(self, position: np.ndarray, released: bool, number: int) -> None:
        """The student dragged the handle to ``position`` (the ``number``-th event): the force points from the tool
        towards it. An event older than one taken already is dropped: a drag's "start" or last "update", run after
        its "end", held the handle where it was let go (it no longer rode with the tool), or turned the force back."""
        offset = position - self._session.state.last.flange[:3, 3]
        if not np.isfinite(offset).all():
            raise ValueError("force direction: the handle's position must be finite")
        with self._handle_lock:
            if number < self._handle_taken:
                return
            self._handle_taken = number
            self._holding = not released
            scale = float(np.abs(offset).max())  # divided out first: a handle 1e300 m out overflowed the norm's squares
            if scale > 1e-3:  # on the tool itself it names no direction: keep the last one
                along = offset / scale
                self.dragged = along / np.linalg.norm(along)
        self._session.redraw()
        if not self._holding:
            self._map_again()

    def payload_kg(self) -> float:
        """The payload set here (kg) that the flange holds; 0 for an arm without link masses, which has no slider."""
        return within(self.payload, "payload (kg)") if self._session.arm.name in MASSES else 0.0

    def loads(self, snapshot: Snapshot) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(force (3,), τ of the force (n,), τ of gravity and payload (n,)) at this snapshot, from the widgets."""
        arm = self._session.arm
        force = self._force(chosen(self.direction, "force direction"), snapshot)
        gravity = np.zeros(arm.n_joints)
        if arm.name in MASSES:  # otherwise (the course's other arms): the force's torques alone
            gravity = arm.gravity_torques(snapshot.q, self.payload_kg())
        return force, arm.static_torques(snapshot.q, force), gravity

    def _force(self, direction: str, snapshot, strict: bool = True) -> np.ndarray:
        """The force; a size out of range is refused (``strict``) or, while drawing the arm, held to the range."""
        if strict:
            newtons = within(self.newtons, "force (N)")
        else:
            newtons = float(self.newtons.value)
            newtons = min(max(newtons, 0.0), MAX_FORCE_N) if math.isfinite(newtons) else 0.0
        return force_vector(direction, newtons, snapshot.flange, self.dragged, self._directions)

    def fixed_force(self) -> np.ndarray:
        """(3,) the force set in the folder, N, base frame: for a map or a search over poses, so fixed in space."""
        direction = chosen(self.direction, "force direction")
        if self._directions[direction] is None:
            raise ValueError("a force fixed in the base frame is needed: pick a direction other than the tool's z")
        return self._force(direction, self._session.state.last)

    def render(self, snapshot: Snapshot) -> None:
        direction = chosen(self.direction, "force direction")
        shown = bool(self.enabled.value) and float(self.newtons.value) > 0.0
        handled = bool(self.enabled.value) and direction == DRAGGED
        tip = snapshot.flange[:3, 3]
        if handled and not self._holding:  # the handle rides with the tool, unless the student holds it
            set_positions([self.handle], (tip + HANDLE_DISTANCE * self._size * self.dragged)[None])
        if self.handle.visible != handled:
            self.handle.visible = handled
        if shown:
            newtons = float(self.newtons.value)
            force = self._force(direction, snapshot, strict=False)
            if self._drawn_force is None or not np.array_equal(force, self._drawn_force):
                self.arrow.points = np.array([[np.zeros(3), self._metres_per_n * force]])  # the way the tool pushes
                self._drawn_force = force
            set_positions([self.arrow], tip[None])
            self._name = (tip + self._metres_per_n * force, f"F = {newtons:.0f} N")
        else:
            self._name = None
        if self.arrow.visible != shown:
            self.arrow.visible = shown

    def names(self) -> list[tuple]:
        name = self._name
        return [(None, "F", FORCE_COLOR) if name is None else (*name, FORCE_COLOR)]

    def obstacles(self) -> list[tuple]:
        """The torque map's largest ‖τ‖ at its red ball, for the placed labels to keep clear of."""
        worst = self._worst  # read once: the map's thread may clear it between two reads
        if worst is None:
            return []
        marker, name = worst
        return [obstacle(name, under=marker.position)]

    def render_panel(self, snapshot: Snapshot) -> None:
        self.bars.visible = bool(self.enabled.value)
        if self.bars.visible and self.held in ("torque", "gravity_torque"):
            self.bars.content = HELD_BACK
        elif self.bars.visible:
            _, force_torques, gravity = self.loads(snapshot)
            arm = self._session.arm
            self.bars.content = bars_html(force_torques, gravity, arm.specs.torque_ratings, arm.joint_names, arm.joint_types)

    def hold_back(self, asked: str | None) -> None:
        super().hold_back(asked)
        mapping = self.held != "largest_torque"
        self.mapped.visible = mapping
        say_held_back(self.held_back, not mapping)
        if not mapping and self.mapped.value:
            self.mapped.value = False  # its callback takes the map away

    def _draw_map(self) -> None:
        session = self._session
        shown = None
        if self.mapped.value and self.held == "largest_torque":  # a click a browser cannot send while it is off
            put_back(self.mapped, False)
            raise ValueError(HELD_BACK)
        refused = None
        if self.mapped.value and not session.closed:
            try:
                force = self.fixed_force()
            except ValueError as why:
                if self._directions[chosen(self.direction, "force direction")] is not None:
                    raise  # a size refused: the map stays
                put_back(self.mapped, False)  # the tool's z turns with the arm: no map, nor the last force's left on
                refused = why
            else:
                shown = force, HEAVY.run(session.client, lambda: torque_map(session.arm, force, TORQUE_MAP_POINTS),
                                         cancelled=lambda: session.closed)
        with self._map_lock:
            if session.closed:
                return
            self._clear_map()
            if refused is None:  # (a refusal is raised after the run its put-back asked for: it is said after this)
                self.map_refusal.clear()
            if self.held == "largest_torque":  # a class challenge began while it was drawn
                shown = None
            self.map_legend.visible = shown is not None
            camera = session.camera
            if shown is None:
                if camera is not None and MAP_VIEW in camera.extra:  # the arm alone in view again
                    camera.show_also(MAP_VIEW, None)
                if refused is not None:
                    raise refused
                return
            force, (points, norms, worst) = shown
            top = float(norms[worst]) or 1.0
            self._map = self._scene.add_point_cloud(f"{self._root}/torque_map", points.astype(np.float32), colormap(norms, top),
                                                    point_size=POINT_SIZE * self._size / UR10_SIZE, point_shape="circle")
            radius = WORST_RADIUS * self._size
            marker = self._scene.add_icosphere(f"{self._root}/worst", radius=radius, color=DANGER_RED, position=points[worst])
            unit = joint_units(session.arm.joint_types)[1]
            # standing on the ball: at its centre, the label hid its upper half
            label = self._scene.add_label(f"{self._root}/worst/label", f"largest ‖τ‖ = {top:.0f} {unit}", font_screen_scale=1.4,
                                          anchor="bottom-center", position=tuple(1.2 * radius * np.asarray(session.arm.up)))
            self._worst = (marker, label)
            if camera is not None:  # framed with the arm (a small arm's camera sat inside it), once: not on each new force
                camera.show_also(MAP_VIEW, points[:: max(1, len(points) // 2000)], session.drawing.world,
                                 now=MAP_VIEW not in camera.extra)
            self.map_legend.content = (f"Colour: ‖Jᵀ F‖ for {np.linalg.norm(force):.0f} N, from 0 (purple) to "
                                       f"{top:.0f} {unit} (yellow), the largest of {len(norms):,} random joint vectors (red ball).")
            session.refresher.request(session)  # its label sized for lecture mode, and kept clear of

    def _clear_map(self) -> None:
        if self._map is not None:
            self._map.remove()
        if self._worst is not None:
            self._worst[0].remove()  # its label goes with it
        self._map, self._worst = None, None

    def close(self) -> None:
        """The session has gone: so do its arrow and map, even from a scene everyone shares."""
        self.arrow.remove()
        self.handle.remove()
        with self._map_lock:
            self._clear_map()
        camera = self._session.camera
        if camera is not None:  # a classroom's browser keeps its camera for its next arm
            camera.show_also(MAP_VIEW, None, now=False)
