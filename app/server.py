"""The viser server: one :class:`ClientSession` per connected browser."""

from __future__ import annotations

import json
import logging
import math
import os
import socket
import threading
import time
from pathlib import Path

import viser

from ur10core import Arm, symbolic

from .meshes import load_links
from .metrics import LATENCY
from .refresh import PanelRefresher
from .session import ClientSession
from .style import JOINT_CAP_BLUE

log = logging.getLogger(__name__)

#: Where the camera starts (and "reset view" returns): the whole arm, a little from above.
CAMERA_POSITION = (2.1, -1.9, 1.4)
CAMERA_LOOK_AT = (0.2, 0.0, 0.5)
CAMERA_FOV_DEGREES = 50.0


def lan_addresses() -> list[str]:
    """This machine's IPv4 addresses other than loopback (what students type), best first."""
    found: list[str] = []
    try:  # the interface of the default route; sends nothing
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.connect(("10.255.255.255", 1))
            found.append(probe.getsockname()[0])
    except OSError:
        pass
    try:
        for info in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET):
            found.append(info[4][0])
    except OSError:
        pass
    return [a for i, a in enumerate(found) if not a.startswith("127.") and a not in found[:i]]


def _resident_bytes() -> int:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


class TeachingServer:
    """The app: a viser server giving every browser its own UR10.

    Parameters
    ----------
    preset : str
        ``"course"``, ``"ur10"`` or ``"ur10e"`` (see :meth:`ur10core.Arm.preset`).
    host, port : str, int
        Where to listen. viser moves to the next free port when ``port`` is busy:
        :attr:`port` is the real one. ``port=0`` lets the OS choose (tests).
    """

    def __init__(self, preset: str = "course", host: str = "127.0.0.1", port: int = 8080) -> None:
        self.arm = Arm.preset(preset)
        self.links = load_links(preset)
        symbolic.load()  # read the cached derivation now rather than in the first student's callback
        self.host = host
        self.server = viser.ViserServer(host=host, port=port, label=f"UR10 kinematics ({preset})", verbose=False)
        self.server.gui.configure_theme(show_share_button=False, brand_color=JOINT_CAP_BLUE, control_width="large")
        self.server.initial_camera.position = CAMERA_POSITION
        self.server.initial_camera.look_at = CAMERA_LOOK_AT
        self.server.initial_camera.up = (0.0, 0.0, 1.0)
        self.server.initial_camera.fov = math.radians(CAMERA_FOV_DEGREES)
        # the floor the arm stands on: half-metre cells, shared by everyone (it never changes)
        self.server.scene.add_grid("/floor", width=3.0, height=3.0, cell_size=0.1, section_size=0.5)
        self.refresher = PanelRefresher()
        self.sessions: dict[int, ClientSession] = {}
        self._sessions_lock = threading.Lock()
        self.server.on_client_connect(self._connected)
        self.server.on_client_disconnect(self._disconnected)
        self._metrics_stop = threading.Event()
        metrics_path = os.environ.get("UR10_TEACH_METRICS")
        if metrics_path:
            threading.Thread(target=self._write_metrics, args=(Path(metrics_path),), daemon=True).start()

    @property
    def port(self) -> int:
        return self.server.get_port()

    @property
    def urls(self) -> list[str]:
        """Where browsers can reach the app."""
        if self.host in ("0.0.0.0", ""):
            return [f"http://127.0.0.1:{self.port}"] + [f"http://{a}:{self.port}" for a in lan_addresses()]
        return [f"http://{self.host}:{self.port}"]

    def _connected(self, client: viser.ClientHandle) -> None:
        try:
            session = ClientSession(client, self.arm, self.links, self.refresher)
        except Exception:
            log.exception("could not set up client %s", client.client_id)
            try:
                client.add_notification("Could not start", "Reload the page to try again.", color="red")
            except Exception:
                pass
            return
        with self._sessions_lock:
            self.sessions[client.client_id] = session

    def _disconnected(self, client: viser.ClientHandle) -> None:
        with self._sessions_lock:
            session = self.sessions.pop(client.client_id, None)
        if session is not None:
            session.close()

    def _write_metrics(self, path: Path) -> None:
        """Once a second: clients, handler latencies, CPU and memory of this process (for benchmarks)."""
        while not self._metrics_stop.wait(1.0):
            with self._sessions_lock:
                clients = len(self.sessions)
            report = {
                "time": time.time(),
                "clients": clients,
                "latency": LATENCY.summary(),
                "cpu_seconds": sum(os.times()[:2]),
                "rss_bytes": _resident_bytes(),
                "threads": threading.active_count(),
            }
            partial = path.with_suffix(".tmp")
            partial.write_text(json.dumps(report))
            partial.replace(path)  # readers never see half a file

    def stop(self) -> None:
        self._metrics_stop.set()
        self.refresher.stop()
        self.server.stop()
