"""The branch-count map: how many IK branches reach each point of a plane, for the tool's orientation.

One batch IK of 200 × 200 poses (100 × 100 for the numpy-only arms), drawn as a PNG of a few
KB lying in the plane, recomputed off the drag path (``FoldedRuns``, ``MAPS``: docs/architecture.md §3).
"""

from __future__ import annotations

import threading
from typing import Any, Callable

import numpy as np
import viser

from ur10core.orientation import quaternion
from ur10core.solvers.ur import URFamily
from ur10core.workspace import BranchCountMap, branch_count_map

from ..feedback import chosen, put_back
from ..serving.workers import MAPS, FoldedRuns
from ..state import Snapshot
from ..style import COLOUR_IS_CONTENT, REACH_COLORS, hex_color
from ..view import HELD_BACK, Session, View, say_held_back
from .branch_labels import LEADER_GREY
from .workspace import FROM_ABOVE

PLANES = {"vertical, through the base axis and the target": "vertical", "horizontal, at the target's height": "horizontal"}
RESOLUTION = 200  #: cells per side for the UR family (compiled batch IK): 40 000 poses, about 1.4 cm each
#: cells per side for the course's other arms, whose IK is numpy's alone (a KR210 map of 10 000 poses: 0.25 s)
COURSE_RESOLUTION = 100


NO_MAP = "a typed table's IK is numerical: it has no branch-count map"


def planes_of(arm) -> tuple[tuple[str, ...], str]:
    """The planes ``arm``'s map offers, and what the folder says of the one it lacks ("" if none).

    An arm that moves in one horizontal plane (the planar elbow) reaches a vertical plane along a
    line only: its map is its own plane, the horizontal one at the target's height.
    """
    if arm.planar:
        return tuple(PLANES)[1:], ("Only the horizontal plane for this arm: it moves in that plane, and a vertical "
                                   "one would meet what it reaches along a line.")
    return tuple(PLANES), ""


