"""The branch numbers (and the DH frames' names) in 3D, placed so that no two overlap on the screen, for any arm.

Numbers whose points fall together on the screen (two elbows in line with the camera) become one
label, "1 · 2"; a label whose spot is taken moves to the nearest free one, with a leader line back
to its point. Placed for the browser's own camera as it moves, and
for the camera a browser frames the classroom's shared scene with (docs/architecture.md §8).
"""

from __future__ import annotations

import contextlib
import functools
import math
import threading
import unicodedata
from dataclasses import dataclass
from typing import Callable

import numpy as np
import viser

from ur10core.orientation import from_frame

from ..style import NUMBER_SCALE
from ..viser_internals.fast_updates import set_positions

#: Where the camera starts (and "reset view" returns): the whole arm, a little from above.
CAMERA_POSITION = (2.1, -1.9, 1.4)
CAMERA_LOOK_AT = (0.2, 0.0, 0.5)
CAMERA_FOV_DEGREES = 50.0
#: viser draws a screen-sized label's em at 12 CSS px times its scale.
EM_PX = 12.0
#: Room kept between two labels (px).
GAP_PX = 6.0
#: What joins the numbers of one label: "arm: 6 · 3".
JOIN = " · "
#: A leader line's colour where a label's point has none of its own.
LEADER_GREY = (90, 94, 102)
#: Labels whose points are this close on the screen (px) read as one (two elbows in line with the camera).
#: Farther apart, a label that overlaps another moves to a free spot (OFFSETS) instead.
MERGE_PX = 14.0
#: Where a label that would overlap another is tried instead, in label heights from its point, nearest first:
#: up, then the other seven directions, out to eight heights (a leader line joins it to its point). A long
#: label among many (the Stanford arm's eight branches as one, on a singularity) needs the far rings.
OFFSETS = np.array([(0.0, 0.0)] + [(radius * dx, radius * dy) for radius in range(1, 9)
                                   for dx, dy in ((0, 1), (1, 1), (-1, 1), (1, 0), (-1, 0), (0, -1), (1, -1), (-1, -1))])


@dataclass(frozen=True)
class ScreenView:
    """A perspective camera as viser has it: vertical field of view ``fov`` (rad), canvas ``height`` (CSS px)."""

    position: tuple[float, float, float]
    look_at: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    fov: float = math.radians(CAMERA_FOV_DEGREES)
    height: float = 700.0  #: the smallest canvas a class looks at: apart there, apart on larger ones
    width: float = 900.0
    #: the share of the canvas's height, from its bottom, that the panel lies over (viser's sheet, in a narrow window)
    covered: float = 0.0

    @classmethod
    def of(cls, camera: viser.CameraHandle, pixel_ratio: float = 1.0) -> ScreenView:
        """``camera``'s view in CSS pixels, the labels' unit: it reports its canvas in ``pixel_ratio`` times as many."""
        return cls(tuple(camera.position), tuple(camera.look_at), tuple(camera.up_direction), float(camera.fov),
                   float(camera.image_height or 700.0) / pixel_ratio, float(camera.image_width or 900.0) / pixel_ratio)

    @functools.cached_property
    def _axes(self) -> np.ndarray:
        forward = np.subtract(self.look_at, self.position, dtype=float)
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, self.up)
        right /= np.linalg.norm(right)
        return np.array([right, np.cross(right, forward), forward])

    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, forward) unit vectors of the camera."""
        right, up, forward = self._axes
        return right, up, forward

    def to_screen(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n, 2) pixels from the canvas centre (x right, y up) and (n,) depths of ``points`` (n, 3).

        >>> view = ScreenView((0.0, -2.0, 0.0), (0.0, 0.0, 0.0), fov=math.radians(90), height=400)
        >>> pixels, depth = view.to_screen(np.array([[1.0, 0.0, 0.0]]))
        >>> pixels.round(6).tolist(), depth.tolist()
        ([[100.0, 0.0]], [2.0])
        """
        seen = (np.asarray(points, dtype=float) - self.position) @ self._axes.T  # (right, up, depth)
        depth = seen[:, 2]
        pixels_per_unit = self.height / 2 / math.tan(self.fov / 2) / np.maximum(depth, 1e-9)
        return seen[:, :2] * pixels_per_unit[:, None], depth


