"""Shared demo mode (``--shared``): everyone watches the presenter's arm.

The demo arm lives in viser's *shared* scene and a shared, read-only "Live from the
presenter" panel, so a redraw is serialised once and broadcast to every browser —
thirty students cost the server one redraw, not thirty.

* A browser starts as a **viewer**: it sees the presenter's arm, target, branches and
  overlays move live; its camera is its own.
* viser has no authentication, so the server prints a short **join code** at start-up;
  the browser that enters it becomes the **presenter** and gets the full panel and the
  gizmo (its own, client-scoped: a shared gizmo would let anyone drag it). Entering the
  code elsewhere hands the role over. Wrong codes from one address lock the code for that
  address for a while, longer each time, however many tabs it guesses from; every wrong
  code is logged on the teacher's console (grouped by address), and this machine, where
  the teacher sits, is never locked out.
* A viewer can **explore on their own**: a private arm starting from the presenter's
  pose, drawn with the same scene names in the browser's own scope, which hides the
  shared arm for that browser only. **Back to the presenter's arm** removes it again.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import secrets
import threading
import time
from typing import TYPE_CHECKING

import viser

from ur10core import Arm

from ..features.arm_picker import ARM_CHOICES, CLASS_CHOICES, SWITCH_INTERVAL, UR10, ArmPicker, panel_title
from ..features.camera import BODY_RADIUS, CameraControls
from ..features.course_arms import panel as course_panel
from ..features.course_arms.desktop_arm import EXPLORER_ROOT as DESKTOP_EXPLORER_ROOT
from ..features.course_arms.desktop_arm import DesktopArmScene
from ..features.course_arms.scene import EXPLORER_ROOT, CourseArmScene
from ..features.course_arms.session import CourseArmSession, arm_scene, body_radius
from ..features.course_arms.state import CourseArmState
from ..feedback import guard
from .gate import address_of
from ..features.floor import add_floor_grid
from ..features.ik_target import branches_markdown
from ..features.readouts import flange_markdown, joints_markdown
from ..features.singularity import alarm, factor_levels, gauges_html
from ..state import ArmState
from ..style import DANGER_RED, SAFE_GREEN, blend

if TYPE_CHECKING:
    from .server import TeachingServer
    from ..session import ClientSession

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
#: Where the shared UR10 is drawn (``SceneViews``): an explorer of another arm hides these in its browser.
UR10_ROOTS = ("/base_frame", "/arm", "/target", "/ghosts", "/floor_hits", "/overlay")


def make_join_code() -> str:
    """Six characters from :data:`JOIN_ALPHABET`, shown as ``ABC-DEF``."""
    code = "".join(secrets.choice(JOIN_ALPHABET) for _ in range(JOIN_LENGTH))
    return f"{code[:3]}-{code[3:]}"


def normalise_code(text: str) -> str:
    return "".join(ch for ch in text.upper() if ch.isalnum())


@dataclasses.dataclass
class Guesses:
    """One address's wrong join codes."""

    wrong: int = 0  #: since its last lock-out or its last right code
    lockouts: int = 0  #: since its last right code: each lasts twice as long as the one before
    locked_until: float = 0.0
    while_locked: int = 0  #: tries refused during its current lock-out


class LivePanel:
    """The shared, read-only panel everyone sees: the presenter's joints, pose, branches, gauges.

    Redrawn three times a second rather than ten: viser serialises and compresses a shared
    widget's update once per browser, and in a lecture hall of a hundred that was most of
    the server's work (BENCHMARKS.md, *lecture hall*). It closes when the presenter shows
    the class another arm, whose own panel takes its place.
    """

    panel_interval = 0.3

    def __init__(self, gui: viser.GuiApi, state: ArmState, overlay_enabled, presenter_here: bool = False) -> None:
        self._state = state
        self._overlay_enabled = overlay_enabled
        self._reach = state.arm.a2 + state.arm.a3
        self.presenter_here = presenter_here
        self.closed = False  # the refresher's protocol
        first = state.last
        # last in every panel: below the presenter's or an explorer's own controls
        self.folder = gui.add_folder("Live from the presenter", order=1e9)
        with self.folder:
            self.status = gui.add_markdown(self._status())
            self.joints = gui.add_markdown(joints_markdown(first.q, with_controller=False))
            self.branches = gui.add_markdown(branches_markdown(first))
            self.flange = gui.add_markdown(flange_markdown(first))
            self.gauges = gui.add_html("", visible=False)

    def _status(self) -> str:
        if self.presenter_here:
            return "The presenter is moving this arm; you can turn the view as you like."
        return "No presenter yet: the teacher enters the join code to take the arm."

    def remove(self) -> None:
        self.closed = True
        self.folder.remove()

    def render_panel(self) -> None:
        snapshot = self._state.last
        self.status.content = self._status()
        self.joints.content = joints_markdown(snapshot.q, with_controller=False)
        self.branches.content = branches_markdown(snapshot)
        self.flange.content = flange_markdown(snapshot)
        self.gauges.visible = self._overlay_enabled()
        if self.gauges.visible:
            levels = factor_levels(snapshot, self._reach)
            colors = [blend(SAFE_GREEN, DANGER_RED, alarm(level)) for level in levels]
            self.gauges.content = gauges_html(snapshot, levels, colors)


