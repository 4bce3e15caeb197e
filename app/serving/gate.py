"""What the server accepts from a browser: one gate on viser's websocket, in every mode.

Why it is built so: docs/architecture.md §4.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import http
import ipaddress
import logging
import math
import os
import re
import secrets
import socket
import threading
import time
import urllib.parse
from typing import Any, Callable, Iterator

import msgspec
import websockets.asyncio.server

from ..viser_internals import connection_of as _connection_of
from ..viser_internals import messages as viser_messages
from ..viser_internals import page_titled
from ..viser_internals import serving_through

log = logging.getLogger(__name__)

#: Largest message a browser may send (bytes): a text of :data:`_LONGEST_TEXT` characters, with room.
MAX_MESSAGE_BYTES = 4 * 1024
#: Messages and bytes a second one connection's socket is read at before decoding (after a burst of a
#: second's worth). A browser sends at most a few dozen small messages a second.
ARRIVALS_PER_SECOND = 200.0
ARRIVAL_BYTES_PER_SECOND = 128 * 1024
#: Messages over those rates a connection may send (refilling at one a second) before it is closed.
OVER_RATE_ALLOWANCE = 100
#: Messages per second a connection's messages pass at, after a burst of :data:`MESSAGE_BURST`.
MESSAGES_PER_SECOND = 60.0
MESSAGE_BURST = 60
#: Messages per second all the connections of one address pass at together (loopback excepted), after a
#: burst of :data:`ADDRESS_MESSAGE_BURST`: two tabs' worth. Eight connections flooding had eight rates.
ADDRESS_MESSAGES_PER_SECOND = 2 * MESSAGES_PER_SECOND
ADDRESS_MESSAGE_BURST = 2 * MESSAGE_BURST
#: Different widgets (or gizmos) one connection may have waiting at once; more are dropped.
MAX_WAITING = 64
#: Open websockets per address (loopback excepted).
CONNECTIONS_PER_ADDRESS = 8
#: New websockets per address and second, after a burst of :data:`NEW_CONNECTION_BURST`. Each builds a
#: whole session (its arm, panel and scene): eight at once from one address held every student up.
NEW_CONNECTIONS_PER_SECOND = 0.5
NEW_CONNECTION_BURST = 3
#: TCP connections per address (loopback excepted): the websockets and a browser's page downloads.
TCP_CONNECTIONS_PER_ADDRESS = 32
#: Seconds a new connection has to send its request (websockets' default is 10).
OPEN_TIMEOUT = 5.0
#: The slowest link a browser is served on (bytes/s): 128 kbit/s, each laptop's share of a lecture hall's Wi-Fi as a
#: hundred students open the page at once.
SLOWEST_LINK = 16 * 1024
#: Bytes the system may hold for a browser beyond the server's own buffer (the system doubles it on Linux): left to
#: itself it took megabytes, and a viewer on a slow link fell further and further behind the presenter's arm, shown
#: what the system held (a minute's worth at 128 kbit/s), until it was dropped. What waits in the server instead
#: is replaced by newer state (viser keeps the newest message of each kind).
SEND_BUFFER = 32 * 1024
#: Seconds a page may take to reach a browser once asked for. websockets gives a connection's whole opening, its
#: answer's sending included, one timeout, and cuts the answer short where it runs out: with 5 s, viser's page
#: (0.67 MB) reached a browser whole only at about 0.6 Mbit/s or more, and a class opening it at once saw blank
#: pages. At :data:`SLOWEST_LINK` the page takes 42 s.
DOWNLOAD_TIMEOUT = 60.0
#: Seconds a browser has to answer the server's keepalive ping (websockets' default is 20). The answer waits behind
#: what was sent before the ping: the workspace cloud (1.8 MB) takes 113 s at :data:`SLOWEST_LINK`, and a student was
#: cut off for asking for it, and again each time the page came back with it shown. A browser that reads nothing is
#: dropped sooner whenever anything waits for it (``ur10teach.viser_internals.shared_frames.SEND_TIMEOUT``).
PONG_TIMEOUT = 120.0

#: The messages the app uses, and what makes two of them the same (the newer replaces the older).
ALLOWED = {
    "GuiUpdateMessage": ("uuid",),
    "TransformControlsUpdateMessage": ("name",),
    "TransformControlsDragStartMessage": ("name",),
    "TransformControlsDragEndMessage": ("name",),
    "SceneNodeClickMessage": ("name", "instance_index"),
    "ViewerCameraMessage": (),
}
#: viser's class of each, whose fields a message must have, of their declared types.
_CLASSES = {kind: getattr(viser_messages, kind) for kind in ALLOWED}
#: A widget value is one of these, or a short list of them (a vector widget).
_SCALARS = (str, int, float, bool)
_LONGEST_TEXT = 1000
_LONGEST_LIST = 16
#: A camera a browser reports stands within this many metres of the world's origin (a student zooming out for a
#: minute stays far inside it), on a canvas at most this many pixels a side (an 8K screen has 7,680).
_FARTHEST_CAMERA = 1e7
_LARGEST_CANVAS = 32_768


class TokenBucket:
    """``rate`` tokens a second up to ``burst``; :meth:`take` says whether one was there.

    ``clock`` gives the time in seconds (a test passes its own).
    """

    def __init__(self, rate: float, burst: float, clock=time.monotonic) -> None:
        self.rate, self.burst, self._clock = rate, burst, clock
        self.tokens, self.stamp = float(burst), clock()

    def _fill(self) -> None:
        now = self._clock()
        self.tokens = min(self.burst, self.tokens + (now - self.stamp) * self.rate)
        self.stamp = now

    def take(self, amount: float = 1.0) -> bool:
        self._fill()
        if self.tokens >= amount:
            self.tokens -= amount
            return True
        return False

    def wait_time(self) -> float:
        """Seconds until a token is there."""
        self._fill()
        return max(0.0, (1.0 - self.tokens) / self.rate)


class SharedRate:
    """A rate the messages of several connections pass at together: one connection at a time waits for
    the next token (the others queue behind it, first come first served, instead of each polling)."""

    def __init__(self, rate: float, burst: float) -> None:
        self.bucket = TokenBucket(rate, burst)
        self._turn = asyncio.Lock()

    async def take(self) -> None:
        async with self._turn:
            delay = self.bucket.wait_time()
            if delay > 0.0:
                await asyncio.sleep(delay)
            self.bucket.take()


def classify(raw: bytes | str, value_fits=lambda uuid, value: True) -> tuple[tuple | None, str]:
    """``(key, kind)``: what the gate knows a browser's message by (None when the app does not take
    it), and the kind it claims to be (for the log). The message is decoded once, here; a widget's
    value must convert to its widget's type (``value_fits(uuid, value)``)."""
    if not isinstance(raw, bytes):
        return None, "text frame"
    try:
        message = msgspec.msgpack.decode(raw)
    except (msgspec.DecodeError, ValueError, TypeError):
        return None, "undecodable message"
    kind = message.get("type") if isinstance(message, dict) else None
    if not isinstance(kind, str) or len(kind) > 64:
        return None, "undecodable message"
    fields = ALLOWED.get(kind)
    if fields is None:
        return None, kind
    if kind == "GuiUpdateMessage" and not _plain_value_update(message.get("updates")):
        return None, f"{kind} setting more than a value"
    try:
        msgspec.convert({k: v for k, v in message.items() if k != "type"}, _CLASSES[kind])
    except msgspec.ValidationError:  # viser would fail on it, closing the sender's connection (1011)
        return None, f"malformed {kind}"
    if kind == "GuiUpdateMessage" and not value_fits(message["uuid"], message["updates"]["value"]):
        return None, f"{kind} of another type than its widget's"  # viser's conversion would raise in its handler
    if kind == "ViewerCameraMessage" and not _camera_a_browser_could_have(message):
        return None, f"{kind} of a camera no browser has"
    key = tuple(message.get(field) for field in fields)
    if not all(value is None or isinstance(value, (str, int)) for value in key):
        return None, f"malformed {kind}"
    return (kind, *key), kind


