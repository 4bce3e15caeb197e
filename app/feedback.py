"""No exception escapes a callback: a refused value is explained, a bug is reported, and the
server carries on serving everyone else."""

from __future__ import annotations

import contextlib
import functools
import html
import logging
import math
import threading
import time
from typing import Any, Callable

import viser

from .serving.gate import TokenBucket
from .style import DANGER_RED, hex_color, sentence
from .viser_internals import send_again

log = logging.getLogger(__name__)

#: Notifications a browser is shown, per second after a burst. Each is queued for that browser
#: alone: one sending bad values fast (or not reading) must not grow the server's memory.
NOTICES_PER_SECOND = 2.0
NOTICE_BURST = 20
#: The time the notices' rate is kept by (a test sets its own).
clock = time.monotonic
#: Seconds a student leaves a slider (or the gizmo) before a value of theirs that crossed the server's is sent
#: back: a key held down or a drag sends one every 50 ms, and a pause as long as typing's is a pause.
STILL_FOR = 0.5


def notify(client: viser.ClientHandle, title: str, body: str, color: str = "yellow") -> None:
    """A notification in one browser; nothing happens if that browser has gone.

    Beyond :data:`NOTICES_PER_SECOND`, notifications are counted, not sent; the next one
    sent says how many were not.
    """
    notices = getattr(client, "_notices", None)
    if notices is None:
        notices = client._notices = [TokenBucket(NOTICES_PER_SECOND, NOTICE_BURST, clock=lambda: clock()), 0]  # the rate, and how many unsent
    if not notices[0].take():
        notices[1] += 1
        return
    if notices[1]:
        body = f"{sentence(body)} ({notices[1]} more messages were not shown.)"
        notices[1] = 0
    try:
        client.add_notification(title, sentence(body), auto_close_seconds=8.0, color=color)
    except Exception:
        log.debug("could not notify client %s", client.client_id, exc_info=True)


class Crossings:
    """Which of a view's inputs the browser may show wrongly because its change crossed the server's on the way
    (docs/architecture.md §1): the server :meth:`sent` a value, then the browser's own was :meth:`received`; once
    the arm has taken it and the student has left the input still for :data:`STILL_FOR` s, :meth:`settle` sends
    it back, since viser, holding it already, would not. Sent sooner, it could reach a browser whose student has
    moved on (a key pressed twice) and show an older value there. A value sent back can cross a newer one in turn.

    ``later()`` asks the view to settle again (it is called once the input has been still long enough). The
    caller holds its own lock around each call. ``key`` names the input (one per view: None).
    """

    def __init__(self, later: Callable[[], None], clock: Callable[[], float] = time.monotonic) -> None:
        self._later, self._clock = later, clock
        self._sent: set = set()  #: set by the server since the browser last sent a value
        self._unsure: dict = {}  #: came from the browser after the server's (it may show that), by when
        self._asked = -math.inf  #: when the later look asked for comes

    def sent(self, key=None) -> None:
        self._sent.add(key)
        self._unsure.pop(key, None)  # what it shows now is the server's

    def received(self, key=None) -> None:
        if key in self._sent or key in self._unsure:
            self._sent.discard(key)
            self._unsure[key] = self._clock()

    def settle(self, handle, key=None) -> None:
        """The server holds ``handle``'s value unchanged: the browser is sent it again if it may show another."""
        if key not in self._unsure:
            return
        now, still = self._clock(), self._unsure[key] + STILL_FOR
        if now < still:
            if now >= self._asked:  # no later look still to come
                self._asked = still
                timer = threading.Timer(still - now, self._later)
                timer.daemon = True
                timer.start()
            return
        del self._unsure[key]
        self.sent(key)
        send_again(handle)


