"""Write one benchmark's results into its own section of BENCHMARKS.md."""

from __future__ import annotations

import datetime
import os
import platform
import re
import time
from pathlib import Path

BENCHMARKS_MD = Path(__file__).resolve().parent.parent / "BENCHMARKS.md"


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import numpy

    return (
        f"{datetime.date.today().isoformat()}, {cpu}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, numpy {numpy.__version__}"
    )


def cpu_ticks() -> list[int]:
    """The machine's CPU time so far by kind (``/proc/stat``: user, nice, system, idle, iowait, irq, softirq, steal)."""
    try:
        return [int(v) for v in Path("/proc/stat").read_text().splitlines()[0].split()[1:9]]
    except (OSError, ValueError, IndexError):
        return [0] * 8


def process_cpu_seconds(pid: int) -> float:
    """CPU time (user and system, s) process ``pid`` has used so far (``/proc/PID/stat``)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(") ", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def stolen_share(before: list[int], after: list[int]) -> float:
    """Share of the machine's CPU time between two :func:`cpu_ticks` that the host gave to other guests.

    On a virtual machine, "steal" is time our cores were ready to run and the host ran
    someone else: every timer and socket on the machine fires late meanwhile.
    """
    spent = [b - a for a, b in zip(before, after)]
    return spent[7] / sum(spent) if sum(spent) > 0 else float("nan")


def idle_timer_lag(seconds: float = 10.0, period: float = 0.02) -> tuple[float, float, float]:
    """How late a ``period`` s sleep wakes, with nothing else to do: (p50, p99, share stolen meanwhile).

    The floor under every latency measured on this machine at this moment.
    """
    import numpy

    before, lags = cpu_ticks(), []
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        expected = time.perf_counter() + period
        time.sleep(period)
        lags.append(max(0.0, time.perf_counter() - expected))
    p50, p99 = numpy.percentile(lags, [50, 99])
    return float(p50), float(p99), stolen_share(before, cpu_ticks())


def quiet_machine(max_wait: float = 600.0, lag_p99: float = 0.02, stolen: float = 0.05) -> tuple[float, float, float, float]:
    """Wait until the idle machine's timer lag p99 and stolen share are under the given bounds.

    On a shared virtual machine the neighbours come and go; a load test that starts while
    the host takes half our cores measures them, not us. Gives up after ``max_wait`` s.
    Returns :func:`idle_timer_lag`'s last (p50, p99, stolen) and the seconds waited before it.
    """
    started = time.monotonic()
    while True:
        waited = time.monotonic() - started
        p50, p99, share = idle_timer_lag()
        if (p99 <= lag_p99 and share <= stolen) or waited > max_wait:
            return p50, p99, share, waited


def work_unit_floor(seconds: float = 3.0) -> tuple[float, float]:
    """The same small piece of pure-Python work, timed over and over in thread CPU time: (p50, p99) in ms.

    The work never changes, so any spread is the machine's: a virtual CPU that the host
    slows or stalls, a hyperthread sibling busy with something else. It is the floor
    under every tail latency measured at that moment.
    """
    import numpy

    def unit() -> int:
        total = 0
        for i in range(20000):
            total += i * i
        return total

    times = []
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        start = time.thread_time()
        unit()
        times.append(time.thread_time() - start)
        time.sleep(0.002)
    p50, p99 = numpy.percentile(times, [50, 99]) * 1e3
    return float(p50), float(p99)


def steady_cpu(max_wait: float = 600.0, spread: float = 1.5) -> tuple[float, float, float]:
    """Wait until :func:`work_unit_floor`'s p99 is within ``spread`` × its p50 (or ``max_wait`` s have passed).

    Returns the last (p50, p99) and the seconds waited.
    """
    started = time.monotonic()
    while True:
        p50, p99 = work_unit_floor()
        if p99 <= spread * p50 or time.monotonic() - started > max_wait:
            return p50, p99, time.monotonic() - started


def write_section(name: str, body: str) -> None:
    """Replace the text between ``<!-- name:begin -->`` and ``<!-- name:end -->``."""
    begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
    text = BENCHMARKS_MD.read_text() if BENCHMARKS_MD.exists() else "# Benchmarks\n"
    block = f"{begin}\n{body.strip()}\n{end}"
    pattern = re.compile(re.escape(begin) + ".*?" + re.escape(end), re.S)
    text = pattern.sub(lambda _: block, text) if pattern.search(text) else text.rstrip() + "\n\n" + block + "\n"
    BENCHMARKS_MD.write_text(text)


def table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)
