"""Class challenges in the panel and the scene: the teacher's desk, each student's card, the class's tools on the projector.

What is checked and how is ``ur10core.challenges``; who is in a run, ``ur10teach.serving.challenge_run``.
"""

from __future__ import annotations

import html
import itertools
from typing import Callable

import numpy as np
import viser

from ur10core import Arm
from ur10core.challenges import POSE_QUESTIONS, Challenge, Verdict, number_names
from ur10core.orientation import from_frame, in_frame, quaternion

from ..feedback import Beside, chosen, within
from ..serving.challenge_run import MAX_NICKNAME, ChallengeRun, Student, summary_markdown, terms_markdown
from ..style import SAFE_GREEN, UR10_SIZE, hex_color, label_scale
from .arm_picker import choice_of
from .branch_labels import BranchLabels, ScreenView, obstacle
from .course_arms.editor import CONVENTIONS, STARTING_TABLE
from .lecture import add_label

#: Okabe-Ito: a student still working (orange) and one who has solved it (bluish green), told apart by any eye.
WORKING_COLOR, SOLVED_COLOR = (230, 159, 0), (0, 158, 115)
GOAL_ROOT = "/challenge/goal"
CLASS_ROOT = "/challenge/class"
MAX_TIME_LIMIT_MINUTES = 120
#: Names the projector shows at most (a lecture hall's hundred read as dots beyond it).
MAX_NAMES = 120
#: The target's ball (radius, m), and the dots' sizes: a solved student's tool is on the target, and its dot is
#: drawn larger than the ball and the working students' dots (twenty students round the target hid the green ones).
#: For the UR10 (``style.UR10_SIZE``): they grow with the arm shown, as its drawing does (a KR210 is 3.9 m across).
GOAL_RADIUS, WORKING_DOT, SOLVED_DOT = 0.02, 0.03, 0.065
#: Before a solved student's name in 3D (a label has no colour of its own, and names at one spot merge).
SOLVED_MARK = "✓ "


def challenge_markdown(challenge: Challenge, time_limit: float | None = None, arm: Arm | None = None) -> str:
    """The task as a student reads it, on ``arm`` (the run's; ``Arm.preset(challenge.arm)`` by default)."""
    lines = [f"### {html.escape(challenge.title, quote=False)}", challenge.text, terms_markdown(challenge, arm)]
    if time_limit:
        lines.append(f"Time limit: {time_limit / 60:g} min.")
    return "\n\n".join(lines)


def verdict_markdown(verdict: Verdict, attempts: int) -> str:
    if verdict.solved:
        return f"<span style='color:{hex_color(SAFE_GREEN)}'>**✓ {html.escape(verdict.message)}**</span> (check {attempts})"
    return f"**Not yet** (check {attempts}): {html.escape(verdict.message)}"


