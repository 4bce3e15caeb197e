"""One class challenge as it runs: each student's attempt, the class's counts and mistakes, the results file.

No viser here: the classroom hands it answers read from each student's own session, and
draws what :meth:`ChallengeRun.summary` says. Why it is built so: docs/architecture.md §9.
"""

from __future__ import annotations

import csv
import dataclasses
import html
import io
import math
import re
import threading
import time
import unicodedata
from collections import Counter

import numpy as np

from ur10core import Arm
from ur10core.challenges import Answer, Challenge, Verdict, check, terms

from .gate import CONNECTIONS_PER_ADDRESS, TokenBucket, address_in

#: Checks a student may ask for: one a second (a burst of one).
CHECKS_PER_SECOND = 1.0
#: Students one run keeps (a bound on its memory, whatever joins).
MAX_STUDENTS = 1000
MAX_NICKNAME = 20
#: Combining marks kept on one letter: a Tibetan stack or a Thai vowel and tone need up to three. A letter with
#: nineteen ("zalgo" text) was drawn, in a projector's 3D label, with a blot of ink over the name above it.
MAX_MARKS = 3
#: The longest final answer kept per student (for the results file).
MAX_ANSWER = 300


def clean_nickname(text: str) -> str:
    """What a student typed as their name, made safe to show: no control characters, at most
    :data:`MAX_MARKS` combining marks on a letter, at most 20 characters.

    The projector shows it as a 3D label's text (never as HTML or markdown).

    >>> clean_nickname("  Ada\\x00\\u202e  Lovelace and a very long tail")
    'Ada Lovelace and a v'
    >>> clean_nickname("Zoe\\u0308") == "Zo\\u00eb", len(clean_nickname("B" + "\\u0301" * 19))
    (True, 4)
    """
    if not isinstance(text, str):
        raise ValueError("a nickname is text")
    kept, marks = [], 0
    for ch in unicodedata.normalize("NFC", text):  # (a letter and its accent typed apart become the one letter)
        kind = "Zs" if ch.isspace() else unicodedata.category(ch)  # (a line break or tab parts words)
        if kind.startswith("C"):  # controls, bidi overrides, ...
            continue
        marks = marks + 1 if kind.startswith("M") else 0
        if marks <= MAX_MARKS:
            kept.append(" " if kind == "Zs" else ch)
    return " ".join("".join(kept).split())[:MAX_NICKNAME]


def spreadsheet_safe(text: str) -> str:
    """A cell no spreadsheet runs as a formula (a nickname "=HYPERLINK(...)" is text)."""
    return "'" + text if text[:1] in ("=", "+", "-", "@", "\t", "\r") else text


@dataclasses.dataclass
class Student:
    """One student's attempt. Kept when their browser leaves: coming back from the same browser finds it."""

    number: int  #: 1, 2, ... in order of joining: the anonymous id the projector shows
    browser: str  #: which browser (``gate.browser_of``: its address, and its cookie's token where it has one)
    nickname: str = ""
    connected: bool = True
    acted: bool = False  #: moved their arm, typed or checked since the start
    attempts: int = 0
    solved_after: float | None = None  #: seconds from the start
    verdict: Verdict | None = None  #: the last check's
    flange: np.ndarray | None = None  #: (4, 4) where their tool is (pose tasks)
    kept: dict = dataclasses.field(default_factory=dict)  #: their session's state while they are away
    away_since: float = 0.0  #: (the run's clock) when their browser left
    bucket: TokenBucket | None = None

    @property
    def name(self) -> str:
        return self.nickname or self.numbered

    @property
    def numbered(self) -> str:
        """The name the projector shows with nicknames off."""
        return f"student {self.number}"


@dataclasses.dataclass(frozen=True)
class Summary:
    joined: int
    here: int
    working: int
    solved: int
    checked: int  #: students who have asked for a check
    groups: tuple[tuple[str, int], ...]  #: (mistake, students whose last check made it), most first
    fastest: float | None
    median: float | None
    seconds_left: float | None
    ended: bool


