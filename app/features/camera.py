"""The "View" folder: frame what is drawn in the part of the window the panel leaves, the standard views, lecture mode,
the light view.

The panel is docked at the right edge (``main_panel.dock_right``), so the 3D canvas is
the window minus the panel and nothing of the arm hides under it. The camera frames the
arm, its ghosts, its target and whatever else is shown (a cloud, a path) in that canvas,
from the direction the student chose: when the canvas changes size, on "Frame the arm",
and after a change that moves the arm far (a singularity button, a typed target, a path).
In a window narrower than 36 em (a phone held upright, a laptop's window beside another) viser lays the panel over
the canvas's lower part instead: the arm is framed above it.
"""

from __future__ import annotations

import dataclasses
import threading
from typing import Callable

import numpy as np
import viser

from ur10core import Arm
from ur10core.orientation import from_frame

from ..feedback import chosen, notify
from ..state import Snapshot
from ..view import View
from .branch_labels import DEFAULT_VIEW, ScreenView, screen_view
from .lecture import LectureMode
from .light_view import LightView

#: Where each view looks from (a direction from the arm towards the camera; z is up).
VIEWS = {
    "Course figure": (1.9, -1.9, 0.9),  # the three-quarter view of the course's drawings
    "Front (x–z plane)": (0.0, -1.0, 0.0),
    "Side (y–z plane)": (1.0, 0.0, 0.0),
    "Top (x–y plane)": (0.0, -0.02, 1.0),  # a hair off vertical: the orbit keeps z up
}
#: The views' names for an arm whose vertical is its y axis (the desktop arm, drawn with its y turned to the world's
#: z): the planes they show in the arm's own axes, which its frame's names in 3D give (they named the world's).
Y_UP_NAMES = {"Front (x–z plane)": "Front (x–y plane)", "Top (x–y plane)": "Top (x–z plane)"}
#: Each renamed view's name in the other naming: a view picked as the arm shown turned its vertical (a class's
#: presenter switched to or from the desktop arm) is that view in the new names.
RENAMED = {**Y_UP_NAMES, **{y_up: z_up for z_up, y_up in Y_UP_NAMES.items()}}


#: The course figure's view of an arm that moves in one horizontal plane (``Arm.planar``): 45° above it. From the
#: three-quarter view, 18° above its plane, a student saw its links nearly edge-on; from straight above, its joints'
#: z axes, which its DH frames are about, point at the camera.
PLANAR_FIGURE = (1.2, -1.2, 1.7)


def views_for(arm) -> dict[str, tuple[float, float, float]]:
    """:data:`VIEWS` for ``arm``: named in its own axes (its vertical is ``Arm.up``), and the course figure
    seen from higher up for an arm that moves in one horizontal plane (:data:`PLANAR_FIGURE`).

    >>> from ur10core import Arm
    >>> list(views_for(Arm.preset("three_dof")))[1:]
    ['Front (x–y plane)', 'Side (y–z plane)', 'Top (x–z plane)']
    >>> views_for(Arm.preset("planar_elbow"))["Course figure"] == PLANAR_FIGURE
    True
    """
    names = Y_UP_NAMES if tuple(arm.up) == (0.0, 1.0, 0.0) else {}
    views = {names.get(name, name): direction for name, direction in VIEWS.items()}
    if arm.planar:
        views["Course figure"] = PLANAR_FIGURE
    return views


#: Room kept around each joint (the link bodies are up to ~9 cm thick) and at the canvas edges.
BODY_RADIUS = 0.1
EDGE_MARGIN = 0.08
#: (position, look-at) viser's page puts its camera back to as its 3D view mounts: the server's initial camera, or
#: viser's own before that has arrived. A phone's page mounts it late, at times after the first framing has arrived,
#: which it then undid; no orbit of a student's lands on one exactly, so a camera found there is framed again.
RESET_POSES = ((DEFAULT_VIEW.position, DEFAULT_VIEW.look_at), ((3.0, 3.0, 3.0), (0.0, 0.0, 0.0)))
#: Canvas sizes whose shapes (width / height) differ by less than this share frame alike. viser draws fewer pixels
#: while its frame rate is low (its adaptive DPR: 1, 0.875 or 0.75 of the screen's), each side rounded: the same
#: canvas then reports another size, mid-orbit on a laptop without a graphics driver, and a framing depends on the
#: shape alone.
SAME_SHAPE = 0.01
#: The share of a narrow window's canvas its panel leaves uncovered: in a window narrower than 36 em (576 px: a phone
#: held upright) viser shows the panel as a sheet over the canvas's lower part, up to 60 % of its height.
SHEET_UNCOVERED = 0.4


