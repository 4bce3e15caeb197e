"""Class challenges: a kinematics task, the exact check of a student's answer, and the kind of mistake it is.

docs/kinematics.md §9. A :class:`Challenge` is built in (:func:`builtin`) or read from a
teacher's TOML file (:func:`load`); :func:`check` takes the student's own state (an
:class:`Answer`: joints, target, typed table, typed numbers, joint rates) and returns a
:class:`Verdict`: solved or not, what is off and by how much, and the group the mistake falls
in (the projector counts students by it); :func:`solution` is what everyone is shown at the end.

Units are metres and radians here; a challenge file and the messages use mm and degrees.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re
import sys

import numpy as np

from .arm import PRESETS, Arm, factor_scales
from .dh import DHTable
from .differential import TASK_ROWS, damped_inverse
from .dynamics import GRAVITY, MASSES, centres_of_mass
from .solvers.spherical_wrist import spherical_wrist, wrist_split
from .solvers.ur import separation_steps, shoulder_angles
from .specs import GRID_JOINTS, WorstPose, largest_torque
from .three_dof import course_path
from .tolerances import LIMIT_TOLERANCE, TIE_TOLERANCE
from .workspace import heights_above_floor

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["KINDS", "POSE_QUESTIONS", "QUANTITIES", "Answer", "Challenge", "Verdict", "about_the_pose", "builtin", "check",
           "load", "parse", "solution", "terms", "unfit"]

KINDS = ("reach", "singularity", "branch_count", "dh_table", "numbers", "velocity", "largest_torque")
#: What a "numbers" challenge asks for at its joints.
QUANTITIES = {"position": "p of the tool frame (x, y, z in mm)",
              "det_j": "det J (lengths in metres; over the rows of J the arm controls, if fewer than six)",
              "torque": "the joint torques τ = Jᵀ [F; M] (N·m, N for a sliding joint)",
              "theta1": "both θ1 of the course's IK for this pose, shoulder left then right (°; the UR family's step 1)",
              "wrist_centre": "WC, where the wrist's three axes meet (x, y, z in mm; decoupling's step 1 on an arm "
                              "with a spherical wrist)",
              "tool_velocity": "v of the tool, J_v q̇, for the given joint rates (vx, vy, vz in mm/s)",
              "gravity_torque": "the joint torques that hold the arm still against its weight and the payload's (N·m; "
                                "UR's link masses and centres of mass)"}
#: The UR family's quantities: its IK's own steps (docs/kinematics.md §4.1)
UR_QUANTITIES = ("theta1",)
#: Quantities of an arm with a spherical wrist (docs/kinematics.md §7.3)
WRIST_QUANTITIES = ("wrist_centre",)
#: Quantities of an arm whose link masses are known (docs/kinematics.md §8.5)
MASS_QUANTITIES = ("gravity_torque",)
#: Quantities that are a point in the base frame (mm): typed in metres is a named mistake
POINTS = ("position", "wrist_centre")
#: Quantities that are angles (°): equal a turn apart, within the relative tolerance of 180°
ANGLES = ("theta1",)
#: The joint rates a student can set (the app's Velocities sliders): °/s for a revolute joint, mm/s for a sliding one.
RATE_LIMITS = {"R": 180.0, "P": 500.0}
MAX_CHALLENGES = 100
MAX_FILE_BYTES = 100_000
MAX_TEXT = 1000
#: a results file's name is "challenge-<key>-<date and time>-<n>.part" at most: 200 bytes of key keep it within 255
KEY_BYTES = 200
#: Joint values a "dh_table" answer is compared at (with the arm's home and zero joints).
DH_SAMPLES = 24


@dataclasses.dataclass(frozen=True)
class Challenge:
    """One task. Only the fields its ``kind`` uses are set (:func:`parse` checks them).

    Lengths in metres and angles in radians; a challenge file gives them in mm and degrees.
    """

    title: str
    kind: str
    arm: str  #: an ``Arm.preset`` name ("ur10": the app's own UR10, whichever preset the server runs)
    text: str  #: the task as the students read it
    joints: tuple[float, ...] | None = None  #: reach: the target's joints; numbers: where to compute; branch_count: the orientation's
    rates: tuple[float, ...] | None = None  #: numbers, tool_velocity: the joint rates (rad/s, m/s for a sliding joint)
    branch: str | int | None = None  #: reach: a slot number (1-based) or words of its label ("elbow down")
    factor: str | None = None  #: singularity: which factor of det J is zero
    min_tool_height: float | None = None  #: singularity: the tool at least this far above the floor (m)
    count: int | None = None  #: branch_count: how many branches reach
    quantity: str | None = None  #: numbers: a key of :data:`QUANTITIES`
    force: tuple[float, ...] = (0.0, 0.0, 0.0)  #: numbers, torque; largest_torque: the force at the tool (N), base frame
    moment: tuple[float, ...] = (0.0, 0.0, 0.0)  #: and the moment (N·m)
    payload: float = 0.0  #: numbers, gravity_torque: the mass at the flange (kg)
    velocity: tuple[float, ...] | None = None  #: velocity: the tool's asked velocity (m/s)
    still: bool = False  #: velocity: the tool must not turn as it moves
    position_tolerance: float = 0.005  #: m
    orientation_tolerance: float = math.radians(2.0)
    factor_tolerance: float = 0.01  #: singularity: |factor| as a share of its typical size (``factor_scales``)
    relative_tolerance: float = 0.01  #: numbers; largest_torque: how far below the largest ‖τ‖ still solves
    velocity_tolerance: float = 0.005  #: m/s
    time_limit: float | None = None  #: s

    @property
    def key(self) -> str:
        """The title as it names the results file: its letters and digits in any script, each run of others a dash,
        cut to :data:`KEY_BYTES` bytes of UTF-8 (a file's name holds 255 on most systems).

        >>> retitled = [dataclasses.replace(builtin()[0], title=t) for t in ("Übung 2: Reichweite", "到达目标", "到" * 80)]
        >>> [c.key for c in retitled[:2]], len(retitled[2].key), len(retitled[2].key.encode())
        (['übung-2-reichweite', '到达目标'], 66, 198)
        """
        return _plain(self.title).encode()[:KEY_BYTES].decode(errors="ignore").rstrip("-")

    @property
    def is_pose(self) -> bool:
        """Its answer is where the arm is: the projector draws every student's tool, and the end moves the arm."""
        return self.kind in ("reach", "singularity", "branch_count", "largest_torque")

    @property
    def asks(self) -> str:
        """What it asks for: its kind, or a numbers challenge's quantity (what the app's panels must not show while
        it runs).

        >>> builtin()[0].asks, next(c for c in builtin() if c.kind == "numbers").asks
        ('reach', 'position')
        """
        return self.quantity if self.kind == "numbers" else self.kind


@dataclasses.dataclass(frozen=True)
class Answer:
    """What the server reads from one student's session when they ask for a check."""

    q: np.ndarray | None = None  #: (n,) their arm's joints
    target: np.ndarray | None = None  #: (4, 4) their IK target
    table: DHTable | None = None  #: the table they typed
    numbers: np.ndarray | None = None  #: what they typed, in the challenge's units (mm, N·m, ...)
    rates: np.ndarray | None = None  #: (n,) their joint rates (rad/s, m/s)


@dataclasses.dataclass(frozen=True)
class Verdict:
    solved: bool
    message: str  #: what the student reads: what is off, and by how much
    group: str = ""  #: the kind of mistake, counted on the projector ("" when solved)
    answer: str = ""  #: the answer in a few words, for the results file


# ---------------------------------------------------------------------- built in


def builtin() -> tuple[Challenge, ...]:
    """The course's challenges, in the order it teaches them (docs/kinematics.md §9.2)."""
    return _BUILTIN


def _deg(*values: float) -> tuple[float, ...]:
    return tuple(math.radians(v) for v in values)


_REACH = _deg(20, 70, -100, 120, 90, 30)
_PATH_AT_4S = course_path(4.0)  #: the desktop arm's joints and rates at t = 4 s of the course's path (docs §8.6)
_BUILTIN = (
    Challenge("Reach the target", "reach", "ur10",
              "Put the tool on the orange target, position and orientation, on any branch (drag the target "
              "or move the joints).", joints=_REACH),
    Challenge("Reach it elbow down", "reach", "ur10",
              "Put the tool on the target **with the elbow down**.", joints=_REACH, branch="elbow down"),
    Challenge("Wrist singularity, tool up high", "singularity", "ur10",
              "Find a pose where the **wrist** factor of det J is zero, with the tool at least 500 mm above the floor.",
              factor="wrist", min_tool_height=0.5),
    Challenge("Elbow singularity", "singularity", "ur10", "Find a pose where the **elbow** factor of det J is zero.",
              factor="elbow"),
    Challenge("Four branches only", "branch_count", "ur10",
              "Keep the tool pointing straight down, as it starts, and move the target to where **exactly 4** "
              "branches reach it (Branches table).", joints=_deg(0, 60, -90, 120, -90, 0), count=4,
              orientation_tolerance=math.radians(5)),
    Challenge("Where is the flange?", "numbers", "ur10",
              "Compute p of T06 at the given joints. Type x y z in mm.",
              joints=_deg(30, 60, -80, 110, 90, 0), quantity="position"),
    Challenge("IK step 1: both shoulders", "numbers", "ur10",
              "The tool is where the given joints put it. Do step 1 of the IK: from P5 = p − d6·z6, "
              "type **both θ1**, shoulder left then right, in degrees.",
              joints=_deg(30, 45, 26, 50, 60, 80), quantity="theta1"),
    Challenge("det J by hand", "numbers", "ur10",
              "Compute det J at the given joints from its factors, lengths in metres.",
              joints=_deg(0, -60, 90, -30, 45, 0), quantity="det_j"),
    Challenge("Holding a weight", "numbers", "ur10",
              "The arm stretched out, the flange pushes down with 100 N. Type the "
              "six joint torques τ = Jᵀ F in N·m.", joints=_deg(0, 0, 0, 90, 0, 0), quantity="torque",
              force=(0.0, 0.0, -100.0)),
    Challenge("Holding itself up", "numbers", "ur10",
              "Stretched out level, the arm holds 5 kg at its flange. Type the six joint torques that hold it still "
              "against gravity, in N·m: for each joint, the weights m g beyond it times their lever arms, by the right "
              "hand about its axis. Joint 1 turns about z; joints 2, 3 and 4 about −y; joint 5 about x; joint 6 about "
              "−y, through the flange (each axis's point is given below).",
              joints=_deg(0, 0, 0, -90, 0, 0), quantity="gravity_torque", payload=5.0),
    Challenge("Straight up", "velocity", "ur10",
              "Set the joint rates (Velocities folder) so that the flange moves **straight up at 100 mm/s** without "
              "turning.", velocity=(0.0, 0.0, 0.1), still=True),
    Challenge("Type the UR10's DH table", "dh_table", "ur10",
              "Type the DH table of the UR10 (either convention): its forward kinematics must match the arm's."),
    Challenge("KR210: reach, wrist flipped", "reach", "kr210",
              "Put the KR210's tool on the target **with the wrist flipped**.",
              joints=_deg(10, 20, -30, 40, 50, 60), branch="wrist flipped"),
    Challenge("KR210: its wrist centre", "numbers", "kr210",
              "Step 1 of the KR210's IK, kinematic decoupling: at the given joints, where do its "
              "wrist's three axes meet? WC = p − 303 mm · z of the gripper frame. Type x y z in mm.",
              joints=_deg(30, 10, -20, 60, 45, 90), quantity="wrist_centre"),
    Challenge("Stanford arm's DH table", "dh_table", "stanford",
              "Type the Stanford arm's DH table (either convention): its forward kinematics must match the arm's."),
    Challenge("SCARA: one branch only", "branch_count", "scara",
              "Move the SCARA's target to where **only 1** of its 2 branches reaches.", count=1),
    Challenge("Cylindrical + wrist: DH table", "dh_table", "cylindrical_wrist",
              "Type the DH table of the cylindrical arm with a spherical wrist (either convention): its forward "
              "kinematics must match the arm's."),
    Challenge("Desktop arm: tool velocity", "numbers", "three_dof",
              "The course drives the desktop arm along θ̇ = (π/6 cos t, π/6 cos t, π/8 cos t) from θ = (0°, 0°, 135°), so "
              "θ = (π/6 sin t, π/6 sin t, 3π/4 + π/8 sin t). At **t = 4 s**, what is the tool's velocity v = J_v θ̇? "
              "Type vx vy vz in mm/s.", joints=tuple(_PATH_AT_4S[0].tolist()), rates=tuple(_PATH_AT_4S[1].tolist()),
              quantity="tool_velocity"),
    Challenge("Desktop arm: heaviest pose", "largest_torque", "three_dof",
              "The course's statics exercise: the desktop arm's tool pushes with **20 N along +x**. Move the joints, "
              "within their ranges, to the pose where holding it needs the **largest ‖τ‖ = ‖J_vᵀ F‖**. "
              "*Forces and gravity* shows τ for 20 N, +x.", force=(20.0, 0.0, 0.0)),
)


#: What a presenter can ask about the pose the class is shown (:func:`about_the_pose`): the picker's words → (kind,
#: quantity or "branch").
POSE_QUESTIONS = {"Pose shown: reach it": ("reach", None), "Pose shown: reach + branch": ("reach", "branch"),
                  "Pose shown: tool position": ("numbers", "position"), "Pose shown: det J": ("numbers", "det_j"),
                  "Pose shown: wrist centre": ("numbers", "wrist_centre"),
                  "Pose shown: holding torques": ("numbers", "gravity_torque")}
_SHOWN = "the joints the class's arm was shown at"
_POSE_TEXTS = {None: "Put your tool on the target, the pose the class's arm was shown in: position and orientation, on "
                     "any branch.",
               "branch": "Put your tool on the target, the pose the class's arm was shown in, **on the branch it was on: "
                         "{label}**.",
               "position": f"Where is the tool at {_SHOWN}? Type x y z in mm.",
               "det_j": f"What is det J at {_SHOWN}?",
               "wrist_centre": f"Where do the wrist's three axes meet at {_SHOWN}? Type x y z in mm.",
               "gravity_torque": f"Which joint torques hold the arm still at {_SHOWN}, against its own weight? In N·m."}


def about_the_pose(question: str, arm: Arm, q) -> Challenge:
    """A presenter's question (a key of :data:`POSE_QUESTIONS`) about the pose the class is shown: ``arm`` (a preset)
    at joints ``q`` (n,), on the branch those joints are on. ``ValueError`` saying why where it does not apply.

    >>> arm = Arm.preset("kr210")
    >>> about_the_pose("Pose shown: wrist centre", arm, arm.specs.home).quantity
    'wrist_centre'
    >>> about_the_pose("Pose shown: holding torques", arm, arm.specs.home)
    Traceback (most recent call last):
    ...
    ValueError: the holding torques need the arm's link masses, and they are known for the UR10 only
    """
    if question not in POSE_QUESTIONS:
        raise ValueError(f"question must be one of {', '.join(POSE_QUESTIONS)}, got {question!r:.40}")
    if arm.name not in PRESETS:
        raise ValueError("a typed table has no challenges: show the class one of the course's arms")
    kind, asked = POSE_QUESTIONS[question]
    if asked == "wrist_centre":  # in the teacher's words: the file's field names mean nothing on the desk
        try:
            spherical_wrist(arm)
        except ValueError as why:
            reason = str(why).removeprefix("no spherical wrist: ")
            raise ValueError(f"the wrist centre is where a spherical wrist's three axes meet, and this arm has none: {reason}") from None
    if asked == "gravity_torque" and arm.name not in MASSES:
        known = "the UR10" if set(MASSES) <= set(Arm.UR_PRESETS) else ", ".join(sorted(MASSES))
        raise ValueError(f"the holding torques need the arm's link masses, and they are known for {known} only")
    q = arm.joints(q)
    values = {"title": question, "kind": kind, "arm": "ur10" if arm.name in Arm.UR_PRESETS else arm.name,
              "joints": tuple(q.tolist())}
    if asked == "branch":  # the slot whose joints are q (not the target's, which may be out of reach)
        slot = _slot_of(arm, arm.ik(arm.fk(q), hint=q), q)
        values["branch"] = slot + 1
        values["text"] = _POSE_TEXTS["branch"].format(label=arm.slot_labels[slot])
    else:
        values["text"] = _POSE_TEXTS[asked]
        if kind == "numbers":
            values["quantity"] = asked
    try:
        return _validated(Challenge(**values), arm)
    except _FieldError as why:  # (no file line to name)
        raise ValueError(str(why)) from None


def unfit(challenge: Challenge, preset: str) -> str:
    """Why ``challenge`` cannot be set where the app's own UR10 is the ``preset`` (one of ``Arm.UR_PRESETS``), or "".

    A challenge on "ur10" is done on that preset, and :func:`parse` checked it on the ``ur10``'s numbers.

    >>> unfit(next(c for c in builtin() if c.quantity == "gravity_torque"), "ur10e")  # the UR10e's masses are UR's
    ''
    """
    if challenge.arm != "ur10" or preset == "ur10":
        return ""
    try:
        _validated(challenge, Arm.preset(preset))
    except _FieldError as why:
        return str(why)
    return ""


# ---------------------------------------------------------------------- files


def load(path) -> tuple[Challenge, ...]:
    """The challenges of a teacher's TOML file; ``ValueError`` naming the line of whatever is wrong."""
    with open(path, "rb") as file:
        raw = file.read(MAX_FILE_BYTES + 1)
    if len(raw) > MAX_FILE_BYTES:
        raise ValueError(f"{path}: a challenge file is at most {MAX_FILE_BYTES // 1000} kB")
    try:  # (a byte-order mark, as older Notepads and PowerShell 5's utf8 write, is not TOML: dropped)
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = raw[:error.start].count(b"\n") + 1
        raise ValueError(f"{path}, line {line}: not UTF-8 text (byte {error.start}, {raw[error.start]:#04x}): "
                         "save the file as UTF-8") from None
    return parse(text, source=str(path))


def parse(text: str, source: str = "challenges") -> tuple[Challenge, ...]:
    """Challenges from TOML text: one ``[[challenge]]`` table each (docs/kinematics.md §9.3).

    >>> [c.title for c in parse('[[challenge]]\\ntitle = "Up"\\nkind = "velocity"\\nvelocity_mm_s = [0, 0, 100]')]
    ['Up']
    >>> parse('[[challenge]]\\ntitle = "Up"\\nkind = "velocty"')
    Traceback (most recent call last):
    ...
    ValueError: challenges, line 3: kind must be one of reach, singularity, branch_count, dh_table, numbers, velocity, largest_torque, got 'velocty'
    """
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:  # (its "end of document" is the last line, which a teacher looks for)
        where = f"at line {len(text.splitlines())}"
        raise ValueError(f"{source}: {str(error).replace('at end of document', where)}") from None
    unknown = set(document) - {"challenge"}
    if unknown:
        raise ValueError(f"{source}, line {_line(text, -1, sorted(unknown)[0])}: only [[challenge]] tables, "
                         f"got {sorted(unknown)[0]!r}")
    tables = document.get("challenge", [])
    if not isinstance(tables, list) or not tables:
        raise ValueError(f"{source}: no [[challenge]] table")
    if len(tables) > MAX_CHALLENGES:
        raise ValueError(f"{source}: at most {MAX_CHALLENGES} challenges, got {len(tables)}")
    challenges = []
    for index, table in enumerate(tables):
        try:
            challenges.append(_from_table(table))
        except _FieldError as error:
            raise ValueError(f"{source}, line {_line(text, index, error.field)}: {error}") from None
    keys = [_plain(c.title) for c in challenges]  # whole: titles may differ only past the results file's cut
    for index, key in enumerate(keys):
        if keys.index(key) != index:
            first, title = challenges[keys.index(key)].title, challenges[index].title
            titled = repr(title) if first == title else f"{first!r} and {title!r}, the same but for case, signs and spaces"
            raise ValueError(f"{source}, line {_line(text, index, 'title')}: two challenges titled {titled}")
        if challenges[index].title in POSE_QUESTIONS:  # (the presenter's desk would offer one of the two)
            raise ValueError(f"{source}, line {_line(text, index, 'title')}: {challenges[index].title!r} is the desk's own "
                             "question about the pose shown: give yours another title")
    return tuple(challenges)


class _FieldError(ValueError):
    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field


def _plain(title: str) -> str:
    """``title`` in lower case, each run of other than letters and digits (any script's) one dash."""
    return re.sub(r"[\W_]+", "-", title.lower()).strip("-")


def _line(text: str, index: int, field: str | None) -> int:
    """The line of ``field`` in the ``index``-th ``[[challenge]]`` (its header's line without one)."""
    lines = text.splitlines()
    headers = [k for k, line in enumerate(lines) if re.match(r"\s*\[\[\s*challenge\s*\]\]", line)]
    start = headers[index] if 0 <= index < len(headers) else 0
    end = headers[index + 1] if 0 <= index < len(headers) - 1 else len(lines)
    if field:
        for k in range(start, end):
            if re.match(rf"\s*{re.escape(field)}\s*=", lines[k]):
                return k + 1
    return start + 1


#: Every key a challenge table may have, and what it becomes.
_FIELDS = {"title", "kind", "arm", "text", "joints", "rates_deg_s", "branch", "factor", "min_tool_height_mm", "count", "quantity",
           "force_n", "moment_nm", "payload_kg", "velocity_mm_s", "still", "position_tolerance_mm", "orientation_tolerance_deg",
           "factor_tolerance", "relative_tolerance", "velocity_tolerance_mm_s", "time_limit_s"}
#: The keys each kind needs, and those it may have beyond the common ones.
_NEEDS = {"reach": ({"joints"}, {"branch", "position_tolerance_mm", "orientation_tolerance_deg"}),
          "singularity": ({"factor"}, {"min_tool_height_mm", "factor_tolerance"}),
          "branch_count": ({"count"}, {"joints", "orientation_tolerance_deg"}),
          "dh_table": (set(), {"position_tolerance_mm"}),
          "numbers": ({"joints", "quantity"}, {"force_n", "moment_nm", "rates_deg_s", "payload_kg", "relative_tolerance"}),
          "velocity": ({"velocity_mm_s"}, {"still", "velocity_tolerance_mm_s"}),
          "largest_torque": ({"force_n"}, {"relative_tolerance"})}
_COMMON = {"title", "kind", "arm", "text", "time_limit_s"}


def _from_table(table: dict) -> Challenge:
    if not isinstance(table, dict):
        raise _FieldError("", "each [[challenge]] is a table of keys")
    for field in table:
        if field not in _FIELDS:
            raise _FieldError(field, f"unknown key {field!r}")
    kind = table.get("kind")
    if kind is None:
        raise _FieldError("kind", f"a challenge needs a kind: one of {', '.join(KINDS)}")
    if kind not in KINDS:
        raise _FieldError("kind", f"kind must be one of {', '.join(KINDS)}, got {kind!r:.40}")
    needs, may = _NEEDS[kind]
    for field in needs:
        if field not in table:
            raise _FieldError("kind", f"a {kind} challenge needs {field!r}")
    for field in table:
        if field not in needs | may | _COMMON:
            raise _FieldError(field, f"{field!r} is not used by a {kind} challenge")
    title = _text(table, "title", 80, required=True)
    arm_name = table.get("arm", "ur10")
    if arm_name not in PRESETS:
        raise _FieldError("arm", f"arm must be one of {', '.join(PRESETS)}, got {arm_name!r:.40}")
    arm = Arm.preset(arm_name)
    values: dict = {"title": title, "kind": kind, "arm": arm_name, "text": _text(table, "text", MAX_TEXT) or title}
    if "joints" in table:
        values["joints"] = _joints(table, arm)
    if "rates_deg_s" in table:
        values["rates"] = tuple(_in_si(arm, _numbers(table, "rates_deg_s", arm.n_joints, 1e5)).tolist())
    if "branch" in table:
        values["branch"] = _branch(table["branch"], arm)
    if "factor" in table:
        names = arm.factor_names
        if table["factor"] not in names:
            raise _FieldError("factor", f"the {arm_name} arm's det J factors are {', '.join(names)}, got {table['factor']!r:.40}")
        values["factor"] = table["factor"]
    if "count" in table:
        values["count"] = _integer(table, "count", 0, len(arm.slot_labels))
    if "quantity" in table:
        if not isinstance(table["quantity"], str) or table["quantity"] not in QUANTITIES:
            raise _FieldError("quantity", f"quantity must be one of {', '.join(QUANTITIES)}, got {table['quantity']!r:.40}")
        values["quantity"] = table["quantity"]
    for field, name, scale, size in (("force_n", "force", 1.0, 3), ("moment_nm", "moment", 1.0, 3),
                                     ("velocity_mm_s", "velocity", 1e-3, 3)):
        if field in table:
            values[name] = tuple(scale * v for v in _numbers(table, field, size, 1e6))
    if "still" in table:
        if not isinstance(table["still"], bool):
            raise _FieldError("still", "still is true or false")
        values["still"] = table["still"]
    for field, name, scale, low, high in (
            ("min_tool_height_mm", "min_tool_height", 1e-3, -1e4, 1e4),
            ("position_tolerance_mm", "position_tolerance", 1e-3, 1e-3, 1000.0),
            ("orientation_tolerance_deg", "orientation_tolerance", math.pi / 180, 1e-3, 180.0),
            ("factor_tolerance", "factor_tolerance", 1.0, 1e-6, 1.0),
            ("relative_tolerance", "relative_tolerance", 1.0, 1e-9, 1.0),
            ("velocity_tolerance_mm_s", "velocity_tolerance", 1e-3, 1e-3, 1e4),
            ("time_limit_s", "time_limit", 1.0, 10.0, 86_400.0)):
        if field in table:
            values[name] = scale * _number(table, field, low, high)
    if "payload_kg" in table:
        if table.get("quantity") not in MASS_QUANTITIES:
            raise _FieldError("payload_kg", f"payload_kg is used by {', '.join(MASS_QUANTITIES)} only")
        if arm_name in MASSES:  # (an arm without them is refused for its quantity below)
            values["payload"] = _number(table, "payload_kg", 0.0, arm.specs.payload_kg or 0.0)
    return _validated(Challenge(**values), arm)


def _validated(challenge: Challenge, arm: Arm) -> Challenge:
    """``challenge``, if it is a task a class can do on ``arm`` (a preset: for "ur10", the server's own UR10's);
    ``_FieldError`` naming the field otherwise."""
    kind, arm_name = challenge.kind, arm.name
    if challenge.quantity == "torque" and not any(challenge.force) and not any(challenge.moment):
        raise _FieldError("quantity", "a torque question needs force_n or moment_nm")
    if (challenge.quantity == "tool_velocity") != (challenge.rates is not None):
        raise _FieldError("quantity" if challenge.rates is None else "rates_deg_s",
                          "tool_velocity needs the joint rates, rates_deg_s, and only it uses them")
    if challenge.quantity in UR_QUANTITIES and arm_name not in Arm.UR_PRESETS:
        raise _FieldError("quantity", f"{challenge.quantity} is a step of the UR family's IK: arm must be one of "
                                      f"{', '.join(Arm.UR_PRESETS)}, got {arm_name!r:.40}")
    if challenge.quantity in WRIST_QUANTITIES:
        try:
            spherical_wrist(arm)
        except ValueError as why:
            raise _FieldError("quantity", f"{challenge.quantity} is a step of decoupling, and the {arm_name} arm has {why}") from None
    if challenge.quantity in MASS_QUANTITIES and arm_name not in MASSES:
        raise _FieldError("quantity", f"{challenge.quantity} needs the arm's link masses, known for "
                                      f"{', '.join(sorted(MASSES))}, not for {arm_name!r:.40}")
    if challenge.velocity is not None and not any(challenge.velocity):
        raise _FieldError("velocity_mm_s", "the asked velocity must not be zero")
    if challenge.still and arm.task == "position":  # (it was taken and never checked)
        raise _FieldError("still", f"the {arm_name} arm places its tool's position only, not its orientation: "
                                   "its tool cannot be asked not to turn")
    if kind == "velocity" and _velocity_pose(challenge, arm) is None:  # nor is a velocity no joint rates give
        limits = ", ".join(f"±{RATE_LIMITS[k]:g} {'°/s' if k == 'R' else 'mm/s'}" for k in sorted(set(arm.joint_types)))
        raise _FieldError("velocity_mm_s", f"no pose of the {arm_name} arm within its limits moves the tool so with joint "
                                           f"rates a student can set ({limits})")
    if kind == "reach" and challenge.branch is not None:  # a branch that does not get there is a task nobody can do
        solution_ = arm.ik(arm.fk(np.array(challenge.joints)), hint=np.array(challenge.joints))
        reaching = np.flatnonzero(solution_.valid & solution_.within_limits)
        if not any(solution_.within_limits[s] for s in _wanted_slots(challenge, arm)):
            raise _FieldError("branch", f"branch {challenge.branch!r} does not reach this target within the joint limits; "
                                        f"branches {', '.join(str(k + 1) for k in reaching)} do")
    if kind == "dh_table" and arm.dh is None:
        raise _FieldError("arm", f"the {arm_name} arm has no DH table to type: the course writes its kinematics in "
                                 "closed form, in frames of its own")
    if kind == "singularity":  # a factor that is zero nowhere within the limits is a task nobody can do
        try:
            singular_pose(arm, challenge.factor, challenge.min_tool_height)
        except ValueError as error:
            raise _FieldError("factor", str(error)) from None
    if kind == "largest_torque":
        if not _searchable(arm):
            raise _FieldError("arm", f"a largest_torque challenge searches every joint's range, so its arm has at most "
                                     f"{GRID_JOINTS} joints, all revolute ({', '.join(n for n in PRESETS if _searchable(Arm.preset(n)))}), "
                                     f"got {arm_name!r}")
        if not any(challenge.force):
            raise _FieldError("force_n", "the force must not be zero")
        if worst_pose(challenge, arm).norm < 1e-6 * float(np.linalg.norm(challenge.force)):
            raise _FieldError("force_n", f"this force needs no torque in any pose of the {arm_name} arm: it pushes along "
                                         "what the joints cannot move")
    if kind == "branch_count":  # so is a count no target has
        try:
            _count_pose(challenge, arm)
        except ValueError as error:
            raise _FieldError("count", str(error)) from None
    return challenge


def _text(table: dict, field: str, limit: int, required: bool = False) -> str:
    value = table.get(field, "")
    if not isinstance(value, str) or (required and not value.strip()):
        raise _FieldError(field, f"{field} must be {'a non-empty' if required else 'a'} string")
    if len(value) > limit:
        raise _FieldError(field, f"{field} is at most {limit} characters, got {len(value)}")
    return value.strip()


def _number(table: dict, field: str, low: float, high: float) -> float:
    value = table[field]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:
        raise _FieldError(field, f"{field} must be a number from {low:g} to {high:g}, got {value!r:.40}")
    return float(value)


def _integer(table: dict, field: str, low: int, high: int) -> int:
    value = table[field]
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise _FieldError(field, f"{field} must be a whole number from {low} to {high}, got {value!r:.40}")
    return value


def _numbers(table: dict, field: str, size: int, bound: float) -> list[float]:
    values = table[field]
    if not isinstance(values, list) or len(values) != size:  # (a long list cut short in the message would not show it)
        got = f"{len(values)} values" if isinstance(values, list) else f"{values!r:.40}"
        raise _FieldError(field, f"{field} must be a list of {size} numbers, got {got}")
    for k, v in enumerate(values, 1):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not abs(v) <= bound:
            raise _FieldError(field, f"value {k} of {field} is {v!r:.40}: each must be a number from {-bound:g} to {bound:g}")
    return [float(v) for v in values]


def _in_si(arm: Arm, shown: list[float]) -> np.ndarray:
    """Joint values (or rates) as a file gives them, degrees (mm for a sliding joint), in radians and metres."""
    return np.where(arm.revolute, np.radians(shown), np.array(shown) / 1000.0)


def _joints(table: dict, arm: Arm) -> tuple[float, ...]:
    """The file's joints (degrees, mm for a sliding joint), within the arm's limits."""
    shown = _numbers(table, "joints", arm.n_joints, 1e5)
    q = _in_si(arm, shown)
    for name, value, si, (low, high), revolute in zip(arm.joint_names, shown, q, arm.limits, arm.revolute):
        if not low - LIMIT_TOLERANCE <= si <= high + LIMIT_TOLERANCE:
            unit = "°" if revolute else " mm"
            low, high = (f"{math.degrees(v) if revolute else 1000 * v:g}{unit}" for v in (low, high))
            raise _FieldError("joints", f"{name} is {value:g}{unit}, outside the {arm.name} arm's limits for it: "
                                        f"{low} to {high}")
    return tuple(np.clip(q, arm.limits[:, 0], arm.limits[:, 1]).tolist())


def _branch(value, arm: Arm) -> str | int:
    labels = arm.slot_labels
    if isinstance(value, int) and not isinstance(value, bool):
        if not 1 <= value <= len(labels):
            raise _FieldError("branch", f"branch is 1 to {len(labels)} on the {arm.name} arm, got {value}")
        return value
    if not isinstance(value, str) or not _slots_named(value, labels):
        raise _FieldError("branch", f"branch is a number or words of a branch's name ({labels[0]!r}, ...), got {value!r:.40}")
    return value


def _label_parts(label: str) -> list[str]:
    """"elbow up (θ2 ≤ 0), wrist flipped" → ["elbow up", "wrist flipped"]: the words a student names a branch by
    (none for an empty part)."""
    parts = (re.sub(r"\(.*?\)", "", part).strip().lower() for part in label.split(","))
    return [part for part in parts if part]


def _slots_named(words: str, labels: tuple[str, ...]) -> list[int]:
    """The slots whose label has every comma-separated part of ``words`` ("elbow down, wrist flipped"; a label copied
    whole, "elbow right (θ2 ≥ 0)", is its words)."""
    parts = _label_parts(words)
    named = [k for k, label in enumerate(labels) if all(p in _label_parts(label) for p in parts)]
    return named if parts else []


# ---------------------------------------------------------------------- terms


def terms(challenge: Challenge, arm: Arm | None = None) -> str:
    """What the check takes and asks, from the challenge's own fields: what a student reads under the task.

    ``arm``: the arm it is checked on (a challenge on "ur10" is checked on the preset the server runs); its
    ``Arm.preset`` by default.

    A teacher's text may leave out the joints, the force or a tolerance; these words cannot,
    since they are written from what :func:`check` compares.

    >>> print(terms(builtin()[0]))
    Checked: your tool on the target, within 5 mm and 2°.
    >>> print(terms(next(c for c in builtin() if c.quantity == "torque")))
    Given: q = (0°, 0°, 0°, 90°, 0°, 0°); F = (0, 0, -100) N at the tool, in the base frame. Asked: the joint torques τ = Jᵀ [F; M] (N·m, N for a sliding joint), each within 1 %.
    """
    arm = arm or Arm.preset(challenge.arm)
    turned = "" if arm.task == "position" else f" and {math.degrees(challenge.orientation_tolerance):.3g}°" + (
        " of its yaw" if arm.task == "position and yaw" else "")
    relative = f"within {100 * challenge.relative_tolerance:.3g} %"
    if challenge.kind == "reach":
        branch = ("" if challenge.branch is None else f", on branch {challenge.branch} ({arm.slot_labels[challenge.branch - 1]})"
                  if isinstance(challenge.branch, int) else f", on the {challenge.branch} branch")
        return f"Checked: your tool on the target{branch}, within {1000 * challenge.position_tolerance:.3g} mm{turned}."
    if challenge.kind == "singularity":
        height = "" if challenge.min_tool_height is None else \
            f", with the tool at least {1000 * challenge.min_tool_height:.0f} mm above the floor"
        return (f"Checked: the {challenge.factor} factor of det J zero, within {100 * challenge.factor_tolerance:.3g} % "
                f"of its usual size{height}.")
    if challenge.kind == "branch_count":
        held = "" if arm.task == "position" else (
            f", with the tool's orientation at q = {_given(arm, _goal_joints(challenge, arm))}{turned.replace(' and ', ', within ')}")
        return f"Checked: your IK target where exactly {_branches(challenge.count)} within the joint limits{held}."
    if challenge.kind == "dh_table":
        return (f"Checked: your table's forward kinematics against the arm's at zero joints, its home and {DH_SAMPLES} "
                f"random joint values: the tool frame within {100 * challenge.position_tolerance:.3g} mm.")
    if challenge.kind == "velocity":
        still = "" if not challenge.still else ", without turning (under 1 °/s)" if arm.task == "pose" else \
            ", without turning about its axis (under 1 °/s)"
        return (f"Checked: your joint rates, at your pose, move the tool at v = {_vector(1000 * np.array(challenge.velocity))} mm/s, "
                f"in the base frame, within {1000 * challenge.velocity_tolerance:.3g} mm/s{still}.")
    force = f"F = {_vector(challenge.force)} N" + (f" and M = {_vector(challenge.moment)} N·m" if any(challenge.moment) else "")
    if challenge.kind == "largest_torque":
        return (f"Given: {force} at the tool, in the base frame. Checked: your joints, within their ranges, need "
                f"‖τ‖ = ‖J_vᵀ F‖ {relative} of the largest any pose needs.")
    given = [f"q = {_given(arm, challenge.joints)}"]
    if challenge.quantity == "torque":
        given.append(f"{force} at the tool, in the base frame")
    if challenge.rates is not None:
        given.append(f"q̇ = {_given(arm, challenge.rates, '/s')}")
    if challenge.quantity == "gravity_torque":  # the app's bars that give the answer are off: what a hand needs
        masses = ", ".join(f"{m:g}" for m in MASSES[arm.name].masses)
        centres = ", ".join(_vector(c) for c in 1000 * centres_of_mass(arm, np.array(challenge.joints)))
        _, on_axes = arm.dh.joint_axes(arm.dh.frames(np.array(challenge.joints)))
        axes = ", ".join(_vector(point) for point in 1000 * on_axes)
        given.append(f"a payload of {challenge.payload:g} kg at the flange; links of ({masses}) kg, their centres of "
                     f"mass at {centres} mm in the base frame; joints 1 to {arm.n_joints}'s axes through {axes} mm; "
                     f"g = {GRAVITY:g} m/s²")
    within = f"within {180 * challenge.relative_tolerance:.3g}°" if challenge.quantity in ANGLES else relative
    each = "each " if len(number_names(challenge, arm)) > 1 else ""
    return f"Given: {'; '.join(given)}. Asked: {QUANTITIES[challenge.quantity]}, {each}{within}."


def _given(arm: Arm, values, per: str = "") -> str:
    """"(30°, 60°, 12.5 mm/s)": joint values (or rates, ``per`` "/s") as a task gives them, each with its unit."""
    return "(" + ", ".join(f"{_short(math.degrees(v))}°{per}" if kind == "R" else f"{_short(1000 * v)} mm{per}"
                           for v, kind in zip(values, arm.joint_types)) + ")"


def _vector(values) -> str:
    return "(" + ", ".join(_short(v) for v in values) + ")"


def _short(value: float) -> str:
    """To two decimals, without trailing zeros: "30", "117.97", "-0.5"."""
    text = f"{value:.2f}".rstrip("0").rstrip(".")
    return "0" if text == "-0" else text


# ---------------------------------------------------------------------- checks


def check(challenge: Challenge, arm: Arm, answer: Answer) -> Verdict:
    """Whether ``answer`` solves ``challenge`` on ``arm``, what is off and by how much, and the mistake's group.

    The answer is the student's own state on the server; nothing a browser claims counts.

    Example: the built-in "Reach it elbow down", answered with the elbow up.

    >>> reach = builtin()[1]
    >>> arm = Arm.preset("course")
    >>> T = arm.fk(reach.joints)
    >>> up = arm.ik(T).q[0]                                    # slot 1: shoulder left, elbow up
    >>> check(reach, arm, Answer(q=up)).group
    'elbow up instead of elbow down'
    >>> check(reach, arm, Answer(q=arm.ik(T).q[1])).solved     # slot 2: elbow down
    True
    """
    return _CHECKS[challenge.kind](challenge, arm, answer)


def _needs(value, what: str):
    if value is None:
        raise ValueError(f"the answer has no {what}")
    return value


def _direction(offset: np.ndarray, up) -> str:
    """"1181 mm from the target: 1180 mm too high, 40 mm too far towards −x": the parts of ``offset`` (m) that matter,
    ``up`` (3,) the arm's vertical (the desktop arm's is y)."""
    largest = np.abs(offset).max()
    words = [f"{1000 * abs(offset[k]):.0f} mm {_side(offset, k, up)}" for k in range(3)
             if abs(offset[k]) >= 0.3 * largest and abs(offset[k]) >= 5e-4]
    return f"{1000 * np.linalg.norm(offset):.0f} mm from the target: {', '.join(words)}"


def _side(offset: np.ndarray, axis: int, up) -> str:
    """Which way ``offset`` (3,) goes along base axis ``axis``: too high or low along ``up``, else towards ±x, ±y or ±z."""
    if up[axis]:
        return "too high" if offset[axis] * up[axis] > 0 else "too low"
    return f"too far towards {'+' if offset[axis] > 0 else '−'}{'xyz'[axis]}"


def _turn_between(arm: Arm, R: np.ndarray, R_goal: np.ndarray) -> float:
    """How far (rad) ``R`` is turned from ``R_goal`` in what the arm controls of it (none for a position-only arm)."""
    if arm.task == "position":
        return 0.0
    if arm.task == "position and yaw":  # the tool axis is the arm's own: the yaw of its x axis
        return abs(math.remainder(math.atan2(R[1, 0], R[0, 0]) - math.atan2(R_goal[1, 0], R_goal[0, 0]), math.tau))
    cosine = (np.trace(R_goal.T @ R) - 1.0) / 2.0
    return math.acos(min(1.0, max(-1.0, cosine)))


def _joints_text(arm: Arm, q, spec: str = ".1f") -> str:
    """Joint values (or rates) as a student reads them: degrees for a revolute joint, mm for a sliding one."""
    return " ".join(format(math.degrees(v) if kind == "R" else 1000 * v, spec) for v, kind in zip(q, arm.joint_types))


def _rows_text(table: DHTable, separator: str) -> str:
    """A table's rows as the DH editor takes them: a α d θ type, mm and degrees."""
    return separator.join(f"{1000 * r.a:.1f} {math.degrees(r.alpha):.1f} {1000 * r.d:.1f} {math.degrees(r.theta):.1f} "
                          f"{r.joint or 'F'}" for r in table.rows)


def _check_reach(challenge: Challenge, arm: Arm, answer: Answer) -> Verdict:
    q = np.asarray(_needs(answer.q, "joints"), dtype=float)
    goal = arm.fk(np.array(challenge.joints))
    T = arm.fk(q)
    text = _joints_text(arm, q)
    offset = T[:3, 3] - goal[:3, 3]
    if np.linalg.norm(offset) > challenge.position_tolerance:
        return Verdict(False, f"Your tool is {_direction(offset, arm.up)}.",
                       f"tool {_side(offset, int(np.argmax(np.abs(offset))), arm.up)}", text)
    turn = _turn_between(arm, T[:3, :3], goal[:3, :3])
    if turn > challenge.orientation_tolerance:
        return Verdict(False, f"The tool is on the target but turned {math.degrees(turn):.0f}° from its orientation.",
                       "tool turned", text)
    if challenge.branch is None:
        return Verdict(True, "Solved: your tool is on the target.", "", text)
    # where the goal leaves joints free (θ5 = 0: only θ4 + θ6 is fixed), each slot takes the student's values of them,
    # so that their branch is the slot nearest their joints
    solution = arm.ik(goal, hint=q)
    wanted = _wanted_slots(challenge, arm)
    on = _slot_of(arm, solution, q, prefer=wanted)
    labels = solution.labels
    if on not in wanted and arm.revolute[0]:
        # a goal on the base's axis leaves θ1 free, and the branches on the base's other side are the same poses
        # with θ1 half a turn on: the student may be on one of those with their θ1 as it is
        turned = q.copy()
        turned[0] += math.pi
        other_side = _slot_of(arm, arm.ik(goal, hint=turned), q, prefer=wanted)
        on = other_side if other_side in wanted else on
    if on in wanted:
        return Verdict(True, f"Solved: on the target on branch {on + 1} ({labels[on]}).", "", text)
    if isinstance(challenge.branch, int):
        return Verdict(False, f"That is branch {on + 1} ({labels[on]}); the task asks for branch {challenge.branch}.",
                       f"branch {on + 1} instead of {challenge.branch}", text)
    asked = _label_parts(challenge.branch)
    differ = [part for part in _label_parts(labels[on]) if part not in asked and any(part.split()[0] == a.split()[0] for a in asked)]
    return Verdict(False, f"That is the {labels[on]} branch (branch {on + 1}); the task asks for {challenge.branch}.",
                   f"{', '.join(differ) or labels[on]} instead of {challenge.branch}", text)


def _wanted_slots(challenge: Challenge, arm: Arm) -> list[int]:
    if isinstance(challenge.branch, int):
        return [challenge.branch - 1]
    return _slots_named(challenge.branch, arm.slot_labels)


def _slot_of(arm: Arm, solution, q: np.ndarray, prefer=()) -> int:
    """The valid slot of ``solution`` whose joints are ``q`` (whole turns apart for a revolute joint); where slots
    tie (at a singular target two are one: the wrist flipped or not at θ5 = 0), the first of ``prefer`` among them."""
    difference = np.where(arm.revolute, np.remainder(solution.q - q + math.pi, math.tau) - math.pi, solution.q - q)
    distance = np.where(solution.valid, np.abs(difference).max(axis=-1), np.inf)
    nearest = int(np.argmin(distance))
    tied = [k for k in prefer if distance[k] <= distance[nearest] + TIE_TOLERANCE]
    return tied[0] if tied else nearest


def _check_singularity(challenge: Challenge, arm: Arm, answer: Answer) -> Verdict:
    q = np.asarray(_needs(answer.q, "joints"), dtype=float)
    names = arm.factor_names
    factors = arm.singularity_factors(q)
    levels = np.abs(factors) / factor_scales(arm)
    asked = names.index(challenge.factor)
    text = _joints_text(arm, q)
    if levels[asked] > challenge.factor_tolerance:
        zero = [name for name, level in zip(names, levels) if level <= challenge.factor_tolerance]
        value = float(factors[asked])
        if zero:
            return Verdict(False, f"That is a {' and '.join(zero)} singularity; the task asks for the {challenge.factor} "
                           f"factor to be zero (it is {value:+.3g}).", f"{' and '.join(zero)} instead of {challenge.factor}", text)
        return Verdict(False, f"The {challenge.factor} factor is {value:+.3g}, {100 * levels[asked]:.0f} % of its usual size: "
                       f"not zero yet (within {100 * challenge.factor_tolerance:g} %).", f"{challenge.factor} factor not zero", text)
    height = float(heights_above_floor(arm, arm.fk(q)[:3, 3]))
    if challenge.min_tool_height is not None and height < challenge.min_tool_height:
        return Verdict(False, f"A {challenge.factor} singularity, but the tool is {1000 * height:.0f} mm above the floor: "
                       f"it must be at least {1000 * challenge.min_tool_height:.0f} mm.",
                       f"tool below {1000 * challenge.min_tool_height:.0f} mm", text)
    return Verdict(True, f"Solved: the {challenge.factor} factor is zero here.", "", text)


def _goal_joints(challenge: Challenge, arm: Arm) -> np.ndarray:
    """Where a branch_count task's orientation is the tool's: its joints, else the arm's home."""
    return np.array(challenge.joints if challenge.joints is not None else arm.specs.home)


def _goal_orientation(challenge: Challenge, arm: Arm) -> np.ndarray:
    return arm.fk(_goal_joints(challenge, arm))[:3, :3]


def _check_branch_count(challenge: Challenge, arm: Arm, answer: Answer) -> Verdict:
    T = np.asarray(_needs(answer.target, "target"), dtype=float)
    p = T[:3, 3]
    text = f"target {1000 * p[0]:.0f} {1000 * p[1]:.0f} {1000 * p[2]:.0f} mm"
    orientation = _goal_orientation(challenge, arm)
    turn = _turn_between(arm, T[:3, :3], orientation)
    if turn > challenge.orientation_tolerance:
        return Verdict(False, f"Keep the tool's orientation as given: your target is turned {math.degrees(turn):.0f}° from it.",
                       "target turned", text)
    goal = T.copy()
    goal[:3, :3] = orientation  # within the tolerance: counted at the asked orientation
    count = _count(arm, goal)
    if count != challenge.count:
        return Verdict(False, f"{_branches(count)} your target; the task asks for {challenge.count}.",
                       f"{count} branch{'es' * (count != 1)} instead of {challenge.count}", f"{text}: {count}")
    return Verdict(True, f"Solved: exactly {_branches(count)} your target.", "", f"{text}: {count}")


def _branches(count: int) -> str:
    return f"{count} branch reaches" if count == 1 else f"{count} branches reach"


def _count(arm: Arm, T: np.ndarray) -> int:
    """How many branches reach ``T`` (4, 4) within the joint limits, as the reach map counts them."""
    solution = arm.ik(T)
    return int((solution.valid & solution.within_limits).sum())


@functools.lru_cache(maxsize=64)
def _count_pose(challenge: Challenge, arm: Arm) -> tuple[float, ...]:
    """Joints of a pose whose target has exactly ``challenge.count`` branches at the asked orientation (a solution)."""
    rotation = _goal_orientation(challenge, arm)
    q = arm.sample_joints(4000, seed=7)
    T = arm.fk(q)
    T[:, :3, :3] = rotation
    solution = arm.ik(T)
    counts = (solution.valid & solution.within_limits).sum(axis=-1)
    above = heights_above_floor(arm, T[:, :3, 3]) > 0.1  # a target above the floor, where one exists
    found = np.flatnonzero((counts == challenge.count) & (counts > 0) & above)
    if not len(found):
        found = np.flatnonzero((counts == challenge.count) & (counts > 0))
    if not len(found):  # (zero branches has no pose to show: any far target is an answer)
        if challenge.count == 0:
            return tuple(arm.specs.home.tolist())
        raise ValueError(f"no target of the {arm.name} arm at this orientation is one where exactly {_branches(challenge.count)}")
    pose = int(found[0])
    slot = int(np.flatnonzero(solution.within_limits[pose])[0])
    return tuple(solution.q[pose, slot].tolist())


def _check_dh_table(challenge: Challenge, arm: Arm, answer: Answer) -> Verdict:
    table = _needs(answer.table, "typed table")
    text = _rows_text(table, "; ")
    if table.joint_types != arm.joint_types:
        return Verdict(False, f"Your table's joints are {table.joint_types or 'none'}; the arm's are {arm.joint_types}.",
                       "wrong joints", text)
    q = np.concatenate([[np.zeros(arm.n_joints), arm.specs.home], arm.sample_joints(DH_SAMPLES, seed=3)])
    error = np.abs(table.fk(q)[:, :3, :] - arm.fk(q)[:, :3, :])
    tolerance = challenge.position_tolerance / 10
    if error.max() <= tolerance:
        return Verdict(True, "Solved: your table's forward kinematics is the arm's.", "", text)
    at_zero = 1000 * float(np.linalg.norm(table.fk(q[0])[:3, 3] - arm.fk(q[0])[:3, 3]))
    row, what = _wrong_row(table, arm.dh.converted(table.convention))
    if row is None:
        return Verdict(False, f"Your table's tool is not where the arm's is ({at_zero:.0f} mm apart at zero joints).",
                       "different rows", text)
    return Verdict(False, f"Row {row + 1}'s {what}. (At zero joints your tool is {at_zero:.0f} mm from the arm's.)",
                   f"row {row + 1}: {what}", text)


def _wrong_row(table: DHTable, reference: DHTable) -> tuple[int | None, str]:
    """The first row of ``table`` that differs from ``reference`` (same convention) and how, or None if they do not line up."""
    rows, goal = [r for r in table.rows if r.joint or r.a or r.alpha or r.d or r.theta], \
        [r for r in reference.rows if r.joint or r.a or r.alpha or r.d or r.theta]
    if len(rows) != len(goal):
        return None, ""
    for k, (mine, theirs) in enumerate(zip(rows, goal)):
        if mine.joint != theirs.joint:
            return k, "type is wrong"
        for name, symbol, angle in (("alpha", "α", True), ("a", "a", False), ("d", "d", False), ("theta", "θ", True)):
            value, wanted = getattr(mine, name), getattr(theirs, name)
            if angle:
                value, wanted = math.remainder(value, math.tau), math.remainder(wanted, math.tau)
            if math.isclose(value, wanted, abs_tol=1e-4):
                continue
            if math.isclose(value, -wanted, abs_tol=1e-4):
                return k, f"{symbol} has the wrong sign"
            if not angle and math.isclose(value, wanted / 1000, abs_tol=1e-6):
                return k, f"{symbol} is in metres where mm are asked"
            return k, f"{symbol} is wrong"
    return None, ""


def expected_numbers(challenge: Challenge, arm: Arm) -> np.ndarray:
    """What a "numbers" challenge's answer is, in the units the student types (mm, m³…, N·m)."""
    q = np.array(challenge.joints)
    if challenge.quantity == "position":
        return 1000 * arm.fk(q)[:3, 3]
    if challenge.quantity == "wrist_centre":
        return 1000 * wrist_split(arm, q).centre
    if challenge.quantity == "tool_velocity":
        return 1000 * arm.tool_twist(q, np.array(challenge.rates))[:3]
    if challenge.quantity == "det_j":
        return np.array([arm.det_jacobian(q)])
    if challenge.quantity == "theta1":
        return np.degrees(separation_steps(arm, q).theta1)
    if challenge.quantity == "gravity_torque":
        return arm.gravity_torques(q, challenge.payload)
    return arm.static_torques(q, challenge.force, challenge.moment)


def number_names(challenge: Challenge, arm: Arm) -> tuple[str, ...]:
    if challenge.quantity in POINTS:
        return ("x", "y", "z")
    if challenge.quantity == "tool_velocity":
        return ("vx", "vy", "vz")
    if challenge.quantity == "det_j":
        return ("det J",)
    if challenge.quantity == "theta1":
        return ("θ1 left", "θ1 right")
    return tuple(f"τ{k + 1}" for k in range(arm.n_joints))


def _slips(challenge: Challenge, arm: Arm, expected: np.ndarray) -> list[tuple[np.ndarray, str, str]]:
    """Whole answers a known slip gives, in the units typed: (the numbers, the group, what the student reads).
    ``expected``: the right answer (:func:`expected_numbers`)."""
    q, quantity = np.array(challenge.joints), challenge.quantity
    if quantity == "position":  # the product of the link transforms stopped one short
        frames = arm.frames(q)
        return [(1000 * frames[-2][:3, 3], "the last transform left out",
                 f"That is where frame {len(frames) - 2}, the frame before the tool's, is: the last link "
                 "transform, from it to the tool, is left out.")]
    if quantity == "det_j" and arm.name in Arm.UR_PRESETS:  # det J = a2 a3 (a2 c2 + a3 c23 − d5 s234) s3 s5
        det = expected
        return [(det / (arm.a2 * arm.a3), "a2·a3 left out", "That is the product of the three factors: det J is a2·a3 times it."),
                (det * 1e9, "lengths in mm, not metres", "Those are lengths in mm: det J is in m³, so it is 10⁹ times smaller.")]
    if quantity == "torque" and arm.n_joints == 6:  # J is square: J [F; M] can be typed in its place
        wrench = np.concatenate([challenge.force, challenge.moment])
        return [(arm.jacobian(q) @ wrench, "J [F; M], not Jᵀ [F; M]",
                 "That is J [F; M]: the joint torques are Jᵀ [F; M] (virtual work: τ · q̇ = [F; M] · J q̇).")]
    if quantity == "tool_velocity":  # the revolute joints' rates in °/s, read as rad/s
        typed_rates = np.where(arm.revolute, np.degrees(challenge.rates), challenge.rates)
        return [(1000 * arm.tool_twist(q, typed_rates)[:3], "joint rates in °/s taken as rad/s",
                 "That is J_v q̇ with the rates in °/s read as rad/s: turn them into rad/s first.")]
    if quantity == "gravity_torque":
        slips = [(-expected, "gravity's torques, not the holding ones",
                  "Those are the torques gravity puts on the joints: holding the arm still takes their opposite."),
                 (expected / GRAVITY, "masses, not weights",
                  f"Those are masses times lever arms: each weight is m g, {GRAVITY} times more (N·m, not kg·m).")]
        if challenge.payload:
            slips.append((arm.gravity_torques(q), "the payload left out",
                          f"Those hold the arm alone: the {challenge.payload:g} kg at the flange is left out."))
        return slips
    if quantity == "theta1":
        d4, d6 = arm.solver.dh_lengths[3], arm.solver.dh_lengths[5]
        return [(np.degrees(shoulder_angles(arm.fk(q)[:3, 3], d4)), "θ1 from p, not from P5",
                 f"Those are the θ1 of p, the flange: step 1 works on P5 = p − d6·z6, {1000 * d6:.1f} mm back along z6.")]
    if quantity == "wrist_centre":
        T, c = arm.fk(q), wrist_split(arm, q).centre_in_tool
        offset = T[:3, :3] @ c
        along = (f"{1000 * np.linalg.norm(c):.0f} mm {'back' if c[2] < 0 else 'on'} along the tool's z"
                 if np.allclose(c[:2], 0.0) else f"R c = ({', '.join(f'{1000 * v:.0f}' for v in offset)}) mm from it")
        return [(1000 * T[:3, 3], "p of the tool, not WC", f"That is p, where the tool is: WC is {along}."),
                (1000 * (T[:3, 3] - offset), "the tool's offset taken the wrong way",
                 f"The offset went the wrong way: WC is {along} from p, not the other way.")]
    return []


def _check_numbers(challenge: Challenge, arm: Arm, answer: Answer) -> Verdict:
    typed = np.asarray(_needs(answer.numbers, "numbers"), dtype=float).reshape(-1)
    expected = expected_numbers(challenge, arm)
    names = number_names(challenge, arm)
    if typed.shape != expected.shape:
        raise ValueError(f"type {len(expected)} number{'s' * (len(expected) != 1)} ({', '.join(names)}), got {typed.size}")
    text = " ".join(f"{v:.6g}" for v in typed)
    angles = challenge.quantity in ANGLES
    if angles:  # a turn more or less is the same angle; the tolerance is a share of a half-turn
        allowed = np.full(expected.shape, 180.0 * challenge.relative_tolerance)
    else:  # relative to each number, with a floor of 1 % of the largest, or of their usual size (a zero is within reach)
        largest = max(float(np.abs(expected).max()), _usual_size(challenge, arm))
        allowed = challenge.relative_tolerance * np.maximum(np.abs(expected), 0.01 * largest)

    def gap(a, b):
        return abs((a - b + 180.0) % 360.0 - 180.0) if angles else abs(a - b)

    wrong = gap(typed, expected) > allowed
    if not wrong.any():
        return Verdict(True, "Solved: every number is right.", "", text)
    for value, group, message in _slips(challenge, arm, expected):
        if not (gap(typed, value) > allowed).any():
            return Verdict(False, message, group, text)
    kinds = []
    for k in np.flatnonzero(wrong):
        if gap(typed[k], -expected[k]) <= allowed[k]:
            kinds.append("has the wrong sign")
        elif angles and abs(typed[k] - math.radians(expected[k])) <= math.radians(allowed[k]):
            kinds.append("is in radians, not degrees")
        elif not angles and abs(typed[k] - expected[k] / 1000) <= allowed[k] / 1000:
            kinds.append("is in metres, not mm" if challenge.quantity in POINTS else "is 1000 times too small")
        elif not angles and abs(typed[k] - 1000 * expected[k]) <= 1000 * allowed[k]:
            kinds.append("is 1000 times too big")
        elif typed[k] != 0.0 and gap(typed[k], expected[k]) <= _last_place(typed[k]) / 2:
            kinds.append("is rounded too far: give another digit")
        else:
            kinds.append("is off")
    off = [names[k] for k in np.flatnonzero(wrong)]
    # a swap only between numbers nothing simpler explains (a flipped sign can look like a swap: vy ≈ −vz)
    unexplained = [k for k, kind in zip(np.flatnonzero(wrong), kinds) if kind == "is off"]
    swapped = [(names[i], names[j]) for i in unexplained for j in unexplained
               if i < j and gap(typed[i], expected[j]) <= allowed[j] and gap(typed[j], expected[i]) <= allowed[i]]
    if swapped:
        group = f"{swapped[0][0]} and {swapped[0][1]} swapped"
    elif len(set(kinds)) == 1:
        group = f"{', '.join(off)} {kinds[0] if len(off) == 1 else kinds[0].replace('has', 'have').replace('is', 'are', 1)}"
    else:
        group = f"{len(off)} numbers off"
    details = "; ".join(f"{name} {kind}" for name, kind in zip(off, kinds))
    # a quantity's name keeps its case at the start (X or Τ1 would be another quantity)
    within = f"{180 * challenge.relative_tolerance:g}°" if angles else f"{100 * challenge.relative_tolerance:g} %"
    return Verdict(False, f"{details} (each within {within}).", group, text)


def _last_place(typed: float) -> float:
    """The value of the last place ``typed`` shows, as the shortest text that gives it back: 0.1 for 2.3, 1 for 2
    (or 2.0), 1e-08 for 1.5e-07. A number typed as rounded to that place is within half of it of the exact one.

    >>> _last_place(2.3), _last_place(-0.05), _last_place(40.0), _last_place(1.5e-07)
    (0.1, 0.01, 1.0, 1e-08)
    """
    mantissa, _, exponent = repr(abs(float(typed))).partition("e")
    decimals = len(mantissa.partition(".")[2].rstrip("0")) - int(exponent or 0)
    return 10.0 ** -decimals


@functools.lru_cache(maxsize=64)
def _usual_size(challenge: Challenge, arm: Arm) -> float:
    """How large a numbers challenge's answers can be on ``arm``, in the units typed: a bound from its reach and the
    given rates, force or payload, and for det J the 99th percentile of |det J| over its joint range. A number near
    zero is judged against it: on a singularity det J is zero to rounding (5e-18 m³ at the UR10's elbow folded
    back), and an exact 0 was "off" by more than 1 % of that."""
    reach = arm.reach_bound
    if challenge.quantity == "det_j":
        return float(np.percentile(np.abs(arm.det_jacobian(arm.sample_joints(2000, seed=3))), 99))
    if challenge.quantity == "tool_velocity":
        return 1000 * reach * float(np.abs(challenge.rates).sum())
    if challenge.quantity == "torque":
        return reach * float(np.linalg.norm(challenge.force)) + float(np.linalg.norm(challenge.moment))
    if challenge.quantity == "gravity_torque":
        return GRAVITY * (float(np.sum(MASSES[arm.name].masses)) + challenge.payload) * reach
    return 1000 * reach  # a point's coordinates


def _check_velocity(challenge: Challenge, arm: Arm, answer: Answer) -> Verdict:
    q = np.asarray(_needs(answer.q, "joints"), dtype=float)
    rates = np.asarray(_needs(answer.rates, "joint rates"), dtype=float)
    twist = arm.tool_twist(q, rates)
    v, asked = twist[:3], np.array(challenge.velocity)
    text = "q̇ " + _joints_text(arm, rates)
    shown = ", ".join(f"{1000 * c:+.0f}" for c in v)
    miss = float(np.linalg.norm(v - asked))
    turning = float(np.linalg.norm(twist[[r for r in TASK_ROWS[arm.task] if r >= 3]])) if challenge.still else 0.0
    if miss > challenge.velocity_tolerance:
        speed, asked_speed = float(np.linalg.norm(v)), float(np.linalg.norm(asked))
        if speed < challenge.velocity_tolerance:
            group = "not moving"
        elif np.linalg.norm(v + asked) <= challenge.velocity_tolerance:
            group = "wrong sign"
        elif np.dot(v, asked) / (speed * asked_speed) > math.cos(math.radians(5)):
            group = "too fast" if speed > asked_speed else "too slow"
        else:
            group = "wrong direction"
        return Verdict(False, f"Your tool moves at ({shown}) mm/s: {1000 * miss:.0f} mm/s from the asked velocity.", group, text)
    if turning > math.radians(1.0):
        return Verdict(False, f"The velocity is right, but the tool turns at {math.degrees(turning):.1f} °/s: it must not turn.",
                       "tool turns", text)
    return Verdict(True, f"Solved: your tool moves at ({shown}) mm/s.", "", text)


def _rates_solve(challenge: Challenge, arm: Arm, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
    """(...) bool: whether joint rates ``qdot`` (..., n) at joints ``q`` (..., n) are rates a student can set that move
    the tool at the asked velocity (within half its tolerance)."""
    limits = np.array([RATE_LIMITS[k] for k in arm.joint_types]) * np.where(arm.revolute, math.pi / 180, 1e-3)
    moves = np.linalg.norm(arm.tool_twist(q, qdot)[..., :3] - challenge.velocity, axis=-1) <= challenge.velocity_tolerance / 2
    return moves & (np.abs(qdot) <= limits).all(axis=-1)


@functools.lru_cache(maxsize=16)
def _velocity_pose(challenge: Challenge, arm: Arm, samples: int = 2000) -> tuple[float, ...] | None:
    """A pose (the home pose, else the first of ``samples`` random ones) whose joint rates a student can set solve a
    velocity challenge; None where none does."""
    q = np.concatenate([[arm.specs.home], arm.sample_joints(samples, seed=8)])
    found = np.flatnonzero(_rates_solve(challenge, arm, q, _velocity_rates(challenge, arm, q)))
    return tuple(q[found[0]].tolist()) if len(found) else None


def _velocity_rates(challenge: Challenge, arm: Arm, q: np.ndarray) -> np.ndarray:
    """Joint rates (..., n) that move the tool at the asked velocity from joints ``q`` (..., n), as the check
    weighs them: without turning where it must not turn (the rows of J the arm controls: a SCARA's yaw with v), else
    from J_v's rows alone (the least-squares rates of all six would trade the asked v for an ω nobody asked about)."""
    if challenge.still:
        return arm.joint_rates(q, np.concatenate([challenge.velocity, np.zeros(3)])).qdot
    return damped_inverse(arm.jacobian(q)[..., :3, :], np.broadcast_to(challenge.velocity, np.shape(q)[:-1] + (3,)))[0]


def _searchable(arm: Arm) -> bool:
    """Whether :func:`largest_torque` searches the arm exactly, in one unit: a few revolute joints."""
    return arm.n_joints <= GRID_JOINTS and set(arm.joint_types) == {"R"}


@functools.lru_cache(maxsize=16)
def worst_pose(challenge: Challenge, arm: Arm) -> WorstPose:
    """Where a largest_torque challenge's force needs the most torque (a grid search, refined: once per challenge)."""
    return largest_torque(arm, challenge.force)


#: A largest_torque answer's groups on the projector: (its share of the largest ‖τ‖ at least this, the group)
TORQUE_SHARES = ((0.9, "over 90 % of the largest"), (0.5, "half to 90 % of the largest"), (0.0, "under half the largest"))


def _check_largest_torque(challenge: Challenge, arm: Arm, answer: Answer) -> Verdict:
    q = np.asarray(_needs(answer.q, "joints"), dtype=float)
    text = _joints_text(arm, q)
    if not arm.within_limits(q):
        return Verdict(False, "Your joints are beyond the arm's ranges: the task keeps to them.", "beyond the joint ranges", text)
    worst = worst_pose(challenge, arm)
    norm = float(np.linalg.norm(arm.static_torques(q, challenge.force)))
    share = norm / worst.norm
    text += f": ‖τ‖ {norm:.4g} N·m"
    if share >= 1.0 - challenge.relative_tolerance:
        return Verdict(True, f"Solved: here ‖τ‖ = {norm:.2f} N·m, the most this force can need.", "", text)
    group = next(words for least, words in TORQUE_SHARES if share >= least)
    return Verdict(False, f"Here ‖τ‖ = {norm:.2f} N·m: {100 * share:.0f} % of the most this force can need. Not yet "
                   f"(within {100 * challenge.relative_tolerance:g} %).", group, text)


_CHECKS = {"reach": _check_reach, "singularity": _check_singularity, "branch_count": _check_branch_count,
           "dh_table": _check_dh_table, "numbers": _check_numbers, "velocity": _check_velocity,
           "largest_torque": _check_largest_torque}


# ---------------------------------------------------------------------- solutions


def solution(challenge: Challenge, arm: Arm, q_current=None) -> tuple[np.ndarray | None, str]:
    """What the class is shown when the challenge ends: joints to move the arm to (None for a typed answer), and words.

    ``q_current``: where a velocity task's arm is (its rates depend on it; the arm's home otherwise). Where no joint
    rates a student can set give the velocity there, the arm goes to a pose where some do, and the words say so.
    """
    if challenge.kind == "reach":
        goal = arm.fk(np.array(challenge.joints))
        if challenge.branch is None:
            q = np.array(challenge.joints)
        else:
            solution_ = arm.ik(goal, hint=np.array(challenge.joints))
            slot = next(s for s in _wanted_slots(challenge, arm) if solution_.within_limits[s])  # (parse made sure)
            q = solution_.take(slot, np.array(challenge.joints))
        return q, f"One answer: joints {_joints_text(arm, q)}."
    if challenge.kind == "singularity":
        q = singular_pose(arm, challenge.factor, challenge.min_tool_height)
        return q, f"One answer: joints {_joints_text(arm, q)}."
    if challenge.kind == "branch_count":
        q = np.array(_count_pose(challenge, arm))
        return q, f"One answer: the target at {', '.join(f'{1000 * v:.0f}' for v in arm.fk(q)[:3, 3])} mm."
    if challenge.kind == "largest_torque":
        worst = worst_pose(challenge, arm)
        return worst.q, f"The largest: ‖τ‖ = {worst.norm:.2f} N·m at joints {_joints_text(arm, worst.q)}."
    if challenge.kind == "dh_table":
        line_break = "  \n"  # markdown's
        return None, f"The arm's table ({arm.dh.convention} convention, a α d θ type):{line_break}{_rows_text(arm.dh, line_break)}"
    if challenge.kind == "numbers":
        values = expected_numbers(challenge, arm)
        if challenge.quantity not in ANGLES:  # what rounding leaves of a zero (det J on a singularity: 5e-18 m³) is 0
            values = np.where(np.abs(values) < 1e-9 * _usual_size(challenge, arm), 0.0, values) + 0.0  # (no "-0")
        return None, "The answer: " + ", ".join(f"{name} = {value:.6g}" for name, value in zip(number_names(challenge, arm), values))
    q = np.asarray(arm.specs.home if q_current is None else q_current, dtype=float)
    at = "your pose" if q_current is not None else "the arm's home pose"
    rates = _velocity_rates(challenge, arm, q)
    if _rates_solve(challenge, arm, q, rates):
        return None, f"At {at}, one answer: q̇ = ({_joints_text(arm, rates, '+.1f')}) °/s (mm/s)."
    # at or near a singularity for this velocity (or needing rates beyond the sliders'): the arm goes where some do
    q = np.array(_velocity_pose(challenge, arm))
    rates = _velocity_rates(challenge, arm, q)
    return q, (f"At {at} no joint rates you can set move the tool so (it is at or near a singularity for this "
               f"velocity). At joints {_joints_text(arm, q)}, one answer: q̇ = ({_joints_text(arm, rates, '+.1f')}) °/s (mm/s).")


def singular_pose(arm: Arm, factor: str, min_tool_height: float | None = None, seed: int = 5) -> np.ndarray:
    """Joints within the limits where ``factor`` of det J is zero (to rounding) and the tool is high enough.

    The pose :meth:`Arm.singular_configuration` puts the arm in from its home pose (docs/kinematics.md §5.2),
    or from random poses (``seed``) where that one's tool is too low.
    """
    if factor not in arm.factor_names:
        raise ValueError(f"the {arm.name} arm has no {factor!r} factor: its det J's are {', '.join(arm.factor_names)}")
    for start in np.concatenate([[arm.specs.home], arm.sample_joints(200, seed=seed)]):
        try:
            q = arm.singular_configuration(factor, start)
        except ValueError:
            continue  # no zero of the factor within reach of this start's single joints
        if min_tool_height is None or heights_above_floor(arm, arm.fk(q)[:3, 3]) >= min_tool_height + 0.01:
            return q
    where = "" if min_tool_height is None else f" and the tool {1000 * min_tool_height:.0f} mm above the floor"
    raise ValueError(f"no pose of the {arm.name} arm within its limits has its {factor} factor zero{where}")
