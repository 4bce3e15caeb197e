"""The class challenges of a classroom: the presenter starts one, every other browser becomes a student, the server checks.

What is checked is ``ur10core.challenges``; who is in a run, ``challenge_run``; the panels and the
projector's scene, ``ur10teach.features.challenge``. Why it is built so: docs/architecture.md §9.
"""

from __future__ import annotations

import functools
import itertools
import logging
import threading
import time
import weakref
from typing import TYPE_CHECKING

import numpy as np

from ur10core import Arm
from ur10core.challenges import POSE_QUESTIONS, Answer, Challenge, about_the_pose, check, number_names, solution

from ..features.arm_picker import CLASS_TYPED_TITLE, CUSTOM, choice_of
from ..features.branch_labels import in_world
from ..features.challenge import ChallengeCard, ChallengeDesk, ClassTools, GoalMarker, goal_pose
from ..features.course_arms.editor import parse_table
from ..feedback import guard
from ..state import ArmState
from .challenge_run import ChallengeRun
from .workers import PanelRefresher

if TYPE_CHECKING:
    from .classroom import Classroom, Member

log = logging.getLogger(__name__)

#: While a challenge runs, its results file is written again as students check, at most this often (s): a teacher's
#: laptop that dies mid-lesson loses no more of the class's answers than this.
SAVE_EVERY = 30.0
#: Seconds within which a second press of *Start the challenge*, *End and show the solution* or *Check my answer* is a
#: double click's.
DOUBLE_PRESS = 0.5


def _one_turnover_at_a_time(method):
    """A start or an end, from first to last, with no other start or end between: viser runs each click's
    callback on a thread of its own, and a start pressed while an end still showed the class its solution took
    the run from under it (the ended run's last answers went unsaved, and the new run's file was written instead).

    A double click's second press is let go (:meth:`ClassChallenges.double_press`): it told the projector "a
    challenge is running: end it first" as the challenge started."""
    @functools.wraps(method)
    def one_at_a_time(self: ClassChallenges, member: Member, *args, **kwargs):
        if self.double_press(member, method.__name__):
            return None
        with self._turnover:
            return method(self, member, *args, **kwargs)

    return one_at_a_time