DEFAULT_VIEW = ScreenView(CAMERA_POSITION, CAMERA_LOOK_AT)


def label_size(text: str, scale: float) -> tuple[float, float]:
    r"""(width, height) px of a label's box: its background quad, a little generous (viser stacks the lines
    of a text with newlines, 1.2 em apart). A character is 0.62 em wide, or a whole em where East Asian
    scripts (and emoji) write it wide: a student's nickname in Chinese, Japanese or Korean.

    >>> [round(px, 2) for px in (*label_size("x1", 1.0), *label_size("x1\nz", 1.0), label_size("李明", 1.0)[0])]
    [23.28, 17.4, 23.28, 31.8, 32.4]
    """
    em = EM_PX * scale
    lines = text.split("\n")
    return em * (max(map(_ems, lines)) + 0.7), em * (1.45 + 1.2 * (len(lines) - 1))


def _ems(line: str) -> float:
    if line.isascii():
        return 0.62 * len(line)
    return sum(1.0 if unicodedata.east_asian_width(ch) in "WF" else 0.62 for ch in line)


def boxes(pixels: np.ndarray, texts: list[str], scale: float, anchor: str = "bottom-center") -> np.ndarray:
    """(n, 4) (left, bottom, right, top) px of labels anchored at ``pixels`` (n, 2) as viser anchors them."""
    sizes = np.array([label_size(text, scale) for text in texts]).reshape(-1, 2)
    vertical, horizontal = anchor.split("-")
    left = pixels[:, 0] - sizes[:, 0] * {"left": 0.0, "center": 0.5, "right": 1.0}[horizontal]
    bottom = pixels[:, 1] - sizes[:, 1] * {"bottom": 0.0, "center": 0.5, "top": 1.0}[vertical]
    return np.column_stack([left, bottom, left + sizes[:, 0], bottom + sizes[:, 1]])


def joined(parts: list[str], scale: float, width: float, height: float = math.inf) -> str:
    r"""``parts`` joined by :data:`JOIN`, in lines no wider than ``width`` px where one line would be wider, and
    as many lines as fit ``height`` px, the last saying how many more there are: a crowd of students' names at one
    spot on the projector (in one line, thirty ran off both sides of the canvas; a lecture hall's hundred in lines
    would have covered it).

    >>> joined(["Ada", "Bo", "Dee"], 1.0, 900.0), joined(["Ada", "Bo", "Dee"], 1.0, 80.0)
    ('Ada · Bo · Dee', 'Ada · Bo\nDee')
    >>> joined(["Ada", "Bo", "Dee", "Eve", "Flo"], 1.0, 80.0, height=35.0)
    'Ada · Bo\n… and 3 more'
    """
    lines = [[parts[0]]]
    for part in parts[1:]:
        if label_size(JOIN.join([*lines[-1], part]), scale)[0] <= width:
            lines[-1].append(part)
        else:
            lines.append([part])
    text = "\n".join(JOIN.join(line) for line in lines)
    while len(lines) > 1 and label_size(text, scale)[1] > height:
        lines.pop()
        more = len(parts) - sum(map(len, lines))
        text = "\n".join([*(JOIN.join(line) for line in lines), f"… and {more} more"])
    return text


def overlapping(a: np.ndarray, b: np.ndarray, gap: float = GAP_PX) -> bool:
    return bool(a[0] < b[2] + gap and b[0] < a[2] + gap and a[1] < b[3] + gap and b[1] < a[3] + gap)