class ChallengeRun:
    """A started challenge: its students and their checks. Thread-safe.

    ``clock`` gives seconds (a test passes its own).
    """

    def __init__(self, challenge: Challenge, arm: Arm, time_limit: float | None = None, clock=time.monotonic) -> None:
        self.challenge, self.arm = challenge, arm
        self.clock = clock
        self.started = clock()
        #: its results file's name, after the challenge and the wall-clock time it started (one file per run)
        self.file_name = time.strftime(f"challenge-{challenge.key}-%Y-%m-%d-%H%M%S.csv")
        self.saved = False  #: its results file is on the server's disk (``ClassChallenges.keep_results``)
        #: why its results file could not be written the last time it was tried (None: it was, or was not tried)
        self.unsaved: str | None = None
        self.saved_at: float | None = None  #: when it was last written, or tried (by ``clock``): the checks' pace
        self.time_limit = time_limit if time_limit is not None else challenge.time_limit
        self.ended = False
        self.solution_words = ""  #: what the class is shown at the end
        self.students: dict[int, Student] = {}  #: by number
        self._lock = threading.Lock()

    # ------------------------------------------------------------------ students

    def join(self, browser: str) -> Student:
        """A browser joins (``gate.browser_of``): the attempt it left (if it is away), else a new one.

        One address holds at most :data:`~ur10teach.serving.gate.CONNECTIONS_PER_ADDRESS` attempts (a page that sends
        a new cookie each time must not fill the board): beyond, a new browser there takes the attempt away longest,
        as any browser from an address did before browsers were told apart."""
        with self._lock:
            for student in self.students.values():
                if not student.connected and student.browser == browser:
                    student.connected = True
                    return student
            address = address_in(browser)
            there = [s for s in self.students.values() if address_in(s.browser) == address]
            away = [s for s in there if not s.connected]
            if len(there) >= CONNECTIONS_PER_ADDRESS and away:
                student = min(away, key=lambda s: s.away_since)
                student.connected, student.browser = True, browser
                return student
            if len(self.students) >= MAX_STUDENTS:
                raise ValueError(f"this challenge already has {MAX_STUDENTS} students")
            number = len(self.students) + 1
            student = self.students[number] = Student(number, browser, bucket=TokenBucket(CHECKS_PER_SECOND, 1.0, clock=self.clock))
            return student

    def leave(self, student: Student, kept: dict) -> None:
        """Their browser has gone: keep their attempt and what their session held (``kept``) for their return."""
        with self._lock:
            student.connected = False
            student.kept = kept
            student.away_since = self.clock()

    def rename(self, student: Student, text: str) -> str:
        name = clean_nickname(text)
        with self._lock:
            student.nickname = name
        return name

    def moved(self, student: Student, flange: np.ndarray | None = None) -> None:
        """Their arm or answer changed: they are working (``flange``: where their tool is now)."""
        student.acted = True
        if flange is not None:
            student.flange = flange

    # ------------------------------------------------------------------ checks

    @property
    def seconds_left(self) -> float | None:
        if self.time_limit is None:
            return None
        return max(0.0, self.started + self.time_limit - self.clock())

    def check(self, student: Student, answer: Answer) -> Verdict:
        """Check ``answer``, read from the student's own session, exactly (``ur10core.challenges.check``).

        ``ValueError`` (nothing counted) when the challenge is over, time is up, or the student
        asked less than a second ago.
        """
        if self.ended:
            raise ValueError("the challenge has ended")
        if self.seconds_left == 0.0:
            raise ValueError("time is up: the teacher will show the solution")
        if not student.bucket.take():
            raise ValueError("one check a second, please: try again in a moment")
        verdict = check(self.challenge, self.arm, answer)  # ValueError for an answer with the wrong count of numbers
        with self._lock:
            student.acted = True
            student.attempts += 1
            if student.solved_after is None:
                student.verdict = dataclasses.replace(verdict, answer=verdict.answer[:MAX_ANSWER])
                if verdict.solved:
                    student.solved_after = self.clock() - self.started
        return verdict

    # ------------------------------------------------------------------ the class

    def summary(self) -> Summary:
        with self._lock:
            students = list(self.students.values())
        solved = sorted(s.solved_after for s in students if s.solved_after is not None)
        groups = Counter(s.verdict.group for s in students
                         if s.solved_after is None and s.verdict is not None and not s.verdict.solved)
        return Summary(
            joined=len(students), here=sum(s.connected for s in students),
            working=sum(s.acted and s.solved_after is None for s in students), solved=len(solved),
            checked=sum(s.attempts > 0 for s in students),
            groups=tuple(sorted(groups.items(), key=lambda item: (-item[1], item[0]))),
            fastest=solved[0] if solved else None, median=float(np.median(solved)) if solved else None,
            seconds_left=self.seconds_left, ended=self.ended)

    def flanges(self, nicknames: bool = True) -> tuple[list[str], np.ndarray, np.ndarray]:
        """(names, (k, 4, 4) tool poses, (k,) solved) of the students here whose tool has been seen; with
        ``nicknames`` False, each named by their number only."""
        with self._lock:
            shown = [s for s in self.students.values() if s.connected and s.flange is not None]
        poses = np.array([s.flange for s in shown]).reshape(-1, 4, 4)
        names = [s.name if nicknames else s.numbered for s in shown]
        return names, poses, np.array([s.solved_after is not None for s in shown], bool)

    def results_csv(self) -> bytes:
        """The results file: anonymous id, nickname, attempts, solved, seconds to solve, final answer.

        UTF-8 with a byte-order mark: without it, Excel on Windows reads the file in the system's code page, and a
        nickname "Zoë" or an answer "90°" arrives as "ZoÃ«" and "90Â°". The seconds are whole: where the decimal
        mark is a comma (most of Europe), Excel reads "12.5" as a date or as 125."""
        out = io.StringIO()
        writer = csv.writer(out)
        writer.writerow(["student", "nickname", "attempts", "solved", "seconds_to_solve", "final_answer"])
        with self._lock:
            students = sorted(self.students.values(), key=lambda s: s.number)
        for s in students:
            writer.writerow([s.number, spreadsheet_safe(s.nickname), s.attempts, "yes" if s.solved_after is not None else "no",
                             "" if s.solved_after is None else f"{s.solved_after:.0f}",
                             spreadsheet_safe(s.verdict.answer if s.verdict else "")])
        return out.getvalue().encode("utf-8-sig")