class Beside:
    """A line right below an input, where a value typed into it and refused is explained: a notice at the
    far edge of the window went unseen (issue 30). Hidden until there is something to say."""

    def __init__(self, gui: viser.GuiApi) -> None:
        self.line = gui.add_markdown("", visible=False)
        self.said = 0  #: refusals said so far: one said by a run the input started is not cleared by its return

    def say(self, message: str) -> bool:
        """Show ``message``; False where the line has gone with its panel, which another browser's action (a
        challenge ended, the presenter's role taken) can rebuild while this input's value is being checked."""
        self.said += 1
        # the message quotes what was typed, and viser renders raw HTML in markdown: "<b>" typed made the rest bold
        text = f"<span style='color:{hex_color(DANGER_RED)}'>**Not accepted.** {html.escape(sentence(message), quote=False)}</span>"
        try:
            self.line.content = text
            self.line.visible = True
        except RuntimeError:  # viser's "Cannot assign to 'content' on a removed" widget
            return False
        return True

    def clear(self) -> None:
        if self.line.visible:
            with contextlib.suppress(RuntimeError):  # gone with its panel meanwhile (see say): nothing left to clear
                self.line.visible = False


def guard(
    client: viser.ClientHandle,
    handler: Callable[[Any], None],
    is_closed: Callable[[], bool] = lambda: False,
    on_refused: Callable[[], None] | None = None,
    beside: Beside | None = None,
) -> Callable[[Any], None]:
    """Wrap a viser callback of ``client``'s.

    ``ValueError`` is a value the user gave that we refuse: it is explained ``beside`` the input it came from (or in
    a notice, "Not accepted", where there is no such line or it has gone) and ``on_refused`` puts the widgets back;
    the explanation stays until the student's next change is accepted (a value the server itself sets, putting one
    back, is none, and neither is work run on a thread of its own: the put-back's run cleared the refusal it
    followed). Anything else is a bug: it is logged and the user is told the app is still running.
    """

    @functools.wraps(handler)
    def guarded(event: Any) -> None:
        if is_closed():
            return
        said = beside.said if beside is not None else 0
        try:
            handler(event)
            if beside is not None and getattr(event, "client", None) is not None and beside.said == said:
                beside.clear()
        except ValueError as error:
            if beside is None or not beside.say(str(error)):
                notify(client, "Not accepted", str(error))
            if on_refused is not None:
                on_refused()
        except Exception as error:
            if is_closed():
                return  # the browser left while we were drawing for it
            log.exception("callback failed for client %s", client.client_id)
            notify(client, "Something went wrong", f"{type(error).__name__}: {error}. The app is still running.", "red")

    return guarded


def put_back(handle, value: Any) -> None:
    """Show ``value`` in a widget again before a refusal, unless the widget has gone meanwhile: another
    browser's action can rebuild this panel (a presenter's controls, when someone else takes over) while
    the refused value is being checked, and the refusal is what the student must see."""
    with contextlib.suppress(RuntimeError):  # viser's "Cannot assign to 'value' on a removed" widget
        handle.value = value


def chosen(handle, what: str) -> str:
    """The value of a dropdown or button group, or ``ValueError`` when a client sent one not among its options.

    A browser only ever sends one of the options it was given; anything else came from
    something else. A dropdown is put back to the last choice it accepted (its first option
    if none), before the refusal: viser runs its callback again at once for that, which then
    applies the choice that stands, not another.
    """
    value, options = handle.value, tuple(handle.options)
    if value in options:
        handle._accepted_choice = value
        return value
    if isinstance(handle, viser.GuiDropdownHandle):  # a button group holds no choice to show
        put_back(handle, getattr(handle, "_accepted_choice", options[0]))
    raise ValueError(f"{what}: {value!r:.40} is not one of the choices")


def within(handle, what: str) -> float:
    """The value of a slider or number field, or ``ValueError`` when a client sent one outside its range.

    A slider's number box in viser's page takes any number typed (99999 beside a joint's ±360°);
    a NaN came from something else. As :func:`chosen` does for a dropdown, the widget is put back to the last
    value it accepted (or the value nearest 0 in its range) before the refusal: a value left
    in it would be refused again at every redraw that reads it.
    """
    value = handle.value
    low = -math.inf if handle.min is None else handle.min
    high = math.inf if handle.max is None else handle.max
    if isinstance(value, (int, float)) and not isinstance(value, bool) and low <= value <= high:  # NaN is not
        handle._accepted_value = value
        return float(value)
    put_back(handle, getattr(handle, "_accepted_value", min(max(0.0, low), high)))
    raise ValueError(f"{what}: from {low:g} to {high:g}, got {value!r:.40}")
