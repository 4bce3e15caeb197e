"""Light view: one browser's 3D view drawn for a laptop without a graphics driver.

One switch per browser, in its "View" folder; ``ur10-teach --light`` starts every browser with it on.
Software WebGL spends most of a frame on the shadow maps, the environment map's lighting and the real
UR10's triangles: the switch turns both lightings off in this browser only and lights its scene with an
even fill instead (without the environment map the real arm is near black), and a session with its own
arm draws it as the schematic, toon-shaded (which keeps the ghosts' colours; BENCHMARKS.md, *frames a
second without a graphics driver*).
"""

from __future__ import annotations

from typing import Callable

import viser

#: The environment map a browser draws when the server never sets one (viser's client embeds only it).
VISER_DEFAULT_ENVIRONMENT = "city"
#: The even light standing in for the environment map's: the real arm grey, not near black; any brighter, and it
#: washes out the toon-shaded ghosts' colours (``test_the_solid_arm_stands_apart_from_its_ghosts``).
FILL_NAME, FILL_INTENSITY = "/light_view_fill", 0.6


class LightView:
    """The light-view switch in one browser's "View" folder.

    ``on_change`` callbacks get the new state (a session draws its arm as the schematic there).
    """

    def __init__(self, client: viser.ClientHandle, folder: viser.GuiFolderHandle, enabled: bool,
                 guard: Callable[[Callable], Callable]) -> None:
        self._scene = client.scene
        self.fill: viser.AmbientLightHandle | None = None  #: the fill light in this browser's scene, while on
        self.on_change: list[Callable[[bool], None]] = []
        with folder:
            self.enabled = client.gui.add_checkbox(
                "Light view", enabled, hint="For a laptop without a graphics driver (\"Software WebGL\"): no shadows "
                "or environment lighting, and your own arm drawn as the schematic; several times the frames a second")
        self.enabled.on_update(guard(lambda _: self.apply()))
        if enabled:  # a browser starts with viser's lighting: only the light view is sent (without an image)
            self._light(True)

    @property
    def on(self) -> bool:
        return bool(self.enabled.value)

    def apply(self) -> None:
        on = self.on
        self._light(on)
        for callback in self.on_change:
            callback(on)

    def scene_reset(self) -> None:
        """The browser's own scene was emptied (``scene.reset``), its fill light with it: light it again."""
        self.fill = None
        if self.on:
            self._light(True)

    def _light(self, on: bool) -> None:
        self._scene.configure_default_lights(enabled=True, cast_shadow=not on)
        self._scene.configure_environment_map(hdri=None if on else VISER_DEFAULT_ENVIRONMENT)
        if self.fill is not None:
            self.fill.remove()
        self.fill = self._scene.add_light_ambient(FILL_NAME, intensity=FILL_INTENSITY) if on else None
