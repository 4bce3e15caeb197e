"""Lecture mode: type, lines and panel sized for the back of a lecture hall.

One switch per browser, in its "View" folder; ``ur10-teach --lecture`` starts every browser
with it on (in shared mode the viewers' too). It sets the page's type to at least 20 px
(the panel's default is about 13 px), a chart's axes to 20 px and every 3D label to at least 24 px, widens the docked
panel to hold it, and thickens the gizmo's lines; "Hide the panel" folds the panel to a strip at the edge, leaving the whole
window to the arm (a click on the strip brings it back).
"""

from __future__ import annotations

import contextlib
from typing import Callable

import viser

from ..style import NARROW_WINDOW, label_scale
from ..viser_internals import labels_of

#: The page's root size: viser's panel text is 0.8125 rem, so this makes it 20.8 px.
ROOT_FONT_PX = 25.6
PANEL_WIDTH_PX = {False: 330, True: 540}  #: a third of a 1024 px window at most, and the lecture one
STYLE = (
    # not in a window as narrow as a phone's (viser's 36 em breakpoint): there the panel is a sheet 20 em wide,
    # which at this size was wider than the phone, and cut off the joints' names; a phone is held close anyway
    f"<style>@media not all and {NARROW_WINDOW} {{"
    f"html {{ font-size: {ROOT_FONT_PX}px !important; }}"
    # the sliders' tick labels and the inputs size themselves in px: bring them up too
    ".mantine-Slider-markLabel, .mantine-Input-input, .mantine-Button-label {"
    " font-size: 0.85rem !important; }"
    # a chart's legend, under it, is the page's; its axes are drawn on its canvas (LECTURE_AXIS)
    ".u-legend { font-size: 0.8rem !important; }"
    "}</style>"
)
#: uPlot draws a chart's tick numbers and axis names on its canvas in px (12 by default), out of the page's
#: type's reach: in lecture mode at the panel's 20 px, with the room they take under the plot (x, the first
#: axis) and beside it (y), and padding (top, right, bottom, left) so that the end ticks' numbers are not cut.
LECTURE_AXIS = {"font": "20px system-ui, sans-serif", "labelFont": "bold 20px system-ui, sans-serif", "labelSize": 32}
LECTURE_AXIS_SIZE = (44, 64)
LECTURE_PADDING = (16, 18, 0, 0)


class LectureMode:
    """The lecture-mode switch and "Hide the panel" button in one browser's "View" folder.

    ``on_change`` callbacks get the new state (the session thickens its gizmo's lines there). ``hide`` hides the
    panel (the camera's controls know whether viser's ``minimize`` can).
    """

    def __init__(self, gui: viser.GuiApi, folder: viser.GuiFolderHandle, enabled: bool,
                 guard: Callable[[Callable], Callable], hide: Callable[[], None]) -> None:
        self._gui = gui
        self.on_change: list[Callable[[bool], None]] = []
        # outside every folder: a style in a folded folder would not be on the page
        self._style = gui.add_html(STYLE, visible=enabled, order=-1e9)
        with folder:
            self.enabled = gui.add_checkbox("Lecture mode", enabled, hint="Big type and thick lines, for a projector")
            self.hide_button = gui.add_button("Hide the panel", icon=viser.Icon.LAYOUT_SIDEBAR_RIGHT_COLLAPSE,
                                              hint="Click the strip at the edge to bring it back")
        self.enabled.on_update(guard(lambda _: self.apply()))
        self.hide_button.on_click(guard(lambda _: hide()))
        gui.main_panel.set_width(PANEL_WIDTH_PX[enabled])

    @property
    def on(self) -> bool:
        return bool(self.enabled.value)

    def apply(self) -> None:
        on = self.on
        self._style.visible = on
        self._gui.main_panel.set_width(PANEL_WIDTH_PX[on])
        for callback in self.on_change:
            callback(on)


def add_label(scene: viser.SceneApi, name: str, text: str, base: float, lecture: bool, **props) -> viser.LabelHandle:
    """A 3D label made at its size in lecture mode or out of it; :func:`size_labels` sizes it from ``base`` later."""
    label = scene.add_label(name, text, font_screen_scale=label_scale(base, lecture), **props)
    label._base_scale = base
    return label


def size_chart(chart: viser.GuiUplotHandle, lecture: bool) -> None:
    """A chart's axes at their size in lecture mode (:data:`LECTURE_AXIS`) or out of it (uPlot's own)."""
    axes = tuple({**{key: value for key, value in axis.items() if key not in (*LECTURE_AXIS, "size")},
                  **({**LECTURE_AXIS, "size": LECTURE_AXIS_SIZE[min(k, 1)]} if lecture else {})}
                 for k, axis in enumerate(chart.axes or ()))
    if axes != tuple(chart.axes or ()):
        chart.axes = axes
        chart.padding = LECTURE_PADDING if lecture else None


def size_labels(scene: viser.SceneApi, lecture: bool) -> None:
    """Every 3D label of ``scene`` at its size in lecture mode or out of it (``style.label_scale``)."""
    for label in labels_of(scene):
        base = getattr(label, "_base_scale", None)
        if base is None:
            base = label._base_scale = label.font_screen_scale
        wanted = label_scale(base, lecture)
        if label.font_screen_scale != wanted:
            with contextlib.suppress(RuntimeError):  # viser's word for a label another thread removed meanwhile
                label.font_screen_scale = wanted
