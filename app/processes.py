"""One port, several processes: thirty students dragging are most of a core's work.

viser serves every websocket from one asyncio event loop in one Python process. Thirty
students dragging at 20 Hz cost that loop 1 to 1.5 ms of server time per drag event (most
of it viser's per-message work), 60 to 90 % of a core depending on the machine
(BENCHMARKS.md). On the slower of the machines measured, one loop fell behind and the
end-to-end p99 passed 50 ms. Independent mode shares nothing between students, so the app
can serve them from several processes on one port: the first process binds the listening
socket and starts helpers that inherit it.

Left to the kernel, whichever process accepts first gets the connection: measured, a
class of thirty split 10 + 20 and the busier process missed the target. So the processes
keep their open-connection counts on a shared :class:`LoadBoard` and only the least
loaded one accepts (:class:`BalancedListener`); the others leave the connection waiting
for it, for at most :data:`BalancedListener.PATIENCE` (a busy or stuck peer).

Shared demo mode stays in one process: everyone there watches one arm.

Run as ``python -m app.processes --listen-fd N ...`` this module is a helper: it serves
the inherited socket until its standard input closes (the first process has stopped or
gone), so a helper never outlives the app.
"""

from __future__ import annotations

import argparse
import contextlib
import ipaddress
import logging
import mmap
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time
from typing import Callable, Iterator

import websockets.asyncio.server

log = logging.getLogger(__name__)

#: More processes than this buys nothing for one class (thirty students fit in two cores).
MAX_PROCESSES = 4
#: A helper that dies is started again, at most this many times (then the app carries on without it).
MAX_RESTARTS = 3
READY = "ready"
PORT_ATTEMPTS = 1000  # as viser: a busy port moves to the next one


def can_share_a_socket() -> bool:
    """Whether this platform lets child processes inherit a listening socket (POSIX)."""
    return os.name == "posix"


