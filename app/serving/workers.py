"""The two background workers every session shares, running on viser's own event loop.

Why it is built so: docs/architecture.md §3.
"""

from __future__ import annotations

import asyncio
import collections
import concurrent.futures
import concurrent.futures.process
import heapq
import itertools
import logging
import multiprocessing
import os
import signal
import sys
import threading
import time
import weakref
from typing import Any, Protocol

from .gate import budget_of
from .metrics import LATENCY

log = logging.getLogger(__name__)

#: Shortest time between two panel redraws of one browser (s).
PANEL_INTERVAL = 0.1
#: Largest share of the machine's time the panel redraws may take: under a classroom's load
#: the panels slow down (each still shows the newest state) before the 3D view does.
#: ``UR10_TEACH_PANEL_DUTY=1`` lets them take all of it (the classroom benchmark measures both).
DUTY = float(os.environ.get("UR10_TEACH_PANEL_DUTY", "0.15"))

#: Largest share of the time one address's slow one-off jobs may take (:class:`HeavyWork`).
HEAVY_DUTY = 0.25
#: Largest share of the time building newcomers' sessions may take (:data:`JOINS`). A hundred
#: joining within 10 s while five dragged (BENCHMARKS.md, one run): at 1, the draggers' p99 was
#: 189 ms; at 0.75, 102 ms, and every newcomer had its scene within 1.5 s. ``UR10_TEACH_JOIN_DUTY`` sets it (the benchmark measures both).
JOIN_DUTY = float(os.environ.get("UR10_TEACH_JOIN_DUTY", "0.75"))
#: Threads for the background work of every session (:data:`BACKGROUND`). Each session's features
#: fold their runs, so this bounds the threads, however fast presses come, not what is done.
BACKGROUND_THREADS = 32


class Cancelled(Exception):
    """A slow job that was not started: its browser has gone, or its run was stopped."""


#: The drag worker serves waiting sessions for this long (s) before the sockets get a turn.
#: A turn after every session cost each of thirty waiting students a pass of the event
#: loop over every socket: with thirty dragging, queue wait p99 was 48 ms against 11 ms
#: with turns of 4 ms (``bench_classroom.py --only independent``, one run each).
DRAG_TURN = 0.004


class HasPanel(Protocol):
    closed: bool

    def render_panel(self) -> None: ...


class HasDrags(Protocol):
    closed: bool
    state: Any  # has a ``lock``

    def drag_to(self, target) -> None: ...

    def notify(self, title: str, body: str, color: str = "yellow") -> None: ...


class _LoopWorker:
    """A task on ``loop``; ``_call`` runs a method on the loop from any thread."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self._loop = loop
        self._stopped = False
        self._wake: asyncio.Event | None = None
        self._started = threading.Event()
        self.done = asyncio.run_coroutine_threadsafe(self._main(), loop)  #: resolves once stopped
        self._started.wait(timeout=10.0)

    async def _main(self) -> None:
        self._wake = asyncio.Event()
        self._started.set()
        while not self._stopped:
            try:
                await self._run()
            except Exception:  # a bug: it must not stop every student's drags or panels for good
                log.exception("%s failed; it starts again", type(self).__name__)
                self._failed()
                await asyncio.sleep(0.05)

    async def _run(self) -> None:
        raise NotImplementedError

    def _failed(self) -> None:
        """Tell whoever was being served when :meth:`_run` failed."""

    def _call(self, function, *args) -> None:
        try:
            running = asyncio.get_running_loop()
        except RuntimeError:
            running = None
        if running is self._loop:
            function(*args)
        else:
            try:
                self._loop.call_soon_threadsafe(function, *args)
            except RuntimeError:
                pass  # the loop has closed: the server is stopping

    def stop(self) -> None:
        self._stopped = True
        self._call(lambda: self._wake.set() if self._wake is not None else None)


class DragQueue(_LoopWorker):
    """The newest drag target of each session, solved and drawn session by session.

    ``clock`` times the turns (:data:`DRAG_TURN`); a test passes its own.
    """

    def __init__(self, loop: asyncio.AbstractEventLoop, clock=time.perf_counter) -> None:
        self._ready: collections.deque[int] = collections.deque()  # session ids, oldest request first
        self._pending: dict[int, tuple[HasDrags, object, float]] = {}  # session, target, filed at
        self._serving: HasDrags | None = None
        self._clock = clock
        super().__init__(loop)

    def submit(self, session: HasDrags, target) -> None:
        """Replace ``session``'s pending target (queueing the session if it was not waiting)."""
        self._call(self._file, session, target, time.perf_counter())

    def _file(self, session: HasDrags, target, now: float) -> None:
        key = id(session)
        if key in self._pending:
            now = self._pending[key][2]  # still waiting since its oldest unserved event
        else:
            self._ready.append(key)
            self._wake.set()
        self._pending[key] = (session, target, now)

    async def _run(self) -> None:
        while not self._stopped:
            await self._wake.wait()
            self._wake.clear()
            turn = self._clock()
            while self._ready and not self._stopped:
                if self._clock() - turn > DRAG_TURN:
                    await asyncio.sleep(0)  # let the sockets have a turn
                    turn = self._clock()
                key = self._ready.popleft()
                session, target, filed = self._pending.pop(key)
                if session.closed:
                    continue
                if not session.state.lock.acquire(blocking=False):
                    # a click on this arm is being handled on viser's thread pool: never
                    # block the loop for it, come back to this session in a moment
                    self._file(session, target, filed)
                    await asyncio.sleep(0.001)
                    continue
                self._serving = session  # until it is served: if this fails, _failed tells them
                try:
                    LATENCY.record("drag_wait", time.perf_counter() - filed)
                    session.drag_to(target)  # guarded by the session: nothing escapes
                finally:
                    session.state.lock.release()
                self._serving = None

    def _failed(self) -> None:
        session, self._serving = self._serving, None
        if session is not None:
            session.notify("Something went wrong", "That drag was lost; drag again. The app is still running.", "red")


