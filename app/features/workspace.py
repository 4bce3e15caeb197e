"""The workspace point cloud, coloured by manipulability |det J|, with a section and its revolved hull.

Sampled off the event loop as a slow job (docs/architecture.md §3) and kept in :data:`CLOUDS`,
whose memory is a fixed budget: 200 k points (the default) are about 1.8 MB per browser.
"""

from __future__ import annotations

import collections
import math
import threading

import numpy as np
import viser

from ur10core import Arm
from ur10core.workspace import base_turn, heights_above_floor, revolved_boundary, turnable_into, vertical_section

from ..feedback import Beside, chosen, within
from ..serving.workers import HEAVY, FoldedRuns
from ..style import COLOUR_IS_CONTENT, UR10_SIZE, hex_color
from ..view import Session, View
from .camera import views_for

SAMPLE_COUNTS = {"10 k": 10_000, "50 k": 50_000, "100 k": 100_000, "200 k": 200_000, "500 k": 500_000, "1 M": 1_000_000}
DEFAULT_COUNT = "200 k"
SECTIONS = ("whole cloud", "vertical section (side view)", "horizontal section (top view)",
            "cut-away (the half behind the arm's plane)", "translucent hull (its outer and inner surfaces)")
HULL = SECTIONS[4]
HULL_COLOR = (86, 180, 233)  # Okabe-Ito sky blue: apart from the grey arm and the aluminium links
HULL_OPACITY = 0.22
HULL_SEGMENTS = 72
#: The cloud's dots (m) on the UR10's drawing; they grow with another arm's.
POINT_SIZE = 0.006
#: Points in a section: sampled in its plane, they cover it densely at this many.
SECTION_POINTS = 40_000
#: Where the camera looks from for a horizontal section: straight down (a hair off, so the orbit keeps z up).
FROM_ABOVE = (0.0, -0.02, 1.0)
#: Viridis, sampled at 9 stops: dark = near-singular (low |det J|), yellow = dexterous.
VIRIDIS = np.array(
    [(68, 1, 84), (71, 44, 122), (59, 81, 139), (44, 113, 142), (33, 144, 141),
     (39, 173, 129), (92, 200, 99), (170, 220, 50), (253, 231, 37)], dtype=float,
)


def colormap(values: np.ndarray, top: float) -> np.ndarray:
    """Viridis colours (n, 3) uint8 for ``values`` in [0, top]."""
    t = np.clip(values / top, 0.0, 1.0) * (len(VIRIDIS) - 1)
    low = np.minimum(t.astype(int), len(VIRIDIS) - 2)
    frac = (t - low)[:, None]
    return ((1 - frac) * VIRIDIS[low] + frac * VIRIDIS[low + 1]).astype(np.uint8)


#: Bytes of clouds and sections kept for every client (a 1 M cloud is 15 MB).
CLOUD_BUDGET_BYTES = 64 * 2**20


class KeptClouds:
    """Clouds by what they were made from, the least recently used forgotten beyond ``budget`` bytes.

    A browser showing a cloud *holds* the values it was drawn from (``holder``, until
    :meth:`release`); :meth:`forget_unheld`, called once browsers have left, forgets the
    rest, so that the server's memory goes back to where it was.
    """

    def __init__(self, budget: int = CLOUD_BUDGET_BYTES) -> None:
        self.budget = budget
        self._kept: collections.OrderedDict[tuple, tuple] = collections.OrderedDict()
        self._held: dict[int, set[tuple]] = {}  #: id(holder) → the keys it shows
        self._lock = threading.Lock()

    @property
    def nbytes(self) -> int:
        with self._lock:
            return sum(_nbytes(value) for value in self._kept.values())

    def get(self, key: tuple, make, holder: object | None = None):
        """The kept value for ``key``, or ``make()`` (called outside the lock), kept within the budget."""
        with self._lock:
            if key in self._kept:
                self._kept.move_to_end(key)
                if holder is not None:
                    self._held.setdefault(id(holder), set()).add(key)
                return self._kept[key]
        value = make()
        with self._lock:
            if holder is not None:
                self._held.setdefault(id(holder), set()).add(key)
            self._kept[key] = value
            total = sum(_nbytes(kept) for kept in self._kept.values())
            while total > self.budget and len(self._kept) > 1:
                total -= _nbytes(self._kept.popitem(last=False)[1])
        return value

    def release(self, holder: object) -> None:
        """``holder`` no longer shows what it asked for."""
        with self._lock:
            self._held.pop(id(holder), None)

    def forget_unheld(self) -> None:
        """Forget every value no holder shows."""
        with self._lock:
            held = set().union(*self._held.values())
            for key in [key for key in self._kept if key not in held]:
                del self._kept[key]


