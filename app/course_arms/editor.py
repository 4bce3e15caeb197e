"""The DH editor: a student types a table, row by row, and gets that arm to drive (numerical IK).

One row per line, ``a  α  d  θ  type`` in millimetres and degrees, ``type`` R (revolute: θ
is its offset), P (prismatic: d is its offset) or F (fixed); commas or spaces between;
``#`` starts a comment. In the modified convention a row's a and α are a_{i−1}, α_{i−1}.
"""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING, Callable

import viser

from ur10core.serial import SerialArm

from ..feedback import chosen
from ..view import View

if TYPE_CHECKING:
    from .session import CourseArmSession

#: What the editor starts with: the lecture notes' articulated arm without its wrist.
STARTING_TABLE = """# a (mm)  alpha (deg)  d (mm)  theta (deg)  type
0     90   400   0   R
400    0     0   0   R
300    0     0   0   R"""
MAX_ROWS = 10
MAX_LENGTH_MM = 5000.0
CONVENTIONS = {"standard (Spong: Rz Tz Tx Rx)": "standard", "modified (Craig: Rx Tx Rz Tz)": "modified"}


def parse_table(text: str, convention: str, name: str = "custom") -> SerialArm:
    """The arm a typed table describes; ``ValueError`` naming the row and what is wrong.

    >>> arm = parse_table("500 0 0 0 R\\n400 0 0 0 R", "standard")
    >>> arm.joint_types, [round(r.a, 3) for r in arm.dh.rows]
    ('RR', [0.5, 0.4])
    """
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        fields = [f for f in re.split(r"[,\s]+", line) if f]
        if len(fields) != 5:
            raise ValueError(f"line {number}: a row is five entries, a α d θ type (mm, degrees, R/P/F); got {len(fields)}")
        try:
            a, alpha, d, theta = (float(f) for f in fields[:4])
        except ValueError:
            raise ValueError(f"line {number}: a, α, d and θ must be numbers, got {' '.join(fields[:4])!r:.60}") from None
        kind = fields[4].upper()
        if kind not in ("R", "P", "F"):
            raise ValueError(f"line {number}: the type must be R (revolute), P (prismatic) or F (fixed), got {fields[4]!r:.10}")
        if not all(math.isfinite(v) for v in (a, alpha, d, theta)):
            raise ValueError(f"line {number}: every entry must be a finite number")
        if max(abs(a), abs(d)) > MAX_LENGTH_MM:
            raise ValueError(f"line {number}: lengths up to {MAX_LENGTH_MM:.0f} mm, please")
        rows.append(((a / 1000, math.radians(alpha), d / 1000, math.radians(theta)), kind))
    if not rows:
        raise ValueError("the table is empty: type one row per line, a α d θ type")
    if len(rows) > MAX_ROWS:
        raise ValueError(f"at most {MAX_ROWS} rows, got {len(rows)}")
    if all(kind == "F" for _, kind in rows):
        raise ValueError("the table needs at least one joint (R or P)")
    return SerialArm.from_dh([values for values, _ in rows], convention, "".join(kind for _, kind in rows), name=name)


class DHEditor(View):
    """The "Your DH table" folder: convention, the rows, and "Build this arm"."""

    def __init__(self, gui: viser.GuiApi, session: "CourseArmSession", text: str, convention: str,
                 rebuild: Callable[[SerialArm, str, str], None]) -> None:
        folder = gui.add_folder("Your DH table", order=0.2)
        self.folders = (folder,)
        with folder:
            gui.add_markdown("One row per line: **a α d θ type** in mm and degrees; type R, P or F (fixed). "
                             "R: θ is the joint's offset; P: d is. The arm gets a numerical IK.")
            label = next(k for k, v in CONVENTIONS.items() if v == convention)
            self.convention = gui.add_dropdown("Convention", tuple(CONVENTIONS), initial_value=label)
            self.rows = gui.add_text("Rows", text, multiline=True)
            self.build = gui.add_button("Build this arm", icon=viser.Icon.HAMMER)
        self.build.on_click(session.guard(lambda _: self._build(rebuild)))

    def _build(self, rebuild: Callable[[SerialArm, str, str], None]) -> None:
        convention = CONVENTIONS[chosen(self.convention, "convention")]
        text = str(self.rows.value)
        if len(text) > 1000:  # the gate (app.gate) lets no longer text through from a browser
            raise ValueError("the table is too long (at most 1000 characters)")
        rebuild(parse_table(text, convention), text, convention)
