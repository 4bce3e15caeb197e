"""How students join: the addresses on the teacher's screen, and a QR code of each for the phones at the back."""

from __future__ import annotations

import threading
from typing import Callable

import numpy as np
import segno
import viser

#: Pixels a module (a QR code's square) in the image sent: more than the page draws (360 to 530 px for the whole
#: code), so it is scaled down, its edges sharp.
MODULE_PX = 16
#: The blank border round a QR code, in modules, that a reader needs to find it (ISO/IEC 18004).
QUIET_ZONE = 4


def join_markdown(urls: list[str]) -> str:
    """What students type to join, for the teacher's screen: ``Students open **http://192.0.2.7:8080**``."""
    if not urls:
        return NO_ADDRESS
    return "Students open " + " or ".join(f"**{url}**" for url in urls)


#: In place of the addresses while this machine has none that students could reach.
NO_ADDRESS = ("**No network address yet**: connect this computer to the class's network (or start its hotspot). "
              "The address to open shows here then.")


def qr_image(url: str) -> np.ndarray:
    """(h, w, 3) uint8: the QR code of ``url``, black on white, :data:`MODULE_PX` pixels a module, with its quiet zone.

    >>> image = qr_image("http://192.0.2.7:8080")
    >>> image.shape, image.dtype.name, sorted(set(image.ravel().tolist()))
    ((528, 528, 3), 'uint8', [0, 255])
    """
    code = segno.make(url, error="m", micro=False)
    dark = np.pad(np.array(code.matrix, dtype=bool), QUIET_ZONE)
    pixels = np.where(dark, 0, 255).astype(np.uint8).repeat(MODULE_PX, axis=0).repeat(MODULE_PX, axis=1)
    return np.repeat(pixels[:, :, None], 3, axis=2)


class JoinHelp:
    """The join addresses in a panel (:func:`join_markdown`) and, on the teacher's screen, a button that shows a
    QR code of each in a window over the page, to put on the projector as the class arrives.

    ``guard`` wraps the button's callback (``ur10teach.feedback.guard``).
    """

    def __init__(self, client: viser.ClientHandle, urls: list[str], teacher: bool,
                 guard: Callable[[Callable], Callable]) -> None:
        self._client, self._urls = client, list(urls)
        self._window = None  #: the window of QR codes, while it is open
        self._lock = threading.Lock()
        self.markdown = client.gui.add_markdown(join_markdown(urls))
        self.button = None
        if teacher:
            self.button = client.gui.add_button("Show a QR code to join", icon=viser.Icon.QRCODE,
                                                hint="A window with each address as a QR code, for phones to scan")
            self.button.on_click(guard(lambda _: self.show()))

    def show(self) -> None:
        """Open the window of QR codes (once: a double click's second press, sent before the window had arrived,
        would open another over it, to be closed twice)."""
        with self._lock:
            if self._window is not None:
                return
            gui = self._client.gui
            with gui.add_modal("Join the class") as window:
                if not self._urls:
                    gui.add_markdown(NO_ADDRESS)
                for url in self._urls:
                    # what to type, large: a browser's address bar takes it without "http://" (which viser's page
                    # would turn into a link, in small type)
                    gui.add_markdown(f"## {url.removeprefix('http://')}")
                    gui.add_image(qr_image(url), format="png")  # (lossless: a JPEG's blur costs readers their edges)
                gui.add_button("Close", icon=viser.Icon.X).on_click(lambda _: self.close())
            self._window = window

    def update(self, urls: list[str]) -> None:
        """Show ``urls`` from here on, if they are not the ones shown (this machine is on another network)."""
        with self._lock:
            if urls == self._urls:
                return
            self._urls = list(urls)
        try:
            self.markdown.content = join_markdown(urls)
        except RuntimeError:  # viser's word for a removed widget: its folder went meanwhile (a new role or arm)
            pass

    def close(self) -> None:
        with self._lock:
            window, self._window = self._window, None
        if window is not None:
            window.close()
