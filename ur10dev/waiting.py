"""Waiting on a condition, in plain and in asyncio code: never a fixed sleep, never a duration compared.

A test waits for what it needs to have happened (the server's state, a message received,
a settled picture) and gives up only after :data:`HANG_TIMEOUT`, which a hang reaches and
a busy machine does not: the whole suite passes with both cores of a 2-core machine held
by busy loops.
"""

from __future__ import annotations

import asyncio
import os
import sys
import time
from typing import Callable

#: Seconds after which a wait is a hang. Generous on purpose: it only bounds a failure's report
#: (``UR10_HANG_TIMEOUT`` shortens it while a change is being debugged).
HANG_TIMEOUT = float(os.environ.get("UR10_HANG_TIMEOUT", 120.0))
#: How often a condition is looked at (seconds).
POLL = 0.02
#: ``UR10_TRACE_WAITS=1`` prints how long each wait took (to find where a slow test spends its time).
TRACE = os.environ.get("UR10_TRACE_WAITS") == "1"


def _trace(what: str, started: float) -> None:
    if TRACE:
        print(f"[{time.monotonic():10.2f}: waited {time.monotonic() - started:6.2f} s] {what}", file=sys.stderr, flush=True)


def _checker(condition: Callable[[], object], timeout: float, what: str) -> Callable[[], object]:
    """One look at ``condition``: its value once true, None while false; fails after ``timeout`` s."""
    started = time.monotonic()
    deadline = started + timeout

    def check() -> object:
        value = condition()
        if value:
            _trace(what, started)
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")
        return None

    return check


def wait_for(condition: Callable[[], object], timeout: float = HANG_TIMEOUT, what: str = "condition") -> object:
    """Poll ``condition`` until it returns something true, and return that; fail after ``timeout`` s."""
    check = _checker(condition, timeout, what)
    while (value := check()) is None:
        time.sleep(POLL)
    return value


async def until(condition: Callable[[], object], timeout: float = HANG_TIMEOUT, what: str = "condition") -> object:
    """:func:`wait_for` for a coroutine: the event loop runs on while ``condition`` is false."""
    check = _checker(condition, timeout, what)
    while (value := check()) is None:
        await asyncio.sleep(POLL)
    return value
