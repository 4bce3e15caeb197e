"""Server-side handler latencies, kept in a fixed-size ring buffer per kind of event.

The drag benchmark and the classroom load test read them; nothing here is shown to
students. ``UR10_TEACH_METRICS=<path>`` makes the server write a JSON summary to
``<path>`` every second when the app runs as ``python -m ur10dev.metered_app``.
"""

from __future__ import annotations

import collections
import threading

import numpy as np

CAPACITY = 100_000


class LatencyLog:
    """The last ``capacity`` samples of each kind, in preallocated float64 rings.

    Allocated and written through when a kind is first recorded, so that measuring a long
    run does not itself show up as memory growth (a deque of Python floats grows by ~32
    bytes a sample until it is full; an untouched ``np.empty`` ring by 8).
    """

    def __init__(self, capacity: int = CAPACITY) -> None:
        self._capacity = capacity
        # re-entrant: the garbage collector's callback (``ur10dev.metered_app``) records
        # its pause on whichever thread allocated, which may be inside record() or summary();
        # with a plain lock that thread waited on itself and every thread recording after it
        # (the event loop's included) waited too: the whole server froze
        self._lock = threading.RLock()
        self._rings: dict[str, np.ndarray] = {}
        self._counts: collections.Counter = collections.Counter()

    def record(self, kind: str, seconds: float) -> None:
        with self._lock:
            ring = self._rings.get(kind)
            if ring is None:
                # written through now: np.empty's pages would join the resident memory only as
                # the ring fills, and a long class would show that as slow growth
                ring = self._rings[kind] = np.full(self._capacity, np.nan)
            ring[self._counts[kind] % self._capacity] = seconds
            self._counts[kind] += 1

    def summary(self) -> dict[str, dict[str, float]]:
        """Per kind: count (all time) and p50 / p99 / max (ms) over the retained samples."""
        with self._lock:
            counts = dict(self._counts)
            data = {kind: ring[: min(counts[kind], self._capacity)].copy() for kind, ring in self._rings.items()}
        out = {}
        for kind, samples in data.items():
            if len(samples):
                p50, p99 = np.percentile(samples, [50, 99]) * 1e3
                out[kind] = {"count": counts[kind], "p50_ms": float(p50), "p99_ms": float(p99),
                             "max_ms": float(samples.max() * 1e3)}
        return out

    def clear(self) -> None:
        with self._lock:
            self._rings.clear()
            self._counts.clear()


#: The process-wide log every session records into.
LATENCY = LatencyLog()