def place(anchors: np.ndarray, texts: list[str], view: ScreenView, scale: float,
          fixed: list[tuple[np.ndarray, str, float, str]] = (), merge_px: float = MERGE_PX,
          ) -> list[tuple[tuple[int, ...], str, np.ndarray, np.ndarray]]:
    """The labels to draw, no two boxes overlapping: (indices, text, position (3,), the point they name (3,)).

    ``anchors`` (n, 3) and ``texts`` (n,) are each label's point and text ("" for none). Labels
    whose points lie within ``merge_px`` of each other on the screen read as one ("1 · 8"), left
    to right, in lines that fit the canvas, up to half its height (:func:`joined`); a label that
    would overlap another, or one of ``fixed`` ((position, text, scale, anchor): labels drawn by
    something else), moves to the nearest free spot on the canvas (above the panel, where it lies over the canvas)
    (:data:`OFFSETS`; a leader line then joins it to its point). A label whose box would stand
    over the canvas's edge is pulled onto it first (centred, on a canvas narrower than it), and
    labels of several lines (legends) are placed before the others.

    >>> view = ScreenView((0.0, -3.0, 0.0), (0.0, 0.0, 0.0))
    >>> placed = place(np.array([[0.0, 0, 0], [0.001, 0, 0], [0.2, 0, 0]]), ["1", "8", "3"], view, 1.6)
    >>> [(members, text, bool(np.allclose(position, point))) for members, text, position, point in placed]
    [((0, 1), '1 · 8', True), ((2,), '3', False)]
    """
    anchors = np.asarray(anchors, dtype=float)
    named = [k for k, text in enumerate(texts) if text]
    if not named:
        return []
    pixels = dict(zip(named, view.to_screen(anchors[named])[0]))
    groups: list[list[int]] = []
    for k in sorted(named, key=lambda k: pixels[k][0]):  # left to right: a merged label reads in screen order
        near = next((g for g in groups if np.linalg.norm(pixels[g[0]] - pixels[k]) <= merge_px), None)
        if near is None:
            groups.append([k])
        else:
            near.append(k)
    if fixed:
        fixed_pixels = view.to_screen(np.array([p for p, _, _, _ in fixed], dtype=float))[0]
        obstacles = [boxes(pixel[None], [t], fixed_scale, anchor)[0]
                     for pixel, (_, t, fixed_scale, anchor) in zip(fixed_pixels, fixed)]
    else:
        obstacles = []
    right, up, _ = view.axes()
    canvas = np.array([-view.width / 2, view.height * (view.covered - 0.5), view.width / 2, view.height / 2])
    placed: list[tuple[tuple[int, ...], str, np.ndarray, np.ndarray, np.ndarray]] = []  # with each one's box
    labels = [(group, joined([texts[k] for k in group], scale, view.width - 2 * GAP_PX, (canvas[3] - canvas[1]) / 2))
              for group in groups]
    # a label of several lines (a map's legend among the names) first: the fewest spots are free for it
    for group, text in sorted(labels, key=lambda label: -label[1].count("\n")):
        point = anchors[group].mean(axis=0)
        pixel, depth = view.to_screen(point[None])
        own = boxes(pixel, [text], scale)[0]
        room, pulled = canvas, np.zeros(2)
        if not ((own[:2] >= canvas[:2]).all() and (own[2:] <= canvas[2:]).all()) and depth[0] > 0 \
                and ((pixel[0] >= canvas[:2]) & (pixel[0] <= canvas[2:])).all():  # a long one near an edge: pulled on
            middle = (canvas[:2] + canvas[2:]) / 2
            half = np.maximum((canvas[2:] - canvas[:2]) / 2, (own[2:] - own[:2]) / 2)  # or centred, if wider
            room = np.concatenate([middle - half, middle + half])
            pulled = np.clip(0.0, room[:2] - own[:2], room[2:] - own[2:])
            own = own + np.tile(pulled, 2)
        shift = _shift(own, obstacles + [entry[4] for entry in placed], room)
        world_per_px = 2 * math.tan(view.fov / 2) * depth[0] / view.height
        moved = pulled + shift  # px, right and up
        position = point + (right * moved[0] + up * moved[1]) * world_per_px
        placed.append((tuple(sorted(group)), text, position, point, own + np.tile(shift, 2)))
    return [entry[:4] for entry in sorted(placed, key=lambda entry: entry[0])]


