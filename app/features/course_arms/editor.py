"""The DH editor: a student types a table, row by row, and gets that arm to drive (numerical IK).

One row per line, ``a  α  d  θ  type`` in millimetres and degrees, ``type`` R (revolute: θ
is its offset), P (prismatic: d is its offset) or F (fixed), and for a joint, optionally, its
limits ``min max`` (degrees or mm; ±180° and 0…1000 mm otherwise); commas or spaces between;
``#`` starts a comment. In the modified convention a row's a and α are a_{i−1}, α_{i−1}.
"""

from __future__ import annotations

import math
from typing import Callable

import viser

from ur10core import Arm

from ...feedback import Beside, chosen
from ...style import half_width, typed_fields
from ...view import Session, View

#: What the editor starts with: the lecture notes' articulated arm without its wrist.
STARTING_TABLE = """# a (mm)  alpha (deg)  d (mm)  theta (deg)  type  [min max]
0     90   400   0   R   -170 170
400    0     0   0   R
300    0     0   0   R"""
MAX_ROWS = 10
MAX_TEXT = 1000
MAX_LENGTH_MM = 5000.0
MAX_TURN_DEGREES = 360.0
#: A joint's limits when its row gives none: degrees for R, millimetres for P.
DEFAULT_LIMITS = {"R": (-180.0, 180.0), "P": (0.0, 1000.0)}
CONVENTIONS = {"standard (Spong: Rz Tz Tx Rx)": "standard", "modified (Craig: Rx Tx Rz Tz)": "modified"}


def starting_table() -> tuple[Arm, str, str]:
    """(arm, text, convention) of the table the DH editor opens with, before anything is typed in it."""
    return parse_table(STARTING_TABLE, "standard"), STARTING_TABLE, "standard"


def parse_table(text: str, convention: str, name: str = "custom") -> Arm:
    """The arm a typed table describes; ``ValueError`` naming the row and what is wrong.

    >>> arm = parse_table("500 0 0 0 R -90 90\\n400 0 0 0 R", "standard")
    >>> arm.joint_types, [round(r.a, 3) for r in arm.dh.rows], [round(math.degrees(v)) for v in arm.limits.ravel()]
    ('RR', [0.5, 0.4], [-90, 90, -180, 180])
    """
    if len(text) > MAX_TEXT:  # the gate (ur10teach.serving.gate) lets no longer text through from a browser
        raise ValueError(f"the table is too long (at most {MAX_TEXT} characters)")
    rows, limits = [], []
    for number, line in enumerate(half_width(text).splitlines(), start=1):  # (a full-width ＃ begins a comment too)
        fields = typed_fields(line.split("#", 1)[0], f"line {number}")
        if not fields:
            continue
        if len(fields) not in (5, 7):
            raise ValueError(f"line {number}: a row is five entries, a α d θ type (mm, degrees, R/P/F), "
                             f"and a joint's limits min max if you like; got {len(fields)}")
        numbers = fields[:4] + fields[5:]
        try:
            values = [float(f) for f in numbers]
        except ValueError:
            raise ValueError(f"line {number}: a, α, d, θ and the limits must be numbers, got {' '.join(numbers)!r:.60}") from None
        kind = fields[4].upper()
        if kind not in ("R", "P", "F"):
            raise ValueError(f"line {number}: the type must be R (revolute), P (prismatic) or F (fixed), got {fields[4]!r:.10}")
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"line {number}: every entry must be a finite number")
        a, alpha, d, theta = values[:4]
        if max(abs(a), abs(d)) > MAX_LENGTH_MM:
            raise ValueError(f"line {number}: lengths up to {MAX_LENGTH_MM:.0f} mm, please")
        rows.append(((a / 1000, math.radians(alpha), d / 1000, math.radians(theta)), kind))
        if kind != "F":
            limits.append(_limits(number, kind, values[4:] or DEFAULT_LIMITS[kind]))
        elif len(values) > 4:
            raise ValueError(f"line {number}: a fixed row has no limits (it does not move)")
    if not rows:
        raise ValueError("the table is empty: type one row per line, a α d θ type")
    if len(rows) > MAX_ROWS:
        raise ValueError(f"at most {MAX_ROWS} rows, got {len(rows)}")
    if all(kind == "F" for _, kind in rows):
        raise ValueError("the table needs at least one joint (R or P)")
    return Arm.from_dh([values for values, _ in rows], convention, "".join(kind for _, kind in rows),
                             limits=limits, name=name)


def _limits(number: int, kind: str, typed) -> tuple[float, float]:
    """One joint's typed limits (degrees or mm) in radians or metres."""
    low, high = typed
    bound = MAX_TURN_DEGREES if kind == "R" else MAX_LENGTH_MM
    unit = "°" if kind == "R" else " mm"
    if not -bound <= low < high <= bound:
        raise ValueError(f"line {number}: limits are min < max within ±{bound:.0f}{unit}, got {low:g} {high:g}")
    return (math.radians(low), math.radians(high)) if kind == "R" else (low / 1000, high / 1000)


class DHEditor(View):
    """The "Your DH table" folder: convention, the rows, and "Build this arm"."""

    def __init__(self, gui: viser.GuiApi, session: Session, text: str, convention: str,
                 rebuild: Callable[[Arm, str, str], None]) -> None:
        folder = gui.add_folder("Your DH table", order=0.2)
        self.folders = (folder,)
        with folder:
            gui.add_markdown("One row per line: **a α d θ type** in mm and degrees; type R, P or F (fixed). "
                             "R: θ is the joint's offset; P: d is. A joint's limits may follow: **min max** "
                             "(±180° and 0…1000 mm if not). The arm gets a numerical IK.")
            label = next(k for k, v in CONVENTIONS.items() if v == convention)
            self.convention = gui.add_dropdown("Convention", tuple(CONVENTIONS), initial_value=label)
            self.rows = gui.add_text("Rows", text, multiline=True)
            self.build = gui.add_button("Build this arm", icon=viser.Icon.HAMMER)
            self.refusal = Beside(gui)
        self.build.on_click(session.guard(lambda _: self._build(rebuild), beside=self.refusal))
        self.convention.on_update(session.guard(lambda _: chosen(self.convention, "convention")))

    def _build(self, rebuild: Callable[[Arm, str, str], None]) -> None:
        convention = CONVENTIONS[chosen(self.convention, "convention")]
        text = str(self.rows.value)
        rebuild(parse_table(text, convention), text, convention)
