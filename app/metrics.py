"""Server-side handler latencies, kept in a ring buffer per kind of event.

The drag benchmark and the classroom load test read them; nothing here is shown to
students. ``UR10_TEACH_METRICS=<path>`` makes the server write a JSON summary to
``<path>`` every second (see ``app.server``).
"""

from __future__ import annotations

import collections
import threading

import numpy as np

CAPACITY = 100_000


class LatencyLog:
    def __init__(self, capacity: int = CAPACITY) -> None:
        self._lock = threading.Lock()
        self._samples: dict[str, collections.deque] = collections.defaultdict(lambda: collections.deque(maxlen=capacity))
        self._counts: collections.Counter = collections.Counter()

    def record(self, kind: str, seconds: float) -> None:
        with self._lock:
            self._samples[kind].append(seconds)
            self._counts[kind] += 1

    def summary(self) -> dict[str, dict[str, float]]:
        """Per kind: count (all time) and p50 / p99 / max (ms) over the retained samples."""
        with self._lock:
            data = {kind: np.array(samples) for kind, samples in self._samples.items()}
            counts = dict(self._counts)
        out = {}
        for kind, samples in data.items():
            if len(samples):
                p50, p99 = np.percentile(samples, [50, 99]) * 1e3
                out[kind] = {"count": counts[kind], "p50_ms": float(p50), "p99_ms": float(p99),
                             "max_ms": float(samples.max() * 1e3)}
        return out

    def clear(self) -> None:
        with self._lock:
            self._samples.clear()
            self._counts.clear()


#: The process-wide log every session records into.
LATENCY = LatencyLog()
