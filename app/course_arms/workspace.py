"""A course arm's workspace: tool positions of random joints, coloured by manipulability (as the UR10's cloud)."""

from __future__ import annotations

import functools
import threading
from typing import TYPE_CHECKING

import numpy as np
import viser

from ur10core import Arm
from ur10core.serial import PRESETS

from ..view import View
from ..workers import HEAVY, FoldedRuns
from ..workspace import POINT_SIZE, colormap, legend_html

if TYPE_CHECKING:
    from .session import CourseArmSession

POINTS = 60_000  #: within the joint limits; a few hundred ms for a six-joint arm, sent once per browser


def cloud(arm: Arm, n: int = POINTS) -> tuple[np.ndarray, np.ndarray, float]:
    """(points (n, 3) float32, colours (n, 3) uint8, colour-scale top): a preset's is computed once for every browser."""
    if arm.name in PRESETS:
        return _preset_cloud(arm.name, n)
    return _cloud(arm, n)


@functools.lru_cache(maxsize=len(PRESETS))
def _preset_cloud(name: str, n: int) -> tuple[np.ndarray, np.ndarray, float]:
    return _cloud(Arm.preset(name), n)


def _cloud(arm: Arm, n: int) -> tuple[np.ndarray, np.ndarray, float]:
    points, manipulability = arm.sample_workspace(n, seed=0)
    top = float(np.percentile(manipulability, 99)) or 1.0
    return points.astype(np.float32), colormap(manipulability, top), top


class CourseWorkspace(View):
    """The "Workspace" folder: the cloud on or off, with its legend."""

    def __init__(self, scene: viser.SceneApi, gui: viser.GuiApi, session: "CourseArmSession") -> None:
        self._scene = scene
        self._session = session
        self._cloud: viser.PointCloudHandle | None = None
        self._lock = threading.Lock()
        self._runs = FoldedRuns(self._update)
        folder = gui.add_folder("Workspace", expand_by_default=False)
        self.folders = (folder,)
        with folder:
            self.enabled = gui.add_checkbox("Show workspace cloud", False,
                                            hint=f"Where the tool gets to: {POINTS:,} random joint vectors within the limits")
            self.legend = gui.add_html("", visible=False)
        self.enabled.on_update(session.guard(lambda _: self._runs.start("course-cloud", session.guard)))
        self._computed: tuple[np.ndarray, np.ndarray, float] | None = None  #: this arm's cloud, once computed

    def close(self) -> None:
        """The session has gone: its cloud goes too (the presenter's is in the scene everyone shares)."""
        with self._lock:  # not while a cloud is being added: it would outlive the session
            if self._cloud is not None:
                self._cloud.remove()
                self._cloud = None

    def _update(self) -> None:
        shown = None
        if self.enabled.value:  # the slow part, outside the lock
            if self._computed is None:
                session = self._session
                self._computed = HEAVY.run(session.client, lambda: cloud(session.arm), cancelled=lambda: session.closed)
            shown = self._computed
        with self._lock:
            if not self._session.closed:
                self._show(shown)

    def _show(self, shown: tuple[np.ndarray, np.ndarray, float] | None) -> None:
        if shown is None:
            if self._cloud is not None:
                self._cloud.remove()
                self._cloud = None
            self.legend.visible = False
            return
        points, colours, top = shown
        if self._cloud is None:
            self._cloud = self._scene.add_point_cloud(f"{self._session.scene.root}/workspace", points, colours, point_size=POINT_SIZE,
                                                      point_shape="circle")
        self.legend.content = legend_html(top).replace(" m³", "")
        self.legend.visible = True
