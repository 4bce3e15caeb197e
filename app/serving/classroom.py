"""Shared demo mode (``--shared``): everyone watches the presenter's arm.

Why it is built so: docs/architecture.md §5.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import secrets
import threading
import time
from typing import TYPE_CHECKING

import numpy as np
import viser

from ur10core import Arm

from ..features.arm_picker import (
    ARM_CHOICES,
    CLASS_TYPED_TITLE,
    CUSTOM,
    SWITCH_INTERVAL,
    ArmPicker,
    panel_title,
    show_title,
)
from ..features.branch_labels import OwnLabels
from ..features.camera import CameraControls, ClassView
from ..features.challenge import ChallengeCard, ChallengeDesk, ClassTools, GoalMarker  # a member's parts
from ..features.course_arms.desktop_arm import EXPLORER_ROOT as DESKTOP_EXPLORER_ROOT
from ..features.course_arms.editor import starting_table
from ..features.course_arms.scene import EXPLORER_ROOT
from ..features.drawings import arm_drawing
from ..features.floor import add_floor_grid
from ..features.ik_target import OWN_SEARCH, branches_markdown
from ..features.joint_panel import joints_markdown
from ..features.lecture import size_labels
from ..features.readouts import flange_markdown
from ..features.singularity import factors_html
from ..feedback import guard, notify
from ..session import ArmSession
from ..state import ArmState
from ..style import half_width
from ..view import HELD_BACK
from ..viser_internals import after_broadcast
from .class_challenges import ClassChallenges
from .gate import RETURN_WINDOW, address_in, browser_of, on_a_phone
from .joining import JoinHelp

if TYPE_CHECKING:
    from .server import TeachingServer

log = logging.getLogger(__name__)

#: Letters and digits that cannot be mistaken for one another when read off a projector.
JOIN_ALPHABET = "ACDEFHJKMNPRTUVWXY3479"
JOIN_LENGTH = 6
#: Wrong codes from one address that lock the join code for it, at first for LOCKOUT_SECONDS, twice as
#: long each time after that up to MAX_LOCKOUT_SECONDS, until it enters the right one.
MAX_WRONG_CODES = 5
LOCKOUT_SECONDS = 10.0
MAX_LOCKOUT_SECONDS = 600.0
#: Addresses whose guesses are remembered (the oldest forgotten beyond it).
MAX_GUESSERS = 10_000
VIEWER, PRESENTER, EXPLORER = "viewer", "presenter", "explorer"
EXPLORE = "Explore on my own"
#: The live panel's name for a typed table's branch search: a viewer has no such button of their own
CLASS_SEARCH = f"The presenter's {OWN_SEARCH} (yours, after *{EXPLORE}*)"


def make_join_code() -> str:
    """Six characters from :data:`JOIN_ALPHABET`, shown as ``ABC-DEF``."""
    code = "".join(secrets.choice(JOIN_ALPHABET) for _ in range(JOIN_LENGTH))
    return f"{code[:3]}-{code[3:]}"


def normalise_code(text: str) -> str:
    """A typed join code as :func:`make_join_code` makes one, without its dash: any case, spaces, full width.

    >>> normalise_code(" abc-def "), normalise_code("ａｂｃ－ｄｅｆ")
    ('ABCDEF', 'ABCDEF')
    """
    return "".join(ch for ch in half_width(text).upper() if ch.isalnum())


@dataclasses.dataclass
class Guesses:
    """One address's wrong join codes."""

    wrong: int = 0  #: since its last lock-out or its last right code
    lockouts: int = 0  #: since its last right code: each lasts twice as long as the one before
    locked_until: float = 0.0
    while_locked: int = 0  #: tries refused during its current lock-out