def _nbytes(value: tuple) -> int:
    return sum(part.nbytes for part in value if isinstance(part, np.ndarray))


CLOUDS = KeptClouds()


def coloured_cloud(arm: Arm, n: int, compute=lambda make: make(),
                   holder: object | None = None) -> tuple[np.ndarray, np.ndarray, float, np.ndarray | None]:
    """(points (n, 3) float32, colours (n, 3) uint8, colour-scale top in m³, and each point's θ1 (n,) where θ1
    turns less than a full turn, for its side view (``ur10core.workspace.vertical_section``), else None), shared
    by all clients.

    ``compute(make)`` runs ``make`` when the cloud is not kept (a session passes its slow-job runner);
    ``holder`` shows it (:class:`KeptClouds`).
    """

    def make():
        partial = _turn_range(arm) is not None  # (the joints kept only then: the UR10's million samples need none)
        points, manipulability, *joints = arm.sample_workspace(n, seed=0, return_joints=partial)
        top = float(np.percentile(manipulability, 99)) or 1.0  # an arm whose measure is zero almost everywhere
        turns = joints[0][:, 0].astype(np.float32) if partial else None
        return points.astype(np.float32), colormap(manipulability, top), top, turns

    return CLOUDS.get(("cloud", arm, n), lambda: compute(make), holder)