def default_process_count(host: str, shared: bool) -> int:
    """How many processes serve the app when ``--processes`` is not given.

    One for a student alone (loopback) and for shared demo mode (one arm for everyone);
    serving the network in independent mode, one per core, at most :data:`MAX_PROCESSES`.
    """
    if shared or not can_share_a_socket() or is_loopback(host):
        return 1
    return max(1, min(os.cpu_count() or 1, MAX_PROCESSES))


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def bind_listener(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host``: ``port``, or the next free port if it is busy (as viser does).

    ``port=0`` lets the OS choose. Raises ``OSError`` when no port in range is free.
    """
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    error: OSError | None = None
    for attempt in range(PORT_ATTEMPTS if port else 1):
        try:
            # SO_REUSEADDR (as asyncio sets it) but not SO_REUSEPORT: another app on this
            # port, or a second copy of this one, must keep the port to itself.
            return socket.create_server((host, port + attempt), family=family, backlog=128)
        except OSError as exc:
            error = exc
    raise OSError(f"no free port from {port} on {host!r}: {error}")


class LoadBoard:
    """Each process's count of open connections, in memory all the processes share.

    Backed by an unlinked temporary file; helpers inherit its descriptor (:attr:`fd`) and
    :meth:`attach`. Slot ``k`` is written only by process ``k``. A slot holding
    :data:`ABSENT` (a helper still starting, or gone) never counts as the least loaded.
    """

    ABSENT = 2**31 - 1

    def __init__(self, slots: int) -> None:
        self._file = tempfile.TemporaryFile()
        self._file.truncate(4 * slots)
        self._attach(self._file.fileno())
        for k in range(1, slots):
            self.counts[k] = self.ABSENT

    @classmethod
    def attach(cls, fd: int) -> "LoadBoard":
        """The board a helper inherited as descriptor ``fd``."""
        board = cls.__new__(cls)
        board._file = None
        board._attach(fd)
        return board

    def _attach(self, fd: int) -> None:
        self.fd = fd
        self._map = mmap.mmap(fd, os.fstat(fd).st_size)
        self.counts = memoryview(self._map).cast("i")

    def least_loaded(self, slot: int) -> bool:
        """Whether no process has fewer open connections than process ``slot``."""
        mine = self.counts[slot]
        return all(mine <= other for other in self.counts)


class _CountedConnection(socket.socket):
    """An accepted connection that tells its listener when it closes."""

    on_close: Callable[[], None] | None = None

    def close(self) -> None:
        callback, self.on_close = self.on_close, None
        if callback is not None:
            callback()
        super().close()


class BalancedListener(socket.socket):
    """A listening socket that accepts only while its process is the least loaded on the board.

    asyncio's server calls :meth:`accept` whenever the socket is readable; refusing with
    ``BlockingIOError`` (what an empty queue gives) leaves the connection for another
    process. A connection no other process takes within :data:`PATIENCE` seconds is
    accepted anyway. Build one with :meth:`wrap`.
    """

    PATIENCE = 0.25
    #: refusals further apart than this were for different connections (someone took the first)
    SAME_CONNECTION = 0.05

    @classmethod
    def wrap(cls, fd: int, board: LoadBoard, slot: int) -> "BalancedListener":
        """The listening socket ``fd`` as process ``slot`` on ``board`` (call :meth:`publish` once serving)."""
        listener = cls(fileno=fd)
        listener.board = board
        listener.slot = slot
        listener._open = 0
        listener._lock = threading.Lock()
        listener._refusing_since = listener._last_refusal = -1e9
        return listener

    def publish(self, change: int = 0) -> None:
        """Change this process's open-connection count on the board by ``change``."""
        with self._lock:
            self._open += change
            self.board.counts[self.slot] = self._open

    def accept(self) -> tuple[socket.socket, object]:
        now = time.monotonic()
        if not self.board.least_loaded(self.slot):
            if now - self._last_refusal > self.SAME_CONNECTION:
                self._refusing_since = now
            self._last_refusal = now
            if now - self._refusing_since < self.PATIENCE:
                raise BlockingIOError("left for a less loaded process")
        fd, address = self._accept()
        connection = _CountedConnection(self.family, self.type, self.proto, fileno=fd)
        connection.on_close = lambda: self.publish(-1)
        self.publish(+1)
        return connection, address


@contextlib.contextmanager
def viser_listens_on(listener: socket.socket) -> Iterator[None]:
    """While active, a viser server that starts serves ``listener`` instead of binding its own port.

    viser passes a host and a port to ``websockets.asyncio.server.serve`` and has no way
    to hand it a socket, so the call is redirected for the moment the server starts
    (``viser.ViserServer()`` returns only once it is listening).
    """
    original = websockets.asyncio.server.serve

    class serve_on_listener(original):  # type: ignore[misc, valid-type]
        def __init__(self, handler, host=None, port=None, **kwargs) -> None:  # noqa: ANN001
            super().__init__(handler, sock=listener, **kwargs)

    websockets.asyncio.server.serve = serve_on_listener
    try:
        yield
    finally:
        websockets.asyncio.server.serve = original


class Helpers:
    """The helper processes serving ``listener`` next to this one; restarted if one dies.

    Parameters
    ----------
    listener : BalancedListener
        The first process's listening socket (slot 0 of its board); helper ``k`` takes slot ``k``.
    preset, host : str
        As for :class:`app.server.TeachingServer`.
    """

    START_TIMEOUT = 120.0

    def __init__(self, listener: BalancedListener, preset: str, host: str) -> None:
        self._listener = listener
        self._preset = preset
        self._host = host
        self._stopping = threading.Event()
        self._lock = threading.Lock()
        count = len(listener.board.counts) - 1
        self.processes: list[subprocess.Popen | None] = [None] * count
        self.restarts = [0] * count
        ready = [self._start(k) for k in range(count)]
        for k, event in enumerate(ready):
            if not event.wait(self.START_TIMEOUT) or self.processes[k].poll() is not None:
                self.stop()
                raise RuntimeError(f"helper process {k + 1} could not start (see the messages above)")

    def _start(self, k: int) -> threading.Event:
        environment = dict(os.environ)
        metrics = environment.get("UR10_TEACH_METRICS")
        if metrics:  # one report per process; benchmarks read them all
            environment["UR10_TEACH_METRICS"] = f"{metrics}.{k + 1}"
        fds = (self._listener.fileno(), self._listener.board.fd)
        process = subprocess.Popen(
            [sys.executable, "-m", "app.processes", "--listen-fd", str(fds[0]), "--board-fd", str(fds[1]),
             "--slot", str(k + 1), "--preset", self._preset, "--host", self._host],
            pass_fds=fds, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=environment,
        )
        with self._lock:
            self.processes[k] = process
        ready = threading.Event()
        threading.Thread(target=self._watch, args=(k, process, ready), name=f"helper {k + 1} watch", daemon=True).start()
        return ready

    def _watch(self, k: int, process: subprocess.Popen, ready: threading.Event) -> None:
        served = False
        for line in process.stdout:  # the helper's own output (viser's banner) is not the teacher's business
            if line.strip() == READY:
                served = True
                ready.set()
        code = process.wait()
        self._listener.board.counts[k + 1] = LoadBoard.ABSENT  # its connections died with it
        ready.set()  # (if it never served: whoever waits for it sees it has exited)
        # Ctrl+C reaches the helpers too, possibly before this process starts stopping them
        if self._stopping.wait(1.0):
            return
        if not served:
            log.error("helper process %d could not start (exit code %s); carrying on without it", k + 1, code)
        elif self.restarts[k] >= MAX_RESTARTS:
            log.error("helper process %d stopped (exit code %s) %d times; carrying on without it",
                      k + 1, code, self.restarts[k] + 1)
        else:
            self.restarts[k] += 1
            log.warning("helper process %d stopped (exit code %s); its students reconnect to the others; "
                        "restarting it", k + 1, code)
            self._start(k)

    def stop(self, timeout: float = 10.0) -> None:
        """Close every helper's standard input (they stop on their own), then make sure they have gone."""
        self._stopping.set()
        with self._lock:
            processes = [p for p in self.processes if p is not None]
        for process in processes:
            with contextlib.suppress(OSError, ValueError):
                process.stdin.close()
        deadline = time.monotonic() + timeout
        for process in processes:
            try:
                process.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()


def serve_balanced(host: str, port: int, processes: int) -> BalancedListener:
    """Bind ``host``: ``port`` (or the next free port) for ``processes`` processes; this one is slot 0."""
    board = LoadBoard(processes)
    return BalancedListener.wrap(bind_listener(host, port).detach(), board, 0)


def _helper_main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m app.processes", description="a helper process of the UR10 app")
    parser.add_argument("--listen-fd", type=int, required=True)
    parser.add_argument("--board-fd", type=int, required=True)
    parser.add_argument("--slot", type=int, required=True)
    parser.add_argument("--preset", default="course")
    parser.add_argument("--host", default="127.0.0.1")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s (helper): %(message)s")
    logging.getLogger("websockets").setLevel(logging.WARNING)  # the first process already said where it listens
    from .server import TeachingServer

    listener = BalancedListener.wrap(args.listen_fd, LoadBoard.attach(args.board_fd), args.slot)
    app = TeachingServer(preset=args.preset, host=args.host, listener=listener)
    listener.publish()  # serving: from now on it can be the least loaded
    print(READY, flush=True)
    try:
        sys.stdin.read()  # returns when the first process closes our stdin or exits
    except KeyboardInterrupt:  # Ctrl+C in the teacher's terminal reaches every process
        pass
    finally:
        app.stop()


if __name__ == "__main__":
    try:
        _helper_main()
    except KeyboardInterrupt:
        pass
