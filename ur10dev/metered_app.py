"""``python -m ur10dev.metered_app ARGS``: the app as ``ur10-teach ARGS`` runs it, writing what it measures.

Every second it writes to ``$UR10_TEACH_METRICS`` (JSON): the clients and sessions, the
handler latencies (``ur10teach.serving.metrics.LATENCY``, the event loop's lag and the
garbage collector's pauses among them), CPU time per kind of thread and resident memory.
The tests and benchmarks read it through :mod:`ur10dev.app_process`.
"""

from __future__ import annotations

import asyncio  # noqa: E402
import gc  # noqa: E402
import json  # noqa: E402
import logging  # noqa: E402
import os  # noqa: E402
import sys  # noqa: E402
import threading  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import ur10teach.__main__ as entry  # first: it sets the allocator up before numpy allocates
from ur10teach.serving.metrics import LATENCY  # noqa: E402

log = logging.getLogger(__name__)


def resident_bytes() -> int:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


async def watch_event_loop(stop: threading.Event, period: float = 0.02) -> None:
    """How late viser's event loop runs a callback it was asked to run ``period`` s from now.

    Everything a browser sends and receives passes through that loop, so its lag adds to
    every round trip; recorded as the ``event_loop_lag`` latency.
    """
    while not stop.is_set():
        expected = time.perf_counter() + period
        await asyncio.sleep(period)
        LATENCY.record("event_loop_lag", max(0.0, time.perf_counter() - expected))


def watch_garbage_collector() -> None:
    """Record each collection's pause as the ``gc`` latency (it stops every thread)."""
    started: dict[str, float] = {}

    def callback(phase: str, info: dict) -> None:
        if phase == "start":
            started["t"] = time.perf_counter()
        elif "t" in started:
            LATENCY.record(f"gc{info['generation']}", time.perf_counter() - started.pop("t"))

    gc.callbacks.append(callback)


def thread_cpu_seconds() -> dict[str, float]:
    """CPU seconds per kind of thread (the event loop, the workers, viser's pool), from /proc."""
    ticks = os.sysconf("SC_CLK_TCK")
    out: dict[str, float] = {}
    for thread in threading.enumerate():
        kind = "viser pool" if thread.name.startswith("ThreadPoolExecutor") else thread.name
        try:
            fields = Path(f"/proc/self/task/{thread.native_id}/stat").read_text().rsplit(") ", 1)[1].split()
        except (OSError, IndexError):
            continue
        out[kind] = out.get(kind, 0.0) + (int(fields[11]) + int(fields[12])) / ticks
    return out


def write_metrics(app, path: Path) -> None:
    """Once a second: clients, handler latencies, CPU and memory of this process."""
    while True:
        time.sleep(1.0)
        try:
            report = {
                "time": time.time(),
                "clients": len(app.server.get_clients()),
                "sessions": len(app.sessions),
                "janitor_sweeps": app.janitor.sweeps,
                "latency": LATENCY.summary(),
                "cpu_seconds": sum(os.times()[:2]),
                "rss_bytes": resident_bytes(),
                "threads": threading.active_count(),
                "thread_cpu_seconds": thread_cpu_seconds(),
            }
            partial = path.with_suffix(".tmp")
            partial.write_text(json.dumps(report))
            partial.replace(path)  # readers never see half a file
        except Exception:  # one failed report must not end the reports (a benchmark waits on them)
            log.exception("metrics report failed")


def start_metering(app) -> None:
    watch_garbage_collector()
    asyncio.run_coroutine_threadsafe(watch_event_loop(threading.Event()), app.server.get_event_loop())
    threading.Thread(target=write_metrics, args=(app, Path(os.environ["UR10_TEACH_METRICS"])), daemon=True).start()


if __name__ == "__main__":
    entry.main(sys.argv[1:], started=start_metering)
