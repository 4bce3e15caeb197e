"""The viser server: one :class:`ArmSession` per connected browser."""

from __future__ import annotations

import asyncio
import ctypes
import functools
import gc
import ipaddress
import logging
import math
import socket
import struct
import sys
import threading
import time
import warnings
from pathlib import Path

import viser

from ur10core import Arm, symbolic, symbolic_arms
from ur10core.arm import factor_scales
from ur10core.challenges import Challenge, builtin, unfit

from ..features.arm_picker import (
    ARM_CHOICES,
    CUSTOM,
    FIRST_ARMS,
    PAGE_TITLE,
    SWITCH_INTERVAL,
    UR10,
    ArmPicker,
    choice_of,
    panel_title,
    show_title,
)
from ..features.branch_labels import CAMERA_FOV_DEGREES, CAMERA_LOOK_AT, CAMERA_POSITION
from ..features.camera import relay_camera_moves
from ..features.course_arms.editor import starting_table
from ..features.floor import add_floor_grid
from ..features.workspace import CLOUDS
from ..feedback import notify
from ..meshes import load_models
from ..session import ArmSession
from ..style import BRAND_BLUE
from ..viser_internals import fast_updates, shared_frames, value_fits
from .classroom import Classroom
from .gate import (
    CONNECTIONS_PER_ADDRESS, RETURN_WINDOW, Gate, TokenBucket, address_in, address_of, browser_of, budget_of, gated_serve,
    hang_up_silent, on_a_phone,
)
from .joining import JoinHelp
from .screens import Screens
from .workers import APART, JOINS, Cancelled, DragQueue, PanelRefresher, refuse_in_worker_process

log = logging.getLogger(__name__)

# A browser that leaves mid-redraw gets a few late messages before its session hears it has
# gone; viser warns about each such connection. The session stops drawing as soon as it
# hears, so nothing accumulates: the warning would only clutter the teacher's console.
warnings.filterwarnings("ignore", message=r"Queued a \w+ on a closed connection", category=UserWarning)


def lan_addresses() -> list[str]:
    """This machine's IPv4 addresses other than loopback (what students type), best first."""
    found: list[str] = []
    try:  # the interface of the default route; sends nothing
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.connect(("10.255.255.255", 1))
            found.append(probe.getsockname()[0])
    except OSError:
        pass
    found += _linux_interface_addresses()
    try:  # (Windows and macOS name each of their addresses here; Debian and Ubuntu only 127.0.1.1)
        for info in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET):
            found.append(info[4][0])
    except OSError:
        pass
    return [a for i, a in enumerate(found) if not a.startswith("127.") and a not in found[:i]]


def _linux_interface_addresses() -> list[str]:
    """The IPv4 address of each network interface that is up and connected, on Linux.

    A laptop whose only network is the hotspot it makes for the class has no default route, and its host name
    stands for 127.0.1.1: without these, the students were given no address at all."""
    if not sys.platform.startswith("linux"):
        return []
    import fcntl

    found = []
    try:
        names = [name for _, name in socket.if_nameindex()]
    except OSError:  # a sandbox that lists no interfaces: the other two ways still name some
        return []
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        for name in names:
            request = struct.pack("256s", name.encode()[:15])
            try:
                flags = struct.unpack_from("H", fcntl.ioctl(probe.fileno(), _SIOCGIFFLAGS, request), 16)[0]
                # (docker0 without a container is up but not running: nobody reaches it)
                if flags & _IFF_UP and flags & _IFF_RUNNING and not flags & _IFF_LOOPBACK:
                    found.append(socket.inet_ntoa(fcntl.ioctl(probe.fileno(), _SIOCGIFADDR, request)[20:24]))
            except OSError:  # no IPv4 address, or gone meanwhile
                pass
    return found


