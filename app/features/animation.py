"""Playing a computed motion on a browser's arm: one frame at a time, on a background thread, until done or stopped."""

from __future__ import annotations

import threading
import time
from typing import Any, Callable

import numpy as np

from ..serving.workers import BACKGROUND, Cancelled
from ..view import Session

#: Frames a second sent to the browser: smooth to the eye, a few messages a frame.
FRAME_RATE = 30.0


class Player:
    """At most one motion at a time per session; a new one stops the last.

    Presses fold: however many come while a motion is computed or played, the one under
    way is stopped and only the newest is played next, on one background thread
    (:data:`ur10teach.serving.workers.BACKGROUND`) per session at most.
    """

    def __init__(self, session: Session) -> None:
        self._session = session
        self._stop = threading.Event()
        self._pending: tuple | None = None  #: the newest request not yet started
        self._running = False  #: a background thread is taking requests
        self._lock = threading.Lock()

    @property
    def playing(self) -> bool:
        with self._lock:
            return self._running

    def cancelled(self) -> bool:
        """Whether the motion being computed is no longer wanted (stopped, replaced, or its browser gone)."""
        return self._stop.is_set() or self._session.closed

    def play(self, compute: Callable[[], tuple[np.ndarray, np.ndarray]], cause: str, done: Callable[[], None] = lambda: None,
             show: Callable[[Any, np.ndarray], Any] | None = None, ended: Callable[[], None] = lambda: None) -> None:
        """Compute ``(t (m,), q (m, n))`` in the background, then move the arm along it in real time.

        ``show(state, q[k])`` is the change that puts each frame on the arm (by default
        ``state.set_joints(q[k], cause=cause)``). Once :meth:`stop` has returned, no frame is
        applied: a change the caller then applies is the last word. ``done()`` follows the last frame;
        ``ended()`` follows a computed motion however it ends (played, stopped, replaced, refused).
        """
        if show is None:
            def show(state, joints: np.ndarray):
                return state.set_joints(joints, cause=cause)
        with self._lock:
            self._stop.set()
            self._pending = (compute, show, done, ended)
            if self._running:
                return
            self._running = True
        # not guarded as a whole: a browser gone before a thread is free must still find the player idle
        BACKGROUND.submit(self._take_requests)

    def _take_requests(self) -> None:
        try:
            while True:
                with self._lock:
                    if self._pending is None or self._session.closed:
                        self._pending = None
                        return
                    (compute, show, done, ended), self._pending = self._pending, None
                    self._stop = stop = threading.Event()
                self._session.guard(lambda _: self._run_unless_cancelled(compute, show, stop, done, ended))(None)
        finally:
            with self._lock:
                self._running = False

    def _run_unless_cancelled(self, compute, show, stop: threading.Event, done: Callable[[], None],
                              ended: Callable[[], None]) -> None:
        try:
            self._run(compute, show, stop, done)
        except Cancelled:
            pass
        finally:
            ended()

    def _run(self, compute, show: Callable[[Any, np.ndarray], Any], stop: threading.Event, done: Callable[[], None]) -> None:
        t, q = compute()
        start = time.monotonic()
        shown = -1.0
        for k in range(len(t)):
            if stop.is_set() or self._session.closed:
                return
            if t[k] - shown < 1.0 / FRAME_RATE and k < len(t) - 1:
                continue  # one frame per tick
            wait = start + t[k] - time.monotonic()
            if wait > 0 and stop.wait(wait):
                return
            # checked under the arm's lock, where stop()'s caller applies its own change
            self._session.apply(lambda state, row=q[k]: state.last if stop.is_set() else show(state, row))
            shown = t[k]
        done()

    def stop(self) -> None:
        """Stop the motion under way, and forget any waiting to start."""
        with self._lock:
            self._pending = None
            self._stop.set()
