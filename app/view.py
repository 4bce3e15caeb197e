"""What every feature module's view offers the session, and what a feature is handed of the session."""

from __future__ import annotations

from typing import Any, Callable, Protocol

import viser

from ur10core import Arm

from .state import ArmState, Snapshot

#: What a view says in place of what it holds back while a class challenge runs (``View.hold_back``).
HELD_BACK = "Off while the class challenge asks you to find this yourself: back when it ends."


def say_held_back(markdown: viser.GuiMarkdownHandle, held: bool) -> None:
    """``markdown`` says :data:`HELD_BACK` while ``held``; otherwise it is hidden, and empty."""
    markdown.content, markdown.visible = (HELD_BACK, True) if held else ("", False)


class Session(Protocol):
    """What a feature is handed (``ur10teach.session.ArmSession``): the browser, its arm, and the means to change
    and redraw it. Features never import the session: the session builds them and hands itself over."""

    client: viser.ClientHandle
    arm: Arm
    state: ArmState
    refresher: Any  #: ``request(session)`` redraws the panel soon
    camera: Any  #: the browser's camera (``features.camera.CameraControls``), or None
    drawing: Any  #: how the arm is drawn (``features.drawings``): its ``world`` places the base frame
    closed: bool

    def apply(self, change: Callable[[ArmState], Snapshot], timed: str | None = None) -> Snapshot: ...

    def redraw(self) -> None: ...

    def guard(self, handler: Callable[[Any], None], beside: Any = None) -> Callable[[Any], None]: ...

    def notify(self, title: str, body: str, color: str = "yellow") -> None: ...

    def colouring_shown(self, shown: View) -> None:
        """``shown`` has just coloured the workspace's points: every other view's colouring goes (``View.hide_colouring``)."""


class View:
    """A feature's part of the scene and of the panel.

    ``render`` draws the 3D scene on every change (it is on the drag path: keep it lean);
    ``render_panel`` draws the GUI, and 3D details that need not follow a drag frame by
    frame (branch numbers, floor markers), at most ten times a second (see ``ur10teach.serving.workers``).
    Both run one at a time per session: ``render`` under the arm's lock
    (``ArmSession.apply`` or ``redraw``), ``render_panel`` on the panel refresher.

    ``close`` lets go of what the view holds in a scene shared with others (the browser
    has gone, or handed the arm over); ``remove`` also takes the view's own widgets out of
    a browser that stays. A view lists its panel folders in ``folders``, its charts in
    ``charts`` (lecture mode sizes their axes), and in ``answers`` what a class challenge may ask
    (``Challenge.asks``: its kind, or a numbers challenge's quantity) that its panel would give away: while
    one asking it runs, ``held`` is what it asks, and the view shows :data:`HELD_BACK` in its place.
    """

    folders: tuple = ()
    charts: tuple = ()
    answers: tuple = ()
    held: str | None = None

    def hold_back(self, asked: str | None) -> None:
        """A class challenge asking ``asked`` runs (None: none does). A view whose ``answers`` hold it takes away
        the readouts and buttons that would answer it (viser's buttons cannot be disabled: they are hidden), until
        it is given back; ``render_panel``, called next, writes its readouts."""
        self.held = asked if asked in self.answers else None

    def unless_held(self, change: Callable[[ArmState], Snapshot],
                    asked: str | None = None) -> Callable[[ArmState], Snapshot]:
        """``change`` for ``ArmSession.apply``, refused with :data:`HELD_BACK` while a challenge asks what this view
        would answer (``asked``: only that). Asked under the arm's lock, which a challenge beginning holds as it holds
        the views back: a slow job pressed for before it began does not put the arm on its answer."""
        def unless(state: ArmState) -> Snapshot:
            if (self.held is not None) if asked is None else (self.held == asked):
                raise ValueError(HELD_BACK)
            return change(state)

        return unless

    def render(self, snapshot: Snapshot) -> None:
        pass

    def render_panel(self, snapshot: Snapshot) -> None:
        pass

    def close(self) -> None:
        pass

    def names(self) -> list[tuple]:
        """What it names in 3D at points that move with the arm (an arrow's tip): ``(point (3,) in the drawing's
        frame, or None while hidden; text; leader colour)`` per name it can show, the same number every time.
        The session places them apart, before the drawing's own labels."""
        return []

    def kept(self) -> dict:
        """What the student set in it beyond its switches and boxes (a velocity asked): the server keeps it with
        the arm, and :meth:`restore` gives it back when the browser comes back to the arm."""
        return {}

    def restore(self, kept: dict) -> None:
        pass

    def hide_colouring(self) -> None:
        """Take away the colours it paints the workspace's points with (|det J|, ‖τ‖): another view has just shown
        its own there, and the two in one space, in one colour scale, would read as one."""

    def obstacles(self) -> list:
        """The 3D labels it draws where they stay (a map's largest ‖τ‖, say), as label nodes or
        ``branch_labels.obstacle`` tuples in the drawing's frame: the placed labels keep clear of them."""
        return []

    def remove(self) -> None:
        self.close()
        for folder in self.folders:
            folder.remove()