class PanelRefresher(_LoopWorker):
    """Panel redraws: each session at most every ``interval`` s, at most ``duty`` of the time."""

    def __init__(self, loop: asyncio.AbstractEventLoop, interval: float = PANEL_INTERVAL, duty: float = DUTY) -> None:
        self.interval = interval
        self.duty = duty
        self._queue: list[tuple[float, int, HasPanel]] = []  # (due, order, session)
        self._waiting: set[int] = set()  # id() of sessions in the queue
        self._last: dict[int, float] = {}
        self._order = itertools.count()
        super().__init__(loop)

    def request(self, session: HasPanel) -> None:
        """Redraw ``session``'s panel soon (at once if it has not been redrawn lately)."""
        self._call(self._file, session)

    def forget(self, session: HasPanel) -> None:
        self._call(self._last.pop, id(session), None)

    def _file(self, session: HasPanel) -> None:
        key = id(session)
        if key in self._waiting:
            return  # already queued: it will draw the newest state when its turn comes
        interval = getattr(session, "panel_interval", self.interval)  # a panel may ask to be redrawn less often
        due = max(time.monotonic(), self._last.get(key, 0.0) + interval)
        heapq.heappush(self._queue, (due, next(self._order), session))
        self._waiting.add(key)
        self._wake.set()

    async def _run(self) -> None:
        while not self._stopped:
            if not self._queue:
                await self._wake.wait()
                self._wake.clear()
                continue
            delay = self._queue[0][0] - time.monotonic()
            if delay > 0:
                self._wake.clear()
                try:
                    await asyncio.wait_for(self._wake.wait(), delay)
                except asyncio.TimeoutError:
                    pass
                continue
            spent = self._draw(heapq.heappop(self._queue)[2])  # no session stays referenced here while it rests
            await asyncio.sleep(spent * (1.0 / self.duty - 1.0))

    def _draw(self, session: HasPanel) -> float:
        """Redraw one session's panel (none once it has closed); the seconds it took."""
        key = id(session)
        self._waiting.discard(key)
        if session.closed:
            self._last.pop(key, None)
            return 0.0
        self._last[key] = time.monotonic()
        started = time.perf_counter()
        try:
            session.render_panel()
        except Exception:
            if not session.closed:
                log.exception("panel redraw failed")
        return time.perf_counter() - started


