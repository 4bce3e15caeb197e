"""What every feature module's view offers the session."""

from __future__ import annotations

from .state import Snapshot


class View:
    """A feature's part of the scene and of the panel.

    ``render`` draws the 3D scene on every change (it is on the drag path: keep it lean);
    ``render_panel`` draws the GUI, at most ten times a second (see ``app.workers``).
    """

    def render(self, snapshot: Snapshot) -> None:
        pass

    def render_panel(self, snapshot: Snapshot) -> None:
        pass