def message_key(raw: bytes) -> tuple | None:
    """What the gate knows a browser's message by, or None when it is not one the app takes."""
    return classify(raw)[0]


def _camera_a_browser_could_have(camera: dict) -> bool:
    """Finite, within :data:`_FARTHEST_CAMERA`, apart from the point it looks at and not looking along its up
    direction, with a field of view and a canvas. A zero field of view, a NaN or a canvas of no pixels failed the
    3D labels' placing and the framing for that browser, at every redraw, each time an error in the teacher's console.

    >>> camera = dict(wxyz=(1.0, 0, 0, 0), position=(2, -2, 1.5), fov=0.87, near=0.01, far=100.0, image_height=720,
    ...               image_width=1280, look_at=(0, 0, 0.5), up_direction=(0, 0, 1))
    >>> _camera_a_browser_could_have(camera), _camera_a_browser_could_have({**camera, "fov": 0.0})
    (True, False)
    """
    position, look_at, up = camera["position"], camera["look_at"], camera["up_direction"]
    numbers = (*camera["wxyz"], *position, *look_at, *up, camera["near"], camera["far"])
    if not all(math.isfinite(v) and abs(v) <= _FARTHEST_CAMERA for v in numbers):
        return False
    forward = [b - a for a, b in zip(position, look_at)]
    across = (forward[1] * up[2] - forward[2] * up[1], forward[2] * up[0] - forward[0] * up[2],
              forward[0] * up[1] - forward[1] * up[0])
    return (0.0 < camera["fov"] < math.pi and math.hypot(*across) > 1e-9 * math.hypot(*forward) * math.hypot(*up) > 0.0
            and 0 < camera["image_height"] <= _LARGEST_CANVAS and 0 < camera["image_width"] <= _LARGEST_CANVAS)