class FoldedRuns:
    """Runs ``run`` for the newest request: requests that come while it runs fold into one more run.

    A cloud or a map takes a moment; however many widget changes or redraws ask for one
    meanwhile, at most one run is under way and one waits, and the waiting one sees the
    newest choices. :meth:`claim` then :meth:`run_claimed` splits the two, so that the
    run can go to a thread of its own only when one is needed.
    """

    def __init__(self, run) -> None:
        self._run = run
        self._lock = threading.Lock()
        self._busy = self._again = False

    @property
    def busy(self) -> bool:
        """A run is under way."""
        with self._lock:
            return self._busy

    @property
    def waiting(self) -> bool:
        """A newer request came during the current run (it will be served by one more)."""
        with self._lock:
            return self._again

    def claim(self) -> bool:
        """True: the caller must now call :meth:`run_claimed`. False: the run under way takes the request."""
        with self._lock:
            if self._busy:
                self._again = True
                return False
            self._busy = True
            return True

    def run_claimed(self) -> None:
        """Run until no request is waiting. A run that raised is followed by the one waiting, if any,
        and the first error is raised once none waits (it may explain a refusal)."""
        error = None
        while True:
            try:
                self._run()
            except BaseException as raised:  # noqa: BLE001 - re-raised below, once no request waits
                error = error or raised
            with self._lock:
                if not self._again:
                    self._busy = False
                    break
                self._again = False
        if error is not None:
            raise error

    def __call__(self) -> None:
        """Run here, in the caller's thread, unless a run is already under way."""
        if self.claim():
            self.run_claimed()

    def start(self, name: str, wrap=lambda handler: handler) -> None:
        """Run on a thread of its own (named ``name``), unless a run is already under way.

        ``wrap`` wraps the thread's work as it does a callback (``session.guard``): nothing escapes.
        """
        if self.claim():
            BACKGROUND.submit(wrap(lambda _: self.run_claimed()), None)


class HeavyWork:
    """Slow one-off jobs: one at a time in the server, each budget's at most ``duty`` of the time.

    A job starts no sooner than the last one of its budget (``budget(who)``: by default
    ``who`` itself; for :data:`HEAVY`, the browser's address) took × (1/duty − 1) after that
    one ended; the rest is kept per budget, so a rebuilt arm or a new tab does not start
    afresh. Call :meth:`run` from a thread of the job's own: it may wait, and it raises
    :class:`Cancelled` instead of starting the job once ``cancelled()`` is true. ``clock``
    and ``sleep`` are the time and the wait (a test passes its own).
    """

    #: Longest single wait (s) before ``cancelled`` is asked again.
    CHECK_EVERY = 0.25

    def __init__(self, duty: float = HEAVY_DUTY, clock=time.monotonic, sleep=time.sleep, budget=lambda who: who) -> None:
        self.duty = duty
        self._clock, self._sleep, self._budget = clock, sleep, budget
        self._slot = threading.Lock()
        self._lock = threading.Lock()
        self._next: dict[Any, float] = {}  #: budget → when its next job may start (monotonic)
        self.started = 0  #: jobs started (for the tests)

    def run(self, who, job, cancelled=lambda: False):
        key = self._budget(who)
        while True:
            if cancelled():
                raise Cancelled
            wait = self._rest(key)
            if wait > 0:
                self._sleep(min(wait, self.CHECK_EVERY))
                continue
            if not self._slot.acquire(timeout=self.CHECK_EVERY):
                continue
            try:
                if self._rest(key) > 0:  # another job of this budget ran while this one waited for the slot
                    continue
                if cancelled():
                    raise Cancelled
                start = self._clock()
                self.started += 1
                try:
                    return job()
                finally:
                    end = self._clock()
                    with self._lock:
                        self._next[key] = end + (end - start) * (1.0 / self.duty - 1.0)
            finally:
                self._slot.release()

    def _rest(self, key) -> float:
        """How long this budget must still wait before its next job (s)."""
        with self._lock:
            now = self._clock()
            self._next = {k: t for k, t in self._next.items() if t > now}  # only budgets still resting
            return self._next.get(key, now) - now


HEAVY = HeavyWork(budget=budget_of)
#: Newcomers' sessions (``ur10teach.serving.server``): built one at a time, resting after each so that the students
#: already there keep dragging while a lecture hall joins (``benchmarks/bench_join_storm.py``).
JOINS = HeavyWork(duty=JOIN_DUTY, budget=lambda who: "joins")
#: The branch-count maps (``ur10teach.features.reach_map``): made while a gizmo turns, so a larger share, and a slot of their own.
MAPS = HeavyWork(duty=0.5, budget=budget_of)
#: The threads background work runs on (a pool: presses cannot multiply them).
BACKGROUND = concurrent.futures.ThreadPoolExecutor(BACKGROUND_THREADS, thread_name_prefix="background")