class ChallengeDesk:
    """The presenter's "Challenge" folder: pick, start, watch the class, end, download the results.

    A panel the refresher redraws (``render_panel``), at most twice a second: the projector's
    summary is at most a second behind the class.
    """

    panel_interval = 0.5

    def __init__(self, gui: viser.GuiApi, challenges: tuple[Challenge, ...], guard: Callable[[Callable], Callable],
                 start: Callable[[Challenge, float | None], None], end: Callable[[], None], download: Callable[[], None],
                 run: Callable[[], ChallengeRun | None], on_render: Callable[[], None] = lambda: None,
                 about_pose: Callable[[str], Challenge] | None = None,
                 arm_of: Callable[[Challenge], Arm | None] = lambda challenge: None,
                 nicknames: bool = True, show_nicknames: Callable[[bool], None] = lambda shown: None,
                 note: Callable[[], str] = lambda: "") -> None:
        self.closed = False
        self._note = note  #: a line the board adds about the projector (the class shown another arm)
        self._arm_of = arm_of  #: the arm a challenge would be checked on (None: its ``Arm.preset``)
        self._on_render = on_render  #: the scene's part of the board (every student's tool)
        self._challenges = {c.title: c for c in challenges}
        #: a question of ``POSE_QUESTIONS`` → the challenge on the class's arm as it is now (None: none offered)
        self._about_pose = about_pose
        titles = (*self._challenges, *(q for q in POSE_QUESTIONS if q not in self._challenges and about_pose))
        self._run = run
        # each callback right after its widget: a widget reaches the browser as it is made, and a click on
        # a button without its callback yet is lost
        self.folder = gui.add_folder("Challenge", order=0.05)
        with self.folder:
            self.picker = gui.add_dropdown("Challenge", titles, hint="Built in, from --challenges FILE, or about the pose shown")
            self.preview = gui.add_markdown("")
            self.picker.on_update(guard(lambda _: self._preview()))
            # a slider, not a number box: a box the teacher empties shows nothing while the server keeps its last value
            self.minutes = gui.add_slider("Time limit (min, 0: none)", min=0, max=MAX_TIME_LIMIT_MINUTES, step=1, initial_value=0)
            self.refusal = Beside(gui)
            self.minutes.on_update(guard(lambda _: within(self.minutes, "time limit (min)"), beside=self.refusal))
            self.start = gui.add_button("Start the challenge", icon=viser.Icon.PLAYER_PLAY, order=self.refusal.line.order - 0.5)
            self.start.on_click(guard(lambda _: start(self.chosen(), self.time_limit()), beside=self.refusal))
            self.board = gui.add_markdown("")
            # a name the teacher would rather not project is gone at the next redraw, without finding whose it is
            self.nicknames = gui.add_checkbox("Nicknames on the projector", nicknames,
                                              hint="Off: every student's tool is named by their number only")
            self.nicknames.on_update(guard(lambda _: show_nicknames(bool(self.nicknames.value))))
            self.end = gui.add_button("End and show the solution", icon=viser.Icon.FLAG, visible=False)
            self.end.on_click(guard(lambda _: end(), beside=self.refusal))
            self.download = gui.add_button("Download results (CSV)", icon=viser.Icon.DOWNLOAD, visible=False)
            self.download.on_click(guard(lambda _: download(), beside=self.refusal))
        self._preview()
        self.render_panel()

    def chosen(self) -> Challenge:
        """The challenge picked; a question about the pose shown is asked of the class's arm as it is now."""
        title = chosen(self.picker, "challenge")
        return self._challenges[title] if title in self._challenges else self._about_pose(title)

    def time_limit(self) -> float | None:
        minutes = within(self.minutes, "time limit (min)")
        return 60 * minutes if minutes else None

    def _preview(self) -> None:
        try:
            challenge = self.chosen()
        except ValueError as why:  # a question about the pose shown that the arm shown cannot be asked
            self._show_preview(f"Not about the arm shown: {html.escape(str(why), quote=False)}.")
            return
        shown = "; asked of the class's arm as it stands when you start" if challenge.title in POSE_QUESTIONS else ""
        self._show_preview(f"{challenge_markdown(challenge, arm=self._arm_of(challenge))}\n\n"
                           f"*{challenge.kind.replace('_', ' ')}, on {choice_of(challenge.arm)}{shown}*",
                           round(challenge.time_limit / 60) if challenge.time_limit else 0)

    def _show_preview(self, text: str, minutes: int = 0) -> None:
        try:
            self.preview.content = text
            if minutes and not self.minutes.value:
                self.minutes.value = minutes
        except RuntimeError:  # viser's word for a removed widget: a hand-over took this folder as the pick came
            if not self.closed:
                raise

    def render_panel(self) -> None:
        self._on_render()  # first: a change from here on asks for the next redraw
        run = self._run()
        running = run is not None and not run.ended
        if not running and self.picker.value in POSE_QUESTIONS:
            self._preview()  # at the joints the class's arm has now
        for handle, show in ((self.picker, not running), (self.minutes, not running), (self.start, not running),
                             (self.preview, not running), (self.end, running), (self.download, run is not None)):
            if handle.visible != show:
                handle.visible = show
        note = self._note()
        self.board.content = (summary_markdown(run) + (f"\n\n{note}" if note else "")) if run is not None else "No challenge running."

    def remove(self) -> None:
        self.closed = True
        self.folder.remove()