class CourseLivePanel(LivePanel):
    """The live panel for one of the course's other arms: the presenter's joints, branches and det J's factors."""

    def __init__(self, gui: viser.GuiApi, state: CourseArmState, title: str, presenter_here: bool = False) -> None:
        self._state = state
        self.presenter_here = presenter_here
        self.closed = False
        arm, first = state.arm, state.last
        self.folder = gui.add_folder("Live from the presenter", order=1e9)
        with self.folder:
            self.status = gui.add_markdown(self._status())
            self.arm = gui.add_markdown(f"**{title}**")
            self.joints = gui.add_markdown(course_panel.joint_text(arm, first.q))
            self.branches = gui.add_markdown(course_panel.branches_markdown(arm, first))
            self.gauges = gui.add_html(course_panel.factors_html(arm, first.q))

    def render_panel(self) -> None:
        snapshot, arm = self._state.last, self._state.arm
        self.status.content = self._status()
        self.joints.content = course_panel.joint_text(arm, snapshot.q)
        self.branches.content = course_panel.branches_markdown(arm, snapshot)
        self.gauges.content = course_panel.factors_html(arm, snapshot.q)


@dataclasses.dataclass
class ClassCourseArm:
    """One of the course's other arms, shown to the class in the server's shared scene."""

    arm: Arm
    state: CourseArmState
    scene: CourseArmScene | DesktopArmScene


class Member:
    """One browser in the classroom and its "Classroom" folder."""

    def __init__(self, client: viser.ClientHandle) -> None:
        self.client = client
        self.role = VIEWER
        self.session: "ClientSession | CourseArmSession | None" = None
        self.folder: viser.GuiFolderHandle | None = None
        self.picker: ArmPicker | None = None  #: the presenter's: which arm the class sees
        self.camera: CameraControls | None = None
        self.join_code: viser.GuiInputHandle | None = None  #: a viewer's box for the presenter's code
        self.closed = False


