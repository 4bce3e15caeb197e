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
import time
from pathlib import Path
from typing import Iterator

ROOT = Path(__file__).resolve().parent.parent
URL = re.compile(r"(http://127\.0\.0\.1:\d+)")


@contextlib.contextmanager
def running_app(*args: str, timeout: float = 60.0) -> Iterator["AppProcess"]:
    """``python -m app --port 0 *args`` in a subprocess; yields once it is serving."""
    with tempfile.TemporaryDirectory() as folder:
        metrics = Path(folder) / "metrics.json"
        environment = dict(os.environ, UR10_TEACH_METRICS=str(metrics), PYTHONUNBUFFERED="1")
        process = subprocess.Popen(
            [sys.executable, "-m", "app", "--port", "0", *args], cwd=ROOT, env=environment,
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        )
        try:
            deadline = time.monotonic() + timeout
            output = []
            url = None
            while url is None:
                line = process.stdout.readline()
                if not line:
                    raise RuntimeError("the app exited before serving:\n" + "".join(output))
                output.append(line)
                match = URL.search(line) if "Open:" not in line and line.startswith("    ") else None
                url = match.group(1) if match else None
                if time.monotonic() > deadline:
                    raise TimeoutError("the app did not start:\n" + "".join(output))
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

    def metrics(self, newer_than: float = 0.0, timeout: float = 10.0) -> dict:
        """The server's latest report written after ``newer_than`` (a time.time())."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                report = json.loads(self.metrics_path.read_text())
                if report["time"] > newer_than:
                    return report
            except (FileNotFoundError, json.JSONDecodeError):
                pass
            time.sleep(0.1)
        raise TimeoutError("no metrics from the app")