def _plain_value_update(updates: Any) -> bool:
    """A browser only ever sends ``{"value": v}``; other properties (options, disabled, ...) are not its to set."""
    if not isinstance(updates, dict) or set(updates) != {"value"}:
        return False
    value = updates["value"]
    if isinstance(value, list):
        return len(value) <= _LONGEST_LIST and all(isinstance(v, _SCALARS) and not isinstance(v, str) for v in value)
    return isinstance(value, _SCALARS) and (not isinstance(value, str) or len(value) <= _LONGEST_TEXT)


class Gate:
    """The limits one server applies, and what it has turned away (for the logs and the tests).

    Parameters
    ----------
    allowed_origins : iterable of str
        Origins (``http://host:port``) allowed besides the server's own pages.
    trust_loopback : bool, optional
        Whether connections from this machine (its loopback, or one of its network addresses: :meth:`trusted`) skip
        the per-address limits: yes, unless ``UR10_TEACH_LOOPBACK_IS_LAN=1`` (a benchmark's attacker on 127.0.0.2
        then counts as a laptop).
    """

    def __init__(self, allowed_origins=(), trust_loopback: bool | None = None) -> None:
        self.allowed_origins = {origin.rstrip("/").lower() for origin in allowed_origins}
        if trust_loopback is None:
            trust_loopback = os.environ.get("UR10_TEACH_LOOPBACK_IS_LAN") != "1"
        self.trust_loopback = trust_loopback
        self.local_names = {"localhost", socket.gethostname().lower()}
        self.local_names |= {f"{name}.local" for name in list(self.local_names)}
        self.dropped: collections.Counter = collections.Counter()  # message kind -> how many
        self.passed: collections.Counter = collections.Counter()  # message kind -> how many were handed to viser
        self.refused: collections.Counter = collections.Counter()  # reason -> how many connections
        self.closed_for: collections.Counter = collections.Counter()  # reason -> how many open connections were closed
        self._open: collections.Counter = collections.Counter()  # address -> open websockets
        self._tcp: collections.Counter = collections.Counter()  # address -> open TCP connections
        self._arrivals: dict[str, TokenBucket] = {}
        self._passing: dict[str, SharedRate] = {}  # address -> the rate its connections' messages pass at
        self._own: set[str] = set()  # this machine's network addresses that connections came from (:meth:`learn`)
        self._lock = threading.Lock()
        #: ``(uuid, value)`` -> whether a widget's value converts to the widget's type (the server sets it)
        self.value_fits: Callable[[Any, Any], bool] = lambda uuid, value: True
        #: a page's request path -> whether it was a report the server heard, answered with nothing (the server sets
        #: it: ``ur10teach.serving.screens``)
        self.heard: Callable[[str], bool] = lambda path: False

    # ------------------------------------------------------------------ connections

    def check_request(self, connection, request) -> Any:
        """``process_request``: None to go on, or the answer to send (a refused websocket, a page's report)."""
        if request.headers.get("Upgrade", "").lower() != "websocket":
            if self.heard(request.path):
                answer = connection.respond(http.HTTPStatus.NO_CONTENT, "")
                answer.headers["Cache-Control"] = "no-store"
                return answer
            return None  # the page and its files: nothing to guard
        hosts, origins = request.headers.get_all("Host"), request.headers.get_all("Origin")
        if len(hosts) != 1 or len(origins) > 1:
            return self._refuse(connection, http.HTTPStatus.BAD_REQUEST, "host", "a request with several Host or Origin headers")
        host, origin = hosts[0], (origins[0] if origins else None)
        if not self._is_our_host(host):
            # the teacher reads this when students opened the app by a name the network gives this machine
            # (a school's DNS name), which the app cannot tell from an attacker's: the teacher can
            return self._refuse(connection, http.HTTPStatus.FORBIDDEN, "host",
                                f"unknown host {host!r}. If students opened the app by that name (this machine's "
                                f"name on a school's network, say), their page never connects: give them an address "
                                f"shown above, or start the app with --allow-origin http://{host:.200}")
        if origin is not None and not self._is_allowed_origin(origin, host):
            return self._refuse(connection, http.HTTPStatus.FORBIDDEN, "origin", f"websocket from the page {origin!r}")
        address = _address(connection)
        if self.trusted(address):
            return None
        with self._lock:
            bucket = self._arrivals.setdefault(address, TokenBucket(NEW_CONNECTIONS_PER_SECOND, NEW_CONNECTION_BURST))
            if self._open[address] >= CONNECTIONS_PER_ADDRESS:
                reason = f"{address} already has {CONNECTIONS_PER_ADDRESS} connections"
            elif not bucket.take():
                reason = f"{address} is opening connections too fast"
            else:
                return None
        # (the teacher reads this when a class reaches this machine through one address: a router's NAT)
        return self._refuse(connection, http.HTTPStatus.TOO_MANY_REQUESTS, "address",
                            f"{reason}. If every student's browser comes from that address (through a router or proxy "
                            f"between their network and this machine's), {CONNECTIONS_PER_ADDRESS} at most can join, "
                            f"one every {1 / NEW_CONNECTIONS_PER_SECOND:g} s: put this machine on their network")

    def _refuse(self, connection, status: http.HTTPStatus, kind: str, reason: str):
        with self._lock:
            self.refused[kind] += 1
            first = self.refused[kind] == 1
        (log.warning if first else log.debug)("refused a websocket: %s", reason)
        return connection.respond(status, f"{status.phrase}: {reason}\n")

    def _is_our_host(self, host: str) -> bool:
        name = _hostname(host)
        if name in self.local_names or name in {urllib.parse.urlsplit(origin).hostname for origin in self.allowed_origins}:
            return True
        with contextlib.suppress(ValueError):
            ipaddress.ip_address(name)
            return True  # an address, not a name: nothing to rebind
        return False

    def _is_allowed_origin(self, origin: str, host: str) -> bool:
        origin = origin.rstrip("/").lower()
        return origin in (f"http://{host.lower()}", f"https://{host.lower()}") or origin in self.allowed_origins

    def trusted(self, address: str) -> bool:
        """Whether ``address`` is this machine's own (and the per-address limits skip it): a loopback address, or a
        network address of this machine that a connection came from (:meth:`learn`)."""
        if not self.trust_loopback:
            return False
        if address in self._own:  # (read without the lock: callers may hold it)
            return True
        with contextlib.suppress(ValueError):
            return ipaddress.ip_address(address).is_loopback
        return False

    def opened(self, address: str) -> SharedRate | None:
        """Count a new websocket from ``address``; the rate all of its websockets' messages pass at together
        (None for this machine's own)."""
        with self._lock:
            self._open[address] += 1
            if self.trusted(address):
                return None
            return self._passing.setdefault(address, SharedRate(ADDRESS_MESSAGES_PER_SECOND, ADDRESS_MESSAGE_BURST))

    def closed(self, address: str) -> None:
        self._forget_one(self._open, address)
        with self._lock:
            if address not in self._open:
                self._passing.pop(address, None)

    def _forget_one(self, counts: collections.Counter, address: str) -> None:
        with self._lock:
            counts[address] -= 1
            if counts[address] <= 0:
                del counts[address]

    def learn(self, address: str, local_address: str) -> None:
        """A TCP connection from ``address`` to this machine's ``local_address``: where the two are one, it came from
        this machine (another host cannot open one from an address this one holds: the handshake's answer comes back
        here), and the address is trusted from then on. The teacher who opens the address the students were given, on the projector's own
        computer, is then this machine's screen, as at 127.0.0.1."""
        if address == local_address and address != "?":
            with self._lock:
                self._own.add(address)

    def tcp_opened(self, address: str) -> bool:
        """Count a new TCP connection from ``address``: False (and not counted) when it holds too many."""
        if self.trusted(address):
            return True
        with self._lock:
            if self._tcp[address] >= TCP_CONNECTIONS_PER_ADDRESS:
                self.refused["tcp"] += 1
                first = self.refused["tcp"] == 1
            else:
                self._tcp[address] += 1
                return True
        (log.warning if first else log.debug)("refused a TCP connection: %s already has %d", address,
                                              TCP_CONNECTIONS_PER_ADDRESS)
        return False

    def tcp_closed(self, address: str) -> None:
        if not self.trusted(address):
            self._forget_one(self._tcp, address)

    def tcp_connections(self, address: str) -> int:
        with self._lock:
            return self._tcp[address]

    def note_closed(self, address: str, reason: str) -> None:
        with self._lock:
            self.closed_for[reason] += 1
        log.warning("closed a connection from %s: it %s", address, reason)

    # ------------------------------------------------------------------ messages

    def note_passed(self, kind: str) -> None:
        with self._lock:
            self.passed[kind] += 1

    def note_dropped(self, kind: str) -> None:
        with self._lock:
            self.dropped[kind] += 1
            first = self.dropped[kind] == 1
        if first:
            log.warning("dropped a %s from a browser; more are counted, not logged", kind)


