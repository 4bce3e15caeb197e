"""What each browser's screen is like, as placing its 3D labels and framing its arm need it:

* how many canvas pixels it draws per CSS pixel: its camera reports its canvas in the first, and viser sizes the
  labels in the second (a 12 px em), 1.25 to 2 on most laptops;
* whether its window is narrow (viser's 36 em breakpoint): the panel is then a sheet over the canvas's lower part, on
  a phone held upright or in a laptop's narrow window alike.

The page says both without a script: a style in its panel asks for pictures at their addresses, chosen by the
browser's own media queries (again when a zoom or a resize changes them), and the gate answers those requests (204).
"""

from __future__ import annotations

import asyncio
import logging
import re
import secrets
import threading
from dataclasses import dataclass, field
from typing import Callable

import viser

from ..style import NARROW_WINDOW
from .gate import TokenBucket

log = logging.getLogger(__name__)

#: The ratios told apart: viser's canvas draws at the browser's device pixel ratio held to 1…2 (a phone's 3 at 2).
RATIOS = tuple(f"{1 + step / 20:.2f}" for step in range(21))
#: What a page says of its window's width: narrower than viser's breakpoint (36 em, the one its layout follows) or not.
NARROW, WIDE = "narrow", "wide"
#: Where a page's style asks for its pictures: ``/dppx/<token>/<ratio>`` and ``/dppx/<token>/narrow`` or ``wide``
#: (named for the CSS unit: a content blocker's rules for tracking pixels would match "pixel" in an address or a
#: class, and stop the request).
PATH = "/dppx/"
_REPORT = re.compile(rf"{PATH}([A-Za-z0-9_-]{{16}})/(\d\.\d\d|{NARROW}|{WIDE})")
#: Changes one page is heard at (a second), after a burst: a few at a zoom; each is a placing of its labels.
CHANGES_PER_SECOND, CHANGE_BURST = 5.0, 10


def probe_html(token: str) -> str:
    """The panel's invisible element whose background picture is at ``PATH/token/<ratio>``, the largest of
    :data:`RATIOS` the browser's resolution reaches (the last rule that applies wins), and whose ``::after``'s is at
    ``PATH/token/narrow`` or ``wide``, by the media query viser's layout follows. The addresses are relative to the
    page's, as viser's websocket's is: a proxy that serves the app under a path of its own passes them on too."""
    name, where = f"dppx-{token}", f"{PATH.lstrip('/')}{token}"
    rules = "".join(f"@media (min-resolution: {ratio}dppx), (-webkit-min-device-pixel-ratio: {ratio}) "
                    f"{{ .{name} {{ background-image: url({where}/{ratio}) }} }}" for ratio in RATIOS[1:])
    width = (f".{name}::after {{ content: ''; display: block; width: 1px; height: 1px; "
             f"background-image: url({where}/{WIDE}) }} "
             f"@media {NARROW_WINDOW} {{ .{name}::after {{ background-image: url({where}/{NARROW}) }} }}")
    return (f'<div class="{name}" style="position: absolute; width: 1px; height: 1px; opacity: 0; '
            f'pointer-events: none"></div><style>.{name} {{ background-image: url({where}/{RATIOS[0]}) }} '
            f'{rules} {width}</style>')


@dataclass
class _Page:
    client: viser.ClientHandle
    changes: TokenBucket
    ratio: float = 1.0
    narrow: bool | None = None  #: None until it has said
    token: str = ""  #: its element's, the one it may report with
    element: viser.GuiHtmlHandle | None = None
    #: what its element has asked for, by field: the page takes that address from its cache if it is wanted again
    asked: dict[str, float | bool] = field(default_factory=dict)


class Screens:
    """Each browser's pixel ratio and window width, as its page reports them.

    ``told(client_id)`` is called, on a thread of viser's event loop's pool, when either changes.
    """

    def __init__(self, told: Callable[[int], None]) -> None:
        self._told = told
        self._lock = threading.Lock()
        self._probing = threading.Lock()
        self._pages: dict[int, _Page] = {}  # client id -> its page
        self._tokens: dict[str, int] = {}  # each page's token -> its client id

    def of(self, client_id: int) -> tuple[float, bool | None]:
        """(pixel ratio, whether the window is narrow): (1, None) until the page has said."""
        page = self._pages.get(client_id)
        return (1.0, None) if page is None else (page.ratio, page.narrow)

    def probe(self, client: viser.ClientHandle, reset: bool = False) -> None:
        """Put the element that reports the screen in ``client``'s panel, in place of the last (unless the panel was
        ``reset``, and with it the last), and again after a change that is the second value of one kind it has
        asked for: at new addresses, since a page takes one it asked for before from its cache."""
        token = secrets.token_urlsafe(12)
        with self._probing:
            with self._lock:
                page = self._pages.setdefault(client.client_id, _Page(client, TokenBucket(CHANGES_PER_SECOND, CHANGE_BURST)))
                self._tokens.pop(page.token, None)
                self._tokens[token] = client.client_id
                page.token, old = token, page.element
                page.asked = {}
            if old is not None and not reset:
                old.remove()
            page.element = client.gui.add_html(probe_html(token), order=1e9)

    def forget(self, client_id: int) -> None:
        with self._lock:
            page = self._pages.pop(client_id, None)
            if page is not None:
                self._tokens.pop(page.token, None)

    def heard(self, path: str) -> bool:
        """Whether ``path`` (a request's, on viser's event loop) is a page's report; a change it reports through its
        page's current element is kept, and told."""
        report = _REPORT.fullmatch(path)
        if report is None or report[2] not in (*RATIOS, NARROW, WIDE):
            return False
        said, value = ("narrow", report[2] == NARROW) if report[2] in (NARROW, WIDE) else ("ratio", float(report[2]))
        with self._lock:
            page = self._pages.get(self._tokens.get(report[1], -1))
            if page is None:
                return True
            cached = said in page.asked  # its address for what it said before is in the page's cache now
            page.asked[said] = value
            if getattr(page, said) == value or not page.changes.take():
                return True
            setattr(page, said, value)
        asyncio.get_running_loop().run_in_executor(None, self._changed, page, cached)
        return True

    def _changed(self, page: _Page, renew: bool) -> None:
        try:
            if self._pages.get(page.client.client_id) is page:
                if renew:
                    self.probe(page.client)
                self._told(page.client.client_id)
        except Exception:  # (on the pool's thread: nobody else would read it)
            log.exception("could not take browser %s's new screen", page.client.client_id)
