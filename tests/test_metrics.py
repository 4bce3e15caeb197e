"""The latency log keeps the newest samples in a fixed ring and summarises them."""

from __future__ import annotations

import numpy as np

from ur10teach.serving.metrics import LatencyLog
from ur10dev.waiting import HANG_TIMEOUT


def test_ring_keeps_the_newest_samples_and_counts_all():
    log = LatencyLog(capacity=5)
    for i in range(12):
        log.record("drag", i / 1000)
    summary = log.summary()["drag"]
    assert summary["count"] == 12
    # only 7..11 ms are retained
    assert summary["max_ms"] == 11.0
    np.testing.assert_allclose(summary["p50_ms"], 9.0)


def test_partly_filled_ring_and_clear():
    log = LatencyLog(capacity=100)
    log.record("panel", 0.002)
    log.record("panel", 0.004)
    summary = log.summary()["panel"]
    assert summary["count"] == 2 and summary["max_ms"] == 4.0
    np.testing.assert_allclose(summary["p50_ms"], 3.0)
    log.clear()
    assert log.summary() == {}


#: Fills one ring in a process of its own and prints how much its resident memory grew meanwhile.
FILL_A_RING = """
from ur10teach.serving.metrics import LatencyLog
from ur10dev.metered_app import resident_bytes
capacity = 500_000  # 4 MB of samples, far above the allocator's noise
log = LatencyLog(capacity=capacity)
log.record("drag", 0.001)
before = resident_bytes()
for _ in range(capacity):
    log.record("drag", 0.001)
print(before, resident_bytes() - before)
"""


def test_filling_the_ring_takes_no_more_memory():
    """A ring's memory is taken when its kind is first recorded, not sample by sample:
    a long class must not look like a leak in the server's resident memory.

    Measured in a process of its own: in the test run's, threads left by earlier tests once
    allocated 7.9 MB while the ring filled (2026-12-04), and this test failed for them."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "PYTHONPATH": os.pathsep.join(path for path in sys.path if path)}
    run = subprocess.run([sys.executable, "-c", FILL_A_RING], capture_output=True, text=True, env=env,
                         timeout=HANG_TIMEOUT, check=True)
    before, grown = (int(value) for value in run.stdout.split())
    assert before > 0, "no resident memory figure on this system"
    assert grown < 1_000_000, f"resident memory grew by {grown / 1e6:.1f} MB while the ring filled"


def test_a_collection_while_the_log_is_held_does_not_freeze_the_server():
    """With metrics on, the garbage collector's callback records its pause on whichever thread
    allocated; inside summary() a plain lock made that thread wait on itself, and every thread
    recording after it (viser's event loop too) waited forever: a classroom benchmark froze."""
    import gc
    import threading

    from ur10teach.serving.metrics import LATENCY

    from ur10dev.metered_app import watch_garbage_collector

    callbacks = list(gc.callbacks)
    threshold = gc.get_threshold()
    watch_garbage_collector()
    gc.set_threshold(1)  # a collection at (nearly) every allocation, summary()'s own included
    try:
        LATENCY.record("drag", 0.001)
        worker = threading.Thread(target=lambda: [LATENCY.summary() for _ in range(50)], daemon=True)
        worker.start()
        worker.join(timeout=HANG_TIMEOUT)  # a deadlock never ends
        assert not worker.is_alive(), "summary() waited on its own lock"
        gc.set_threshold(*threshold)
        assert LATENCY.summary()["gc0"]["count"] > 0  # the pauses were recorded meanwhile
    finally:
        gc.set_threshold(*threshold)
        gc.callbacks[:] = callbacks
