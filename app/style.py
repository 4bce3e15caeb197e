"""Colours, labels and number formatting: change the look of the app here."""

from __future__ import annotations

import re
import unicodedata

import numpy as np

#: Light-grey aluminium of the link bodies and the charcoal of the joint caps (RGB 0-255): the
#: solid arm is neutral, so that no ghost's colour can be mistaken for it.
ALUMINIUM = (205, 208, 212)
JOINT_CAP_GREY = (70, 72, 78)
#: The brand colour of the page (title bar, buttons).
BRAND_BLUE = (28, 64, 128)
#: One fixed colour per IK slot k = 4 i + 2 j + l. Chosen from the Okabe-Ito, Paul Tol and
#: IBM colour-blind-safe sets so that every pair stays apart (CIE76 ΔE ≥ 5) for normal,
#: protan and deutan vision, drawn at GHOST_OPACITY over the page and on a washed-out
#: projector (tests/test_palette.py). Colour alone cannot carry eight branches for
#: everyone: every ghost also carries its number in 3D.
SLOT_COLORS: tuple[tuple[int, int, int], ...] = (
    (0, 114, 178),  # blue
    (238, 119, 51),  # orange
    (51, 187, 238),  # cyan
    (204, 51, 17),  # brick red
    (240, 228, 66),  # yellow
    (68, 170, 153),  # teal
    (100, 143, 255),  # cornflower
    (221, 204, 119),  # sand
)
GHOST_OPACITY = 0.6
#: The UR10's reach (m), which its drawing is sized for (its DH frames' axes and labels, its gizmo); another
#: arm's drawing is sized by its own reach, and what is drawn beside it grows with that.
UR10_SIZE = 1.3
#: The page behind the ghosts (viser's light theme).
PAGE_BACKGROUND = (235, 235, 235)
UNREACHABLE_RED = (220, 30, 30)
#: Singularity overlay: calm and alarming ends of the gauges, and the lit geometry.
SAFE_GREEN = (46, 160, 67)
DANGER_RED = (220, 38, 38)
#: Branch-count map (RGB, alpha): no branch (a faint grey, so the plane's extent shows), then
#: 2, 4, 6 and 8 branches along viridis, whose lightness rises for every kind of colour vision.
REACH_COLORS: tuple[tuple[tuple[int, int, int], int], ...] = (
    ((150, 150, 150), 40),
    ((253, 231, 37), 150),
    ((94, 201, 98), 150),
    ((33, 145, 140), 150),
    ((68, 1, 84), 150),
)
SHOULDER_COLOR = (230, 159, 0)
ELBOW_COLOR = (0, 158, 115)
WRIST_COLOR = (204, 121, 167)

#: Size of the branch numbers in 3D (viser's font_screen_scale: an em of 12 px times it). In lecture
#: mode every 3D label grows by LECTURE_LABEL_FACTOR, to at least LECTURE_LABEL_MIN (an em of 24 px:
#: read from the back of a lecture hall on a 1080p projector).
NUMBER_SCALE = 1.6
NAME_SCALE = 1.4  #: the arrows' and the ellipsoids' names
LECTURE_LABEL_FACTOR, LECTURE_LABEL_MIN = 1.6, 2.0


def label_scale(base: float, lecture: bool) -> float:
    """A 3D label's font_screen_scale in or out of lecture mode, from its size out of it.

    >>> label_scale(1.6, False), label_scale(1.6, True), label_scale(1.1, True)
    (1.6, 2.56, 2.0)
    """
    return round(max(base * LECTURE_LABEL_FACTOR, LECTURE_LABEL_MIN), 6) if lecture else base

def hex_color(rgb: tuple[int, int, int]) -> str:
    return "#%02x%02x%02x" % tuple(int(c) for c in rgb)


def blend(calm: tuple[int, int, int], alarm: tuple[int, int, int], alarm_level: float) -> tuple[int, int, int]:
    """Linear mix of two colours; ``alarm_level`` in [0, 1]."""
    t = float(np.clip(alarm_level, 0.0, 1.0))
    return tuple(int(round((1 - t) * a + t * b)) for a, b in zip(calm, alarm))


def number(value: float, spec: str) -> str:
    """``format(value, spec)``, except that what rounds to zero never shows a minus sign ("−0.0"), and a value of a
    billion or more is written with four figures and a power of ten (a slide typed 1e300 m out read as 300 digits).

    >>> number(-0.04, ".1f"), number(1e300, "+.1f")
    ('0.0', '+1e+300')
    """
    if spec.endswith("f") and abs(value) >= 1e9:
        spec = spec.rsplit(".", 1)[0] + ".4g"
    text = format(value, spec)
    if text.lstrip("+-").strip("0.") == "" and text.startswith("-"):
        return format(0.0, spec)
    return text