def coloured_horizontal_section(arm: Arm, height: float, n: int, top: float, compute=lambda make: make(),
                                holder: object | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(points (n, 3) float32 in the plane z = height, colours on the whole cloud's scale ``top``)."""

    def make():
        points, manipulability = arm.sample_horizontal_section(height, n, seed=0)
        return points.astype(np.float32), colormap(manipulability, top)

    return CLOUDS.get(("horizontal", arm, height, n, top), lambda: compute(make), holder)


def revolved_mesh(heights: np.ndarray, inner: np.ndarray, outer: np.ndarray,
                  segments: int = HULL_SEGMENTS) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (V, 3) float32, faces (F, 3) uint32): the profile turned about z, closed top and bottom.

    Rings k = 0…m−1 of the outer surface, then of the inner; quads between neighbouring
    rings, and an annulus from the inner to the outer ring at each end.
    """
    m = len(heights)
    angle = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    ring = np.stack([np.cos(angle), np.sin(angle)], axis=1)
    rings = [np.column_stack([radius * ring, np.full(segments, z)])
             for radii in (outer, inner) for radius, z in zip(radii, heights)]
    vertices = np.vstack(rings).astype(np.float32)
    j, k = np.meshgrid(np.arange(segments), np.arange(m - 1))
    j, k = j.ravel(), k.ravel()
    nxt = (j + 1) % segments

    def band(first_ring: np.ndarray, second_ring: np.ndarray) -> np.ndarray:
        a, b = first_ring * segments + j, first_ring * segments + nxt
        c, d = second_ring * segments + j, second_ring * segments + nxt
        return np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])

    faces = [band(k, k + 1), band(m + k + 1, m + k)]  # outer facing out, inner facing the axis
    j, nxt = np.arange(segments), (np.arange(segments) + 1) % segments
    k = np.zeros(segments, int)
    faces += [band(m + k, k), band(k + m - 1, k + 2 * m - 1)]  # bottom and top annuli
    return vertices, np.vstack(faces).astype(np.uint32)


#: What the hull is, and no more: between its surfaces a KR210 has pockets it cannot reach (56 mm wide at 2.3 m up).
HULL_LEGEND = ("the workspace's outline turned about the base axis:\nat each height, as far out as the flange\n"
               "reaches and as near the axis as it gets")


def manipulability_unit(arm: Arm) -> str:
    """|det J| of six revolute joints is in m³ (three rows of metres); other arms' measures mix units."""
    return " m³" if arm.joint_types == "RRRRRR" else ""


def legend_text(top: float, unit: str = " m³") -> str:
    """The legend beside the cloud in 3D, for everyone who sees the cloud (viewers included), in two lines that
    fit a projector's canvas in lecture mode."""
    return f"colour = manipulability |det J|:\ndark violet 0 (singular) … yellow ≥ {top:.3f}{unit}"


def legend_html(top: float, unit: str = " m³") -> str:
    stops = ", ".join(hex_color(tuple(int(c) for c in rgb)) for rgb in VIRIDIS)
    return (
        "<div style='font-size:0.85em'>Colour = manipulability |det J|"
        f"<div style='height:12px;border-radius:3px;margin:4px 0;background:linear-gradient(to right, {stops});"
        f"{COLOUR_IS_CONTENT}'></div>"
        "<div style='display:flex;justify-content:space-between'><span>0 (singular)</span>"
        f"<span>≥ {top:.4f}{unit}</span></div></div>"
    )


#: The room framed over the cloud's legend for its lines, as a share of the cloud's height.
LEGEND_ROOM = 0.15


def above(points: np.ndarray, up) -> np.ndarray:
    """(3,) where a cloud's legend goes: on the base axis, 12 cm over the highest of ``points`` (n, 3) along ``up``
    (the arm's vertical, ``Arm.up``: the desktop arm's is its y).

    >>> above(np.array([[0.3, 0.0, 1.0], [0.0, 2.0, 0.5]]), (0.0, 1.0, 0.0)).tolist()
    [0.0, 2.12, 0.0]
    """
    up = np.asarray(up, dtype=float)
    return up * (float((points @ up).max()) + 0.12)


def _turn_range(arm: Arm) -> tuple[float, float] | None:
    """``ur10core.workspace.base_turn``, None also where θ1 does not turn the arm about its vertical (no side view then)."""
    try:
        return base_turn(arm)
    except ValueError:
        return None


def section_heights(arm: Arm) -> tuple[float, float]:
    """The section height slider's range (mm above the floor): the heights the tool reaches (``Arm.tool_heights``), on
    the slider's 10 mm steps within them, so that every height on it has a section."""
    lowest, highest = (1000.0 * v for v in arm.tool_heights)
    low = 10.0 * math.ceil(lowest / 10.0 - 1e-9)
    return low, max(10.0 * math.floor(highest / 10.0 + 1e-9), low + 10.0)  # (a slider needs some range)


def sections_of(arm: Arm) -> tuple[tuple[str, ...], str]:
    """The sections ``arm``'s cloud offers, and what the folder says of those it lacks ("" if none).

    A horizontal section needs a tool that moves up and down (``Arm.tool_heights``). The side view and the hull turn
    the cloud about the base axis by θ1: the hull a full turn, so it needs a workspace that is a solid of revolution,
    and some height. The axis is the arm's vertical (``Arm.up``: the desktop arm's y).
    """
    sections, missing = list(SECTIONS), []
    lowest, highest = arm.tool_heights
    if highest - lowest < 1e-9:
        sections.remove(SECTIONS[2])
        missing.append(f"No horizontal section: the tool stays {1000 * lowest:.0f} mm above the floor, so the whole "
                       f"cloud is already its top view.")
    try:
        turn = base_turn(arm)
    except ValueError as why:
        sections.remove(SECTIONS[1])
        sections.remove(HULL)
        missing.append(f"No side view and no hull: they turn the cloud about the base axis by θ1, and {why}.")
    else:
        if turn is not None:
            sections.remove(HULL)
            low, high = (math.degrees(v) for v in turn)
            missing.append(f"No hull: it turns the cloud's outline a full turn about the base axis, and θ1 turns from "
                           f"{low:g}° to {high:g}° only, so it would take in places the tool never reaches. The side "
                           f"view keeps only the points θ1 can turn into its plane.")
        elif arm.planar:
            sections.remove(HULL)
            missing.append("No hull: the tool moves in one horizontal plane, so the workspace has no height to bound.")
    return tuple(sections), " ".join(missing)


class WorkspaceView(View):
    """The "Workspace" folder and the cloud it draws (in the session's scene: the classroom's, for a presenter).

    A cloud takes a moment; widget changes that come meanwhile are folded into one more
    computation with the newest choices, however many there were, so one student moving
    the section slider costs at most one cloud in the making and one waiting.
    """

    def __init__(self, scene: viser.SceneApi, gui: viser.GuiApi, session: Session, root: str = "",
                 size: float = UR10_SIZE) -> None:
        self._scene = scene
        self._session = session
        self._root = root  #: the cloud is ``{root}/workspace``: a classroom explorer's arm has a root of its own
        self._point_size = POINT_SIZE * size / UR10_SIZE  # ``size``: the drawing's; a 3.9 m arm's cloud looks the UR10's
        self._unit = manipulability_unit(session.arm)
        self._cloud: viser.PointCloudHandle | None = None
        self.legend_label: viser.LabelHandle | None = None
        self._lock = threading.Lock()
        self._closed = False
        self._clouds = FoldedRuns(self._update_or_explain)
        folder = gui.add_folder("Workspace", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            self.enabled = gui.add_checkbox("Show workspace cloud", False)
            self.count = gui.add_dropdown("Samples", tuple(SAMPLE_COUNTS), initial_value=DEFAULT_COUNT,
                                          hint="Every client downloads its cloud: about 9 bytes per point")
            sections, missing = sections_of(session.arm)
            self.section = gui.add_dropdown("Section", sections, initial_value=SECTIONS[0], hint=missing or None)
            # (said in the folder too: a projector's audience cannot hover over a tooltip)
            self.sections_missing = gui.add_markdown(missing, visible=bool(missing))
            low, high = section_heights(session.arm)
            self.height = gui.add_slider(
                "Section height (mm)", min=low, max=high, step=10.0, initial_value=10.0 * round((low + high) / 20.0),
                visible=False, hint=f"Above the floor: from {low:g} to {high:g} mm, the heights the tool reaches in a "
                                    f"cloud of 20 000")
            within(self.height, "section height (mm)")  # accepted: a first value refused puts it back here, not at 0
            self.through_tool = gui.add_button("Section through the tool", visible=False,
                                               hint="The section at the tool's height (to 10 mm): the tool lies in it")
            self.refusal = Beside(gui)  # a height beyond the slider's range or the flange's reach, an empty section
            self.progress = gui.add_progress_bar(0.0, animated=True, visible=False)
            self.legend = gui.add_html("", visible=False)
        for widget in (self.enabled, self.count, self.section, self.height):
            widget.on_update(session.guard(self._changed, beside=self.refusal))
        self.through_tool.on_click(session.guard(self._through_tool, beside=self.refusal))

    def obstacles(self) -> list:
        legend = self.legend_label  # over the cloud, in the drawing's frame
        return [] if legend is None else [legend]

    def _changed(self, event: viser.GuiEvent) -> None:
        within(self.height, "section height (mm)")  # refused as it comes, shown or not
        if event.target is self.enabled and self.enabled.value:
            self._session.colouring_shown(self)
        # a run under way picks up the newest choices; what it refuses is said below the inputs
        self._clouds.start("workspace", lambda run: self._session.guard(run, beside=self.refusal))

    def _through_tool(self, _event: viser.GuiEvent) -> None:
        """The slider to the tool's height above the floor (the desktop arm's along its y), which draws that section."""
        tool = self._session.state.last.flange[:3, 3]
        height = 10.0 * round(100.0 * float(heights_above_floor(self._session.arm, tool)))  # mm, on the slider's steps
        if not self.height.min <= height <= self.height.max:
            raise ValueError(f"the tool is {height:.0f} mm above the floor, beyond the heights the slider spans "
                             f"({self.height.min:g} to {self.height.max:g} mm)")
        self.height.value = height  # (its callback draws the section)

    def hide_colouring(self) -> None:
        self.enabled.value = False  # its callback takes the cloud away

    def _slow_job(self, make):
        session = self._session
        return HEAVY.run(session.client, make, cancelled=lambda: session.closed)

    def _update_or_explain(self) -> None:
        try:
            self._update()
        except ValueError as error:
            if not self._clouds.waiting:
                raise  # the browser is told why (a section height nobody reaches, say)
            self.refusal.say(str(error))  # and the newer choice waiting is drawn

    def _update(self) -> None:
        section = chosen(self.section, "section")
        count = SAMPLE_COUNTS[chosen(self.count, "samples")]
        self.height.visible = self.through_tool.visible = section == SECTIONS[2]
        if not self.enabled.value:
            self.clear()
            self.legend.visible = False
            return
        self.progress.value = 5.0
        self.progress.visible = True
        CLOUDS.release(self)  # what it showed until now; it holds what it is about to draw
        try:
            points, colors, top, turns = coloured_cloud(self._session.arm, count, self._slow_job, holder=self)
            self.progress.value = 60.0
            if section == HULL:
                vertices, faces = revolved_mesh(*revolved_boundary(points))
            else:
                points, colors = self._section(section, points, colors, top, turns)
                if not len(points):  # (a typed arm of zero lengths, all on the base axis)
                    raise ValueError(f"the {section} holds no point of this arm's workspace")
            legend_at = above(points, self._session.arm.up)
            with self._lock:
                if self._closed:  # it left while its cloud was made
                    return
                if self._cloud is not None:
                    self._cloud.remove()
                if section == HULL:  # faint, both faces drawn: the arm and the hole show through it
                    self._cloud = self._scene.add_mesh_simple(
                        f"{self._root}/workspace", vertices, faces, color=HULL_COLOR, opacity=HULL_OPACITY, side="double",
                        cast_shadow=False, receive_shadow=False)
                else:
                    self._cloud = self._scene.add_point_cloud(
                        f"{self._root}/workspace", points, colors, point_size=self._point_size, point_shape="circle"
                    )
                # above the cloud, in the same scene: it goes with the cloud and reaches every viewer
                self.legend_label = self._scene.add_label(
                    f"{self._root}/workspace/legend", HULL_LEGEND if section == HULL else legend_text(top, self._unit),
                    position=legend_at, font_screen_scale=1.3, anchor="bottom-center",
                )
            self.legend.content = HULL_LEGEND if section == HULL else legend_html(top, self._unit)
            self.legend.visible = True
            self._look_square_on(section, points, legend_at)
            if self._closed:  # it left as it was framed: the camera (a classroom's outlives the arm) frames it no more
                self.clear()
            self._session.refresher.request(self._session)  # the new legend sized for lecture mode, and kept clear of
        finally:
            if self._closed:  # it left while its cloud was made: it holds none
                CLOUDS.release(self)
            self.progress.value = 100.0
            self.progress.visible = False

    def _section(self, section: str, points: np.ndarray, colors: np.ndarray, top: float,
                 turns: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        if section == SECTIONS[1]:
            azimuth = float(self._session.state.last.q[0])  # the plane the arm moves in
            upright = self._session.arm.upright  # (the section turns points about the arm's vertical, there its z)
            standing = points @ upright.T
            turned = (vertical_section(standing, azimuth) @ upright).astype(np.float32)
            if turns is None:
                return turned, colors
            kept = turnable_into(standing, azimuth, turns, _turn_range(self._session.arm))
            return turned[kept], colors[kept]
        if section == SECTIONS[2]:  # sampled in the plane itself: a slab of the cloud holds only a few hundred
            return coloured_horizontal_section(self._session.arm, within(self.height, "section height (mm)") / 1000.0,
                                               min(SECTION_POINTS, len(points)), top, self._slow_job, holder=self)
        if section == SECTIONS[3]:  # the cut face shows the inside: the hole about the base axis, the dexterous core
            behind = points @ self._plane_normal() < 0
            return points[behind], colors[behind]
        return points, colors

    def _plane_normal(self) -> np.ndarray:
        """The horizontal normal of the vertical plane the arm moves in (through the base axis, at θ1), in the arm's
        base frame."""
        azimuth = float(self._session.state.last.q[0])
        return self._session.arm.upright.T @ np.array([-math.sin(azimuth), math.cos(azimuth), 0.0])

    def _look_square_on(self, section: str, points: np.ndarray, legend_at: np.ndarray) -> None:
        """The cloud is framed with the arm and its legend; a section is seen square-on (the camera turns to face its plane)."""
        camera = self._session.camera
        if camera is None:
            return
        up = np.asarray(self._session.arm.up)
        legend = legend_at + LEGEND_ROOM * float(np.ptp(points @ up)) * up  # its lines stand over its anchor
        camera.show_also("cloud", np.vstack([points[:: max(1, len(points) // 2000)], legend]), self._session.drawing.world,
                         now=False)
        if section == SECTIONS[0]:
            camera.frame()
            return
        facing = self._session.drawing.world[:3, :3] @ self._plane_normal()  # the arm's plane's normal, in the world
        if section == HULL:  # the whole of it in view, from the course's three-quarter angle
            direction = views_for(self._session.arm)["Course figure"]
        elif section == SECTIONS[1]:
            direction = -facing
        elif section == SECTIONS[3]:
            direction = facing  # from the open side, onto the cut face
        else:
            direction = FROM_ABOVE
        camera.look_from(direction)

    def clear(self) -> None:
        """Take the cloud out of the scene (toggled off), and out of the camera's framing."""
        CLOUDS.release(self)
        with self._lock:
            if self._cloud is not None:
                self._cloud.remove()  # and the legend under it
                self._cloud = self.legend_label = None
        camera = getattr(self._session, "camera", None)
        if camera is not None and "cloud" in camera.extra:  # framed again without it (a classroom's camera outlives the arm)
            camera.show_also("cloud", None, now=not self._closed)

    def close(self) -> None:
        """The session has gone: its cloud goes too, even from a scene everyone shares."""
        with self._lock:
            self._closed = True
        self.clear()
