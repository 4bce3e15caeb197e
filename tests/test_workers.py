"""The drag queue on an event loop of its own: who waits, and for how many turns of the loop."""

from __future__ import annotations

import asyncio
import threading
import time

from app import workers
from app.workers import DragQueue


class Arm:
    def __init__(self) -> None:
        self.lock = threading.RLock()


class Student:
    """A session whose drag takes ``cost`` seconds of the loop."""

    closed = False

    def __init__(self, cost: float, served: list) -> None:
        self.state, self.cost, self.served = Arm(), cost, served

    def drag_to(self, target) -> None:
        end = time.perf_counter() + self.cost
        while time.perf_counter() < end:
            pass
        self.served.append(target)

    def notify(self, *args) -> None:
        pass


def test_thirty_waiting_students_are_served_in_a_few_turns_of_the_loop():
    """A turn of the loop after every student made the thirtieth wait thirty turns (48 ms p99 in a classroom)."""
    loop = asyncio.new_event_loop()
    thread = threading.Thread(target=loop.run_forever, daemon=True)
    thread.start()
    try:
        queue = DragQueue(loop)
        served: list = []
        turns: list[int] = []

        async def other_sockets():  # what else wants the loop: one step per turn
            turns.append(len(served))
            await asyncio.sleep(0)
            while len(served) < 30:
                turns.append(len(served))
                await asyncio.sleep(0)

        students = [Student(0.0001, served) for _ in range(30)]

        def submit_all():
            for k, student in enumerate(students):
                queue.submit(student, k)
            asyncio.ensure_future(other_sockets())

        loop.call_soon_threadsafe(submit_all)
        deadline = time.monotonic() + 10
        while len(served) < 30 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert served == list(range(30))  # oldest first, each once
        # 30 × 0.1 ms = 3 ms of drags: the sockets get a turn every few ms, not after each student
        assert workers.DRAG_TURN <= 0.005  # no student is kept from the sockets for long either
        interruptions = len(set(turns)) - 1
        assert interruptions <= 5, f"the loop turned {interruptions} times while serving 30 students: {turns}"
        queue.stop()
        time.sleep(0.05)  # its task ends
    finally:
        loop.call_soon_threadsafe(loop.stop)
        thread.join(5)


def test_slow_jobs_run_one_at_a_time_and_each_browser_rests_between_its_own():
    from app.workers import HeavyWork

    heavy = HeavyWork(duty=0.25)
    spans: list[tuple[int, float, float]] = []  # (client, start, end)
    running, overlaps = [], []

    def job(client: int):
        def work():
            running.append(client)
            if len(running) > 1:
                overlaps.append(tuple(running))
            start = time.monotonic()
            time.sleep(0.05)
            spans.append((client, start, time.monotonic()))
            running.remove(client)
        return work

    threads = [threading.Thread(target=heavy.run, args=(client, job(client))) for client in (1, 1, 2)]
    for thread in threads:
        thread.start()
        time.sleep(0.005)  # in this order: client 1, client 1 again, client 2
    for thread in threads:
        thread.join()
    assert not overlaps and len(spans) == 3
    ones = sorted(s for s in spans if s[0] == 1)
    # client 1's second job waited three times its first's length (duty 1/4); client 2 did not wait for that
    assert ones[1][1] - ones[0][2] >= 3 * (ones[0][2] - ones[0][1]) - 1e-3
    two = next(s for s in spans if s[0] == 2)
    assert two[1] < ones[1][1]