#: Dashes a student may type for a minus, or copy from a task's text (the course writes −, U+2212), the
#: degree sign a student may type after an angle, and the brackets of a vector written (x, y, z), as the panel shows one.
_TYPED_SIGNS = str.maketrans({"\u2212": "-", "\u2013": "-", "°": "", "(": " ", ")": " ", "[": " ", "]": " "})


def half_width(text: str) -> str:
    """``text`` as an ASCII keyboard types it: the full-width forms a Chinese, Japanese or Korean keyboard's input mode
    types (３０，４５；－２６．５) and its ideographic comma (、) as the ASCII they stand for. ``float`` reads ３０ as
    30 already, but a full-width comma was no comma: the whole line was "not a number".

    >>> half_width("３０，４５、－２６．５　（１）")
    '30,45,-26.5 (1)'
    """
    return unicodedata.normalize("NFKC", text).replace("\u3001", ",")


def typed_fields(text: str, what: str) -> list[str]:
    """The entries a student typed (:func:`half_width`), split at commas, semicolons, spaces and brackets, each minus
    sign one ``float`` reads and no degree signs. A comma between digits, where numbers are also parted without one, is
    read as a decimal comma (as much of Europe writes 1,5) and refused: read as a list it gave wrong numbers.

    >>> typed_fields("−30°, 45;26  0.5", "joint values")
    ['-30', '45', '26', '0.5']
    >>> typed_fields("(+100, −20.5, 0) [1 2]", "target")
    ['+100', '-20.5', '0', '1', '2']
    >>> typed_fields("1,5 2,5 3,5", "target")
    Traceback (most recent call last):
    ...
    ValueError: target: is '1,5' one number or two? Write decimals with a point (1.5) and a space after each comma
    """
    text = half_width(text).translate(_TYPED_SIGNS).strip()
    if re.search(r"\d,\d", text) and any("," not in gap for gap in re.findall(r"[\s;,]+", text)):
        group = next(g for g in re.split(r"[\s;]+", text) if re.search(r"\d,\d", g))
        raise ValueError(f"{what}: is {group!r:.20} one number or two? Write decimals with a point "
                         f"({group.replace(',', '.'):.20}) and a space after each comma")
    return [field for field in re.split(r"[\s;,]+", text) if field]


def sentence(text: str) -> str:
    """``text`` with a capital first letter (messages are written to follow a colon); a variable that
    starts it (θ2, d3, ḋ3) keeps its case: Θ2 or D3 would be another quantity."""
    first = text.split(" ", 1)[0]
    if not first[:1].isascii() or any(character.isdigit() for character in first):
        return text
    return text[:1].upper() + text[1:]


#: The media query of viser's layout breakpoint (Mantine's xs): in a window it matches, a phone's held upright or a
#: laptop's beside another, the panel is a sheet over the canvas's lower part, not docked beside it.
NARROW_WINDOW = "(max-width: 36em)"
#: The style of a panel element whose colour is what it says (a swatch, a gauge, a legend): kept where the system
#: forces its own colours (Windows' contrast themes drop every background, and the gauges went blank). Inherited.
COLOUR_IS_CONTENT = "forced-color-adjust:none"


def swatch(rgb: tuple[int, int, int]) -> str:
    """A small coloured square for markdown tables."""
    return (f'<span style="display:inline-block;width:0.9em;height:0.9em;border-radius:2px;background:{hex_color(rgb)};'
            f'{COLOUR_IS_CONTENT}"></span>')


def turning_and_sliding(joint_types: str) -> bool:
    """Whether joints ``joint_types`` ("R" turns, "P" slides) are of both kinds: a norm over them adds rad/s to
    m/s, N·m to N."""
    return {"R", "P"} <= set(joint_types)


def joint_units(joint_types: str) -> tuple[str, str]:
    """(a joint rate's unit, a joint effort's) for joints ``joint_types`` ("R" turns, "P" slides).

    >>> joint_units("RRRRRR"), joint_units("RRPR")
    (('rad/s', 'N·m'), ('rad/s or m/s', 'N·m or N'))
    """
    if turning_and_sliding(joint_types):
        return "rad/s or m/s", "N·m or N"
    return ("m/s", "N") if "R" not in joint_types else ("rad/s", "N·m")