def _shift(own: np.ndarray, taken: list[np.ndarray], room: np.ndarray) -> np.ndarray:
    """How far (px, right and up) the box ``own`` (4,) moves to keep clear of ``taken`` in ``room``: to the first
    free spot of :data:`OFFSETS`, else to the nearest free one on a grid over the room (a crowd on a small canvas, a
    phone's band above its panel: the rings' spots lie in eight directions only), else to the spot of
    :data:`OFFSETS` overlapping the others least."""
    step = own[3] - own[1] + GAP_PX
    rings = step * OFFSETS
    k, free = _free_spot(own + rings[:, [0, 1, 0, 1]], taken, room)
    if free:
        return rings[k]
    lefts, bottoms = np.meshgrid(np.arange(room[0], room[2] - (own[2] - own[0]), step / 2),
                                 np.arange(room[1], room[3] - (own[3] - own[1]), step / 2))
    shifts = np.column_stack([lefts.ravel() - own[0], bottoms.ravel() - own[1]])
    if not len(shifts):  # wider or taller than the room: no spot on it
        return rings[k]
    shifts = shifts[np.argsort(np.hypot(shifts[:, 0], shifts[:, 1]), kind="stable")]
    j, free = _free_spot(own + shifts[:, [0, 1, 0, 1]], taken, room)
    return shifts[j] if free else rings[k]


def _free_spot(spots: np.ndarray, taken: list[np.ndarray], canvas: np.ndarray) -> tuple[int, bool]:
    """The first of ``spots`` (k, 4) boxes on the ``canvas`` that overlaps none of ``taken``, and True; if there is
    none, the one on the canvas overlapping them least (else the first), and False."""
    inside = (spots[:, :2] >= canvas[:2]).all(axis=1) & (spots[:, 2:] <= canvas[2:]).all(axis=1)
    if not taken:
        return int(np.argmax(inside)), bool(inside.any())
    others = np.array(taken)[None]
    wide = np.minimum(spots[:, None, 2], others[..., 2] + GAP_PX) - np.maximum(spots[:, None, 0], others[..., 0] - GAP_PX)
    high = np.minimum(spots[:, None, 3], others[..., 3] + GAP_PX) - np.maximum(spots[:, None, 1], others[..., 1] - GAP_PX)
    covered = (np.clip(wide, 0.0, None) * np.clip(high, 0.0, None)).sum(axis=1)
    free = inside & (covered == 0.0)
    if free.any():
        return int(np.argmax(free)), True
    return (int(np.argmin(np.where(inside, covered, np.inf))) if inside.any() else 0), False


def screen_view(client, pixel_ratio: float = 1.0) -> ScreenView:
    """``client``'s camera, to place labels for (the default one until it reports, or once it has gone)."""
    try:
        return ScreenView.of(client.camera, pixel_ratio)
    except Exception:  # no camera message yet, or the browser has gone
        return DEFAULT_VIEW