def same_shape(size: tuple[int, int], other: tuple[int, int] | None) -> bool:
    """Canvases of ``size`` and ``other`` (width, height) px frame alike (:data:`SAME_SHAPE`).

    >>> same_shape((946, 800), (709, 600)), same_shape((1280, 800), (1000, 700)), same_shape((946, 800), None)
    (True, False, False)
    """
    return other is not None and abs(size[0] * other[1] - other[0] * size[1]) <= SAME_SHAPE * other[0] * size[1]


def framing(points: np.ndarray, direction, fov: float, aspect: float, margin: float = EDGE_MARGIN,
            top: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(camera position, look-at point) that show every one of ``points`` (n, 3) in the canvas.

    The camera looks at the points' bounding-box centre from ``direction``, with z up,
    vertical field of view ``fov`` (rad) and ``aspect`` = width / height, and stands just
    far enough back that each point is inside the canvas by ``margin`` of its half-size.
    With ``top`` < 1 the points are framed in that share of the canvas's height from its top
    (a phone's panel covers the rest): camera and look-at sink together, as little as puts every
    point, near or far, in that band.

    >>> position, look_at = framing(np.array([[1.0, 0, 0], [-1.0, 0, 0]]), (0, -1, 0), np.radians(90), 1.0, margin=0.0)
    >>> position.round(6).tolist(), look_at.tolist()
    ([0.0, -1.0, 0.0], [0.0, 0.0, 0.0])
    >>> position, look_at = framing(np.array([[0, 0, 1.0], [0, 0, -1.0]]), (0, -1, 0), np.radians(90), 1.0, margin=0.0, top=0.5)
    >>> position.round(6).tolist(), look_at.round(6).tolist()  # 2 back, the canvas spans z -2..2 about its middle
    ([0.0, -2.0, -1.0], [0.0, 0.0, -1.0])
    """
    points = np.asarray(points, dtype=float)
    back = np.asarray(direction, dtype=float)
    back = back / np.linalg.norm(back)
    forward = -back
    right = np.cross(forward, (0.0, 0.0, 1.0))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    centre = (points.min(axis=0) + points.max(axis=0)) / 2
    relative = points - centre
    x, y, depth = relative @ right, relative @ up, relative @ forward
    tan_half = np.tan(fov / 2)
    tan_v, tan_h = tan_half * (1 - margin), tan_half * aspect * (1 - margin)
    # a point at depth d beyond the centre is seen at x / (distance + d): solve for the distance
    distance = max(float(np.max(np.abs(x) / tan_h - depth)), float(np.max(-depth)) + 0.05)  # never inside the arm
    if top >= 1:
        distance = max(distance, float(np.max(np.abs(y) / tan_v - depth)))
        return centre + distance * back, centre
    # sunk by s, a point is in the band when low ≤ (y + s) / (distance + d) ≤ high: the least distance that leaves
    # room for an s, then the s in the middle of that room
    high, low = tan_half * (1 - margin * top), tan_half * (1 - 2 * top + margin * top)
    distance = max(distance, float(np.max(low * depth - y) - np.min(high * depth - y)) / (high - low))
    sink = (np.max(low * (distance + depth) - y) + np.min(high * (distance + depth) - y)) / 2
    look_at = centre - sink * up
    return look_at + distance * back, look_at


def framed_view(points: np.ndarray, direction=VIEWS["Course figure"]) -> ScreenView:
    """The camera a browser has once it frames ``points`` from ``direction`` (:func:`framing`), on the
    smallest canvas a class looks at: what a scene everyone shares places its 3D labels apart for."""
    view = DEFAULT_VIEW
    position, look_at = framing(points, direction, view.fov, view.width / view.height)
    return ScreenView(tuple(position), tuple(look_at), fov=view.fov, height=view.height, width=view.width)


class ClassView:
    """:func:`framed_view` of a drawing's arm at its state's newest snapshot, worked out once per change (its
    label pools each ask for it): the camera a browser watching a shared scene frames it with."""

    def __init__(self, drawing, state) -> None:
        self._drawing, self._state = drawing, state
        self._for: tuple = (None, DEFAULT_VIEW)  #: (snapshot, its view)

    def __call__(self) -> ScreenView:
        snapshot, view = self._for
        if snapshot is not self._state.last:
            snapshot = self._state.last
            view = framed_view(arm_points(self._drawing.framed(snapshot), self._drawing.body_radius),
                               views_for(self._state.arm)["Course figure"])
            self._for = (snapshot, view)
        return view


def arm_points(snapshot: Snapshot, body_radius: float = BODY_RADIUS) -> np.ndarray:
    """What the camera must show: the joints, every branch's joints (the ghosts) and the target,
    each with ``body_radius`` of room around it."""
    solution = getattr(snapshot, "solution", None)
    ghosts = snapshot.ghost_frames[solution.valid, :, :3, 3].reshape(-1, 3) if solution is not None else np.zeros((0, 3))
    centres = np.vstack([snapshot.frames[:, :3, 3], ghosts, snapshot.target[:3, 3], snapshot.lowest[0]])
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * body_radius
    return (centres[:, None, :] + corners[None]).reshape(-1, 3)


def relay_camera_moves(client: viser.ClientHandle, controls: Callable[[], CameraControls | None]) -> None:
    """Hand each move of ``client``'s camera to the camera controls ``controls()`` gives (None: to none).

    viser keeps a camera callback for the browser's whole visit and cannot take one back. Camera controls that
    followed the camera themselves, one for each arm a browser changed to, kept every arm it had left in
    memory, and each ran on every move of its camera: the server registers this once per browser instead.
    """
    def moved(camera: viser.CameraHandle) -> None:
        current = controls()
        if current is not None:
            current.camera_moved(camera)

    client.camera.on_update(moved)


class CameraControls(View):
    """One browser's camera: framed on arrival and on every new canvas size, and the "View" folder.

    Parameters
    ----------
    client : viser.ClientHandle
    snapshot : callable
        The newest snapshot of the arm this browser is looking at.
    guard : callable
        Wraps a handler so that nothing it raises escapes (``ArmSession.guard``, ``feedback.guard``).
    lecture, light : bool
        Start in lecture mode (:mod:`ur10teach.features.lecture`) or in the light view
        (:mod:`ur10teach.features.light_view`), whose switches are in this folder too.
    arm : Arm
        The arm shown first: the views are named in its axes, and look at it as it is best seen (:func:`views_for`,
        :meth:`show_arm`).
    body_radius : float
        Room kept around each joint (m): the UR10's link bodies by default; a course arm's
        rods and gizmo scale with its reach.
    follow : bool
        Follow the browser's camera itself, for the browser's whole visit (a classroom's member has one for all
        its arms); otherwise it is handed the moves (:func:`relay_camera_moves`).
    phone : bool
        The browser is a phone's: until its page says how wide its window is (:meth:`show_screen`), a canvas taller
        than wide is taken for one under viser's sheet, and the arm is framed above it (:data:`SHEET_UNCOVERED`).
    """

    def __init__(self, client: viser.ClientHandle, snapshot: Callable[[], Snapshot],
                 guard: Callable[[Callable], Callable], lecture: bool = False, *, arm: Arm,
                 body_radius: float = BODY_RADIUS, follow: bool = True, light: bool = False, phone: bool = False) -> None:
        self._client = client
        self.phone = phone
        self._views = views_for(arm)  #: the "Look from" choices, for the arm shown
        self._view = "Course figure"  #: the view last picked in "Look from", which :meth:`frame` looks from
        self.body_radius = body_radius  #: the arm shown's (:meth:`show_arm`)
        self._snapshot = snapshot
        self._guard = guard
        self.closed = False
        self._framed_size: tuple[int, int] | None = None
        self._framed_at: tuple[np.ndarray, np.ndarray] | None = None  #: (position, look_at) this framed the camera at
        #: canvas pixels per CSS pixel: the camera reports its canvas in the first, the 3D labels are sized in the second
        self.pixel_ratio = 1.0
        #: whether the window is narrower than viser's breakpoint, the panel a sheet over the canvas (None: not known)
        self.narrow: bool | None = None
        #: called whenever the camera moves (the branch numbers are placed for it)
        self.on_moved: list[Callable[[], None]] = []
        #: what else is drawn and framed with the arm, by what draws it: a cloud, a path
        self.extra: dict[str, np.ndarray] = {}
        self._lock = threading.Lock()
        gui = client.gui
        gui.main_panel.dock_right()  # the canvas is what the panel leaves: nothing hides under it
        folder = gui.add_folder("View", order=0.5, expand_by_default=False)  # near the top: a teacher wants it first
        self.folders = (folder,)
        with folder:
            self.direction = gui.add_dropdown("Look from", tuple(self._views), initial_value=self._view)
            self.frame_button = gui.add_button("Frame the arm", icon=viser.Icon.FOCUS_CENTERED,
                                               hint="The arm, its ghosts, its target and what else is shown")
        self.lecture = LectureMode(gui, folder, lecture, guard, hide=self._hide_panel)
        self.light = LightView(client, folder, light, guard)
        self.direction.on_update(guard(lambda _: self._picked()))
        self.frame_button.on_click(guard(lambda _: self.frame()))
        if follow:
            client.camera.on_update(self.camera_moved)

    def close(self) -> None:
        self.closed = True

    def view(self) -> ScreenView:
        """The browser's camera in CSS pixels, and the share of its canvas the panel covers, to place labels for (the
        default one until it reports)."""
        view = screen_view(self._client, self.pixel_ratio)
        return dataclasses.replace(view, covered=1.0 - self._uncovered(view.width / view.height))

    def show_screen(self, ratio: float, narrow: bool | None) -> None:
        """The browser draws ``ratio`` canvas pixels per CSS pixel (a zoom, a laptop's screen), in a window that is
        ``narrow`` or not (None: not known): its labels are placed anew, and where the panel now lies over another
        part of the canvas, its arm is framed anew, unless the student has moved the camera since it was framed."""
        if self.closed or (ratio, narrow) == (self.pixel_ratio, self.narrow):
            return
        aspect = self._client.camera.aspect
        uncovered = self._uncovered(aspect)
        self.pixel_ratio, self.narrow = ratio, narrow
        if self._uncovered(aspect) != uncovered and self._where_framed():
            self.frame()  # (which places the labels)
            return
        for moved in self.on_moved:
            moved()

    def camera_moved(self, camera: viser.CameraHandle) -> None:
        if self.closed:
            return
        for moved in self.on_moved:
            moved()
        size = (camera.image_width, camera.image_height)
        with self._lock:
            reset = self._framed_at is not None and not self._where_framed() and any(
                np.allclose(camera.position, position, atol=1e-3) and np.allclose(camera.look_at, look_at, atol=1e-3)
                for position, look_at in RESET_POSES)
            if (same_shape(size, self._framed_size) and not reset) or 0 in size:
                return  # an orbit or zoom of the student's own (a size of the same shape is viser's DPR): leave it
            self._framed_size = size
        self._guard(lambda _: self.frame())(None)

    def _picked(self) -> None:
        """A view picked in "Look from" is framed, and from then on. One picked in the list as the arm shown turned
        its vertical is that view in the new names; one not among the choices is refused, and put back."""
        name = self.direction.value
        if name not in self._views and RENAMED.get(name) in self._views:
            self.direction.value = RENAMED[name]  # (which frames it, from this callback again)
            return
        self._view = chosen(self.direction, "look from")
        self.frame()

    def frame(self) -> None:
        """Point this browser's camera at the arm and its target, from the view last picked. (viser holds what a
        browser sent before its callback has refused it: a student's set-up that framed their camera then failed.)"""
        self.look_from(self._views.get(self._view, VIEWS["Course figure"]))

    def show_arm(self, body_radius: float, arm: Arm) -> None:
        """Look at another arm (a classroom's camera outlives its arms): frame it with ``body_radius`` of room about
        each joint from now on, and take its views (:func:`views_for`: the view chosen stays chosen; a renamed one
        is framed again)."""
        self.body_radius = body_radius
        views = views_for(arm)
        if tuple(views) == tuple(self._views):
            self._views = views  # (the same names: the course figure may look from elsewhere)
            return
        names = list(self._views)
        view = list(views)[names.index(self._view) if self._view in names else 0]
        self._views, self._view = views, view
        self.direction.options = tuple(views)  # (a value no longer among them goes to the first, and is framed)
        self.direction.value = view

    def show_also(self, name: str, points: np.ndarray | None, world: np.ndarray | None = None, now: bool = True) -> None:
        """Keep ``points`` (n, 3; None: no more) in view with the arm from now on, and (``now``) frame them now.

        ``world`` (4, 4): where the frame ``points`` are in lies in the world (the arm's base frame: the
        desktop arm's has y up); the world's own by default.
        """
        if points is None:
            self.extra.pop(name, None)
        else:
            points = np.asarray(points, dtype=float).reshape(-1, 3)
            self.extra[name] = points if world is None else from_frame(world, points)
        if now:
            self.frame()

    def keep_in_view(self, name: str, points: np.ndarray | None) -> None:
        """Keep world ``points`` in view with the arm (:meth:`show_also`), and frame them all at once when one has
        left the canvas, unless the camera has been moved since this framed it (a view the user chose stays)."""
        self.show_also(name, points, now=False)
        if points is None or self.closed or not self._where_framed():
            return
        view = self.view()
        pixels, depth = view.to_screen(self.extra[name])
        bottom = view.height * (view.covered - 0.5)
        if (depth <= 0).any() or (np.abs(pixels[:, 0]) > view.width / 2).any() or \
                ((pixels[:, 1] > view.height / 2) | (pixels[:, 1] < bottom)).any():
            self.frame()

    def _hide_panel(self) -> None:
        """Fold the panel to a strip at the edge; a narrow window's sheet has none, and the student is told what does
        fold it."""
        if self._uncovered(self._client.camera.aspect) < 1:
            notify(self._client, "In a window this narrow",
                   "Tap or click the panel's title to fold the panel away, and again to bring it back.", color="blue")
        else:
            self._client.gui.main_panel.minimize()

    def _uncovered(self, aspect: float) -> float:
        """The share of the canvas's height, from its top, that the panel leaves uncovered, for a canvas of
        ``aspect`` (width / height): a sheet's where the page says its window is narrow, or where it has not said, on a
        phone's canvas taller than wide."""
        narrow = (self.phone and aspect < 1) if self.narrow is None else self.narrow
        return SHEET_UNCOVERED if narrow else 1.0

    def _where_framed(self) -> bool:
        """The camera is where this last framed it."""
        camera, framed = self._client.camera, self._framed_at
        return framed is not None and np.allclose(camera.position, framed[0], atol=1e-3) and np.allclose(
            camera.look_at, framed[1], atol=1e-3)

    def look_from(self, direction) -> None:
        """Frame everything drawn (the arm, its ghosts, its target, :attr:`extra`) from ``direction``."""
        if self.closed:
            return
        camera = self._client.camera
        size = (camera.image_width, camera.image_height)
        shown = np.vstack([arm_points(self._snapshot(), self.body_radius), *self.extra.values()])
        aspect = size[0] / size[1]
        position, look_at = framing(shown, direction, camera.fov, aspect, top=self._uncovered(aspect))
        # one framing at a time (a worker's map and a redraw may frame at once): two interleaved left the camera
        # at one's position and the other's look-at, which no framing had chosen, taken for a view the user chose
        with self._lock, self._client.atomic():
            if not same_shape((camera.image_width, camera.image_height), size):
                return  # the canvas changed meanwhile: the framing its report asks for is the one to show
            camera.up_direction = (0.0, 0.0, 1.0)
            camera.position = position
            camera.look_at = look_at  # after the position: viser moves both together otherwise
            self._framed_at = (position, look_at)
            self._framed_size = size  # a later report of this shape is the student's own move
        for moved in self.on_moved:  # placed for where the camera is going (the browser reports only a change)
            moved()
