"""Redrawing the side panel at most ten times a second, off the drag path.

A drag moves the 3D arm and ghosts twenty times a second; the panel's text (joint
sliders, branch table, readouts, gauges, plot) cannot be read faster than a few times a
second, yet redrawing it costs more than the 3D update. So a change redraws the 3D view
in the callback and only *asks* for a panel redraw; one thread per server serves those
requests, each session at most every :data:`PANEL_INTERVAL` seconds, always with the
session's newest state. A burst of drag events therefore costs one panel redraw, and a
student clicking a button sees the panel follow at once.
"""

from __future__ import annotations

import heapq
import itertools
import logging
import threading
import time
from typing import Protocol

log = logging.getLogger(__name__)

#: Shortest time between two panel redraws of one browser (s).
PANEL_INTERVAL = 0.1


class HasPanel(Protocol):
    closed: bool

    def render_panel(self) -> None: ...


class PanelRefresher:
    def __init__(self, interval: float = PANEL_INTERVAL) -> None:
        self.interval = interval
        self._condition = threading.Condition()
        self._queue: list[tuple[float, int, HasPanel]] = []  # (due, order, session)
        self._waiting: set[int] = set()  # id() of sessions in the queue
        self._last: dict[int, float] = {}
        self._order = itertools.count()
        self._stopped = False
        self._thread = threading.Thread(target=self._run, name="panel-refresher", daemon=True)
        self._thread.start()

    def request(self, session: HasPanel) -> None:
        """Redraw ``session``'s panel soon (at once if it has not been redrawn lately)."""
        key = id(session)
        with self._condition:
            if key in self._waiting:
                return  # already queued: it will draw the newest state when its turn comes
            due = max(time.monotonic(), self._last.get(key, 0.0) + self.interval)
            heapq.heappush(self._queue, (due, next(self._order), session))
            self._waiting.add(key)
            self._condition.notify()

    def forget(self, session: HasPanel) -> None:
        with self._condition:
            self._last.pop(id(session), None)

    def stop(self) -> None:
        with self._condition:
            self._stopped = True
            self._condition.notify()
        self._thread.join(timeout=2.0)

    def _run(self) -> None:
        while True:
            with self._condition:
                while not self._stopped and (not self._queue or self._queue[0][0] > time.monotonic()):
                    timeout = None if not self._queue else self._queue[0][0] - time.monotonic()
                    self._condition.wait(timeout)
                if self._stopped:
                    return
                _, _, session = heapq.heappop(self._queue)
                self._waiting.discard(id(session))
                self._last[id(session)] = time.monotonic()
            if session.closed:
                self.forget(session)
                continue
            try:
                session.render_panel()
            except Exception:
                if not session.closed:
                    log.exception("panel redraw failed")