def _hostname(host: str) -> str:
    """The name in a ``Host`` header: ``name:port``, ``[v6 address]:port`` or ``name``."""
    if host.startswith("["):
        return host[1 : host.find("]")].lower()
    return (host.rsplit(":", 1)[0] if host.count(":") == 1 else host).lower()


def _address(connection) -> str:
    remote = connection.remote_address
    return str(remote[0]) if remote else "?"


#: How long (s) a browser that left is known again (:func:`browser_of`): viser makes one that reconnects (a reload,
#: a laptop woken, the Wi-Fi back) a new client, and the server gives the next page of that browser what the last one
#: left (its arms; its attempt at a challenge; the presenter's role).
RETURN_WINDOW = 7200.0
#: The cookie that tells browsers behind one address apart (a class behind a router's NAT, the accounts of one
#: computer): a random token the page is given, HttpOnly and this site's alone, which its websocket sends back.
BROWSER_COOKIE = "ur10teach_browser"
_BROWSER_TOKEN = re.compile(r"[A-Za-z0-9_-]{22}")
#: How long (s) a browser keeps its cookie: the week's lessons, not only the return window.
COOKIE_SECONDS = 7 * 24 * 3600
#: How long (s) a page has to answer a ping when another page of its browser connects. A browser that reconnects
#: (its page retries every second) often comes back before the server notices its old connection has died: its
#: websocket is pinged every 20 s and given 20 s more. A pong follows what was sent before the ping: a live page
#: still reading a large scene over a slow Wi-Fi takes seconds.
ANSWER_SECONDS = 3.0