def listening_problem(host: str, port: int) -> str:
    """Why this computer cannot serve at ``host``:``port`` ("" if it can): a port out of range, a name, or an
    address that is not this computer's (a typo, or the network it was on yesterday). viser tried a thousand ports
    there, then waited for ever without a word (a port beyond 65535: after a traceback).

    >>> listening_problem("127.0.0.1", 0), listening_problem("0.0.0.0", 70000)[:24]
    ('', 'the port is from 1 to 65')
    """
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        return f"the port is from 1 to 65535 (0: any free one), got {port!r:.20}"
    if host in ("", "localhost"):
        return ""
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        return (f"the host is an address of this computer: 127.0.0.1 (this computer alone) or 0.0.0.0 (students on "
                f"the network too), got {host!r:.60}")
    try:
        with socket.socket(socket.AF_INET6 if address.version == 6 else socket.AF_INET, socket.SOCK_STREAM) as probe:
            probe.bind((host, 0))
    except OSError as error:
        return (f"this computer has no address {host} ({error.strerror or error}); its network may have changed. "
                "0.0.0.0 lets students on the network join at whatever address it has")
    return ""


_SIOCGIFFLAGS, _SIOCGIFADDR = 0x8913, 0x8915  # <linux/sockios.h>
_IFF_UP, _IFF_LOOPBACK, _IFF_RUNNING = 0x1, 0x8, 0x40  # <net/if.h>


#: How often (s) a server open to the network looks at this machine's addresses again: a laptop that slept between
#: the office and the lecture hall wakes on another network, at another address.
ADDRESS_CHECK_S = 10.0
#: Addresses whose arm changes are remembered (all forgotten beyond it).
MAX_SWITCH_BUDGETS = 10_000
#: Browsers whose arms are kept for their return (``gate.RETURN_WINDOW``; the oldest forgotten first).
MAX_RETURNING = 256
#: Open files the server asks for at start: a connection is one, and 1 024 (a common default) ran out
#: when one address held a thousand half-open requests.
OPEN_FILES = 65_536
#: The most open files macOS lets a process ask for (its ``OPEN_MAX``), whatever the hard limit says: its setrlimit(2)
#: refuses a soft limit above it, and a Mac's default soft limit is 256.
MACOS_OPEN_MAX = 10_240


def raise_open_file_limit(wanted: int = OPEN_FILES) -> int:
    """Raise this process's soft limit on open files towards ``wanted`` (up to the hard limit) where the OS allows.

    Returns the soft limit in force afterwards (0 where there is none to read, as on Windows).
    """
    try:
        import resource
    except ImportError:  # Windows: no such limit on sockets
        return 0
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    target = wanted if hard == resource.RLIM_INFINITY else min(wanted, hard)
    if soft != resource.RLIM_INFINITY and soft < target:
        for asked in (target, MACOS_OPEN_MAX):  # (a teacher's Mac: its hard limit unlimited, but not beyond OPEN_MAX)
            if soft < asked <= target:  # (never lowered)
                try:
                    resource.setrlimit(resource.RLIMIT_NOFILE, (asked, hard))
                    return asked
                except (ValueError, OSError):
                    pass
        log.info("could not raise the open-file limit from %d", soft)
    return soft


