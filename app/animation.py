"""Playing a computed motion on a browser's arm: one frame at a time, on a thread of its own, until done or stopped."""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING, Callable

import numpy as np

if TYPE_CHECKING:
    from .session import ClientSession

#: Frames a second sent to the browser: smooth to the eye, a few messages a frame.
FRAME_RATE = 30.0


class Player:
    """At most one motion at a time per session; a new one stops the last."""

    def __init__(self, session: "ClientSession") -> None:
        self._session = session
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    @property
    def playing(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def play(self, compute: Callable[[], tuple[np.ndarray, np.ndarray]], cause: str, done: Callable[[], None] = lambda: None) -> None:
        """Compute ``(t (m,), q (m, 6))`` on the thread, then move the arm along it in real time."""
        self.stop()
        with self._lock:
            self._stop = threading.Event()
            stop = self._stop
            self._thread = threading.Thread(target=self._session.guard(lambda _: self._run(compute, cause, stop, done)),
                                            args=(None,), name="animation", daemon=True)
            self._thread.start()

    def _run(self, compute, cause: str, stop: threading.Event, done: Callable[[], None]) -> None:
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
            self._session.apply(lambda state, joints=q[k]: state.set_joints(joints, cause=cause))
            shown = t[k]
        done()

    def stop(self) -> None:
        self._stop.set()