def _worker_started() -> None:
    """In the worker process: Ctrl+C is the server's to handle, and the server's drags come first."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(os, "nice"):
        os.nice(5)


def refuse_in_worker_process() -> None:
    """Raise ``RuntimeError`` in a worker process that is running the script which started the server.

    A "spawn" worker runs the main script again, named ``__mp_main__``, before its first job. A
    teacher's own launcher without ``if __name__ == "__main__":`` would start a second server
    there, and the server's job would wait on it for ever. Refused, the worker ends, and the
    server runs its slow jobs itself (:class:`WorkerProcess`).
    """
    if getattr(sys.modules.get("__mp_main__"), "__name__", None) == "__mp_main__":  # (the parent's own is "__main__")
        raise RuntimeError("the app's worker process ran the script that starts the app again: start the app "
                           "under `if __name__ == \"__main__\":` in that script (until then, slow jobs run in the server)")


class WorkerProcess:
    """Runs ``function(*args, **kwargs)`` in a process of its own, from the thread that waits for it.

    The process is started at the first call ("spawn", as on Windows and macOS) and used
    again by the calls that follow; it ends once no job has come for :attr:`IDLE` seconds, so
    that its memory (about 60 MiB) is the server's only while jobs come. One job runs at a time
    (:data:`HEAVY` runs one at a time anyway). The function and its arguments must pickle (a
    function of a module, an arm). Where no process can be started, or the one started has
    died, the job runs in the caller's thread; a process that died before its first job
    came back is not started again (it cannot start: see :func:`refuse_in_worker_process`).
    """

    IDLE = 10.0

    def __init__(self) -> None:
        self._pool: concurrent.futures.ProcessPoolExecutor | None = None
        self._lock = threading.Lock()
        #: no process could be started (or ``UR10_TEACH_NO_WORKER_PROCESS=1``, for the benchmark that
        #: measures both): jobs run in the caller's thread
        self._unavailable = os.environ.get("UR10_TEACH_NO_WORKER_PROCESS") == "1"
        self.processes_started = 0  #: (for the tests)
        self._jobs = 0  #: jobs handed over and not yet back
        self._idle: threading.Timer | None = None
        self._served: weakref.WeakSet = weakref.WeakSet()  #: the pools a job came back from

    def run(self, function, *args, **kwargs):
        pool = self._started()
        try:
            if pool is not None:
                try:
                    result = pool.submit(function, *args, **kwargs).result()
                    self._served.add(pool)
                    return result
                except concurrent.futures.BrokenExecutor as broken:  # raised by the pool, never by the job
                    if pool in self._served:
                        log.warning("the worker process is gone (%s); this job runs in the server", broken)
                    else:
                        log.warning("the worker process could not start (%s): slow jobs run in the server", broken)
                        self._unavailable = True
                    self._discard(pool)
                except RuntimeError as error:
                    if not str(error).startswith("cannot schedule new futures"):
                        raise  # the job's own
                    self._discard(pool)  # shut down as its server stopped
            return function(*args, **kwargs)
        finally:
            self._finished()

    def _started(self) -> concurrent.futures.ProcessPoolExecutor | None:
        with self._lock:
            self._jobs += 1
            if self._idle is not None:
                self._idle.cancel()
                self._idle = None
            if self._pool is None and not self._unavailable:
                try:
                    self._pool = concurrent.futures.ProcessPoolExecutor(
                        1, mp_context=multiprocessing.get_context("spawn"), initializer=_worker_started)
                    self.processes_started += 1
                except (OSError, NotImplementedError, ImportError) as error:
                    log.warning("no worker process (%s): slow jobs run in the server", error)
                    self._unavailable = True
            return self._pool

    def _finished(self) -> None:
        """A job is back: the idle time counts from the last one's end."""
        with self._lock:
            self._jobs -= 1
            if self._jobs == 0 and self._pool is not None:
                timer = self._idle = threading.Timer(self.IDLE, lambda: self._stop_if_idle(timer))
                timer.daemon = True
                timer.start()

    def _stop_if_idle(self, timer: threading.Timer) -> None:
        """``timer`` has run out: the process ends, unless a job came meanwhile (a pool shut down with a
        job waiting in it cancels the job)."""
        with self._lock:
            pool = self._pool if self._idle is timer and self._jobs == 0 else None
            if pool is not None:  # taken away under the lock: the next job starts a new process
                self._idle = self._pool = None
        if pool is not None:
            pool.shutdown(wait=False)

    def _discard(self, pool: concurrent.futures.ProcessPoolExecutor) -> None:
        with self._lock:
            if self._pool is pool:
                self._pool = None
        pool.shutdown(wait=False, cancel_futures=True)

    def stop(self) -> None:
        """End the process, if one was started (a job under way in it is not waited for)."""
        with self._lock:
            pool = self._pool
            if self._idle is not None:
                self._idle.cancel()
                self._idle = None
        if pool is not None:
            self._discard(pool)


#: The worker process of the jobs that hold the GIL.
APART = WorkerProcess()
