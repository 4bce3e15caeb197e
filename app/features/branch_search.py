"""A typed table's "Find every branch": its numerical IK from many starts, in the worker process; by itself for
a target typed or let go of that the arm's own search did not reach."""

from __future__ import annotations

import viser

from ur10core.solvers.numerical import STARTS

from ..serving.workers import APART, HEAVY, FoldedRuns
from ..view import Session, View

#: The button's label, as the status lines name it
SEARCH_BUTTON = "Find every branch"


class BranchSearch(View):
    """The "Numerical IK" folder: damped least squares from many starts, its branches shown as the closed forms' are."""

    def __init__(self, gui: viser.GuiApi, session: Session) -> None:
        self._session = session
        self._runs = FoldedRuns(self._search)
        self._searched = None  #: the last target typed or let go of that was searched for without a press
        folder = gui.add_folder("Numerical IK", order=0.3)
        self.folders = (folder,)
        with folder:
            self.button = gui.add_button(SEARCH_BUTTON, icon=viser.Icon.SEARCH,
                                         hint=f"Damped least squares from {STARTS} starts: every distinct solution it finds")
        self.button.on_click(session.guard(lambda _: self._runs.start("branch-search", session.guard)))

    def render_panel(self, snapshot) -> None:
        # a target typed, or let go of, that the arm's search from its own joints did not reach (stopped short, or on a
        # branch that would leave a joint's range): the student chose that pose, so every branch is searched for, as
        # "Find every branch" would. A drag's poses on the way are not: the arm follows them from its joints.
        unreached = snapshot.solution is None and not snapshot.reachable
        if snapshot.cause in ("typed", "dropped") and unreached and snapshot is not self._searched:
            self._searched = snapshot
            self._runs.start("branch-search", self._session.guard)

    def _search(self) -> None:
        session = self._session
        snapshot = session.state.last
        solution = HEAVY.run(session.client, lambda: APART.run(session.state.arm.ik, snapshot.target, hint=snapshot.q),
                             cancelled=lambda: session.closed)
        if not session.closed:
            session.apply(lambda state: state.with_branches(snapshot, solution))
