"""What every feature module's view offers the session."""

from __future__ import annotations

from .state import Snapshot


class View:
    """A feature's part of the scene and of the panel.

    ``render`` draws the 3D scene on every change (it is on the drag path: keep it lean);
    ``render_panel`` draws the GUI, and 3D details that need not follow a drag frame by
    frame (branch numbers, floor markers), at most ten times a second (see ``ur10teach.serving.workers``).
    Both run one at a time per session: ``render`` under the arm's lock
    (``ClientSession.apply`` or ``redraw``), ``render_panel`` on the panel refresher.

    ``close`` lets go of what the view holds in a scene shared with others (the browser
    has gone, or handed the arm over); ``remove`` also takes the view's own widgets out of
    a browser that stays. A view lists its panel folders in ``folders``.
    """

    folders: tuple = ()

    def render(self, snapshot: Snapshot) -> None:
        pass

    def render_panel(self, snapshot: Snapshot) -> None:
        pass

    def close(self) -> None:
        pass

    def remove(self) -> None:
        self.close()
        for folder in self.folders:
            folder.remove()