def terms_markdown(challenge: Challenge, arm: Arm | None = None) -> str:
    """What the check takes and asks (``ur10core.challenges.terms``), its "Given:", "Asked:", "Checked:" in bold."""
    return re.sub(r"\b(Given|Asked|Checked):", r"**\1:**", html.escape(terms(challenge, arm), quote=False))


def summary_markdown(run: ChallengeRun) -> str:
    """The projector's view of the class: the task's terms, counts, times, and the mistakes most made."""
    s = run.summary()
    lines = [f"### {html.escape(run.challenge.title, quote=False)}", terms_markdown(run.challenge, run.arm),
             f"#### **{s.solved}** solved · **{s.working}** working · **{s.joined}** joined"
             + (f" ({s.joined - s.here} away)" if s.here < s.joined else "")]
    if s.fastest is not None:
        lines.append(f"Time to solve: fastest {_duration(s.fastest)}, median {_duration(s.median)}")
    if s.ended:
        lines.append(f"**Ended**: the solution is on every screen. {html.escape(run.solution_words)}")
        if run.saved and run.unsaved is None:
            lines.append(f"Results saved on the server's computer as *{run.file_name}*.")
    elif s.seconds_left is not None:
        lines.append("**Time is up.**" if s.seconds_left == 0 else f"Time left: {_duration(s.seconds_left)} (as of this update)")
    if run.unsaved is not None:
        lines.append(f"**The results could not be saved**: {html.escape(run.unsaved, quote=False)}. "
                     "*Download results (CSV)* still gives them; they are saved again at the next check and at the end.")
    if s.groups:
        lines.append("\n".join(["| students | last wrong answer |", "|:---:|---|", *(f"| {n} | {html.escape(g)} |" for g, n in s.groups)]))
    elif s.checked:
        lines.append("No wrong answers standing.")
    return "\n\n".join(lines)


def _duration(seconds: float) -> str:
    minutes, rest = divmod(int(math.floor(seconds)), 60)
    return f"{minutes} min {rest:02d} s" if minutes else f"{rest} s"