def address_of(client) -> str:  # noqa: ANN001
    """The address ``client`` (a ``viser.ClientHandle``) connected from, or "?" once it has gone."""
    connection = _connection_of(client)
    return _address(connection) if connection is not None else "?"


def browser_token(request) -> str | None:  # noqa: ANN001
    """The token of :data:`BROWSER_COOKIE` a request (``websockets.http11.Request``) carries, if it is one the gate
    could have given."""
    for header in request.headers.get_all("Cookie"):
        for pair in header.split(";"):
            name, _, value = pair.strip().partition("=")
            if name == BROWSER_COOKIE and _BROWSER_TOKEN.fullmatch(value):
                return value
    return None


def give_browser_cookie(request, response) -> None:  # noqa: ANN001
    """A page sent without the browser's cookie gets one (``response``: what viser answers ``request`` with)."""
    if (response is not None and response.status_code == http.HTTPStatus.OK and browser_token(request) is None
            and response.headers.get("Content-Type", "").startswith("text/html")):
        response.headers["Set-Cookie"] = (f"{BROWSER_COOKIE}={secrets.token_urlsafe(16)}; Path=/; "
                                          f"Max-Age={COOKIE_SECONDS}; SameSite=Lax; HttpOnly")


def browser_of(client) -> str:  # noqa: ANN001
    """Which browser ``client`` (a ``viser.ClientHandle``) is, as its return is known: its address, and its cookie's
    token where its page has one (students behind one address are then each their own; a browser that sends no
    cookie is known by its address alone). "?" once it has gone."""
    connection = _connection_of(client)
    return "?" if connection is None else connection.browser