class LivePanel:
    """The shared, read-only panel everyone sees: the presenter's arm, joints, branches, tool pose and det J's factors.

    Redrawn three times a second rather than ten: viser serialises and compresses a shared
    widget's update once per browser, and in a lecture hall of a hundred that was most of
    the server's work (BENCHMARKS.md, *lecture hall*). It closes when the presenter shows
    the class another arm, whose own panel takes its place.
    """

    panel_interval = 0.3

    def __init__(self, gui: viser.GuiApi, state: ArmState, title: str, overlay=None, presenter_here: bool = False) -> None:
        self._state = state
        self._overlay = overlay  #: the class's singularity overlay: its gauges show with it (or always, without one)
        self.presenter_here = presenter_here
        #: what a class challenge running on this arm asks (``Challenge.asks``): its answer is not shown here, on any
        #: screen (``ClassChallenges.hold_back_live``)
        self.asked: str | None = None
        self.closed = False  # the refresher's protocol
        self.on_render: list = []  #: called before each redraw (the shared scene's labels sized for the hall)
        # last in every panel: below the presenter's or an explorer's own controls
        self.folder = gui.add_folder("Live from the presenter", order=1e9)
        with self.folder:
            self.status = gui.add_markdown(self._status())
            self.title = gui.add_markdown(f"**{title}**")
            self.joints = gui.add_markdown("")
            self.branches = gui.add_markdown("")
            self.flange = gui.add_markdown("")
            self.gauges = gui.add_html("")
        self.render_panel()

    def _status(self) -> str:
        if self.presenter_here:
            return "The presenter is moving this arm; you can turn the view as you like."
        return "No presenter yet: the teacher takes the arm from their own computer, or with the join code."

    def remove(self) -> None:
        self.closed = True
        self.folder.remove()

    def render_panel(self) -> None:
        snapshot, arm = self._state.last, self._state.arm
        for sized in self.on_render:
            sized()
        self.status.content = self._status()
        self.joints.content = joints_markdown(arm, snapshot.q)
        # the branches give both θ1, the tool pose p, the gauges det J's factors (as the sessions' own folders do)
        self.branches.content = HELD_BACK if self.asked == "theta1" else branches_markdown(snapshot, CLASS_SEARCH)
        self.flange.content = HELD_BACK if self.asked == "position" else flange_markdown(snapshot)
        # a shared widget's update is sent to every browser: the gauges only while the presenter shows the overlay
        self.gauges.visible = self._overlay is None or self._overlay.enabled
        if self.gauges.visible:
            self.gauges.content = HELD_BACK if self.asked == "det_j" else factors_html(arm, snapshot.q)


class Member:
    """One browser in the classroom and its "Classroom" folder."""

    def __init__(self, client: viser.ClientHandle) -> None:
        self.client = client
        self.browser = browser_of(client)  #: which browser it is, as its return is known
        self.role = VIEWER
        self.session: ArmSession | None = None
        self.folder: viser.GuiFolderHandle | None = None
        self.picker: ArmPicker | None = None  #: the presenter's: which arm the class sees
        self.camera: CameraControls | None = None
        self.join_code: viser.GuiInputHandle | None = None  #: a viewer's box for the presenter's code
        self.join_help: JoinHelp | None = None  #: the addresses to join at, and the teacher's QR codes of them
        self.desk: ChallengeDesk | None = None  #: the presenter's "Challenge" folder
        self.tools: ClassTools | None = None  #: the presenter's view of every student's tool
        self.student = None  #: a student's attempt at the running challenge (``challenge_run.Student``)
        self.card: ChallengeCard | None = None  #: and their "Challenge" folder
        self.goal: GoalMarker | None = None
        self.observer = None  #: what the student's session calls after each change
        self.controls_lock = threading.Lock()  #: held while its "Classroom" folder is drawn
        #: a viewer's own copies of the class's labels, placed for its camera where the shared placing does not fit
        self.own_labels: OwnLabels | None = None
        self.labels_held = False  #: none made for it now (it is on its way to exploring)
        self.labels_lock = threading.Lock()
        #: what the student's own arm showed and its folders were set to, by arm: it comes back so next time they explore
        self.displays: dict[Arm, dict] = {}
        self.closed = False

    @property
    def address(self) -> str:
        """Where it connected from (its browser's address)."""
        return address_in(self.browser)

    def goal_name(self, frame: np.ndarray) -> list[tuple]:
        """The challenge target's name where this browser shows it (``GoalMarker.name``), for placed labels to keep clear of."""
        goal = self.goal
        return [] if goal is None else [goal.name(frame)]


