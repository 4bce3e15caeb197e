"""What every arm session does alike: batched redraws, the panel, guarded callbacks, leaving."""

from __future__ import annotations

import contextlib
from typing import Any, Callable

from .feedback import guard, notify


class SessionBasics:
    """The shared half of the UR10's ``ClientSession`` and the course arms' sessions.

    The class using it has ``render(snapshot)`` and sets ``client``, ``state`` (with a ``lock``
    and ``last``), ``refresher``, ``closed``, ``panel_views`` (the views it built in the
    browser's own panel, which leaving closes) and ``_senders`` (the browser, and the server
    when it draws in the shared scene).

    Its widgets reach the browser as they are made, so a quick click can run a callback before
    the constructor ends: until the constructor sets ``built``, nothing is drawn, and the first
    render then draws the state as that click left it.
    """

    built = False
    panel_views: tuple = ()
    #: the arm picker's label of this arm, and the typed table (arm, text, convention) it was
    #: built from: the server sets them, and keeps the state under them when the browser leaves the arm
    choice: str = ""
    typed: tuple | None = None

    @contextlib.contextmanager
    def _batch(self):
        """One redraw's messages, sent together to every sender."""
        with contextlib.ExitStack() as batch:
            for sender in self._senders:
                batch.enter_context(sender.atomic())
            yield
        for sender in self._senders:
            sender.flush()

    def redraw(self) -> None:
        """The 3D view again, unchanged state (a toggle changed what is shown), and the panel after it."""
        with self.state.lock:
            self.render(self.state.last)
        self.refresher.request(self)

    def render_panel(self) -> None:
        """The side panel, from the newest state (called by the refresher, one thread at a time)."""
        if self.closed or not self.built:
            return
        snapshot = self.state.last
        with self.client.atomic():
            for view in self.panel_views:
                view.render_panel(snapshot)

    def guard(self, handler: Callable[[Any], None]) -> Callable[[Any], None]:
        """Wrap a viser callback so that nothing it raises escapes (see ``ur10teach.feedback``)."""
        return guard(self.client, handler, is_closed=lambda: self.closed, on_refused=lambda: self.refresher.request(self))

    def notify(self, title: str, body: str, color: str = "yellow") -> None:
        if not self.closed:
            notify(self.client, title, body, color)

    def close(self) -> None:
        """The browser has gone (or handed over): stop drawing and let go of everything shared."""
        self._leave(lambda view: view.close())

    def remove(self) -> None:
        """Close, and take this session's panel out of a browser that stays."""
        self._leave(lambda view: view.remove())

    def _leave(self, how: Callable[[Any], None]) -> None:
        self.closed = True
        with self.state.lock:  # not while a drag is being drawn
            for view in self.panel_views:
                how(view)
        self.refresher.forget(self)