class BranchLabels:
    """One drawing's 3D labels of one kind (the branch numbers, the DH axes' names): a pool of labels,
    placed apart for a camera (:func:`place`), each moved one with a leader line back to its point.

    ``view`` gives the camera to place for (the browser's own, or for the shared scene the one
    each browser frames it with); ``fixed`` the labels drawn by something else that these keep
    clear of (label nodes in the pool's frame, or :func:`obstacle` tuples);
    ``world`` (4, 4) where the labels' parent node is in the world (both in its frame);
    ``colours[k]`` the leader line's colour for label k's point.
    """

    def __init__(self, scene: viser.SceneApi, root: str, count: int, scale: float = NUMBER_SCALE,
                 colours=None, merge_px: float = MERGE_PX) -> None:
        self.labels = [scene.add_label(f"{root}/number{k + 1}", "", visible=False, font_screen_scale=scale,
                                       anchor="bottom-center") for k in range(count)]
        # one per label, each one colour: viser's browser reads per-vertex uint8 colours as 0…1 (white)
        self.leaders = [scene.add_line_segments(f"{root}/leader{k + 1}", np.zeros((1, 2, 3)), LEADER_GREY, thickness=2.0,
                                                thickness_units="screen", visible=False) for k in range(count)]
        self.colours = colours or [LEADER_GREY] * count
        self.merge_px = merge_px
        self.view: Callable[[], ScreenView] = lambda: DEFAULT_VIEW
        self.fixed: Callable[[], list] = lambda: []
        self.outside: Callable[[], list] = lambda: []  #: what :func:`chain` keeps these clear of besides other pools
        self.world = np.eye(4)
        self.placed: list[tuple[tuple[int, ...], str, np.ndarray]] = []  #: what the labels show now
        self.copies: list[BranchLabels] = []  #: browsers' own copies of these, shown what these show (:class:`OwnLabels`)
        self._wanted: tuple[np.ndarray, list[str]] = (np.zeros((0, 3)), [])
        self._leaders: list[bytes] = [b""] * count
        self._positions = b""
        self._lock = threading.Lock()
        self._removed = False
        #: held while pools are placed in order (:func:`chain` shares the first one's): a camera move's placing
        #: cannot come between two pools of a panel's, leaving a later pool placed clear of where an earlier was
        self.placing = threading.RLock()

    def carriers(self, keys: list[str]) -> dict[str, viser.LabelHandle]:
        """The label that shows each point's text, by the points' ``keys`` (one label may show several)."""
        return {keys[k]: label for (members, _, _), label in zip(self.placed, self.labels) for k in members}

    def remove(self) -> None:
        """Take its labels and leader lines out of the scene (a scene shared with others outlives it); a placing
        under way finishes first, and none comes after."""
        with self._lock:
            self._removed = True
            for node in (*self.labels, *self.leaders):
                node.remove()

    def show(self, anchors: np.ndarray, texts: list[str]) -> None:
        """Label the points ``anchors`` (n, 3) with ``texts`` ("" for none)."""
        with self._lock:
            self._wanted = (np.asarray(anchors, dtype=float), list(texts))
        self.place()
        for copy in tuple(self.copies):
            copy.size_as(self)
            copy.show(anchors, texts)

    def size_as(self, other: BranchLabels) -> None:
        """Its labels at ``other``'s size (lecture mode's, say)."""
        scale = other.labels[0].font_screen_scale
        for label in self.labels:
            if label.font_screen_scale != scale:
                label.font_screen_scale = scale

    def place(self) -> None:
        """Place the labels again (the camera moved, or lecture mode changed their size)."""
        with self.placing, self._lock:
            anchors, texts = self._wanted
            if self._removed or (not any(texts) and not self.placed):
                return  # nothing to show, and nothing shown
            scale = self.labels[0].font_screen_scale if self.labels else NUMBER_SCALE  # grown in lecture mode
            R, t = self.world[:3, :3], self.world[:3, 3]
            fixed = [(np.asarray(position) @ R.T + t, text, scale, anchor)
                     for position, text, scale, anchor in filter(None, map(obstacle, self.fixed()))]
            placed = place(anchors @ R.T + t, texts, self.view(), scale, fixed, self.merge_px) if any(texts) else []
            self.placed = [(members, text, (position - t) @ R) for members, text, position, _ in placed]
            shown = len(self.placed)
            for label, (_, text, _) in zip(self.labels, self.placed):
                if label.text != text:
                    label.text = text
            if shown:  # moved in one message each, as the ghosts are (at the panel's pace, but for every browser)
                positions = np.array([point for _, _, point in self.placed], np.float32)
                if positions.tobytes() != self._positions:
                    self._positions = positions.tobytes()
                    set_positions(self.labels[:shown], positions)
            for k, label in enumerate(self.labels):
                if label.visible != (k < shown):
                    label.visible = k < shown
            for k, leader in enumerate(self.leaders):  # a moved label's line back to its point, in its point's colour
                members, _, position, point = placed[k] if k < shown else ((), "", None, None)
                moved = position is not None and bool(np.any(position != point))
                if moved:
                    segment = np.array([[(point - t) @ R, (position - t) @ R]], np.float32)
                    colour = np.array(self.colours[members[0]], np.uint8)
                    if segment.tobytes() + colour.tobytes() != self._leaders[k]:
                        self._leaders[k] = segment.tobytes() + colour.tobytes()
                        leader.points, leader.colors = segment, colour
                if leader.visible != moved:
                    leader.visible = moved


