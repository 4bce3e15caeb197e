"""One browser's arm, panel and target.

viser runs plain ``def`` callbacks on a thread pool, so callbacks of one browser can
overlap: every change goes through :meth:`ClientSession.apply`, which holds the arm's
lock while it changes the state and redraws the 3D view, then asks the
:class:`~app.refresh.PanelRefresher` to redraw the side panel. Every callback is wrapped
by :meth:`ClientSession.guard`: no exception escapes, a refused value is explained in a
notification in that browser, and every other browser carries on.

Each view has ``render(snapshot)`` (the 3D scene, on every change) and
``render_panel(snapshot)`` (the GUI, at most ten times a second).
"""

from __future__ import annotations

import functools
import logging
import time
from typing import Any, Callable

import viser

from ur10core import Arm

from .ik_target import IKTargetView
from .joint_panel import JointPanel
from .meshes import LinkMesh
from .metrics import LATENCY
from .readouts import Readouts
from .refresh import PanelRefresher
from .robot import RobotView
from .singularity import SingularityOverlay
from .state import ArmState, Snapshot
from .workspace import WorkspaceView

log = logging.getLogger(__name__)


class ClientSession:
    def __init__(
        self, client: viser.ClientHandle, arm: Arm, links: tuple[LinkMesh, ...], refresher: PanelRefresher,
        state: ArmState | None = None,
    ) -> None:
        self.client = client
        self.arm = arm
        self.state = state or ArmState(arm)
        self.refresher = refresher
        self.closed = False
        scene, gui = client.scene, client.gui
        self.robot = RobotView(scene, links, self.state.last)
        self.joints = JointPanel(gui, self)
        self.ik_target = IKTargetView(scene, gui, links, self)
        self.readouts = Readouts(gui, arm, self.state.last)
        self.singularity = SingularityOverlay(scene, gui, self)
        self.workspace = WorkspaceView(scene, gui, self)
        self.views = (self.robot, self.joints, self.ik_target, self.readouts, self.singularity)
        self.render(self.state.last)
        self.render_panel()

    # ------------------------------------------------------------------ changes

    def apply(self, change: Callable[[ArmState], Snapshot], timed: str | None = None) -> Snapshot:
        """Change the state and redraw this browser's 3D view; the panel follows shortly."""
        start = time.perf_counter()
        with self.state.lock:
            snapshot = change(self.state)
            self.render(snapshot)
        if timed:
            LATENCY.record(timed, time.perf_counter() - start)
        self.refresher.request(self)
        return snapshot

    def render(self, snapshot: Snapshot) -> None:
        """The 3D scene, atomically."""
        if self.closed:
            return
        with self.client.atomic():
            for view in self.views:
                view.render(snapshot)

    def render_panel(self) -> None:
        """The side panel, from the newest state (called by the refresher, one thread at a time)."""
        if self.closed:
            return
        start = time.perf_counter()
        snapshot = self.state.last
        with self.client.atomic():
            for view in self.views:
                view.render_panel(snapshot)
        LATENCY.record("panel", time.perf_counter() - start)

    # ------------------------------------------------------------------ safety

    def guard(self, handler: Callable[[Any], None]) -> Callable[[Any], None]:
        """Wrap a viser callback so that nothing it raises escapes."""

        @functools.wraps(handler)
        def guarded(event: Any) -> None:
            if self.closed:
                return
            try:
                handler(event)
            except ValueError as error:
                self.notify("Not accepted", str(error), color="yellow")
                self._restore()
            except Exception as error:  # a bug must not take the class down
                if self.closed:
                    return  # the browser left while we were drawing for it
                log.exception("callback failed for client %s", self.client.client_id)
                self.notify("Something went wrong", f"{type(error).__name__}: {error}. The app is still running.", color="red")

        return guarded

    def _restore(self) -> None:
        """Put every widget back on the state after a refused value (a slider may show it)."""
        self.refresher.request(self)

    def notify(self, title: str, body: str, color: str = "yellow") -> None:
        if self.closed:
            return
        try:
            self.client.add_notification(title, body, auto_close_seconds=8.0, color=color)
        except Exception:  # the connection is gone: nobody left to tell
            log.debug("could not notify client %s", self.client.client_id, exc_info=True)

    def close(self) -> None:
        """The browser has gone: stop drawing; viser drops its scene and GUI with the client."""
        self.closed = True
        self.refresher.forget(self)
