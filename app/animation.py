"""Playing a computed motion on a browser's arm: one frame at a time, on a thread of its own, until done or stopped."""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING, Any, Callable

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

    def play(self, compute: Callable[[], tuple[np.ndarray, np.ndarray]], cause: str, done: Callable[[], None] = lambda: None,
             show: Callable[[Any, np.ndarray], Any] | None = None) -> None:
        """Compute ``(t (m,), q (m, n))`` on the thread, then move the arm along it in real time.

        ``show(state, q[k])`` is the change that puts each frame on the arm (by default
        ``state.set_joints(q[k], cause=cause)``). Once :meth:`stop` has returned, no frame is
        applied: a change the caller then applies is the last word.
        """
        self.stop()
        if show is None:
            def show(state, joints: np.ndarray):
                return state.set_joints(joints, cause=cause)
        with self._lock:
            self._stop = threading.Event()
            stop = self._stop
            self._thread = threading.Thread(target=self._session.guard(lambda _: self._run(compute, show, stop, done)),
                                            args=(None,), name="animation", daemon=True)
            self._thread.start()

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
        self._stop.set()