class OwnLabels:
    """One browser's own copies of a shared scene's label ``pools``, placed for its own camera ``view``: a phone's,
    say, whose canvas, small and half under the panel's sheet, the shared placing (for the class's larger screens)
    crowds. They carry the shared labels' names in the browser's own scope, where viser shows a browser's node in
    place of the shared one of its name; removed, the shared ones show again."""

    def __init__(self, scene: viser.SceneApi, pools: tuple[BranchLabels, ...], view: Callable[[], ScreenView]) -> None:
        self.of = pools  #: the shared scene's pools these copy
        self.pools = pools = tuple(pool for pool in pools if pool.labels)
        self.copies = chain(tuple(
            BranchLabels(scene, pool.labels[0].name.rsplit("/", 1)[0], len(pool.labels), pool.labels[0].font_screen_scale,
                         pool.colours, pool.merge_px) for pool in pools), pools[0].outside if pools else list)
        for pool, copy in zip(pools, self.copies):
            copy.view, copy.world, copy._wanted = view, pool.world, pool._wanted
            pool.copies.append(copy)
        self.place()

    def place(self) -> None:
        if self.copies:
            place_in_order(self.copies)

    def remove(self) -> None:
        """Take the copies out of the browser's scene: the shared labels show again."""
        self.forget()
        for copy in self.copies:
            copy.remove()

    def forget(self) -> None:
        """Stop copying the shared labels (the browser has gone)."""
        for pool, copy in zip(self.pools, self.copies):
            with contextlib.suppress(ValueError):
                pool.copies.remove(copy)


def obstacle(label, under=(0.0, 0.0, 0.0)) -> tuple | None:
    """(position (3,), text, scale, anchor) of a label node (None while hidden), ``under`` (3,) where the node
    it hangs under is; a tuple (or None) stays as it is."""
    if label is None or isinstance(label, tuple):
        return label
    return (np.add(under, label.position), label.text, label.font_screen_scale, label.anchor) if label.visible else None


def in_world(pools: tuple[BranchLabels, ...]) -> list[tuple]:
    """The :func:`obstacle` tuples of every label ``pools`` show, their positions in the world (for labels hung elsewhere)."""
    return [(from_frame(pool.world, position), text, scale, anchor)
            for pool in pools for position, text, scale, anchor in filter(None, map(obstacle, pool.labels))]


def chain(pools: tuple[BranchLabels, ...], outside: Callable[[], list] = lambda: []) -> tuple[BranchLabels, ...]:
    """``pools`` placed in order, each keeping clear of ``outside()`` (labels drawn by something else: the
    session's names at the tool, a map's largest ‖τ‖) and of every label of the pools before it. They share
    the first one's :attr:`BranchLabels.placing` lock, which whoever places them in turn holds."""
    for k, pool in enumerate(pools):
        pool.fixed = lambda earlier=pools[:k]: [*outside(), *(label for other in earlier for label in other.labels)]
        pool.outside = outside
        pool.placing = pools[0].placing
    return pools


def place_in_order(pools: tuple[BranchLabels, ...]) -> None:
    """Place ``pools`` again, one after the other, none of them placed by anyone else meanwhile."""
    with pools[-1].placing:
        for pool in pools:
            pool.place()