class ChallengeCard:
    """A student's "Challenge" folder: the task, their nickname, what they type, "Check my answer" and its verdict.

    ``check()`` checks the answer; ``working()`` is told each time the student types at it.
    """

    def __init__(self, gui: viser.GuiApi, run: ChallengeRun, student: Student, guard: Callable[..., Callable],
                 check: Callable[[], None], working: Callable[[], None]) -> None:
        challenge = run.challenge
        self.challenge = challenge
        self.folder = gui.add_folder("Challenge", order=0.05)
        self.numbers = self.rows = self.convention = None
        kept = student.kept
        with self.folder:
            self.task = gui.add_markdown(challenge_markdown(challenge, run.time_limit, run.arm))
            self.nickname = gui.add_text(f"Your nickname (up to {MAX_NICKNAME} characters)", student.nickname,
                                         hint="What the projector shows by your tool; your student number if empty")
            self.named = Beside(gui)
            if challenge.kind == "numbers":
                names = ", ".join(number_names(challenge, run.arm))
                self.numbers = gui.add_text(f"Your numbers ({names})", kept.get("numbers", ""))
            elif challenge.kind == "dh_table":
                self.convention = gui.add_dropdown("Convention", tuple(CONVENTIONS), initial_value=kept.get("convention", tuple(CONVENTIONS)[0]))
                self.rows = gui.add_text("Your DH table (a α d θ type, mm and °)", kept.get("rows", STARTING_TABLE), multiline=True)
            self.refusal = Beside(gui)
            self.check = gui.add_button("Check my answer", icon=viser.Icon.CHECK, order=self.refusal.line.order - 0.5)
            self.check.on_click(guard(lambda _: check(), beside=self.refusal))
            self.verdict = gui.add_markdown(verdict_markdown(student.verdict, student.attempts) if student.verdict else "")
        self.nickname.on_update(guard(lambda _: self._renamed(run, student), beside=self.named))
        for box in (self.numbers, self.rows):
            if box is not None:
                box.on_update(guard(lambda _: working()))
        if self.convention is not None:
            self.convention.on_update(guard(lambda _: self._convention_changed(working)))

    def _convention_changed(self, working: Callable[[], None]) -> None:
        self.convention_chosen()  # refused (and put back) as it comes: the card keeps it when rebuilt
        working()

    def _renamed(self, run: ChallengeRun, student: Student) -> None:
        name = run.rename(student, self.nickname.value)
        if name != self.nickname.value:
            self.nickname.value = name

    def typed(self) -> dict:
        """What the student has typed, to keep while they are away."""
        kept = {}
        if self.numbers is not None:
            kept["numbers"] = str(self.numbers.value)
        if self.rows is not None:
            kept["rows"], kept["convention"] = str(self.rows.value), str(self.convention.value)
        return kept

    def convention_chosen(self) -> str:
        return CONVENTIONS[chosen(self.convention, "convention")]

    def show(self, verdict: Verdict, attempts: int) -> None:
        self.verdict.content = verdict_markdown(verdict, attempts)

    def ended(self, words: str) -> None:
        self.check.visible = False
        self.task.content += f"\n\n**The challenge has ended.** {html.escape(words)}"

    def remove(self) -> None:
        self.folder.remove()


class GoalMarker:
    """The pose a reach challenge asks for, in one browser's scene: a frame and a label, in the arm's world."""

    def __init__(self, scene: viser.SceneApi, pose: np.ndarray, lecture: bool = False, size: float = UR10_SIZE) -> None:
        self.pose = pose  #: (4, 4) in the world
        scale = size / UR10_SIZE  # ``size``: the drawing's, the arm's reach (m)
        self.frame = scene.add_frame(GOAL_ROOT, wxyz=quaternion(pose[:3, :3], check=False), position=pose[:3, 3],
                                     axes_length=0.15 * scale, axes_radius=0.01 * scale, origin_radius=GOAL_RADIUS * scale)
        self.label = add_label(scene, f"{GOAL_ROOT}/name", "challenge target", 1.4, lecture, anchor="bottom-left")

    def face(self, view: ScreenView) -> None:
        """Its name on the side of the target towards the middle of ``view``'s canvas: hung to the right of a target in
        the canvas's right half, it ran off the canvas (under the panel)."""
        pixels, _ = view.to_screen(self.pose[None, :3, 3])
        anchor = "bottom-right" if pixels[0, 0] > 0 else "bottom-left"
        if self.label.anchor != anchor:
            self.label.anchor = anchor

    def name(self, frame: np.ndarray) -> tuple | None:
        """Its label as the placed labels keep clear of it (``branch_labels.obstacle``), in ``frame`` (4, 4): where
        their nodes hang in the world (the label itself hangs under the target's frame)."""
        return obstacle(self.label, under=in_frame(frame, self.pose[:3, 3]))

    def remove(self) -> None:
        self.frame.remove()