def address_in(browser: str) -> str:
    """The address part of a :func:`browser_of`."""
    return browser.split(" ", 1)[0]


def on_a_phone(client) -> bool:  # noqa: ANN001
    """Whether ``client``'s browser (a ``viser.ClientHandle``) says it runs on a phone: "Mobi" in its User-Agent, as
    browsers' makers advise (tablets leave it out)."""
    connection = _connection_of(client)
    return connection is not None and "Mobi" in connection.request.headers.get("User-Agent", "")


async def hang_up_silent(clients: list, timeout: float = ANSWER_SECONDS) -> list:
    """Ping each of ``clients`` (``viser.ClientHandle``) and drop, without a goodbye, those that do not answer within
    ``timeout`` s; returns those (on viser's event loop)."""
    async def answered(connection) -> None:  # noqa: ANN001
        await (await connection.ping())  # (sending it waits for what is queued before it to leave)

    async def silent(client) -> bool:  # noqa: ANN001
        connection = _connection_of(client)
        if connection is None:
            return True
        try:  # a laptop that stopped reading mid-download backs its socket up: the ping's sending is timed too
            await asyncio.wait_for(answered(connection), timeout)
            return False
        except (asyncio.TimeoutError, websockets.ConnectionClosed):
            connection.transport.abort()
            return True

    found = await asyncio.gather(*(silent(client) for client in clients))
    return [client for client, gone in zip(clients, found) if gone]


def budget_of(client) -> str:  # noqa: ANN001
    """Whose share of the server's slow work ``client``'s is: its address, shared by every tab there,
    or, for this machine's own tabs (which the gate trusts), each tab's own."""
    connection = _connection_of(client)
    if connection is None:
        return f"gone #{client.client_id}"
    address = _address(connection)
    return f"{address} #{client.client_id}" if getattr(connection, "trusted", False) else address


class GatedConnection:
    """A websocket connection as viser sees it, passing only what the gate lets through.

    A reader task takes every message off the socket as it arrives, keeps the newest of
    each kind (:func:`message_key`) waiting, and :meth:`recv` hands them out oldest
    first at the connection's rate. Everything else is the connection's own.
    """

    def __init__(self, connection, gate: Gate, address_rate: SharedRate | None = None) -> None:
        self._connection = connection
        self._gate = gate
        self.trusted = gate.trusted(_address(connection))  #: this machine's: no per-address limits
        token = browser_token(connection.request)  # (read once: its headers may be long, and every arrival asks)
        #: which browser it is (:func:`browser_of`)
        self.browser = _address(connection) if token is None else f"{_address(connection)} {token}"
        self._address_rate = address_rate  #: shared by every connection of its address
        self._waiting: dict[tuple, bytes] = {}
        self._arrived = asyncio.Event()
        self._ended: BaseException | None = None
        self._rate = TokenBucket(MESSAGES_PER_SECOND, MESSAGE_BURST)
        self._arrivals = TokenBucket(ARRIVALS_PER_SECOND, ARRIVALS_PER_SECOND)
        self._arrival_bytes = TokenBucket(ARRIVAL_BYTES_PER_SECOND, ARRIVAL_BYTES_PER_SECOND)
        self._over_rate = TokenBucket(1.0, OVER_RATE_ALLOWANCE)
        self._closing: asyncio.Task | None = None  #: closing it for sending over its rate
        self._reader = asyncio.get_running_loop().create_task(self._read())

    def __getattr__(self, name: str) -> Any:
        return getattr(self._connection, name)

    async def _read(self) -> None:
        try:
            while True:
                raw = await self._connection.recv()
                await asyncio.sleep(0)  # queued frames of this socket wait their turn with everyone else's
                if self._closing is not None:
                    continue  # read and dropped: websockets stops reading the socket while frames wait, and the client's Close is behind them
                if not (self._arrivals.take() and self._arrival_bytes.take(len(raw))):
                    self._gate.note_dropped("message over its connection's rate")
                    if not self._over_rate.take():
                        self._gate.note_closed(_address(self._connection), "kept sending over its rate")
                        self._closing = asyncio.get_running_loop().create_task(self._connection.close(1008, "too many messages"))
                    continue
                key, kind = classify(raw, self._gate.value_fits)
                if key is None:
                    self._gate.note_dropped(kind)
                    continue
                if key not in self._waiting and len(self._waiting) >= MAX_WAITING:
                    self._gate.note_dropped("message over the waiting limit")
                    continue
                self._waiting[key] = raw  # a newer one for the same widget keeps the older one's place
                self._arrived.set()
        except BaseException as error:  # the connection closed (or we were cancelled): recv says so
            self._ended = error
            self._arrived.set()

    async def recv(self) -> bytes:
        while True:
            if self._waiting:
                delay = self._rate.wait_time()
                if delay > 0.0:
                    await asyncio.sleep(delay)  # newer messages for the same keys replace those waiting meanwhile
                    continue
                if self._address_rate is not None:
                    await self._address_rate.take()
                self._rate.take()
                key = next(iter(self._waiting))
                self._gate.note_passed(key[0])
                return self._waiting.pop(key)
            if self._ended is not None:
                raise self._ended
            self._arrived.clear()
            await self._arrived.wait()

    def close_reader(self) -> None:
        self._reader.cancel()