class Classroom:
    def __init__(self, app: "TeachingServer") -> None:
        self.app = app
        self.code = make_join_code()
        self.choice = app.first_choice  #: the arm the class is shown (an ``ARM_CHOICES`` label)
        #: each arm the class has been shown, by label: it comes back where the presenter left it
        self.states: dict[str, ArmState] = {}
        self.displays: dict[str, dict] = {}  #: and what the presenter had shown on it (overlay, cloud, ...)
        self.typed: tuple[Arm, str, str] | None = None  #: (arm, text, convention) of the table the presenter built last
        self.state = self._state_of(self.choice)
        self.drawing = self._draw()
        # drawn whole for those who join before a presenter (the live panel lists the branches by their ghosts' colours);
        # from then on the presenter's session draws it
        self.drawing.render(self.state.last)
        self.drawing.render_panel(self.state.last)
        self.live = self._live_panel(self.choice)
        self.tab_title = show_title(app.server.gui, panel_title(self.choice, app.arm.name))
        self._last_switch = -math.inf
        self.members: dict[int, Member] = {}
        self.presenter: Member | None = None
        self.guesses: dict[str, Guesses] = {}  #: by address
        #: (address, when) of a presenter whose browser left: the next browser from there presents again, unless
        #: another has taken the role (viser makes a browser that reconnects, the projector's reloaded, a new client)
        self.presenter_left: tuple[str, float] | None = None
        self.claims = 0  #: join codes answered, right or wrong (for the tests)
        self.challenges = ClassChallenges(self, app.challenges)  #: the presenter's challenges to the class
        self._lock = threading.RLock()

    def _state_of(self, label: str) -> ArmState:
        if label not in self.states:
            name, app = ARM_CHOICES[label], self.app
            if name is None:
                self.states[label] = ArmState(app.arm, body_points=app.models.outline)
            elif name == "custom":
                self.typed = self.typed or starting_table()
                self.states[label] = ArmState(self.typed[0])
            else:
                self.states[label] = ArmState(Arm.preset(name))
        return self.states[label]

    def _models(self, arm: Arm):
        """UR's meshes for the server's own UR10; other arms are drawn from their tables."""
        return self.app.models if arm == self.app.arm else None

    def _live_panel(self, title: str, presenter_here: bool = False) -> LivePanel:
        """The live panel of the class's arm; before each redraw the shared scene's 3D labels are sized for the hall."""
        live = LivePanel(self.app.server.gui, self.state, title, self.drawing.overlay, presenter_here)
        live.on_render.append(lambda: size_labels(self.app.server.scene, self.app.lecture))
        return live

    def _draw(self):
        """The class's arm in the shared scene, with a marker for its target (only the presenter has a gizmo)."""
        arm, state = self.state.arm, self.state
        drawing = arm_drawing(self.app.server.scene, arm, state.last, self._models(arm), target_marker=True)
        view = ClassView(drawing, state)
        for pool in drawing.label_sets:  # its 3D labels placed apart for the camera each browser frames it with
            pool.view = view
        return drawing

    # ------------------------------------------------------------------ clients

    def connect(self, client: viser.ClientHandle) -> None:
        member = Member(client)
        with self._lock:
            self.members[client.client_id] = member
            left, free = self.presenter_left, self.presenter is None
            due_back = left is not None and self.app.clock() - left[1] <= RETURN_WINDOW  # a presenter's page may return
            back = free and due_back and left[0] == member.browser
            if back:  # once: a second tab from there is a viewer
                self.presenter_left = None
            # the teacher's own screen, where the console shows the code anyway, takes a role nobody has or awaits
            own_screen = free and not due_back and self.app.gate.trusted(member.address)
        # one camera per browser, whatever its role: it frames the arm this browser is watching
        member.camera = CameraControls(
            client, lambda: self._watched(member),
            lambda handler: guard(client, handler, is_closed=lambda: member.closed), lecture=self.app.lecture,
            arm=self.state.arm, body_radius=self._body_radius(), light=self.app.light, phone=on_a_phone(client),
        )
        member.camera.on_moved.append(lambda: self.challenges.face_goal(member))
        member.camera.on_moved.append(lambda: self._fit_labels(member))
        self.app.screens.probe(client)  # (its labels are placed for the screen its page reports)
        if back:
            self._present(member)
            notify(client, "Welcome back", "You are presenting again.", color="blue")
        elif own_screen:
            self._present(member)
        self._draw_controls(member)
        if self.challenges.running:
            self.challenges.enlist(member)
        member.camera.frame()  # (its page may send no other camera until the student moves it)

    def _watched(self, member: Member):
        """The newest snapshot of the arm ``member`` looks at: its own, or the class's."""
        session = member.session  # read once: a hand-over on another thread may take it away meanwhile
        if session is not None:
            return session.drawing.framed(session.state.last)
        return self.drawing.framed(self.state.last)

    def _body_radius(self) -> float:
        return self.drawing.body_radius

    def disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            member = self.members.pop(client.client_id, None)
            if member is None:
                return
            member.closed = True
            if member.camera is not None:
                member.camera.close()
            with member.labels_lock:  # (after which none are made for it)
                if member.own_labels is not None:
                    member.own_labels.forget()
            self.challenges.step_out(member)
            if member.desk is not None:
                member.desk.closed = True
            if member.session is not None:
                member.session.close()
                member.session = None
            if self.presenter is member:
                self.presenter = None
                self.live.presenter_here = False
                self.presenter_left = (member.browser, self.app.clock())
        self.app.refresher.request(self.live)

    def members_from(self, address: str) -> list[Member]:
        """The browsers in the class that connected from ``address``."""
        with self._lock:
            return [member for member in self.members.values() if member.address == address]

    def join_helps(self) -> list[JoinHelp]:
        """The addresses to join at, as each browser in the class shows them."""
        with self._lock:
            return [member.join_help for member in self.members.values() if member.join_help is not None]

    @property
    def sessions(self) -> dict[int, ArmSession]:
        """The sessions of the presenter and the explorers."""
        with self._lock:
            return {cid: m.session for cid, m in self.members.items() if m.session is not None}

    # ------------------------------------------------------------------ roles

    def claim(self, member: Member, code: str) -> None:
        """Make ``member`` the presenter if ``code`` is the join code (``ValueError`` if not)."""
        address = member.address
        with self._lock:  # one claim at a time, and none for a browser that has gone meanwhile
            self.claims += 1
            if member.closed:
                return
            now = time.monotonic()
            guesses = self.guesses.get(address) if not self.app.gate.trusted(address) else None
            if guesses is not None and now < guesses.locked_until:
                guesses.while_locked += 1
                raise ValueError(f"too many wrong codes from this computer: the code works again in "
                                 f"{guesses.locked_until - now:.0f} s")
            # compared as bytes: any text a browser sends is a wrong code, not a TypeError
            if not secrets.compare_digest(normalise_code(code).encode(), normalise_code(self.code).encode()):
                self._wrong_code(address, member, now)
                raise ValueError("that is not the join code (the teacher's screen shows it)")
            self.guesses.pop(address, None)
            if self.presenter is member:
                return
            self._present(member)
        self._draw_controls(member)

    def _present(self, member: Member) -> None:
        """``member`` takes the role of presenter from whoever has it."""
        with self._lock:
            previous = self.presenter
            if previous is not None:
                self._leave_role(previous)
                self._draw_controls(previous)
            self.challenges.step_out(member)  # a student who presents now: their attempt is kept
            self._leave_role(member)
            member.session, member.role = self._presenter_session(member), PRESENTER
            self.presenter, self.presenter_left = member, None
            self.live.presenter_here = True
        self.app.refresher.request(self.live)
        log.info("client %s is presenting", member.client.client_id)

    def _presenter_session(self, member: Member) -> ArmSession:
        """The presenter's panel and gizmo, driving the class's arm in the shared scene."""
        app, arm = self.app, self.state.arm
        editor = {} if self.choice != CUSTOM else dict(  # a table built shows the class its arm
            text=self.typed[1], convention=self.typed[2],
            rebuild=lambda new, text, convention: self.show_arm(member, CUSTOM, typed=(new, text, convention)))
        session = ArmSession(member.client, arm, app.refresher, app.drags, models=self._models(arm), state=self.state,
                             server=app.server, drawing=self.drawing, own_camera=False, asks=self.challenges.asked_of(arm),
                             **editor)
        session.follow_lecture_mode(member.camera.lecture)
        session.names_elsewhere = member.goal_name
        session.observers.append(lambda _: app.refresher.request(self.live))
        session.redrawn.append(lambda: app.refresher.request(self.live))
        session.observers.append(lambda _: self.challenges.class_arm_moved())
        session.watch_camera(member.camera)  # the browser's own camera, for the workspace sections
        app.janitor.settle()
        return session

    def _wrong_code(self, address: str, member: Member, now: float) -> None:
        """Count a wrong code from ``address`` and lock it out after :data:`MAX_WRONG_CODES` (never this machine)."""
        if self.app.gate.trusted(address):
            log.warning("a wrong join code from %s, this machine (browser %s)", address, member.client.client_id)
            return
        guesses = self.guesses.pop(address, None) or Guesses()
        self.guesses[address] = guesses  # the most recent guesser last: the oldest is forgotten first
        if len(self.guesses) > MAX_GUESSERS:
            del self.guesses[next(iter(self.guesses))]
        guesses.wrong += 1
        log.warning("a wrong join code from %s (browser %s; %d since its last lock-out)", address,
                    member.client.client_id, guesses.wrong)
        if guesses.wrong >= MAX_WRONG_CODES:
            seconds = min(MAX_LOCKOUT_SECONDS, LOCKOUT_SECONDS * 2**guesses.lockouts)
            log.warning("the join code is locked for %s for %.0f s after %d wrong codes (%d more tries refused "
                        "during its last lock-out)", address, seconds, guesses.wrong, guesses.while_locked)
            guesses.wrong, guesses.lockouts, guesses.locked_until, guesses.while_locked = 0, guesses.lockouts + 1, now + seconds, 0

    def can_switch(self) -> bool:
        """Whether the class's arm may change now (:data:`SWITCH_INTERVAL` after the last change)."""
        return self.app.clock() - self._last_switch >= SWITCH_INTERVAL

    def show_arm(self, member: Member, label: str, paced: bool = True, typed: tuple[Arm, str, str] | None = None) -> None:
        """The presenter shows the class another arm (``ARM_CHOICES``): everyone's scene and live panel follow.

        Each arm comes back where the presenter left it; a new one starts at its home pose, as does a table
        ``typed`` in the presenter's DH editor, (arm, text, convention), shown as ``CUSTOM``.
        ``ValueError`` for anyone but the presenter, or (``paced``) sooner than
        :data:`SWITCH_INTERVAL` after the last change.
        """
        if label not in ARM_CHOICES:
            raise ValueError(f"arm: {label!r:.40} is not one of the choices")
        failed = None
        with self._lock:
            if member.closed or self.presenter is not member:
                raise ValueError("only the presenter chooses the class's arm")
            if label == self.choice and typed is None:
                return
            if paced and not self.can_switch():
                raise ValueError(f"one change of arm every {SWITCH_INTERVAL:g} s, please: try again in a moment")
            previous = self.choice
            self.displays[previous] = member.session.display_choices()
            kept = self.typed, dict(self.states), dict(self.displays)
            if typed is not None:
                self.typed = typed
                self.states.pop(CUSTOM, None)
                self.displays.pop(CUSTOM, None)
            member.session.remove()
            member.session = None
            self.live.remove()
            try:
                self._draw_class(label)
            except Exception as error:  # the shared scene is cleared by then: the class sees the arm it had, not nothing
                failed = error
                self.typed, self.states, self.displays = kept
                self._draw_class(previous)
            session = self._presenter_session(member)
            session.show_choices(self.displays.get(self.choice, {}))
            member.session = session  # shown as left before anyone finds it
            self._last_switch = self.app.clock()
            members = list(self.members.values())
        self.app.janitor.soon()  # the arm shown before, its drawing and the presenter's panel for it hold cycles
        self._draw_controls(member)
        for other in members:
            if other.role == EXPLORER:
                self._hide_class_arm(other)
            elif other.camera is not None:  # the presenter and the viewers look at the new arm
                other.camera.show_arm(self._body_radius(), self.state.arm)
                other.camera.frame()
        self.challenges.class_arm_shown()  # (redraws the live panel)
        if failed is not None:  # a challenge must not start on the arm the class had
            raise RuntimeError(f"the {label} could not be drawn; the class still sees the {previous}") from failed
        log.info("the class is shown the %s", label)

    def _draw_class(self, label: str) -> None:
        """The arm ``label`` in the shared scene, in place of everything there, and its live panel."""
        app = self.app
        app.server.scene.reset()
        add_floor_grid(app.server.scene)
        self.choice = label
        self.state = self._state_of(label)
        self.drawing = self._draw()
        title = CLASS_TYPED_TITLE if label == CUSTOM else label
        self.live = self._live_panel(title, presenter_here=True)
        self.tab_title = show_title(app.server.gui, panel_title(title, app.arm.name), self.tab_title)

    def stop_presenting(self, member: Member) -> None:
        with self._lock:
            if self.presenter is member:
                self._leave_role(member)
                self.presenter = None
                self.live.presenter_here = False
        self._draw_controls(member)
        self.app.refresher.request(self.live)

    def explore(self, member: Member) -> None:
        """A private copy of the class's arm, starting from the presenter's pose (a student's: the challenge's arm)."""
        app = self.app
        with self._lock:
            if member.role == EXPLORER:
                return
            if self.presenter is member:
                self.stop_presenting(member)
            arm = self.challenges.arm_for(member) or self.state.arm
            models = self._models(arm)
            self._fit_labels(member, hold=True)  # (its own arm's labels take the same names)
            member.session = ArmSession(
                member.client, arm, app.refresher, app.drags, models=models, own_camera=False,
                state=ArmState(arm, self.state.q if arm == self.state.arm else None,
                               body_points=None if models is None else models.outline),
                root=DESKTOP_EXPLORER_ROOT if arm.dh is None else EXPLORER_ROOT, asks=self.challenges.asked_of(arm))
            member.session.show_choices(member.displays.get(arm, {}))
            member.session.follow_lecture_mode(member.camera.lecture)
            member.session.follow_light_view(member.camera.light)
            member.session.names_elsewhere = member.goal_name
            member.session.watch_camera(member.camera)
            app.janitor.settle()
            member.role = EXPLORER
            self._hide_class_arm(member)
        self.challenges.resume(member)  # a student's arm as they left it, before it tells the challenge of changes
        self.challenges.watch(member)
        self._draw_controls(member)

    def _hide_class_arm(self, member: Member) -> None:
        """In an explorer's browser, hide what of the class's arm its own arm does not already cover.

        A private UR10 reuses the shared UR10's scene names, which hides all of it but the
        presenter's target marker; a private course arm has a root of its own. The hiding waits
        for the class's arm, just drawn anew, to have left for that browser: sent first, it
        could arrive after the class's arm and be replaced by it.
        """
        drawing = self.drawing

        def hide() -> None:  # on viser's event loop, which must not wait for the classroom's lock
            session = member.session
            if member.closed or member.role != EXPLORER or session is None or self.drawing is not drawing:
                return  # gone, back to watching, or the class's arm changed again (that change hides it)
            for name in set(drawing.roots) - set(session.drawing.roots):
                member.client.scene.add_frame(name, show_axes=False, visible=False)

        after_broadcast(member.client, hide)

    def rejoin(self, member: Member) -> None:
        """Back to watching the presenter: drop the private arm (the shared one shows again)."""
        with self._lock:
            if member.role != EXPLORER:
                return
            self._leave_role(member)
        self._draw_controls(member)

    def _leave_role(self, member: Member) -> None:
        self.challenges.set_aside(member)
        if member.session is not None:
            if member.role == EXPLORER:
                member.displays[member.session.arm] = member.session.display_choices()
            member.session.remove()
            member.session = None
            self.app.janitor.soon()
        if member.role == EXPLORER:
            member.client.scene.reset()  # the private arm goes; the shared one is visible again
            if member.camera is not None:
                member.camera.light.scene_reset()
            if member.goal is not None:  # and so did the challenge's target, which a student still needs
                member.goal = None
                self.challenges.show_goal(member)
        if member.camera is not None:  # framed with the class's arm's room again, its views named in its axes
            member.camera.show_arm(self._body_radius(), self.state.arm)
        member.role = VIEWER
        with member.labels_lock:
            member.labels_held = False  # (its own arm's labels are gone)

    # ------------------------------------------------------------------ the Classroom folder

    def _draw_controls(self, member: Member) -> None:
        """The "Classroom" folder for ``member``'s role (and a presenter's "Challenge" folder), one drawing at a
        time: a claim from another browser redraws a presenter's controls while they may still be being drawn."""
        with member.controls_lock:
            self._draw_controls_now(member)
        self._fit_labels(member)  # (a new role)

    def _fit_labels(self, member: Member, hold: bool = False) -> None:
        """A viewer whose canvas lies partly under the panel's sheet (a phone's, held upright) gets the class's
        labels placed for its own camera, which the shared placing, for the class's larger screens, crowds; any other
        browser the shared ones, and so does one on its way to exploring (``hold``, until it watches again: its own
        arm's labels take the same names, and a camera move while its arm is being built must not make copies)."""
        with member.labels_lock:
            member.labels_held |= hold
            own, pools = member.own_labels, self.drawing.label_sets
            fits = not (member.closed or member.labels_held) and member.role == VIEWER and member.camera is not None and (
                member.camera.view().covered > 0)
            if own is not None and (not fits or own.of is not pools):
                member.own_labels = None
                own.remove()
            if fits and member.own_labels is None:
                member.own_labels = OwnLabels(member.client.scene, pools, member.camera.view)
            elif fits:
                own.place()

    def _draw_controls_now(self, member: Member) -> None:
        if member.closed:
            return
        gui = member.client.gui

        def action(handler):
            return guard(member.client, handler, is_closed=lambda: member.closed)

        if member.folder is not None:
            member.folder.remove()  # and the picker in it
        if member.desk is not None and member.role != PRESENTER:
            member.desk.remove()
            member.desk = None
            self.challenges.step_out(member, keep=False)  # and the class's tools from its scene
        if member.desk is None and member.role == PRESENTER:
            member.desk = self.challenges.desk(member)
        member.folder, member.picker = gui.add_folder("Classroom", order=0.0), None
        with member.folder:
            member.join_help = None
            if self.app.open_to_network:  # on the projector, where the class reads it; its QR code on the teacher's screen
                member.join_help = JoinHelp(member.client, self.app.join_urls, guard=action,
                                            teacher=member.role == PRESENTER or self.app.gate.trusted(member.address))
            if member.role == PRESENTER:
                gui.add_markdown("You are **presenting**: everyone sees your arm, target and overlays.")
                stop = gui.add_button("Stop presenting", icon=viser.Icon.PLAYER_STOP)
                stop.on_click(action(lambda _: self.stop_presenting(member)))
                member.picker = ArmPicker(gui, self.choice, lambda label: self.show_arm(member, label), action,
                                          hint="The arm the whole class sees: its branches, singularities and DH frames")
            elif member.role == EXPLORER:
                gui.add_markdown("You are **exploring on your own**: nobody else sees this arm.")
                back = gui.add_button("Back to the presenter's arm", icon=viser.Icon.ARROW_BACK_UP)
                back.on_click(action(lambda _: self.rejoin(member)))
            else:
                gui.add_markdown("You are **watching** the presenter's arm.")
                explore = gui.add_button(EXPLORE, icon=viser.Icon.ROBOT)
                explore.on_click(action(lambda _: self.explore(member)))
                code = member.join_code = gui.add_text("Join code", "", hint="The code on the teacher's screen makes this browser the presenter")
                claim = gui.add_button("Become presenter", icon=viser.Icon.PRESENTATION)
                claim.on_click(action(lambda _: self.claim(member, code.value)))