class Janitor:
    """Keeps the collector off the browsers' arms while they are here, and hands their memory back once they leave.

    A full collection scans every object; with a lecture hall's arms built, that paused
    every browser for 0.1 to 0.17 s every few seconds (BENCHMARKS.md, *a class challenge in a
    lecture hall*). Each arm is frozen once built (:meth:`settle`), out of the collector's
    sight. A class leaving at the bell frees thousands of small objects at once; Python keeps
    the freed memory for reuse and glibc keeps the pages. A few seconds after the last
    departure or change of arm (:meth:`soon`), the sweep drops the clouds no one shows,
    thaws, collects what the departed left (their arms hold cycles), freezes again and
    calls ``malloc_trim``: one pass however many leave. While they keep coming (a hundred
    students trying arms), it still sweeps at least every :data:`LONGEST` seconds, since only
    a sweep frees a frozen arm. Large buffers are handed back as soon as they are freed
    (``ur10teach.__main__``).
    """

    DELAY = 3.0
    LONGEST = 30.0

    def __init__(self, forget=(), clock=time.monotonic) -> None:
        self._forget = forget  #: what to drop first: caches nobody uses any more
        self.sweeps = 0  #: how many times it has swept (the memory tests wait for one)
        self._timer: threading.Timer | None = None
        self._first: float | None = None  #: when the oldest request the next sweep answers came
        self._clock = clock
        self._stopped = False
        self._lock = threading.Lock()
        try:
            self._trim = ctypes.CDLL("libc.so.6").malloc_trim
        except (OSError, AttributeError):  # not glibc: collecting is all we can do
            self._trim = None

    def soon(self) -> None:
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
            if self._stopped:
                return
            now = self._clock()
            if self._first is None:
                self._first = now
            self._timer = threading.Timer(max(0.0, min(self.DELAY, self._first + self.LONGEST - now)), self.sweep)
            self._timer.daemon = True
            self._timer.start()

    def stop(self) -> None:
        """The server has stopped: no sweep is due any more (a sweep scans everything the process holds)."""
        with self._lock:
            self._stopped = True
            if self._timer is not None:
                self._timer.cancel()

    @staticmethod
    def settle() -> None:
        """A browser's arm is built: it and whatever else lives now stay out of full collections until the next sweep."""
        gc.freeze()

    def sweep(self) -> None:
        with self._lock:
            self._first = None  # a request from here on waits for the next sweep
        for forget in self._forget:
            forget()
        gc.unfreeze()
        gc.collect()
        gc.freeze()
        if self._trim is not None:
            self._trim(0)
        self.sweeps += 1