class ClassChallenges:
    """The challenges the presenter can set (``offered``), the one started last (``run``), and the board.

    Each member keeps its own part (``desk``, ``tools``; ``student``, ``card``, ``goal``,
    ``observer``); the classroom calls :meth:`enlist`, :meth:`watch` and :meth:`step_out` as
    browsers come, explore and go.
    """

    def __init__(self, room: Classroom, challenges: tuple[Challenge, ...]) -> None:
        self.room = room
        self.offered = challenges
        self.run: ChallengeRun | None = None  #: the challenge started last (running, or ended and its results kept)
        self._board_due = False  #: a redraw of the presenter's board is requested
        self._rates_watched: weakref.WeakSet = weakref.WeakSet()  #: the sessions whose rate sliders tell :meth:`_rates_moved`
        #: the board's own refresher: behind a hundred students' panels in the shared one, it fell 7 s behind
        #: (BENCHMARKS.md, *a class challenge in a lecture hall*); alone in this one it is due every 0.5 s
        self.boards = PanelRefresher(room.app.server.get_event_loop(), interval=ChallengeDesk.panel_interval, duty=0.5)
        self.clock = time.monotonic  #: what a challenge's times and check pacing are kept by (a test sets its own)
        self._saving = threading.Lock()  #: one writer of a results file at a time (a check, the end, the stop)
        self._turnover = threading.Lock()  #: held by a start or an end throughout (:func:`_one_turnover_at_a_time`)
        #: each browser's last press of *Start*, *End* or *Check my answer*: (which, what it acted on, its time.monotonic())
        self._presses: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
        self._pressing = threading.Lock()
        self.nicknames = True  #: the projector names each student's tool by their nickname (else by their number)

    @property
    def running(self) -> bool:
        return self.run is not None and not self.run.ended

    def desk(self, member: Member) -> ChallengeDesk:
        """The presenter's "Challenge" folder (and, for one who takes over a reach challenge, its target)."""
        if self.run is not None:
            self.show_goal(member)
        return ChallengeDesk(member.client.gui, self.offered, lambda handler, beside=None: self._guard(member, handler, beside),
                             start=lambda challenge, limit: self.start(member, challenge, limit),
                             end=lambda: self.end(member), download=lambda: self.download(member),
                             run=lambda: self.run, on_render=lambda: self._render_board(member), about_pose=self.about_the_pose,
                             arm_of=lambda challenge: self.room.app.arm if challenge.arm == "ur10" else None,
                             nicknames=self.nicknames, show_nicknames=self.show_nicknames, note=self.shown_elsewhere)

    def show_nicknames(self, shown: bool) -> None:
        self.nicknames = shown
        self._board_changed()

    def about_the_pose(self, question: str) -> Challenge:
        """A question of ``POSE_QUESTIONS`` about the class's arm as it is now."""
        state = self.room.state
        return about_the_pose(question, state.arm, state.q)

    @_one_turnover_at_a_time
    def start(self, member: Member, challenge: Challenge, time_limit: float | None) -> None:
        """The presenter starts ``challenge``: the class is shown its arm, and every other browser gets its own copy and the task."""
        with self.room._lock:
            if member.closed or self.room.presenter is not member:
                raise ValueError("only the presenter starts a challenge")
            if self.run is not None and not self.run.ended:
                raise ValueError("a challenge is running: end it first")
            self.room.show_arm(member, choice_of(challenge.arm), paced=False)
            state = self.room.state
            home = state.arm.specs.home
            # nobody starts on the answer: the students' arms start where the class's is
            on_answer = challenge.is_pose and check(challenge, state.arm, Answer(q=state.q, target=state.last.target)).solved
            if on_answer and check(challenge, state.arm, Answer(q=home, target=state.arm.fk(home))).solved:
                raise ValueError("the class's arm is on the answer, and so is its home pose, where it would go instead: "
                                 "move it off the answer first")
            for other in self.room.members.values():  # the last run's cards and targets go
                self.step_out(other, keep=False)
            self.run = ChallengeRun(challenge, state.arm, time_limit, clock=lambda: self.clock())
            members = [m for m in self.room.members.values() if m is not member]
            session = member.session  # (the presenter's, which a hand-over from here on takes away: closed, not None)
        if on_answer:  # so the class's arm goes home
            session.apply(lambda arm_state: arm_state.set_joints(home, cause="typed"))
        self.hold_back(session)
        self.hold_back_live()
        self.show_goal(member)
        for other in members:
            try:
                self.enlist(other)
            except Exception:  # one browser's trouble (it left meanwhile, say) must not keep the task from the rest
                if not other.closed:
                    log.exception("could not give browser %s the challenge", other.client.client_id)
        self._board_changed()
        log.info("challenge %r started with %d students", challenge.title, len(members))

    def enlist(self, member: Member) -> None:
        """Make ``member`` a student of the running challenge: their own arm (as it was if they left and came back) and the task."""
        with self.room._lock:  # the start and the browser's own arrival may both enlist it: once
            run = self.run
            if member.closed or member is self.room.presenter or run is None or run.ended or member.student is not None:
                return
            student = member.student = run.join(member.browser)
        if member.session is not None and member.session.arm != run.arm:
            self.room.rejoin(member)
        if member.session is not None:  # exploring the challenge's arm already
            self.resume(member)
        else:
            self.room.explore(member)  # which resumes
        session = member.session
        member.observer = lambda snapshot: self._moved(member, snapshot)  # from here on, a change is the student's
        self.watch(member)
        member.card = ChallengeCard(member.client.gui, run, student, lambda handler, beside=None: self._guard(member, handler, beside),
                                    check=lambda: self.check(member), working=lambda: self._moved(member))
        if run.challenge.is_pose and session is not None:  # (None: they went back to watching meanwhile)
            student.flange = session.state.last.flange  # drawn on the projector from the start; not yet working
        self.show_goal(member)
        self._board_changed()

    def arm_for(self, member: Member) -> Arm | None:
        """The arm a student of the running challenge works on, whatever the class is shown (None for anyone else)."""
        run = self.run
        return run.arm if run is not None and not run.ended and member.student is not None else None

    def resume(self, member: Member) -> None:
        """A student's own arm, just made: as they left it (back from watching, or in the same browser), else where
        the task starts."""
        run, student, session = self.run, member.student, member.session
        if run is None or run.ended or student is None or session is None or session.arm != run.arm:
            return
        self.hold_back(session)
        kept = student.kept
        if "q" in kept:
            session.apply(lambda state: state.set_joints(kept["q"], cause="typed"))
            if not kept.get("reached", True):
                session.apply(lambda state: state.move_target(kept["target"], cause="typed"))
        elif run.challenge.kind == "branch_count" and run.challenge.joints is not None:
            session.apply(lambda state: state.set_joints(run.challenge.joints, cause="typed"))
        elif run.challenge.is_pose and session.arm == self.room.state.arm:  # from where the class's arm is, as everyone
            start = self.room.state.q  # (an arm kept from the last challenge may be on this one's answer)
            if not np.array_equal(session.state.q, start):
                session.apply(lambda state: state.set_joints(start, cause="typed"))

    def asked_of(self, arm: Arm) -> str | None:
        """What the running challenge asks (``Challenge.asks``) if it runs on ``arm``, else None: what a panel of
        that arm holds back (a session made now is handed it: ``ArmSession(asks=...)``)."""
        return self.run.challenge.asks if self.running and arm == self.run.arm else None

    def hold_back(self, session) -> None:
        """Nothing in ``session``'s panel gives away the running challenge (on its arm): a student's, and the
        presenter's, which the class sees on the projector."""
        asked = None if session is None else self.asked_of(session.arm)
        if asked is not None:
            session.hold_back(asked)

    def hold_back_live(self) -> None:
        """The class's live panel, which every browser shows (the projector too), gives away nothing of the running
        challenge on the class's arm: a question about the pose shown is asked at the joints it shows."""
        self.room.live.asked = self.asked_of(self.room.state.arm)
        self.room.app.refresher.request(self.room.live)

    def set_aside(self, member: Member) -> None:
        """A student's own arm is going (they watch the class, or leave): where it is, kept for :meth:`resume`."""
        run, student, session = self.run, member.student, member.session
        if run is not None and student is not None and session is not None and session.arm == run.arm:
            last = session.state.last
            student.kept.update(q=last.q.copy(), target=last.target.copy(), reached=last.reachable)

    def watch(self, member: Member) -> None:
        """A student's own arm tells the challenge each change (however they came to have it: the start, Explore on my own)."""
        session = member.session
        if member.observer is not None and session is not None and member.observer not in session.observers:
            session.observers.append(member.observer)
            if session not in self._rates_watched:  # once per arm: the session outlives one challenge
                self._rates_watched.add(session)
                for slider in session.velocity.sliders:
                    slider.on_update(self._guard(member, lambda _: self._rates_moved(member)))

    def show_goal(self, member: Member) -> None:
        """The reach target, in ``member``'s own scene (once: a scene reset takes it, and the classroom draws it again)."""
        session = member.session  # a student's own arm is the challenge's; the class may be shown another
        own = session is not None and session.arm == self.run.arm
        if not (own or self._on_class_arm()):  # over another arm it is not where it is asked for
            return
        drawing = session.drawing if own else self.room.drawing
        pose = goal_pose(self.run.challenge, self.run.arm, drawing.world)
        if pose is not None and member.goal is None:
            member.goal = GoalMarker(member.client.scene, pose, self.room.app.lecture, drawing.size)
            self.face_goal(member)
            if session is not None:  # its placed labels make way for the target's name (``ArmSession.names_elsewhere``)
                session.refresher.request(session)

    @staticmethod
    def face_goal(member: Member) -> None:
        """The reach target's name turned towards the middle of ``member``'s canvas, for its camera as it is now."""
        goal = member.goal
        if goal is not None:
            goal.face(member.camera.view())

    def _moved(self, member: Member, snapshot=None) -> None:
        """A student's arm changed (``snapshot``), or they typed at their answer: they are working; the projector
        draws their tool."""
        run, student = self.run, member.student
        if run is None or student is None or run.ended:
            return
        run.moved(student, snapshot.flange if snapshot is not None and run.challenge.is_pose else None)
        self._board_changed()

    def _rates_moved(self, member: Member) -> None:
        """A student's joint rates changed: their answer in a velocity challenge (set without moving the arm)."""
        if self.run is not None and self.run.challenge.kind == "velocity":
            self._moved(member)

    def double_press(self, member: Member, button: str, answer=None) -> bool:
        """Whether this press of ``button`` by ``member`` is a double click's second: the button it pressed last,
        :data:`DOUBLE_PRESS` s or less before (by the time a person clicks in, not a test's ``clock``), with the
        same ``answer`` (what the press acts on: changed, the press is a new one, however soon)."""
        now = time.monotonic()
        with self._pressing:
            last = self._presses.get(member)
            self._presses[member] = (button, answer, now)
        return last is not None and last[:2] == (button, answer) and now - last[2] <= DOUBLE_PRESS

    def check(self, member: Member) -> None:
        """Check what ``member`` has on the server (their joints, target, rates, typed answer): never what a browser
        claims. A double click checks once: its second press said "one check a second, please" under the verdict."""
        session, card = member.session, member.card
        answer = (tuple(card.typed().items()) if card is not None else (), None if session is None else (
            session.state.last.q.tobytes(), session.state.last.target.tobytes(),
            tuple(float(slider.value) for slider in session.velocity.sliders)))
        if self.double_press(member, "check", answer):
            return
        run, student, session, card = self.run, member.student, member.session, member.card
        if run is None or student is None or card is None:
            raise ValueError("there is no challenge to answer")
        if session is None:
            raise ValueError("your own arm is needed: press Explore on my own")
        challenge, snapshot = run.challenge, session.state.last
        numbers = table = rates = None
        if challenge.kind == "numbers":
            numbers = ArmState.parse_numbers(str(card.numbers.value), len(number_names(challenge, run.arm)), "your numbers")
        elif challenge.kind == "dh_table":
            table = parse_table(str(card.rows.value), card.convention_chosen()).dh
        elif challenge.kind == "velocity":
            rates = session.velocity.joint_rates()
        verdict = run.check(student, Answer(q=snapshot.q, target=snapshot.target, table=table, numbers=numbers, rates=rates))
        card.show(verdict, student.attempts)
        self._board_changed()
        if run.saved_at is None or self.clock() - run.saved_at >= SAVE_EVERY:
            self.keep_results(quiet=True)

    @_one_turnover_at_a_time
    def end(self, member: Member) -> None:
        """The presenter ends the challenge: everyone is shown the solution (a pose: every arm moves to it)."""
        with self.room._lock:
            if member.closed or self.room.presenter is not member:
                raise ValueError("only the presenter ends a challenge")
            run = self.run
            if run is None or run.ended:
                raise ValueError("no challenge is running")
            run.ended = True
            members = list(self.room.members.values())
        self.hold_back_live()
        challenge, arm = run.challenge, run.arm
        common = solution(challenge, arm, self.room.state.q if self._on_class_arm() else None)  # (the class's, if it is the arm)
        run.solution_words = common[1]
        for other in members:
            session = other.session
            own = session is not None and session.arm == arm  # a student watching the class's arm has none
            # a velocity's joint rates depend on where each arm is; any other answer is everyone's
            q, words = solution(challenge, arm, session.state.q) if own and challenge.kind == "velocity" else common
            try:
                if own:
                    session.hold_back(None)
                if own and q is not None:
                    session.apply(lambda state: state.set_joints(q, cause="typed"))
                if other.card is not None:
                    other.card.ended(words)
            except Exception:  # one browser's trouble must not keep the solution from the rest
                if not other.closed:
                    log.exception("could not show browser %s the solution", other.client.client_id)
        self.keep_results()
        self._board_changed()
        summary = run.summary()
        log.info("challenge %r ended: %d of %d solved", challenge.title, summary.solved, summary.joined)

    def download(self, member: Member) -> None:
        if self.room.presenter is not member or self.run is None:
            raise ValueError("only the presenter downloads the results, after starting a challenge")
        member.client.send_file_download(self.run.file_name, self.run.results_csv())

    def keep_results(self, quiet: bool = False) -> None:
        """The last run's results file, written to the teacher's results folder (``--results``): as students check
        (every :data:`SAVE_EVERY` s at most), as the run ends, and as the server stops, so that a teacher who never
        pressed *Download* still has them. The console names the file the first time and, unless ``quiet``, again."""
        run, folder = self.run, self.room.app.results
        if run is None or folder is None:
            return
        with self._saving:
            quiet = quiet and run.saved
            run.saved_at = self.clock()
            path = folder / run.file_name
            try:
                folder.mkdir(parents=True, exist_ok=True)
                stem = path.stem
                numbered = (folder / f"{stem}-{number}.csv" for number in itertools.count(2))

                def free(path):  # the path, or the next numbered one that no file has
                    while path.exists():
                        path = next(numbered)
                    return path

                if not run.saved:  # another run's file may have the name: two started within one second
                    path = free(path)
                written = path.with_suffix(".part")
                written.write_bytes(run.results_csv())
                try:
                    written.replace(path)  # whole or not at all: the server may be stopping
                except PermissionError:  # Windows: the teacher has the file open in a spreadsheet, which locks it
                    locked, path = path, free(path)
                    written.replace(path)
                    log.warning("%s is open in another program: the results of %r are saved as %s from now on",
                                locked.name, run.challenge.title, path.name)
                run.file_name = path.name
            except OSError as error:
                log.warning("could not save the results of %r in %s: %s", run.challenge.title, folder, error)
                told, run.unsaved = run.unsaved, f"{error.strerror or error}: {error.filename or folder}"
                if told is None:  # the teacher's board says so (the console is not on the projector)
                    self._board_changed()
                return
            told, run.saved, run.unsaved = run.unsaved, True, None
            if told is not None:
                self._board_changed()
        if not quiet:
            log.info("results of %r saved: %s", run.challenge.title, path)

    def step_out(self, member: Member, keep: bool = True) -> None:
        """``member`` leaves the challenge (their browser went: ``keep`` their attempt and arm for their return)."""
        run, student = self.run, member.student
        if student is not None and run is not None and keep:
            self.set_aside(member)
            run.leave(student, {**student.kept, **({} if member.card is None else member.card.typed())})
            self._board_changed()
        if member.session is not None and member.observer in member.session.observers:
            member.session.observers.remove(member.observer)
        for part in ("card", "goal", "tools"):
            self._take_off(member, part)
        member.student = member.observer = None

    @staticmethod
    def _take_off(member: Member, part: str) -> None:
        """``member``'s ``card``, ``goal`` or ``tools`` off their screen."""
        shown = getattr(member, part)
        if part == "tools" and shown is not None and member.camera is not None and shown.place in member.camera.on_moved:
            member.camera.on_moved.remove(shown.place)
        if shown is not None and not member.closed:
            shown.remove()
        setattr(member, part, None)

    def _on_class_arm(self) -> bool:
        """Whether the class is shown the challenge's arm, in whose world its target and the students' tools are."""
        return self.run is not None and self.room.state.arm == self.run.arm

    def class_arm_shown(self) -> None:
        """The class is shown another arm: its live panel holds back what the challenge asks of it, and the target
        and the students' tools show over the class's arm only while it is the challenge's (over another arm they
        stood where its world put them: the UR10's target by the KR210's base, its tools a third of its size)."""
        self.hold_back_live()
        if self.run is None:
            return
        with self.room._lock:
            # the presenter and the viewers (an explorer's target is over their own arm, the challenge's)
            watching = [m for m in self.room.members.values() if m is self.room.presenter or m.session is None]
        for member in watching:
            self._take_off(member, "goal")
            self._take_off(member, "tools")  # (made again for the class's drawing of the moment: its labels kept clear of)
            if member is self.room.presenter or member.student is not None:  # (not a browser that came after the end)
                self.show_goal(member)
        self._board_changed()

    def shown_elsewhere(self) -> str:
        """What the board says while the class is shown another arm than a pose challenge's ("" otherwise)."""
        run = self.run
        if run is None or not run.challenge.is_pose or self._on_class_arm():
            return ""
        choice = self.room.choice  # (a typed table by its title, mid-sentence)
        shown = CLASS_TYPED_TITLE[:1].lower() + CLASS_TYPED_TITLE[1:] if choice == CUSTOM else f"the {choice}"
        return (f"*The class is shown {shown}: the students' tools"
                f"{' and the target' if run.challenge.kind == 'reach' else ''} show with the "
                f"{choice_of(run.challenge.arm)}.*")

    def class_arm_moved(self) -> None:
        """The class's arm moved: a question about the pose shown, previewed, is previewed at its new joints."""
        presenter = self.room.presenter
        if not self.running and presenter is not None and presenter.desk is not None \
                and presenter.desk.picker.value in POSE_QUESTIONS:
            self._board_changed()

    def _board_changed(self) -> None:
        """The presenter's board redraws soon (at its own pace: a hundred students moving ask for it once)."""
        presenter = self.room.presenter
        if presenter is None or presenter.desk is None or self._board_due:
            return
        self._board_due = True
        self.boards.request(presenter.desk)

    def _render_board(self, member: Member) -> None:
        self._board_due = False
        if self.run is not None and member.tools is None and self.run.challenge.is_pose and self._on_class_arm():
            drawing = self.room.drawing
            member.tools = ClassTools(member.client.scene, drawing.world, member.camera.view, self.room.app.lecture,
                                      fixed=lambda: [*in_world(drawing.label_sets), *member.goal_name(np.eye(4))],
                                      keep_in_view=lambda points: member.camera.keep_in_view("class", points), size=drawing.size)
            member.camera.on_moved.append(member.tools.place)
        tools = member.tools
        if tools is not None and self.run is not None:
            try:
                tools.show(self.run, self.nicknames)
            except RuntimeError:  # viser's word for a removed node: a start or a hand-over took these tools meanwhile
                if not tools.removed:  # (the next drawing makes new ones)
                    raise

    def _guard(self, member: Member, handler, beside=None):
        return guard(member.client, handler, is_closed=lambda: member.closed, beside=beside)