class ClassTools:
    """Every student's tool on the projector: a dot each (orange working, green solved) and their names (a solved
    one marked ✓), placed apart for the projector's camera as the branch numbers are (names at one spot read as one)."""

    def __init__(self, scene: viser.SceneApi, world: np.ndarray, view: Callable[[], ScreenView], lecture: bool = False,
                 fixed: Callable[[], list[tuple]] = lambda: [],
                 keep_in_view: Callable[[np.ndarray | None], None] = lambda points: None, size: float = UR10_SIZE) -> None:
        self._scene, self._world, self._view, self._scale = scene, world, view, label_scale(1.2, lecture)
        self._fixed = fixed  #: the labels already on the projector (branch numbers, the target's name), in the world: kept clear of
        self._keep_in_view = keep_in_view  #: the projector's camera keeps the tools (world points) in view; None: no more
        self._reached: np.ndarray | None = None  #: (2, 3) the box round every tool seen in this challenge (world)
        self.working, self.solved = (
            scene.add_point_cloud(f"{CLASS_ROOT}/{name}", np.zeros((1, 3), np.float32), colour, point_size=dot * size / UR10_SIZE,
                                  point_shape="circle", visible=False)
            for name, colour, dot in (("working", WORKING_COLOR, WORKING_DOT), ("solved", SOLVED_COLOR, SOLVED_DOT)))
        self.names: BranchLabels | None = None
        self.removed = False  #: taken off the projector (a new challenge, a hand-over): a drawing under way stops

    def _pool(self, count: int) -> BranchLabels:
        """Labels for ``count`` names: the pool grows (to :data:`MAX_NAMES`) as the class does."""
        if self.names is None or len(self.names.labels) < count:
            self._remove_names()
            capacity = min(MAX_NAMES, max(16, 2 * count))
            self.names = BranchLabels(self._scene, f"{CLASS_ROOT}/names{capacity}", capacity, scale=self._scale)
            self.names.view, self.names.fixed = self._view, self._fixed
        return self.names

    def show(self, run: ChallengeRun, nicknames: bool = True) -> None:
        if self.removed:  # (no new names' pool in a scene these have left)
            return
        names, poses, solved = run.flanges(nicknames)
        points = from_frame(self._world, poses[:, :3, 3])
        for dots, which, colour in ((self.working, ~solved, WORKING_COLOR), (self.solved, solved, SOLVED_COLOR)):
            if which.any():
                dots.points = points[which].astype(np.float32)
                dots.colors = np.tile(np.array(colour, np.uint8), (int(which.sum()), 1))
            if dots.visible != bool(which.any()):
                dots.visible = bool(which.any())
        if len(names):  # the box round everywhere a tool has been only grows: the projector's camera settles
            ends = np.array([points.min(axis=0), points.max(axis=0)])
            self._reached = ends if self._reached is None else np.array([np.minimum(self._reached[0], ends[0]),
                                                                           np.maximum(self._reached[1], ends[1])])
            self._keep_in_view(np.array(list(itertools.product(*self._reached.T))))
        shown = min(len(names), MAX_NAMES)  # beyond it, a dot without a name
        if shown or self.names is not None:
            self._pool(shown).show(points[:shown], [SOLVED_MARK + name if done else name
                                                    for name, done in zip(names[:shown], solved)])

    def place(self) -> None:
        """The projector's camera moved: its names placed apart again."""
        if self.names is not None:
            self.names.place()

    def _remove_names(self) -> None:
        if self.names is not None:
            self.names.remove()
            self.names = None

    def remove(self) -> None:
        self.removed = True  # first: a drawing on another thread that meets a removed node knows why
        self._keep_in_view(None)
        self.working.remove()
        self.solved.remove()
        self._remove_names()


def goal_pose(challenge: Challenge, arm: Arm, world: np.ndarray) -> np.ndarray | None:
    """Where a reach challenge's target is in the scene (None for other kinds)."""
    if challenge.kind != "reach":
        return None
    return world @ arm.fk(np.array(challenge.joints))
