"""The teacher's console: every kind of problem shown, none of them a flood.

A client sending bad values, or a machine out of file descriptors failing every accept,
repeats the same error hundreds of times a second; written out with a traceback each,
that was 15 MB in 2.6 s. :class:`RepeatLimiter` lets the first few of each kind through
in a window, notes that the rest are being counted, and says how many there were when
the kind comes back after the window.
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass

#: Records of one kind shown per window, and the window (s).
BURST = 3
WINDOW = 60.0
#: Kinds remembered at once; the oldest is forgotten beyond this.
KINDS = 1000


@dataclass
class _Seen:
    since: float
    shown: int = 0
    hidden: int = 0


class RepeatLimiter(logging.Filter):
    """A filter showing :data:`BURST` records of each kind per :data:`WINDOW` seconds.

    The kind of a record is its logger, the first line of its message (asyncio's reports
    name a different task each time below it), its text arguments (what was dropped, from
    which address) and the type of its exception. Numbers do not make a kind: "3 wrong" and
    "4 wrong" are one.
    """

    def __init__(self, burst: int = BURST, window: float = WINDOW) -> None:
        super().__init__()
        self.burst, self.window = burst, window
        self._seen: dict[tuple, _Seen] = {}
        self._lock = threading.Lock()

    def filter(self, record: logging.LogRecord) -> bool:
        first_line = str(record.msg).split("\n", 1)[0][:200]
        texts = tuple(arg[:100] for arg in (record.args if isinstance(record.args, tuple) else ()) if isinstance(arg, str))
        kind = (record.name, first_line, texts, record.exc_info[0] if record.exc_info else None)
        now = time.monotonic()
        with self._lock:
            seen = self._seen.get(kind)
            if seen is None or now - seen.since > self.window:
                hidden = seen.hidden if seen is not None else 0
                self._seen.pop(kind, None)
                if len(self._seen) >= KINDS:
                    self._seen.pop(next(iter(self._seen)))
                seen = self._seen[kind] = _Seen(now)
                if hidden:
                    record.msg = f"{record.msg}\n(and {hidden} more like this in the minute before, not shown)"
            seen.shown += 1
            if seen.shown <= self.burst:
                return True
            seen.hidden += 1
            if seen.hidden > 1:
                return False
        # the first one hidden: say so, once, without its traceback
        try:
            first_line = record.getMessage().split("\n", 1)[0][:200]
        except (TypeError, ValueError):  # arguments that do not fit the message: the message as it is
            pass
        record.msg = f"{first_line} (repeating: more like this are counted, not shown, for {self.window:.0f} s)"
        record.args, record.exc_info, record.exc_text, record.stack_info = (), None, None, None
        return True


def install(level: int = logging.INFO) -> None:
    """The app's logging: one line per record, each handler behind a :class:`RepeatLimiter`."""
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
    # ("server listening on 127.0.0.1:8080" above the app's own address, then "connection open" as students joined)
    logging.getLogger("websockets").setLevel(max(level, logging.WARNING))
    limiter = RepeatLimiter()
    for handler in logging.getLogger().handlers:
        handler.addFilter(limiter)