def legend_counts(slots: int) -> tuple[int, ...]:
    """The branch counts the legend names for an arm of ``slots`` IK slots: 2, 4, 6, 8 for the UR10; 1 … 4 for four."""
    step = max(slots // 4, 1)
    return tuple(range(step, slots + 1, step))


def map_image(counts: np.ndarray, slots: int = 8) -> np.ndarray:
    """(n, n) branch counts → (n, n, 4) RGBA: 0 faint grey, then the four REACH_COLORS in equal steps up to ``slots``
    (for the UR10, 2, 4, 6, 8; an odd count as the next even)."""
    palette = np.array([(*rgb, alpha) for rgb, alpha in REACH_COLORS], dtype=np.uint8)
    return palette[np.ceil(4 * counts.astype(int) / slots).astype(int)]


def colour_of(count: int, slots: int) -> tuple[int, int, int]:
    return REACH_COLORS[int(np.ceil(4 * count / slots))][0]


def map_pose(reach: BranchCountMap) -> tuple[np.ndarray, np.ndarray]:
    """(wxyz, position) of the image node in the arm's base frame (the node it hangs from): its x along u, its y
    along v (an image's top row is +y)."""
    rotation = np.stack([reach.u, reach.v, np.cross(reach.u, reach.v)], axis=1)
    return quaternion(rotation, check=False), np.asarray(reach.centre, dtype=float)


COLOUR_NAMES = {REACH_COLORS[1][0]: "yellow", REACH_COLORS[2][0]: "green", REACH_COLORS[3][0]: "teal", REACH_COLORS[4][0]: "purple"}


#: What of the target's orientation each point is reached with, by what the arm controls (``arm.task``).
KEPT = {"pose": "tool turned as now", "position and yaw": "tool's yaw as now", "position": ""}

#: The folder's title, by ``arm.task``: an arm that places its tool's position only has no orientation to keep.
TITLES = {"pose": "Reachable with this orientation", "position and yaw": "Reachable with this orientation",
          "position": "Reachable points"}

#: What the folder asks, by ``arm.task``: an arm that places its tool's position only has a gizmo that does not
#: turn, and a SCARA's yaw only turns its roll joint (until 2026-12-05 every arm was told "turn the gizmo and
#: watch the rings change", which changed nothing on those).
QUESTIONS = {
    "pose": "Keep the tool turned as the gizmo has it and move it anywhere in a plane: how many of the {slots} "
            "branches get there? Turn the gizmo and watch the rings change.",
    "position and yaw": "Move the tool anywhere in a plane, pointing down, with the gizmo's yaw: how many of the "
                        "{slots} branches get there? The yaw turns the last joint only, so it changes the map only "
                        "where that joint would go beyond its limits.",
    "position": "This arm places its tool's position only (its gizmo does not turn): how many of the {slots} "
                "branches reach each point of a plane through the target?",
}


def legend_text(slots: int = 8, task: str = "pose") -> str:
    """The map's label in 3D: "… yellow 2 · green 4 · teal 6 · purple 8" for the UR10, in lines that fit a
    projector's canvas in lecture mode (at the names' size: it is placed with them)."""
    names = " · ".join(f"{COLOUR_NAMES[colour_of(count, slots)]} {count}" for count in legend_counts(slots))
    kept = KEPT.get(task)
    heading = "branches reaching each point" + (f",\n{kept}" if kept else "")
    return f"{heading}:\n{names}"


def legend_html(slots: int = 8, task: str = "pose") -> str:
    entries = [("none", REACH_COLORS[0][0]), *((str(count), colour_of(count, slots)) for count in legend_counts(slots))]
    swatches = "".join(
        f"<span style='display:inline-block;margin-right:10px'><span style='display:inline-block;width:14px;height:14px;"
        f"border-radius:3px;vertical-align:middle;background:{hex_color(rgb)};{COLOUR_IS_CONTENT}'></span> {label}</span>"
        for label, rgb in entries
    )
    kept = KEPT.get(task, "")
    return f"<div style='font-size:0.85em'>Branches that reach each point{', ' + kept if kept else ''}:<br>{swatches}</div>"


class ReachMapView(View):
    """The "Reachable with this orientation" folder ("Reachable points" where the arm places a position only) and its
    map, in the session's scene (``root``).

    For any arm with a closed-form IK; a typed table's folder says why it has no map.
    ``target_of(snapshot)`` is the pose whose orientation is kept (the IK target; the desktop
    arm's tool). ``root`` hangs from the arm's base frame, in which the map is drawn; ``world`` (4, 4)
    puts that frame in the scene, for the camera.
    """

    answers = ("branch_count",)  # the map shows where each count of branches reaches

    def __init__(self, scene: viser.SceneApi, gui: viser.GuiApi, session: Session, root: str = "/reach_map",
                 target_of: Callable[[Any], np.ndarray] = lambda snapshot: snapshot.target,
                 world: np.ndarray = np.eye(4)) -> None:
        self._scene = scene
        self._session = session
        self._root = root
        self._target_of, self._world = target_of, world
        arm = session.arm
        self.resolution = RESOLUTION if isinstance(arm.solver, URFamily) else COURSE_RESOLUTION  # the kernels' speed
        self.slots = 0 if arm.numerical else int(arm.ik(arm.fk(arm.specs.home)).q.shape[-2])
        self.image: viser.ImageHandle | None = None
        #: the legend's point, the middle of the map's top edge in the drawing's frame, while a map is shown
        self.legend_at: np.ndarray | None = None
        self.legend_text = legend_text(max(self.slots, 1), arm.task)
        self.shown_key: tuple | None = None  #: (target bytes, plane) of the map on screen
        self.computed = 0  #: maps computed so far (tests and benchmarks read it)
        self._lock = threading.Lock()
        self._closed = False
        self._maps = FoldedRuns(self._draw)
        self._face_next = False  # turn the camera to face the plane once the next map is drawn
        folder = gui.add_folder(TITLES.get(arm.task, TITLES["pose"]), expand_by_default=False)
        self.folders = (folder,)
        with folder:
            self.question = gui.add_markdown(
                "A typed table's IK is numerical, from one start at a time: a map of thousands of poses would take "
                "minutes, so this arm has none. The course's arms all have one." if arm.numerical
                else QUESTIONS[arm.task].format(slots=self.slots))
            self.enabled = gui.add_checkbox("Show branch-count map", False, disabled=arm.numerical)
            planes, missing = planes_of(arm)
            self.plane = gui.add_dropdown("Plane", planes, initial_value=planes[0], hint=missing or None)
            self.legend = gui.add_html(legend_html(max(self.slots, 1), arm.task), visible=False)
            self.held_back = gui.add_markdown("", visible=False)
        self.enabled.on_update(session.guard(self._toggled))
        self.plane.on_update(session.guard(self._toggled))

    def names(self) -> list[tuple]:
        # placed with the names at the tool, not where it falls: standing where the cloud's legend stands (the
        # top of the same reach), it would be drawn over it
        return [(self.legend_at, self.legend_text, LEADER_GREY)]

    def hold_back(self, asked: str | None) -> None:
        super().hold_back(asked)
        self.enabled.visible = self.held is None
        say_held_back(self.held_back, self.held is not None)
        if self.held and self.enabled.value:
            self.enabled.value = False  # its callback takes the map away

    def _toggled(self, _: viser.GuiEvent) -> None:
        chosen(self.plane, "plane")
        why = NO_MAP if not self.slots else HELD_BACK if self.held else None
        if self.enabled.value and why:  # its checkbox is disabled or hidden: only a made-up message gets here
            put_back(self.enabled, False)  # refused once, not again at every redraw of the panel
            raise ValueError(why)
        self.legend.visible = self.enabled.value
        if self.enabled.value:
            self._face_next = True
            self._request()
        else:
            self.clear()

    def render_panel(self, snapshot: Snapshot) -> None:
        # a plane not among the options is refused by the dropdown's own callback; meanwhile nothing to do
        plane = PLANES.get(self.plane.value)
        if self.enabled.value and plane is not None and (self._target_of(snapshot).tobytes(), plane) != self.shown_key:
            self._request()

    def _key(self, snapshot: Snapshot) -> tuple:
        return self._target_of(snapshot).tobytes(), PLANES[chosen(self.plane, "plane")]

    def _request(self) -> None:
        """Compute the map for the newest target, in a worker thread of this view."""
        with self._lock:
            if self._closed:
                return
        self._maps.start("reach-map", self._session.guard)

    def _draw(self) -> None:
        snapshot = self._session.state.last
        key = self._key(snapshot)
        if not self.enabled.value or self.held or key == self.shown_key:
            return
        if not self.slots:
            raise ValueError(NO_MAP)
        reach = MAPS.run(self._session.client,
                         lambda: branch_count_map(self._session.arm, self._target_of(snapshot), key[1], self.resolution),
                         cancelled=lambda: self._closed or self._session.closed)
        self.computed += 1
        image, (wxyz, position) = map_image(reach.counts, self.slots), map_pose(reach)
        with self._lock:
            if self._closed or not self.enabled.value or self.held:  # gone, off, or a class challenge began meanwhile
                return
            if self.image is None:
                self.image = self._scene.add_image(
                    self._root, image, reach.size, reach.size, format="png", wxyz=wxyz, position=position,
                    cast_shadow=False, receive_shadow=False)
            else:
                self.image.image = image
                if not np.allclose(self.image.position, position) or not np.allclose(self.image.wxyz, wxyz):
                    self.image.wxyz, self.image.position = wxyz, position
            before, self.legend_at = self.legend_at, reach.centre + reach.size / 2 * reach.v
            moved = before is None or not np.allclose(before, self.legend_at)
            self.shown_key = key
        if moved:
            self._session.refresher.request(self._session)  # the legend placed where the map now is
        if self._face_next:
            self._face_next = False
            self._face(reach)
            if self._closed:  # it left as it was framed: the camera (a classroom's outlives the arm) frames it no more
                self.clear()

    def _face(self, reach: BranchCountMap) -> None:
        """Turn the camera square-on to the plane, framing the part of it that some branch reaches."""
        camera = self._session.camera
        if camera is None:
            return
        turn, shift = self._world[:3, :3], self._world[:3, 3]
        reached = reach.points()[reach.counts > 0] @ turn.T + shift
        if (turn @ reach.v)[2] > 0.5:  # vertical: from the side of the plane the camera is on
            normal = turn @ np.cross(reach.u, reach.v)
            side = np.sign(normal @ (np.asarray(self._session.client.camera.position) - (turn @ reach.centre + shift))) or 1.0
            direction = side * normal
        else:
            direction = FROM_ABOVE
        camera.extra["reach map"] = reached[:: max(1, len(reached) // 2000)]
        camera.look_from(direction)

    def clear(self) -> None:
        with self._lock:
            if self.image is not None:
                self.image.remove()
                self.image = self.legend_at = None
                self._session.refresher.request(self._session)  # and its legend taken away
            self.shown_key = None
        camera = getattr(self._session, "camera", None)
        if camera is not None:
            camera.extra.pop("reach map", None)

    def close(self) -> None:
        with self._lock:
            self._closed = True
        self.clear()
