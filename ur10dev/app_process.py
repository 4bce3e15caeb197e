"""Run the app in its own process, as in class, and read the figures it reports (tests and benchmarks).

The load generator must not share the server's interpreter (and its GIL): the server
runs as ``python -m ur10dev.metered_app`` (the app, writing its handler latencies, CPU time
and resident memory to a JSON file every second).
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
#: how long :meth:`AppProcess.metrics` waits for a fresh report (the app writes one every second)
METRICS_TIMEOUT_S = 10.0


@contextlib.contextmanager
def serving(command: list[str], cwd: Path, env: dict[str, str], timeout: float = 60.0) -> Iterator[tuple[subprocess.Popen, list[str]]]:
    """Start the app with ``command``; yields (the process, its output so far, still growing) once it is serving.

    Raises ``RuntimeError`` with its output if it exits or does not say it is ready within
    ``timeout`` s; terminates it afterwards.
    """
    process = subprocess.Popen(command, cwd=cwd, env=dict(env, PYTHONUNBUFFERED="1"),
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    output: list[str] = []
    ready = threading.Event()

    def drain() -> None:  # keep reading, or a chatty server would block on a full pipe
        for line in process.stdout:
            output.append(line)
            if line.startswith("Press Ctrl+C"):
                ready.set()
        ready.set()

    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    try:
        if not ready.wait(timeout) or process.poll() is not None:
            raise RuntimeError("the app did not start:\n" + "".join(output))
        yield process, output
    finally:
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
        reader.join(timeout=10)  # to the pipe's end: a helper the app left would still hold it open
        if not reader.is_alive():
            process.stdout.close()


@contextlib.contextmanager
def running_app(*args: str, timeout: float = 60.0, env: dict[str, str] | None = None,
                root: Path = ROOT) -> Iterator["AppProcess"]:
    """``python -m ur10teach --port 0 *args`` in a subprocess (a later ``--port`` wins); yields once it is serving.

    ``env`` adds to the environment (``UR10CORE_BACKEND``, say); ``root`` is the checkout
    whose app runs (another commit's, for a before-and-after benchmark).
    """
    with tempfile.TemporaryDirectory() as folder:
        metrics = Path(folder) / "metrics.json"
        environment = dict(os.environ, **(env or {}), UR10_TEACH_METRICS=str(metrics))
        # an older checkout (bench_page --against) measured itself when UR10_TEACH_METRICS was set, and
        # before the app was installed as ur10teach it ran as ``-m app``
        if (root / "ur10dev" / "metered_app.py").exists():
            module = "ur10dev.metered_app"
        else:
            module = "ur10teach" if "ur10teach" in (root / "pyproject.toml").read_text() else "app"
        command = [sys.executable, "-m", module, "--port", "0", *args]
        if "--shared" in args and "--results" not in args and "--results" in (root / "app" / "__main__.py").read_text("utf-8"):
            command += ["--results", str(Path(folder) / "results")]  # a challenge's results: not in the user's home
        with serving(command, root, environment, timeout) as (process, output):
            url = next(URL.search(line).group(1) for line in output if line.startswith("    ") and URL.search(line))
            yield AppProcess(process, url, metrics, output)


class AppProcess:
    def __init__(self, process: subprocess.Popen, url: str, metrics: Path, output: list[str]) -> None:
        self.process = process
        self.url = url
        self.metrics_path = metrics
        self.output = output

    def metrics(self, newer_than: float = 0.0, timeout: float = METRICS_TIMEOUT_S) -> dict:
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
        raise TimeoutError(f"no metrics from the app newer than {newer_than:.1f} after {timeout:.0f} s: "
                           f"{self._metrics_state()}; the app's last output:\n" + "".join(self.output[-40:]))

    def _metrics_state(self) -> str:
        """The report's age (or why it cannot be read) and whether the app still runs."""
        try:
            state = f"the report is {time.time() - json.loads(self.metrics_path.read_text())['time']:.1f} s old"
        except (OSError, ValueError, KeyError) as error:
            state = f"the report is unreadable ({type(error).__name__})"
        code = self.process.poll()
        return state + ("; the app is running" if code is None else f"; the app exited with {code}")