class TeachingServer:
    """The app: a viser server giving every browser its own arm (the UR10 first, or ``first_arm``; then any arm it picks).

    Parameters
    ----------
    preset : str
        ``"course"``, ``"ur10"`` or ``"ur10e"`` (see :meth:`ur10core.Arm.preset`).
    first_arm : str
        The arm every browser opens on (``--arm``; in shared mode, the class's first): ``"ur10"``, the app's own
        UR10 with ``preset``'s numbers, or the ``Arm.preset`` name of one of the course's other arms.
    host, port : str, int
        Where to listen. viser moves to the next free port when ``port`` is busy:
        :attr:`port` is the real one. ``port=0`` lets the OS choose (tests).
    shared : bool
        Shared demo mode: everyone watches the presenter's arm (:class:`ur10teach.serving.classroom.Classroom`).
    allowed_origins : iterable of str
        Web pages besides the app's own that may open its websocket (``--allow-origin``).
    gate : Gate, optional
        What the server accepts from browsers (:mod:`ur10teach.serving.gate`); one with
        ``allowed_origins`` by default.
    lecture : bool
        Every browser starts in lecture mode (:mod:`ur10teach.features.lecture`).
    light : bool
        The arm and its ghosts shaded for laptops without a graphics driver (``--light``,
        :class:`ur10teach.meshes.ArmModels`).
    challenges : tuple of Challenge
        What the classroom's presenter can set (``--challenges``; the built-in ones by default).
    results : Path, optional
        The folder each class challenge's results file is written to as it ends, and as the server stops
        (``--results``); none written without it.
    """

    def __init__(self, preset: str = "course", first_arm: str = "ur10", host: str = "127.0.0.1", port: int = 8080, shared: bool = False,
                 allowed_origins=(), gate: Gate | None = None, lecture: bool = False, light: bool = False,
                 challenges: tuple[Challenge, ...] | None = None, results: Path | None = None) -> None:
        refuse_in_worker_process()
        problem = listening_problem(host, port)
        if problem:
            raise ValueError(problem)
        self.arm = Arm.preset(preset)
        if first_arm not in FIRST_ARMS:
            raise ValueError(f"first_arm: {first_arm!r} is not an arm of the picker")
        #: the picker's label of the arm every browser opens on
        self.first_choice = UR10 if first_arm == "ur10" else choice_of(first_arm)
        # what the app's own UR10 cannot be asked on this preset is not offered
        self.challenges = tuple(c for c in (builtin() if challenges is None else challenges) if not unfit(c, preset))
        self.results = results
        self.lecture, self.light = lecture, light
        self.models = load_models(preset, light)
        symbolic.load()  # read the cached derivations now rather than in the first student's callback
        for name in ARM_CHOICES.values():
            if name not in (None, "custom"):
                if name != "three_dof":  # its factors are a closed form
                    symbolic_arms.load(name)
                factor_scales(Arm.preset(name))  # the gauges' scales: a few hundred ms in all, never in a callback
        factor_scales(self.arm)
        if host not in ("", "localhost") and ipaddress.ip_address(host) == ipaddress.IPv6Address("::"):
            host = ""  # every interface, as a teacher means: at "::" asyncio listens on IPv6 alone (IPV6_V6ONLY)
        self.host = host
        #: it listens on every interface of this machine, whichever they are now
        self.everywhere = host in ("0.0.0.0", "")
        label = panel_title(self.first_choice, preset)
        self.gate = gate or Gate(allowed_origins)
        raise_open_file_limit()
        shared_frames.install()
        fast_updates.share_type_hints()
        with gated_serve(self.gate, PAGE_TITLE):
            self.server = viser.ViserServer(host=host, port=port, label=label, verbose=False)
        self.gate.value_fits = functools.partial(value_fits, self.server)
        self.screens = Screens(self._screen_told)
        self.gate.heard = self.screens.heard
        self.server.gui.configure_theme(show_share_button=False, brand_color=BRAND_BLUE, control_width="large")
        self.server.initial_camera.position = CAMERA_POSITION
        self.server.initial_camera.look_at = CAMERA_LOOK_AT
        self.server.initial_camera.up = (0.0, 0.0, 1.0)
        self.server.initial_camera.fov = math.radians(CAMERA_FOV_DEGREES)
        add_floor_grid(self.server.scene)
        loop = self.server.get_event_loop()
        self.refresher = PanelRefresher(loop)
        self.drags = DragQueue(loop)
        self._sessions: dict[int, ArmSession] = {}
        self._last_switch: dict[int, float] = {}  # client id → when its arm was last rebuilt
        #: client id → picker choice → (state, typed table, display choices) of each arm the browser has
        #: left: going back to one finds its pose, target, typed table and what it showed as they were
        self._left_arms: dict[int, dict[str, tuple]] = {}
        #: client id → (which browser it is (``gate.browser_of``: its address first), the client)
        self._browsers: dict[int, tuple[str, viser.ClientHandle]] = {}
        #: browser → (when, choice shown, its left arms, (lecture mode, light view)) as its page left last
        self._departed: dict[str, tuple[float, str, dict[str, tuple], tuple[bool, bool]]] = {}
        self._switches: dict[str, TokenBucket] = {}  # budget (an address) → its arm changes
        #: the time arm changes are paced by (an address's, and a class's) and a browser's return is timed by (a test
        #: sets its own)
        self.clock = time.monotonic
        self._sessions_lock = threading.Lock()
        self.janitor = Janitor(forget=(CLOUDS.forget_unheld,))
        #: what students type to join: the addresses of this machine the server listens on beyond itself (none
        #: when it serves this machine only), shown on the teacher's screen (:func:`join_markdown`)
        self.join_urls = self._reachable_urls()
        #: students can join from other machines: the teacher's screen shows how (with no address yet, that it has none)
        self.open_to_network = bool(self.join_urls) or self.everywhere
        self._stopping = threading.Event()
        #: shared demo mode (``--shared``): everyone watches the presenter (``ur10teach.serving.classroom``)
        self.classroom = Classroom(self) if shared else None
        if self.everywhere:
            threading.Thread(target=self._follow_addresses, name="addresses", daemon=True).start()
        self.server.on_client_connect(self._connected)
        self.server.on_client_disconnect(self._disconnected)
        # everything loaded so far (numpy, sympy, viser, the meshes) lives as long as the server
        gc.collect()
        self.janitor.settle()

    @property
    def port(self) -> int:
        return self.server.get_port()

    def _reachable_urls(self) -> list[str]:
        return [url for url in self.urls if not url.startswith(("http://127.", "http://localhost"))]

    def _follow_addresses(self) -> None:
        """Keep :attr:`join_urls`, and every teacher's screen, to this machine's addresses as they change."""
        while not self._stopping.wait(ADDRESS_CHECK_S):
            urls = self._reachable_urls()
            if urls != self.join_urls:
                self.join_urls = urls
                log.info("this computer's network changed: students now open %s", " or ".join(urls) or "nothing yet")
            if self.classroom is not None:
                helps = self.classroom.join_helps()
            else:
                helps = [session.join_help for session in self.sessions.values() if hasattr(session, "join_help")]
            for join_help in helps:  # (one built as the addresses changed, too)
                try:
                    join_help.update(urls)
                except Exception:  # one screen's trouble: the others, and the next change, still get theirs
                    log.exception("could not show a browser the new addresses")

    @property
    def urls(self) -> list[str]:
        """Where browsers can reach the app."""
        if self.everywhere:
            return [f"http://127.0.0.1:{self.port}"] + [f"http://{a}:{self.port}" for a in lan_addresses()]
        host = f"[{self.host}]" if ":" in self.host else self.host  # (an IPv6 address goes in brackets)
        return [f"http://{host}:{self.port}"]

    @property
    def sessions(self) -> dict[int, ArmSession]:
        """Client id → the session driving an arm for it (independent mode: every client)."""
        if self.classroom is not None:
            return self.classroom.sessions
        with self._sessions_lock:
            return dict(self._sessions)

    def _connected(self, client: viser.ClientHandle) -> None:
        if client.client_id in self.server.get_clients():  # (one gone already is not built either: below)
            self._drop_dead_twins(client)
        try:
            JOINS.run(client, lambda: self._build_first(client),
                      cancelled=lambda: client.client_id not in self.server.get_clients())
        except Cancelled:  # it left before its turn
            return
        except Exception:
            log.exception("could not set up client %s", client.client_id)
            try:
                client.add_notification("Could not start", "Reload the page to try again.", color="red")
            except Exception:
                pass
            return
        # viser runs connect and disconnect callbacks on its thread pool side by side: a
        # browser that left while its arm was being built was not here to be freed yet
        if client.client_id not in self.server.get_clients():
            self._disconnected(client)

    def _drop_dead_twins(self, client: viser.ClientHandle) -> None:
        """Let this browser's other pages that no longer answer leave now (``gate.hang_up_silent``): the page
        connecting may be one of them back, before the server has noticed it had gone. Other students' browsers
        behind the same address are not pinged: one still reading its scene over a slow Wi-Fi would be hung up. The
        pages of this address viser has let go already leave now too: viser lists a client gone, then runs its
        disconnect callback on its thread pool, where thirty students' arrivals may hold it up, and a reloaded
        projector would come back as a viewer."""
        address, browser = address_of(client), browser_of(client)
        if self.classroom is not None:
            let_go = [member.client for member in self.classroom.members_from(address)]
        else:
            with self._sessions_lock:
                let_go = [other for known, other in self._browsers.values() if address_in(known) == address]
        current = self.server.get_clients()  # (after: each of those was listed before it was kept)
        for gone in let_go:
            if gone.client_id not in current:
                self._disconnected(gone)
        if self.gate.trusted(address):  # this machine's own tabs do not drop off the network (nor its load tests)
            return
        twins = [other for other_id, other in self.server.get_clients().items()
                 if other_id != client.client_id and browser_of(other) == browser]
        if twins:
            for twin in asyncio.run_coroutine_threadsafe(hang_up_silent(twins), self.server.get_event_loop()).result():
                log.info("browser %s from %s no longer answers: it has left", twin.client_id, address)
                self._disconnected(twin)

    def _build_first(self, client: viser.ClientHandle) -> None:
        if self.classroom is not None:
            self.classroom.connect(client)
        else:
            relay_camera_moves(client, lambda: getattr(self._sessions.get(client.client_id), "camera", None))
            choice, view, browser = self.first_choice, self._view_of(None), browser_of(client)
            with self._sessions_lock:
                self._browsers[client.client_id] = (browser, client)
                when, *left = self._departed.pop(browser, (-math.inf, None, {}, view))
                back = self.clock() - when <= RETURN_WINDOW  # from where a browser left: its arms as it left them
                if back:
                    choice, self._left_arms[client.client_id], view = left
            try:
                self._start_session(client, choice, view)
            except Exception:
                if not back:
                    raise
                # what was kept must not stop this browser's every return: it starts afresh
                log.exception("could not bring back the arms browser %s's computer left; it starts afresh", client.client_id)
                with self._sessions_lock:
                    self._left_arms.pop(client.client_id, None)
                client.gui.reset()
                client.scene.reset()
                self._start_session(client, self.first_choice, self._view_of(None))
                return
            if back:
                notify(client, "Welcome back", "Your arms are as this browser left them.", color="blue")

    def _start_session(self, client: viser.ClientHandle, choice: str, view: tuple[bool, bool], typed=None) -> None:
        """Build the arm ``choice`` (an ``ARM_CHOICES`` label) in this browser, with the picker above it.

        ``view``: (lecture mode, light view) (:meth:`_view_of`); ``typed``: (arm, text, convention) of a table
        typed in the DH editor.
        """
        name = ARM_CHOICES[choice]
        lecture, light = view
        phone = on_a_phone(client)
        state, display = None, {}
        if typed is None:  # not a newly typed table: the arm as this browser left it, if it has been here
            with self._sessions_lock:
                state, typed, display = self._left_arms.get(client.client_id, {}).get(choice, (None, None, {}))
        if name is None:
            session = ArmSession(client, self.arm, self.refresher, self.drags, models=self.models, lecture=lecture,
                                 light=light, phone=phone, state=state)
        elif name == "custom":
            typed = typed or starting_table()
            arm, text, convention = typed
            session = ArmSession(
                client, arm, self.refresher, self.drags, lecture=lecture, light=light, phone=phone, text=text,
                convention=convention, state=state,
                rebuild=lambda new, new_text, new_convention: self._switch(client, CUSTOM, (new, new_text, new_convention)))
        else:
            session = ArmSession(client, state.arm if state else Arm.preset(name), self.refresher, self.drags,
                                 lecture=lecture, light=light, phone=phone, state=state)
        session.choice, session.typed = choice, typed
        session.show_choices(display)
        show_title(client.gui, panel_title(choice, self.arm.name))
        with self._sessions_lock:
            if client.client_id in self._last_switch:  # a change of arm: the interval starts before its picker shows
                self._last_switch[client.client_id] = time.monotonic()
        session.arm_picker = ArmPicker(client.gui, choice, lambda label: self._switch(client, label), session.guard)
        if self.open_to_network and self.gate.trusted(address_of(client)):  # the teacher's own screen
            with session.arm_picker.folder:
                session.join_help = JoinHelp(client, self.join_urls, teacher=True, guard=session.guard)
        self.janitor.settle()
        with self._sessions_lock:
            self._sessions[client.client_id] = session
        self.screens.probe(client, reset=True)  # (a new arm's panel: the last was reset with the old arm)
        session.camera.show_screen(*self.screens.of(client.client_id))

    def _switch(self, client: viser.ClientHandle, choice: str, typed=None) -> None:
        """Take this browser's arm out (panel and scene) and build ``choice`` in its place.

        Building an arm costs tens of milliseconds: one browser may start a build only
        :data:`SWITCH_INTERVAL` seconds after its last one was ready (timed just before its
        picker is shown, so a browser that waits that long after seeing it is never refused),
        and all the tabs of one address together as often as one (:func:`ur10teach.serving.gate.budget_of`),
        so that flicking the picker, in one tab or eight, cannot load the server.
        """
        budget = budget_of(client)
        with self._sessions_lock:
            if len(self._switches) > MAX_SWITCH_BUDGETS:
                self._switches.clear()
            switches = self._switches.setdefault(budget, TokenBucket(1.0 / SWITCH_INTERVAL, 2, clock=lambda: self.clock()))
            # each tab as often as its picker allows; all of one address's tabs together no more than one would
            if not self.can_switch(client.client_id) or not switches.take():
                raise ValueError(f"one change of arm every {SWITCH_INTERVAL:g} s, please: try again in a moment")
            self._last_switch[client.client_id] = math.inf  # refused while this one is being built
            old = self._sessions.pop(client.client_id, None)
            if old is not None:
                self._leave(client.client_id, old)
        view = self._view_of(old)
        if old is not None:
            old.close()
            self.janitor.soon()
        try:
            client.gui.reset()
            client.scene.reset()
            self._start_session(client, choice, view, typed)
        finally:
            with self._sessions_lock:
                if self._last_switch.get(client.client_id) == math.inf:  # the build failed before its picker
                    self._last_switch[client.client_id] = time.monotonic()
        if client.client_id not in self.server.get_clients():  # it left meanwhile
            self._disconnected(client)

    def can_switch(self, client_id: int) -> bool:
        """Whether this browser may change its arm now (:data:`SWITCH_INTERVAL` after its last change was ready)."""
        return time.monotonic() - self._last_switch.get(client_id, -math.inf) >= SWITCH_INTERVAL

    def _screen_told(self, client_id: int) -> None:
        """A browser's pixel ratio or window width changed: its labels are placed anew for it, its arm framed anew."""
        held = self.classroom.members if self.classroom is not None else self.sessions
        camera = getattr(held.get(client_id), "camera", None)
        if camera is not None:
            camera.show_screen(*self.screens.of(client_id))

    def _disconnected(self, client: viser.ClientHandle) -> None:
        self.screens.forget(client.client_id)
        if self.classroom is not None:
            self.classroom.disconnect(client)
        else:
            with self._sessions_lock:
                session = self._sessions.pop(client.client_id, None)
                self._last_switch.pop(client.client_id, None)
                if session is not None:
                    self._leave(client.client_id, session)
                left = self._left_arms.pop(client.client_id, {})
                browser, _ = self._browsers.pop(client.client_id, (None, None))
                if browser is not None and left:  # kept for its return (one that left mid-change: the arm it changed from)
                    self._departed.pop(browser, None)
                    self._departed[browser] = (self.clock(), next(reversed(left)), left, self._view_of(session))
                    # (oldest first) one address keeps as many as it may have browsers open, and all keep MAX_RETURNING:
                    # a page that sends a new cookie each time must not push the others' arms out
                    there = [kept for kept in self._departed if address_in(kept) == address_in(browser)]
                    for kept in there[:-CONNECTIONS_PER_ADDRESS] + list(self._departed)[:-MAX_RETURNING]:
                        self._departed.pop(kept, None)
            if session is not None:
                session.close()
        self.janitor.soon()

    def _view_of(self, session: ArmSession | None) -> tuple[bool, bool]:
        """(lecture mode, light view) in the browser of ``session`` (the server's defaults without one)."""
        if session is None or session.camera is None:
            return self.lecture, self.light
        return session.camera.lecture.on, session.camera.light.on

    def _leave(self, client_id: int, session: ArmSession) -> None:
        """Keep ``session``'s arm as the browser leaves it, the most recent last (the caller holds the sessions' lock)."""
        left = self._left_arms.setdefault(client_id, {})
        left.pop(session.choice, None)
        left[session.choice] = (session.state, session.typed, session.display_choices())

    def stop(self) -> None:
        self._stopping.set()
        self.refresher.stop()
        if self.classroom is not None:
            self.classroom.challenges.keep_results()  # a challenge still running as the teacher stops the server
            self.classroom.challenges.boards.stop()
        self.drags.stop()
        self.janitor.stop()
        APART.stop()
        self.server.stop()
