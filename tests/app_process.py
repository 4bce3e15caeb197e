"""Run the app in its own process, as in class, and read the figures it reports.

The load generator must not share the server's interpreter (and its GIL): the server
runs as ``python -m app`` with ``UR10_TEACH_METRICS`` set, and writes its handler
latencies, CPU time and resident memory to a JSON file every second.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Iterator

ROOT = Path(__file__).resolve().parent.parent
URL = re.compile(r"(http://127\.0\.0\.1:\d+)")
PROCESSES = re.compile(r"(\d+) processes\) is running")
#: how long :meth:`AppProcess.metrics` waits for a fresh report (the app writes one every second)
METRICS_TIMEOUT_S = 10.0


@contextlib.contextmanager
def running_app(*args: str, timeout: float = 60.0, env: dict[str, str] | None = None) -> Iterator["AppProcess"]:
    """``python -m app --port 0 *args`` in a subprocess (a later ``--port`` wins); yields once it is serving.

    ``env`` adds to the environment (``UR10CORE_BACKEND``, say).
    """
    with tempfile.TemporaryDirectory() as folder:
        metrics = Path(folder) / "metrics.json"
        environment = dict(os.environ, **(env or {}), UR10_TEACH_METRICS=str(metrics), PYTHONUNBUFFERED="1")
        process = subprocess.Popen(
            [sys.executable, "-m", "app", "--port", "0", *args], cwd=ROOT, env=environment,
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        )
        output: list[str] = []
        ready = threading.Event()

        def drain() -> None:  # keep reading, or a chatty server would block on a full pipe
            for line in process.stdout:
                output.append(line)
                if line.startswith("Press Ctrl+C"):
                    ready.set()
            ready.set()

        threading.Thread(target=drain, daemon=True).start()
        try:
            if not ready.wait(timeout) or process.poll() is not None:
                raise RuntimeError("the app did not start:\n" + "".join(output))
            url = next(URL.search(line).group(1) for line in output if line.startswith("    ") and URL.search(line))
            yield AppProcess(process, url, metrics, output)
        finally:
            process.terminate()
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()


class AppProcess:
    def __init__(self, process: subprocess.Popen, url: str, metrics: Path, output: list[str]) -> None:
        self.process = process
        self.url = url
        self.metrics_path = metrics
        self.output = output
        found = PROCESSES.search("".join(output))
        #: how many processes serve the app (``--processes``; helpers write ``<metrics>.1``, ``.2``, ...)
        self.processes = int(found.group(1)) if found else 1

    def metrics(self, newer_than: float = 0.0, timeout: float = METRICS_TIMEOUT_S) -> dict:
        """The server's latest report written after ``newer_than`` (a time.time()), over all its processes.

        Clients, CPU seconds and resident bytes are summed; each latency kind gives the
        total count and the worst process's p50 / p99 / max. ``"processes"`` keeps the
        per-process reports (the first process first).
        """
        paths = [self.metrics_path] + [Path(f"{self.metrics_path}.{k}") for k in range(1, self.processes)]
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                reports = [json.loads(path.read_text()) for path in paths]
                if all(report["time"] > newer_than for report in reports):
                    return merge_reports(reports)
            except (FileNotFoundError, json.JSONDecodeError):
                pass
            time.sleep(0.1)
        raise TimeoutError(f"no metrics from the app newer than {newer_than:.1f} after {timeout:.0f} s: "
                           f"{self._metrics_state(paths)}; the app's last output:\n" + "".join(self.output[-40:]))

    def _metrics_state(self, paths: list[Path]) -> str:
        """Each report's age (or why it cannot be read) and whether the first process still runs."""
        now, states = time.time(), []
        for path in paths:
            try:
                states.append(f"{path.name} {now - json.loads(path.read_text())['time']:.1f} s old")
            except (OSError, ValueError, KeyError) as error:
                states.append(f"{path.name} unreadable ({type(error).__name__})")
        code = self.process.poll()
        return ", ".join(states) + ("; the app is running" if code is None else f"; the app exited with {code}")


def merge_reports(reports: list[dict]) -> dict:
    """One report for an app served by several processes (see :meth:`AppProcess.metrics`)."""
    merged = {"time": min(r["time"] for r in reports), "processes": reports, "latency": {}}
    for key in ("clients", "sessions", "cpu_seconds", "rss_bytes"):
        merged[key] = sum(r[key] for r in reports)
    for kind in {kind for r in reports for kind in r["latency"]}:
        parts = [r["latency"][kind] for r in reports if kind in r["latency"]]
        merged["latency"][kind] = {"count": sum(p["count"] for p in parts),
                                   **{f: max(p[f] for p in parts) for f in ("p50_ms", "p99_ms", "max_ms")}}
    return merged
