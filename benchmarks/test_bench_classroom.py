"""The classroom load test's own judgements: memory after the warm-up, and the competing load.

They test the benchmark's machinery, not the product: marked ``harness``, out of the default run.
"""

from __future__ import annotations

import asyncio
import time

import pytest

import websockets
from websockets.frames import Close

from benchmarks._report import process_cpu_seconds
from benchmarks.bench_classroom import (
    FLAT_MIB, TARGET_P99_MS, WARMUP_S, competing_load, drag_loop, sample_server, settled_growth, verdict,
)

from ur10dev.waiting import wait_for

pytestmark = pytest.mark.harness

MIB = 2**20


def samples(rss_mib) -> list[dict]:
    """Server reports every 5 s with the given resident memory (MiB)."""
    return [{"time": 1000.0 + 5 * k, "rss_bytes": int(r * MIB)} for k, r in enumerate(rss_mib)]


def warm_then(after) -> list[dict]:
    """A run whose memory climbs 10 MiB in its first 25 s (warm-up), then follows ``after(t)``."""
    return samples([170 + min(t, 25) * 0.4 + (after(t) if t >= 25 else 0.0) for t in range(0, 185, 5)])


def test_the_warm_up_is_not_counted():
    run = warm_then(lambda t: 1.5 * ((t // 30) % 2))  # allocator wander up and down after it
    settled, end, highest = settled_growth(run)
    assert settled == run[12]["rss_bytes"] / MIB  # the sample 60 s in
    assert end - settled <= FLAT_MIB and highest >= settled
    assert verdict(10.0, run) == "PASS"


def test_a_steady_creep_fails_on_memory():
    creep = 3.0 / 60  # MiB per second: 6 MiB over the two minutes after the warm-up
    run = warm_then(lambda t: creep * (t - 25))
    settled, end, _ = settled_growth(run)
    assert end - settled > FLAT_MIB
    assert verdict(10.0, run) == "FAIL (memory)"
    assert verdict(TARGET_P99_MS + 1, run) == "FAIL (p99, memory)"
    assert verdict(TARGET_P99_MS + 1, warm_then(lambda t: 0.0)) == "FAIL (p99)"


def test_a_dropped_student_fails_the_run_without_ending_it():
    class DroppedAfterTwo:
        sent = 0

        async def send_drag(self, step):
            if self.sent == 2:
                raise websockets.ConnectionClosedError(Close(1011, "keepalive ping timeout"), None)
            self.sent += 1
            return time.perf_counter()

    sends, dropped = [], []
    steps = [(None, k) for k in range(5)]
    asyncio.run(drag_loop(DroppedAfterTwo(), steps, sends, 0.0, dropped))
    assert [position for _, position in sends] == [0, 1]
    assert len(dropped) == 1 and "keepalive ping timeout" in dropped[0]
    run = warm_then(lambda t: 0.0)
    assert verdict(10.0, run, dropped) == "FAIL (dropped)"
    assert verdict(10.0, run, []) == "PASS"


def test_a_run_shorter_than_the_warm_up_is_judged_from_its_last_sample():
    run = samples([170, 175, 180])
    assert (run[-1]["time"] - run[0]["time"]) < WARMUP_S
    assert settled_growth(run) == (180.0, 180.0, 180.0)


def test_the_competing_load_burns_cpu_and_is_gone_afterwards():
    """Each busy loop runs and burns CPU time (waited for, not timed) until the block ends; then it is gone."""
    with competing_load(2) as spinners:
        assert len(spinners) == 2
        wait_for(lambda: all(process_cpu_seconds(spinner.pid) > 0.2 for spinner in spinners), what="the busy loops to burn CPU")
        assert all(spinner.poll() is None for spinner in spinners)
    assert all(spinner.returncode is not None for spinner in spinners)


class EndOfTest(Exception):
    """Raised by :class:`StallingApp` on its third read: the sampling loop has gone on past the late report."""


class StallingApp:
    """An app whose first metrics read times out; ``exit_code`` None means it is still running."""

    def __init__(self, exit_code: int | None) -> None:
        self.reads = 0
        self.process = type("Process", (), {"poll": lambda _: exit_code})()

    def metrics(self, newer_than: float) -> dict:
        self.reads += 1
        if self.reads == 1:
            raise TimeoutError("no metrics from the app newer than 0.0 after 10 s: metrics.json 12.0 s old\nlog")
        if self.reads == 3:
            raise EndOfTest
        return {"time": time.time(), "rss_bytes": 0}


def test_a_late_report_from_a_running_app_is_recorded_and_sampling_goes_on():
    app, reports, late = StallingApp(exit_code=None), [], []
    with pytest.raises(EndOfTest):
        asyncio.run(sample_server(app, time.time() + 3600, reports, late, interval=0.0))
    assert late == ["no metrics from the app newer than 0.0 after 10 s: metrics.json 12.0 s old"]
    assert len(reports) == 1 and app.reads == 3


def test_a_late_report_from_an_app_that_exited_ends_the_run():
    with pytest.raises(TimeoutError):
        asyncio.run(sample_server(StallingApp(exit_code=1), time.time() + 3600, [], [], interval=0.0))


def test_end_to_end_matches_each_update_to_the_newest_event_it_could_answer():
    """The x-sorted search gives what a brute-force match of every update against every event does,
    on a looping path (each position sent many times) with folded events and stray updates."""
    import numpy as np

    from ur10dev.viser_client import staleness

    rng = np.random.default_rng(3)
    loop = rng.uniform(-1, 1, (40, 3)).astype(np.float32)  # one lap; the path goes round it 10 times
    sends = [(0.05 * k, loop[k % 40]) for k in range(400)]
    updates = []
    for k in range(400):
        if rng.random() < 0.3:
            continue  # folded into a later event
        flanges = np.zeros((8, 3), np.float32)
        flanges[rng.integers(0, 8):] = loop[k % 40]  # branches before it invalid (at the origin)
        updates.append((0.05 * k + rng.uniform(0.001, 0.12), flanges))
    updates.append((30.0, np.zeros((8, 3), np.float32)))  # nothing valid: answers nothing
    updates.append((30.0, np.full((8, 3), 5.0, np.float32)))  # a target nobody sent
    updates.sort(key=lambda u: u[0])

    def brute_force():
        first = np.full(len(sends), np.inf)
        for arrival, flanges in updates:
            valid = np.abs(flanges).sum(axis=-1) > 0
            if not valid.any():
                continue
            hits = [k for k, (t, p) in enumerate(sends) if t <= arrival and np.abs(p - flanges[valid][0]).max() < 1e-5]
            if hits:
                first[hits[-1]] = min(first[hits[-1]], arrival)
        shown = np.minimum.accumulate(first[::-1])[::-1]
        return [float(a - t) if np.isfinite(a) else None for (t, _), a in zip(sends, shown)]

    expected = brute_force()
    assert sum(v is not None for v in expected) > 300
    assert staleness(sends, updates) == expected