@contextlib.contextmanager
def gated_serve(gate: Gate, title: str) -> Iterator[None]:
    """While active, a viser server that starts serves through ``gate``, its page's tab titled ``title``.

    Its websocket server (``viser_internals.serving_through``) gets the gate's limit and timeouts, a request
    check in front of viser's HTTP handler (and the browser's cookie on its page), TCP connections counted by
    address, and a handler that sees each connection through :class:`GatedConnection`.
    """

    class CountedConnection(websockets.asyncio.server.ServerConnection):
        """A TCP connection counted against its address from its first byte, handshake or not, and closed if its
        request is not whole within :data:`OPEN_TIMEOUT`."""

        def connection_made(self, transport) -> None:  # noqa: ANN001
            peer, local = transport.get_extra_info("peername"), transport.get_extra_info("sockname")
            self._peer = str(peer[0]) if peer else "?"
            if local:
                gate.learn(self._peer, str(local[0]))
            self._counted = gate.tcp_opened(self._peer)
            super().connection_made(transport)
            if not self._counted:
                transport.abort()
            else:  # (websockets' own timeout is the download's: DOWNLOAD_TIMEOUT)
                self._unasked = self.loop.call_later(OPEN_TIMEOUT, self._abort_unless_asked)
                with contextlib.suppress(OSError, AttributeError):
                    transport.get_extra_info("socket").setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER)

        def _abort_unless_asked(self) -> None:
            if self.request is None:
                self.transport.abort()

        def connection_lost(self, exc) -> None:  # noqa: ANN001
            if self._counted:
                self._unasked.cancel()
                gate.tcp_closed(self._peer)
                self._counted = False
            super().connection_lost(exc)

    def through_gate(handler, process_request, keywords: dict):  # noqa: ANN001, ANN202
        async def gated_handler(connection) -> None:  # noqa: ANN001
            address = _address(connection)
            gated = GatedConnection(connection, gate, gate.opened(address))
            try:
                await handler(gated)
            finally:
                gated.close_reader()
                gate.closed(address)

        def check_then_serve(connection, request):  # noqa: ANN001
            refusal = gate.check_request(connection, request)
            if refusal is not None:
                return refusal
            response = process_request(connection, request) if process_request is not None else None
            response = page_titled(response, title)
            give_browser_cookie(request, response)
            return response

        return gated_handler, check_then_serve, {**keywords, "max_size": MAX_MESSAGE_BYTES, "open_timeout": DOWNLOAD_TIMEOUT,
                                                 "ping_timeout": PONG_TIMEOUT, "create_connection": CountedConnection}

    with serving_through(through_gate):
        yield
