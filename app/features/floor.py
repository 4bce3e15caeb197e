"""The floor check: a red disc under every arm on screen that reaches below the floor (z = 0).

The core gives each arm's lowest body point (``Snapshot.lowest``); a real UR10 there would
hit the table it stands on, so the solid arm and each ghost drawn get a warning disc, and
their numbers in 3D and the branch table say "floor". Drawn with the panel (≤ 10 Hz), not
on the drag path.
"""

from __future__ import annotations

import functools

import numpy as np
import trimesh
import viser

from ..state import Snapshot
from ..style import DANGER_RED
from ..view import View
from ..viser_internals.fast_updates import set_instances
from .ik_target import BranchesScene

DISC_RADIUS = 0.09
#: Just above the floor grid, so the disc is not hidden in it.
DISC_HEIGHT = 0.003


def add_floor_grid(scene: viser.SceneApi) -> None:
    """The floor the arms stand on: 10 cm cells, 50 cm sections (the server's, shared by everyone)."""
    scene.add_grid("/floor", width=3.0, height=3.0, cell_size=0.1, section_size=0.5)


@functools.lru_cache(maxsize=1)
def disc_mesh() -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of the red disc, made once for every browser."""
    disc = trimesh.creation.cylinder(radius=DISC_RADIUS, height=0.002, sections=48)
    return disc.vertices, disc.faces


class FloorScene(View):
    """Instance 0 marks the solid arm, instance k + 1 the ghost of slot k."""

    def __init__(self, scene: viser.SceneApi, branches: BranchesScene) -> None:
        self._branches = branches
        vertices, faces = disc_mesh()
        self.discs = scene.add_batched_meshes_simple(
            "/floor_hits", vertices, faces,
            batched_wxyzs=np.tile([1.0, 0.0, 0.0, 0.0], (9, 1)), batched_positions=np.zeros((9, 3)),
            batched_scales=np.zeros(9), batched_colors=np.tile(np.array(DANGER_RED, np.uint8), (9, 1)), opacity=0.75, lod="off",
            cast_shadow=False, receive_shadow=False,
        )
        self._drawn = b""

    def render_panel(self, snapshot: Snapshot) -> None:
        """At the panel's pace (≤ 10 Hz), off the drag path: the floor check is not needed 20 times a second."""
        on_screen = np.concatenate([[True], self._branches.shown])
        hits = snapshot.through_floor & on_screen
        positions = np.where(hits[:, None], snapshot.lowest, 0.0)
        positions[:, 2] = DISC_HEIGHT
        drawn = hits.tobytes() + positions.astype(np.float32).tobytes()
        if drawn == self._drawn:
            return  # usually nothing is through the floor: nothing to send
        self._drawn = drawn
        if self.discs.batched_scales.astype(bool).tobytes() != hits.tobytes():
            self.discs.batched_scales = hits.astype(np.float32)
        set_instances(self.discs, np.tile([1.0, 0.0, 0.0, 0.0], (9, 1)), positions)