class Classroom:
    def __init__(self, app: "TeachingServer") -> None:
        from ..session import SceneViews  # the session module imports views; keep the import graph one-way

        self.app = app
        self.code = make_join_code()
        #: the class's UR10: kept while the presenter shows another arm, so that it comes back where it was
        self.state = ArmState(app.arm, body_points=app.models.outline)
        self.scene_views = SceneViews.build(app.server.scene, app.models, self.state.last, target_marker=True)
        self.live: LivePanel = LivePanel(app.server.gui, self.state, lambda: self.scene_views.overlay.enabled)
        self.choice = UR10  #: the arm the class is shown (an ``ARM_CHOICES`` label)
        self.course: ClassCourseArm | None = None  #: that arm, when it is not the UR10
        self._last_switch = -math.inf
        self.members: dict[int, Member] = {}
        self.presenter: Member | None = None
        self.guesses: dict[str, Guesses] = {}  #: by address
        self.claims = 0  #: join codes answered, right or wrong (for the tests)
        self._lock = threading.RLock()

    # ------------------------------------------------------------------ clients

    def connect(self, client: viser.ClientHandle) -> None:
        member = Member(client)
        with self._lock:
            self.members[client.client_id] = member
        # one camera per browser, whatever its role: it frames the arm this browser is watching
        member.camera = CameraControls(
            client, lambda: self._watched(member),
            lambda handler: guard(client, handler, is_closed=lambda: member.closed), lecture=self.app.lecture,
            body_radius=self._body_radius(),
        )
        self._draw_controls(member)

    def _watched(self, member: Member):
        """The newest snapshot of the arm ``member`` looks at: its own, or the class's."""
        if member.session is not None:
            return member.session.state.last
        return (self.course or self).state.last

    def _body_radius(self) -> float:
        return BODY_RADIUS if self.course is None else body_radius(self.course.scene.size)

    def disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            member = self.members.pop(client.client_id, None)
            if member is None:
                return
            member.closed = True
            if member.camera is not None:
                member.camera.close()
            if member.session is not None:
                member.session.close()
                member.session = None
            if self.presenter is member:
                self.presenter = None
                self.live.presenter_here = False
        self.app.refresher.request(self.live)

    @property
    def sessions(self) -> dict[int, "ClientSession | CourseArmSession"]:
        """The sessions of the presenter and the explorers."""
        with self._lock:
            return {cid: m.session for cid, m in self.members.items() if m.session is not None}

    # ------------------------------------------------------------------ roles

    def claim(self, member: Member, code: str) -> None:
        """Make ``member`` the presenter if ``code`` is the join code (``ValueError`` if not)."""
        address = address_of(member.client)
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
            previous = self.presenter
            if previous is member:
                return
            if previous is not None:
                self._leave_role(previous)
                self._draw_controls(previous)
            self._leave_role(member)
            member.session, member.role = self._presenter_session(member), PRESENTER
            self.presenter = member
            self.live.presenter_here = True
        self._draw_controls(member)
        self.app.refresher.request(self.live)
        log.info("client %s is presenting", member.client.client_id)

    def _presenter_session(self, member: Member) -> "ClientSession | CourseArmSession":
        """The presenter's panel and gizmo, driving the class's arm in the shared scene."""
        from ..session import ClientSession

        app = self.app
        if self.course is None:
            session = ClientSession(member.client, app.arm, app.models, app.refresher, app.drags, state=self.state,
                                    server=app.server, scene_views=self.scene_views, own_camera=False)
            session.follow_lecture_mode(member.camera.lecture)
        else:
            session = CourseArmSession(member.client, self.course.arm, app.refresher, app.drags, state=self.course.state,
                                       scene=self.course.scene, server=app.server, own_camera=False)
        session.observers.append(lambda _: app.refresher.request(self.live))
        session.camera = member.camera  # the browser's own camera, for the workspace sections
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
        return time.monotonic() - self._last_switch >= SWITCH_INTERVAL

    def show_arm(self, member: Member, label: str) -> None:
        """The presenter shows the class another arm (``CLASS_CHOICES``): everyone's scene and live panel follow.

        The UR10 stays where the presenter left it; another arm starts at its home pose.
        ``ValueError`` for anyone but the presenter, or sooner than :data:`SWITCH_INTERVAL`
        after the last change.
        """
        from ..session import SceneViews

        if label not in CLASS_CHOICES:
            raise ValueError(f"arm: {label!r:.40} is not one of the choices")
        app = self.app
        with self._lock:
            if member.closed or self.presenter is not member:
                raise ValueError("only the presenter chooses the class's arm")
            if label == self.choice:
                return
            if not self.can_switch():
                raise ValueError(f"one change of arm every {SWITCH_INTERVAL:g} s, please: try again in a moment")
            member.session.remove()
            member.session = None
            self.live.remove()
            app.server.scene.reset()  # the class's arm and everything drawn with it
            add_floor_grid(app.server.scene)
            name = ARM_CHOICES[label]
            if name is None:
                self.course = None
                self.scene_views = SceneViews.build(app.server.scene, app.models, self.state.last, target_marker=True)
                self.live = LivePanel(app.server.gui, self.state, lambda: self.scene_views.overlay.enabled, True)
            else:
                arm = Arm.preset(name)
                state = CourseArmState(arm)
                self.course = ClassCourseArm(arm, state, arm_scene(app.server.scene, arm, state.last))
                self.live = CourseLivePanel(app.server.gui, state, label, True)
            self.choice = label
            app.server.gui.set_panel_label(panel_title(label, app.arm.name))
            member.session = self._presenter_session(member)
            self._last_switch = time.monotonic()
            members = list(self.members.values())
        self._draw_controls(member)
        for other in members:
            if other.role == EXPLORER:
                self._hide_class_arm(other)
            elif other.camera is not None:  # the presenter and the viewers look at the new arm
                other.camera.body_radius = self._body_radius()
                other.camera.frame()
        app.refresher.request(self.live)
        log.info("the class is shown the %s", label)

    def stop_presenting(self, member: Member) -> None:
        with self._lock:
            if self.presenter is member:
                self._leave_role(member)
                self.presenter = None
                self.live.presenter_here = False
        self._draw_controls(member)
        self.app.refresher.request(self.live)

    def explore(self, member: Member) -> None:
        """A private copy of the class's arm, starting from the presenter's pose."""
        from ..session import ClientSession

        app = self.app
        with self._lock:
            if member.role == EXPLORER:
                return
            if self.presenter is member:
                self.stop_presenting(member)
            if self.course is None:
                member.session = ClientSession(
                    member.client, app.arm, app.models, app.refresher, app.drags,
                    state=ArmState(app.arm, self.state.q, body_points=app.models.outline), own_camera=False,
                )
                member.session.follow_lecture_mode(member.camera.lecture)
            else:
                arm = self.course.arm
                member.session = CourseArmSession(member.client, arm, app.refresher, app.drags,
                                                  state=CourseArmState(arm, self.course.state.last.q), own_camera=False,
                                                  root=DESKTOP_EXPLORER_ROOT if arm.dh is None else EXPLORER_ROOT)
            member.session.camera = member.camera
            member.role = EXPLORER
            self._hide_class_arm(member)
        self._draw_controls(member)

    def _hide_class_arm(self, member: Member) -> None:
        """In an explorer's browser, hide what of the class's arm its own arm does not already cover.

        A private UR10 uses the shared UR10's scene names, which hides all of it but the
        presenter's target marker; a private course arm has a root of its own.
        """
        if self.course is not None:
            hidden: tuple[str, ...] = (self.course.scene.top,)
        elif isinstance(member.session, CourseArmSession):
            hidden = UR10_ROOTS
        else:
            hidden = ("/target",)
        for name in hidden:
            member.client.scene.add_frame(name, show_axes=False, visible=False)

    def rejoin(self, member: Member) -> None:
        """Back to watching the presenter: drop the private arm (the shared one shows again)."""
        with self._lock:
            if member.role != EXPLORER:
                return
            self._leave_role(member)
        self._draw_controls(member)

    def _leave_role(self, member: Member) -> None:
        if member.session is not None:
            member.session.remove()
            member.session = None
        if member.role == EXPLORER:
            member.client.scene.reset()  # the private arm goes; the shared one is visible again
        member.role = VIEWER

    # ------------------------------------------------------------------ the Classroom folder

    def _draw_controls(self, member: Member) -> None:
        if member.closed:
            return
        gui = member.client.gui

        def action(handler):
            return guard(member.client, handler, is_closed=lambda: member.closed)

        if member.folder is not None:
            member.folder.remove()  # and the picker in it
        member.folder, member.picker = gui.add_folder("Classroom", order=0.0), None
        with member.folder:
            if member.role == PRESENTER:
                gui.add_markdown("You are **presenting**: everyone sees your arm, target and overlays.")
                stop = gui.add_button("Stop presenting", icon=viser.Icon.PLAYER_STOP)
                stop.on_click(action(lambda _: self.stop_presenting(member)))
                member.picker = ArmPicker(gui, self.choice, lambda label: self.show_arm(member, label), action,
                                          CLASS_CHOICES, hint="The arm the whole class sees: its branches, singularities and DH frames")
            elif member.role == EXPLORER:
                gui.add_markdown("You are **exploring on your own**: nobody else sees this arm.")
                back = gui.add_button("Back to the presenter's arm", icon=viser.Icon.ARROW_BACK_UP)
                back.on_click(action(lambda _: self.rejoin(member)))
            else:
                gui.add_markdown("You are **watching** the presenter's arm.")
                explore = gui.add_button("Explore on my own", icon=viser.Icon.ROBOT)
                explore.on_click(action(lambda _: self.explore(member)))
                code = member.join_code = gui.add_text("Join code", "", hint="The code on the teacher's screen makes this browser the presenter")
                claim = gui.add_button("Become presenter", icon=viser.Icon.PRESENTATION)
                claim.on_click(action(lambda _: self.claim(member, code.value)))
