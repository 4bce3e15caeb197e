"""How many canvas pixels each browser draws per CSS pixel: its camera reports its canvas in the first, and viser
sizes the 3D labels in the second (a 12 px em), so placing labels apart needs the ratio (1.25 to 2 on most laptops).

The page says it without a script: a style in its panel asks for a picture at its ratio's address, chosen by the
browser's own media queries (again when a zoom changes it), and the gate answers that request (204).
"""

from __future__ import annotations

import asyncio
import logging
import re
import secrets
import threading
from dataclasses import dataclass
from typing import Callable

import viser

from .gate import TokenBucket

log = logging.getLogger(__name__)

#: The ratios told apart: viser's canvas draws at the browser's device pixel ratio held to 1…2 (a phone's 3 at 2).
RATIOS = tuple(f"{1 + step / 20:.2f}" for step in range(21))
#: Where a page's style asks for its ratio's picture: ``/dppx/<token>/<ratio>`` (named for the CSS unit: a content
#: blocker's rules for tracking pixels would match "pixel" in an address or a class, and stop the request).
PATH = "/dppx/"
_REPORT = re.compile(rf"{PATH}([A-Za-z0-9_-]{{16}})/(\d\.\d\d)")
#: Changes of ratio one page is heard at (a second), after a burst: a few at a zoom; each is a placing of its labels.
CHANGES_PER_SECOND, CHANGE_BURST = 5.0, 10


def probe_html(token: str) -> str:
    """The panel's invisible element whose background picture is at ``PATH/token/<ratio>``: the largest of
    :data:`RATIOS` the browser's resolution reaches (the last rule that applies wins). The address is relative to the
    page's, as viser's websocket's is: a proxy that serves the app under a path of its own passes it on too."""
    name, where = f"dppx-{token}", f"{PATH.lstrip('/')}{token}"
    rules = "".join(f"@media (min-resolution: {ratio}dppx), (-webkit-min-device-pixel-ratio: {ratio}) "
                    f"{{ .{name} {{ background-image: url({where}/{ratio}) }} }}" for ratio in RATIOS[1:])
    return (f'<div class="{name}" style="position: absolute; width: 1px; height: 1px; opacity: 0; '
            f'pointer-events: none"></div><style>.{name} {{ background-image: url({where}/{RATIOS[0]}) }} '
            f'{rules}</style>')


@dataclass
class _Page:
    client: viser.ClientHandle
    changes: TokenBucket
    ratio: float = 1.0
    token: str = ""  #: its element's, the one it may report with
    element: viser.GuiHtmlHandle | None = None


class PixelRatios:
    """Each browser's pixel ratio, as its page reports it (1 until it has).

    ``told(client_id)`` is called, on a thread of viser's event loop's pool, when a browser's ratio changes.
    """

    def __init__(self, told: Callable[[int], None]) -> None:
        self._told = told
        self._lock = threading.Lock()
        self._probing = threading.Lock()
        self._pages: dict[int, _Page] = {}  # client id -> its page
        self._tokens: dict[str, int] = {}  # each page's token -> its client id

    def of(self, client_id: int) -> float:
        page = self._pages.get(client_id)
        return 1.0 if page is None else page.ratio

    def probe(self, client: viser.ClientHandle, reset: bool = False) -> None:
        """Put the element that reports the ratio in ``client``'s panel, in place of the last (unless the panel was
        ``reset``, and with it the last), and again after each report: at a new address, since a page takes one
        it asked for before from its cache."""
        token = secrets.token_urlsafe(12)
        with self._probing:
            with self._lock:
                page = self._pages.setdefault(client.client_id, _Page(client, TokenBucket(CHANGES_PER_SECOND, CHANGE_BURST)))
                self._tokens.pop(page.token, None)
                self._tokens[token] = client.client_id
                page.token, old = token, page.element
            if old is not None and not reset:
                old.remove()
            page.element = client.gui.add_html(probe_html(token), order=1e9)

    def forget(self, client_id: int) -> None:
        with self._lock:
            page = self._pages.pop(client_id, None)
            if page is not None:
                self._tokens.pop(page.token, None)

    def heard(self, path: str) -> bool:
        """Whether ``path`` (a request's, on viser's event loop) is a page's report; a new ratio of a page's current
        element is kept, and told."""
        report = _REPORT.fullmatch(path)
        if report is None or report[2] not in RATIOS:
            return False
        ratio = float(report[2])
        with self._lock:
            page = self._pages.get(self._tokens.get(report[1], -1))
            if page is None or page.ratio == ratio or not page.changes.take():
                return True
            page.ratio = ratio
        asyncio.get_running_loop().run_in_executor(None, self._changed, page)
        return True

    def _changed(self, page: _Page) -> None:
        try:
            if self._pages.get(page.client.client_id) is page:
                self.probe(page.client)
                self._told(page.client.client_id)
        except Exception:  # (on the pool's thread: nobody else would read it)
            log.exception("could not take browser %s's new pixel ratio", page.client.client_id)
